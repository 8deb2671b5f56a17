//! The planning pipeline: a plan's options ([`options`]), a mesh rendered on the table and
//! planned on ([`pipeline`]), depth predicted from RGB views ([`rgb`]) and a sensor's depth
//! images ([`sensor`]). The planning on depth images itself (the sampler, the GQ-CNN policies,
//! the fused multi-view planner, the shipped networks) is `mvgrasp_planner`'s, re-exported
//! here.

pub mod options;
pub mod pipeline;
pub mod rgb;
pub mod sensor;

pub use mvgrasp_planner::{
    CemParams, DepthImage, DepthSource, Fusion, FusionParams, GqcnnPolicy, HoldProbability,
    ImageSamplerParams, Mask, MultiViewPlanner, Occupancy, Plan, Planner, ScoredGrasp,
    ShippedModel, View, ViewSetting, VirtualScorer, VirtualViewParams, models, sample_image_grasps,
    theta_rad,
};
pub use options::{ChanceSource, FUSED_VIEWS, PlanOptions};
pub use pipeline::{
    AnalyticCheck, PlanParams, PlanReport, PlanTimings, RgbInput, Scene, check_grasp, check_grasps,
    plan_grasp, render_rgb, render_scene,
};
pub use rgb::{
    DepthFrom, DepthPredictor, RgbPlanReport, plan_on_rgb_dir, plan_on_rgb_views, predict_views,
    read_rgb_dir,
};
pub use sensor::{
    ObjectSource, SensorFiles, SensorPlanParams, SensorPlanReport, ViewsPlanReport,
    plan_on_sensor_depth, plan_on_view, plan_on_views, plan_on_views_dir, read_view,
    read_views_dir,
};
