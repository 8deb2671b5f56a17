//! The main job: an object on a table, seen by the seed paper's test cameras, a grasp planned
//! by a GQ-CNN in every view, and the winner checked analytically and in physics.

use std::time::Instant;

use mvgrasp_geometry::{
    Camera, HemisphereLayout, Intrinsics, IntrinsicsPreset, Pose3, RestingPoses, TriangleMesh,
};
use mvgrasp_grasp::physics::{PhysicsObject, PhysicsOutcome, simulate_grasp};
use mvgrasp_grasp::quality::robust_qualities;
use mvgrasp_grasp::{GraspObject, PaperGrasp, check_collision};
use mvgrasp_render::Renderer;
use serde::Serialize;

use crate::error::Result;
use crate::grasp_dataset::GraspDatasetConfig;
use crate::grasp_dataset::object::render_depths;
use mvgrasp_planner::{GqcnnPolicy, ScoredGrasp, View, theta_rad};

/// What [`plan_grasp`] does.
#[derive(Clone, Debug)]
pub struct PlanParams {
    /// The cameras: the paper's 10 test views (the first top-down) unless told otherwise.
    pub views: HemisphereLayout,
    /// Use only the first this many views (1: the top-down view alone, Dex-Net 2.0's setting).
    pub max_views: usize,
    /// Camera intrinsics.
    pub intrinsics: Intrinsics,
    /// Which pose the object rests in: an index into its offered resting poses
    /// ([`RestingPoses`]: the non-marginal ones, most probable first; the marginal ones for an
    /// object that has no other).
    pub stable_pose: usize,
    /// Seeds the cameras and the sampler.
    pub seed: u64,
    /// The gripper, quality, collision and physics settings: the grasp dataset's, so that the
    /// check measures what the network was trained to predict.
    pub labels: GraspDatasetConfig,
    /// Run the rapier trial on the best grasp.
    pub physics: bool,
}

impl Default for PlanParams {
    fn default() -> Self {
        let labels = GraspDatasetConfig::default();
        Self {
            views: HemisphereLayout::paper_test(),
            max_views: usize::MAX,
            // The grasp datasets' camera (`GraspDatasetConfig::default().intrinsics`).
            intrinsics: Intrinsics::preset(IntrinsicsPreset::PhoxiS),
            stable_pose: 0,
            seed: 0,
            labels,
            physics: true,
        }
    }
}

/// One view's share of the plan.
#[derive(Clone, Debug, Serialize)]
pub struct ViewSummary {
    /// Elevation of the camera above the table plane, degrees (90: top-down).
    pub elevation_deg: f32,
    /// Candidates sampled and scored.
    pub candidates: usize,
    /// The best score in this view.
    pub best_quality: Option<f32>,
}

/// The analytic check of the chosen grasp, with the dataset's label settings.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct AnalyticCheck {
    /// Robust Ferrari-Canny epsilon.
    pub robust_epsilon: f64,
    /// Whether the gripper reaches the grasp without touching the object or the table.
    pub collision_free: bool,
    /// The dataset's label: collision-free and robust epsilon above the threshold.
    pub robust: bool,
}

/// What [`plan_grasp`] found.
#[derive(Clone, Debug, Serialize)]
pub struct PlanReport {
    /// The stable pose the object rests in (index into all its poses, most probable first)
    /// and its probability.
    pub stable_pose: usize,
    /// See `stable_pose`.
    pub stable_pose_probability: f32,
    /// Where the object rests: the table (world) frame from the object's.
    #[serde(with = "mvgrasp_geometry::pose_as_matrix")]
    pub table_from_object: Pose3,
    /// The cameras, in view order.
    pub cameras: Vec<Camera>,
    /// Per view, in camera order.
    pub views: Vec<ViewSummary>,
    /// The best grasp over all views.
    pub best: Option<ScoredGrasp>,
    /// The best ten, best first.
    pub top: Vec<ScoredGrasp>,
    /// Every candidate of every view, best first (not in the JSON: thousands).
    #[serde(skip)]
    pub candidates: Vec<ScoredGrasp>,
    /// The best grasp in the paper's form (p, phi, theta).
    pub best_paper: Option<PaperGrasp>,
    /// The analytic check of the best grasp.
    pub analytic: Option<AnalyticCheck>,
    /// The rapier trial of the best grasp (close, lift, shake).
    pub physics: Option<PhysicsOutcome>,
    /// Wall-clock times (not in the JSON, which is the same bytes for the same seed).
    #[serde(skip)]
    pub timings: PlanTimings,
}

/// Seconds spent in each stage of [`plan_grasp`].
#[derive(Clone, Copy, Debug, Default)]
pub struct PlanTimings {
    /// Rendering the views' depth.
    pub render_s: f64,
    /// Sampling, cropping and scoring in every view.
    pub plan_s: f64,
    /// The analytic and physics checks of the best grasp.
    pub check_s: f64,
}

/// Rests `mesh` on a table in a stable pose, renders the views' depth, plans with `policy`,
/// and checks the best grasp.
///
/// # Errors
/// An object with no stable pose, or an error of the renderer, the network or the checks.
pub fn plan_grasp(
    renderer: &Renderer,
    mesh: &TriangleMesh,
    policy: &GqcnnPolicy,
    params: &PlanParams,
) -> Result<PlanReport> {
    let rest = RestingPoses::of(mesh)?;
    let (pose_index, &pose) = rest.get(params.stable_pose)?;
    let table_from_object = pose.table_from_object;
    let object = GraspObject::new(mesh.clone())?;
    let target = table_from_object.transform_point(object.center_of_mass());
    let mut cameras = params
        .views
        .cameras(params.intrinsics, target, params.seed)?;
    cameras.truncate(params.max_views.max(1));

    let started = Instant::now();
    let depths = render_depths(renderer, mesh, &table_from_object, &cameras)?;
    let render_s = started.elapsed().as_secs_f64();

    let started = Instant::now();
    let views = cameras
        .iter()
        .zip(depths)
        .enumerate()
        .map(|(i, (camera, depth))| View::new(i, *camera, depth))
        .collect::<mvgrasp_planner::Result<Vec<_>>>()?;
    let plan = policy.plan(&views, params.seed)?;
    let plan_s = started.elapsed().as_secs_f64();

    let started = Instant::now();
    let best = plan.best().copied();
    let gripper = params.labels.gripper()?;
    let mut analytic = None;
    let mut physics = None;
    if let Some(best) = &best {
        let object_from_gripper = table_from_object.inverse() * best.grasp.world_from_gripper;
        let quality = robust_qualities(
            &object,
            &[object_from_gripper],
            &gripper,
            &params.labels.quality,
            params.seed,
        )?[0];
        let collision_free = check_collision(
            &object,
            &gripper,
            &object_from_gripper,
            Some(&table_from_object),
            &params.labels.sampling.collision,
        )
        .is_free();
        analytic = Some(AnalyticCheck {
            robust_epsilon: quality.robust_epsilon,
            collision_free,
            robust: params
                .labels
                .quality
                .dexnet_label(quality.robust_epsilon, collision_free),
        });
        if params.physics {
            let physics_object = PhysicsObject::from_grasp_object(&object, &Default::default())?;
            physics = Some(simulate_grasp(
                &physics_object,
                &table_from_object,
                &best.grasp,
                &gripper,
                &params.labels.physics,
            )?);
        }
    }
    let check_s = started.elapsed().as_secs_f64();
    let views = cameras
        .iter()
        .enumerate()
        .map(|(i, camera)| ViewSummary {
            elevation_deg: theta_rad(camera).to_degrees(),
            candidates: plan.candidates_per_view[i],
            best_quality: plan.best_in_view(i).map(|c| c.quality),
        })
        .collect();
    Ok(PlanReport {
        stable_pose: pose_index,
        stable_pose_probability: pose.probability,
        views,
        cameras,
        table_from_object,
        best_paper: best.map(|b| b.grasp.to_paper()),
        best,
        top: plan.candidates.iter().take(10).copied().collect(),
        candidates: plan.candidates,
        analytic,
        physics,
        timings: PlanTimings {
            render_s,
            plan_s,
            check_s,
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_planner_sees_with_the_camera_its_networks_were_trained_with() {
        let params = PlanParams::default();
        assert_eq!(
            Ok(params.intrinsics),
            params.labels.intrinsics().map_err(|_| ())
        );
    }
}
