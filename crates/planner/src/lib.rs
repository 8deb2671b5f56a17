#![doc = include_str!("../README.md")]

pub mod cem;
pub mod cloud_sampler;
pub mod contract;
pub mod crop;
pub mod depth_image;
pub mod error;
pub mod fusion;
pub mod hand_check;
pub mod models;
pub mod multiview;
pub mod plan;
pub mod policy;
pub mod probability;
pub mod ranker;
pub mod sampler;
pub mod scored;
pub mod seed;
pub mod table;
#[cfg(test)]
mod test_scenes;
pub mod virtual_view;

pub use cem::CemParams;
pub use cloud_sampler::{CloudSamplerParams, sample_cloud_grasps};
pub use contract::InputContract;
pub use crop::{CropParams, crop_depth};
pub use depth_image::{DepthImage, Mask, View, theta_rad};
pub use error::{PlannerError, Result};
pub use fusion::{Fusion, FusionParams, Occupancy};
pub use hand_check::check_hand;
pub use models::{ShippedModel, ViewSetting};
pub use multiview::{MultiViewPlanner, Planner};
pub use plan::Plan;
pub use policy::GqcnnPolicy;
pub use probability::{DepthSource, HoldProbability, PlannerKind};
pub use ranker::Ranker;
pub use sampler::{ImageSamplerParams, sample_image_grasps};
pub use scored::{Rejection, Rejections, ScoredGrasp, tilt_rad};
pub use table::{TableFit, TableFitParams, fit_table, objects_above};
pub use virtual_view::{VirtualScorer, VirtualViewParams, virtual_crop};
