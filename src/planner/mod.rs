//! Grasp planning from depth images: the depth-image antipodal sampler ([`sampler`]), the
//! GQ-CNN policy over one or many views ([`policy`]), and the networks that ship with mvgrasp
//! ([`models`]).

pub mod models;
pub mod pipeline;
pub mod policy;
pub mod sampler;

pub use models::{ShippedModel, ViewSetting};
pub use pipeline::{PlanParams, PlanReport, PlanTimings, plan_grasp};
pub use policy::{GqcnnPolicy, Plan, ScoredGrasp, View};
pub use sampler::{ImageSamplerParams, sample_image_grasps};
