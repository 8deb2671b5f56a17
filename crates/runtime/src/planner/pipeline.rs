//! The main job: an object on a table, seen by the seed paper's test cameras, a grasp planned
//! by a GQ-CNN in every view, and the winner checked analytically and in physics.

use std::time::Instant;

use mvgrasp_geometry::{
    Camera, HemisphereLayout, Intrinsics, IntrinsicsPreset, Pose3, RestingPoses, TriangleMesh,
};
use mvgrasp_grasp::physics::{PhysicsObject, PhysicsOutcome};
use mvgrasp_grasp::{GraspLabel, GraspObject, Gripper, LabelSettings, PaperGrasp, label_grasps};
use mvgrasp_render::{Colors, Lighting, Renderer, random_colors};
use serde::Serialize;

use crate::convert::rgb_view_of;
use crate::error::Result;
use crate::planner::rgb::{DepthPredictor, predict_views};
use crate::scene::photoreal::render_photoreal;
use crate::scene::{OBJECT_ID, SceneData, TABLE_HALF_SIDE_M, render_depths, render_frames};
use crate::stereo::RgbView;
use mvgrasp_planner::seed::splitmix;
use mvgrasp_planner::{Fusion, FusionParams, Planner, Rejections, ScoredGrasp, View};

/// The best candidates a report lists (and the hand check makes sure of).
const TOP_KEPT: usize = 10;

/// What [`plan_grasp`] does.
#[derive(Clone, Debug)]
pub struct PlanParams {
    /// The cameras: the paper's 10 test views (the first top-down) unless told otherwise.
    pub views: HemisphereLayout,
    /// Use only the first this many views (1: the top-down view alone, Dex-Net 2.0's setting).
    pub max_views: usize,
    /// Plan in the first this many of the views only; the others still inform the depth
    /// predicted from RGB ([`PlanParams::depth_from_rgb`]). `None`: plan in every view.
    pub plan_views: Option<usize>,
    /// Camera intrinsics.
    pub intrinsics: Intrinsics,
    /// Which pose the object rests in: an index into its offered resting poses
    /// ([`RestingPoses`]: the non-marginal ones, most probable first; the marginal ones for an
    /// object that has no other).
    pub stable_pose: usize,
    /// Seeds the cameras and the sampler.
    pub seed: u64,
    /// The gripper, sampling, quality, collision and physics settings: the shipped grasp
    /// datasets' by default, so that the check measures what the networks were trained to
    /// predict.
    pub labels: LabelSettings,
    /// Run the rapier trial on the best grasp.
    pub physics: bool,
    /// Before a grasp is returned, reject candidates whose open hand meets a point some view
    /// observed, or whose contacts are off the observed surface
    /// ([`mvgrasp_planner::Plan::reject_colliding`]).
    pub hand_check: bool,
    /// Plan on depth predicted from RGB instead of the rendered depth: the views are rendered
    /// in colour (random colours, as the RGB-D datasets' test views) with the object's masks,
    /// and each view's depth is predicted ([`RgbInput::depth`]); the masks go with the
    /// views. `None`: the rendered depth.
    pub depth_from_rgb: Option<RgbInput>,
    /// Fuse the views ([`Fusion`]) before the hand check: the open hand must also stay out of
    /// space that no view has seen, and above the table; and the multi-view planner
    /// ([`mvgrasp_planner::MultiViewPlanner`]) re-scores the best candidates on views drawn from
    /// the fused points. `None`: each view on its own.
    pub fusion: Option<FusionParams>,
}

impl Default for PlanParams {
    fn default() -> Self {
        Self {
            views: HemisphereLayout::paper_test(),
            max_views: usize::MAX,
            plan_views: None,
            // The grasp datasets' camera (a test in `grasp_dataset::config` checks both).
            intrinsics: Intrinsics::preset(IntrinsicsPreset::PhoxiS),
            stable_pose: 0,
            seed: 0,
            labels: LabelSettings::default(),
            physics: true,
            hand_check: true,
            depth_from_rgb: None,
            fusion: None,
        }
    }
}

/// How [`PlanParams::depth_from_rgb`] colours the object and predicts depth.
#[derive(Clone, Debug, PartialEq)]
pub struct RgbInput {
    /// The depth predictor.
    pub depth: DepthPredictor,
    /// Random colours per triangle (as half the RGB-D datasets' objects) instead of per vertex
    /// (interpolated across the faces).
    pub per_face: bool,
    /// The photographic look ([`crate::scene::photoreal`]: textures, gloss, room lights and
    /// shadows, a background, sensor noise, blur, JPEG) instead of random colours under each
    /// camera's headlight (`per_face` is then ignored).
    pub photo: bool,
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
    /// Candidates rejected before the best was chosen, by reason (the hand check).
    pub rejections: Rejections,
    /// Wall-clock times (not in the JSON, which is the same bytes for the same seed).
    #[serde(skip)]
    pub timings: PlanTimings,
    /// The views planned on, with their (rendered or predicted) depth (not in the JSON).
    #[serde(skip)]
    pub scene_views: Vec<View>,
    /// The colour views the depth was predicted from; none for rendered depth (not in the
    /// JSON).
    #[serde(skip)]
    pub rgb_views: Vec<RgbView>,
}

/// Seconds spent in each stage of [`plan_grasp`].
#[derive(Clone, Copy, Debug, Default)]
pub struct PlanTimings {
    /// Rendering the views' depth (with [`PlanParams::depth_from_rgb`]: rendering them in
    /// colour and predicting their depth).
    pub render_s: f64,
    /// Predicting the views' depth from RGB (part of `render_s`; 0 for rendered depth).
    pub depth_s: f64,
    /// Fusing the views (part of `plan_s`).
    pub fuse_s: f64,
    /// Fusing, sampling, cropping and scoring in every view, the hand check and re-scoring.
    pub plan_s: f64,
    /// The analytic and physics checks of the best grasp.
    pub check_s: f64,
}

/// An object at rest on the table and the views of it the planner looks through: the first
/// stage of [`plan_grasp`], and what a depth sensor (or a depth predictor) gives instead.
#[derive(Clone, Debug)]
pub struct Scene {
    /// The offered resting pose used (index into all the object's stable poses).
    pub stable_pose: usize,
    /// Its probability.
    pub stable_pose_probability: f32,
    /// Where the object rests: the table (world) frame from the object's.
    pub table_from_object: Pose3,
    /// The views, each a camera and its depth image.
    pub views: Vec<View>,
    /// Seconds spent predicting the views' depth from RGB (0 for rendered depth).
    pub depth_s: f64,
    /// The colour views the depth was predicted from (none for rendered depth).
    pub rgb: Vec<RgbView>,
}

/// Rests `object` on the table in the offered pose `params.stable_pose` and renders the depth
/// of `params`' views of it, looking at its centre of mass.
///
/// # Errors
/// An object with no such pose, or a renderer error.
pub fn render_scene(
    renderer: &Renderer,
    object: &GraspObject,
    params: &PlanParams,
) -> Result<Scene> {
    let mesh = object.mesh();
    let rest = RestingPoses::of(mesh)?;
    let (pose_index, &pose) = rest.get(params.stable_pose)?;
    let table_from_object = pose.table_from_object;
    let target = table_from_object.transform_point(object.center_of_mass());
    let mut cameras = params
        .views
        .cameras(params.intrinsics, target, params.seed)?;
    cameras.truncate(params.max_views.max(1));
    let mut depth_s = 0.0;
    let mut colour = Vec::new();
    let views = match &params.depth_from_rgb {
        None => render_depths(renderer, mesh, &table_from_object, &cameras)?
            .into_iter()
            .zip(cameras)
            .enumerate()
            .map(|(i, (depth, camera))| View::new(i, camera, depth))
            .collect::<mvgrasp_planner::Result<Vec<_>>>()?,
        Some(rgb) => {
            let rendered = if rgb.photo {
                render_photoreal(renderer, mesh, &table_from_object, &cameras, params.seed)?.views
            } else {
                render_rgb(
                    renderer,
                    mesh,
                    &table_from_object,
                    &cameras,
                    rgb,
                    params.seed,
                )?
            };
            let views: Vec<RgbView> = rendered.into_iter().map(|(view, _)| view).collect();
            let started = Instant::now();
            let predicted = predict_views(&views, &rgb.depth)?;
            depth_s = started.elapsed().as_secs_f64();
            colour = views;
            predicted
        }
    };
    Ok(Scene {
        stable_pose: pose_index,
        stable_pose_probability: pose.probability,
        table_from_object,
        views,
        depth_s,
        rgb: colour,
    })
}

/// The views of `cameras` in colour, with the object's masks, and the rendered (true) depth of
/// each beside it: the mesh in random colours seeded by `seed` on the datasets' grey table.
///
/// # Errors
/// A renderer error.
pub fn render_rgb(
    renderer: &Renderer,
    mesh: &TriangleMesh,
    table_from_object: &Pose3,
    cameras: &[Camera],
    rgb: &RgbInput,
    seed: u64,
) -> Result<Vec<(RgbView, Vec<f32>)>> {
    let data = SceneData::of_mesh(mesh, table_from_object, TABLE_HALF_SIDE_M);
    let count = if rgb.per_face {
        mesh.triangles().len()
    } else {
        mesh.vertices().len()
    };
    let colors = random_colors(splitmix(seed ^ 0x7267_6221), count);
    let colors = if rgb.per_face {
        Colors::PerFace(&colors)
    } else {
        Colors::PerVertex(&colors)
    };
    let inputs = data.mesh_inputs(mesh.triangles(), colors, true);
    let frames = render_frames(renderer, &inputs, cameras, &Lighting::Headlight)?;
    Ok(cameras
        .iter()
        .zip(frames)
        .map(|(camera, frame)| rgb_view_of(camera, frame, OBJECT_ID))
        .collect())
}

/// Checks `grasp` made for `gripper` on `object` at `table_from_object`: the grasp dataset's
/// label (robust Ferrari-Canny and collision) and, when `params.physics`, a rapier trial.
///
/// # Errors
/// An object the checks cannot use, or bad label settings.
pub fn check_grasp(
    object: &GraspObject,
    table_from_object: &Pose3,
    grasp: &ScoredGrasp,
    gripper: &Gripper,
    params: &PlanParams,
) -> Result<GraspLabel> {
    Ok(check_grasps(
        object,
        table_from_object,
        std::slice::from_ref(grasp),
        gripper,
        params,
    )?[0])
}

/// [`check_grasp`] for several grasps on one object, which is prepared for physics once.
///
/// # Errors
/// See [`check_grasp`].
pub fn check_grasps(
    object: &GraspObject,
    table_from_object: &Pose3,
    grasps: &[ScoredGrasp],
    gripper: &Gripper,
    params: &PlanParams,
) -> Result<Vec<GraspLabel>> {
    let body = if params.physics {
        Some(PhysicsObject::from_grasp_object(
            object,
            &params.labels.physics_shape,
        )?)
    } else {
        None
    };
    let grasps: Vec<_> = grasps.iter().map(|g| g.grasp).collect();
    Ok(label_grasps(
        object,
        table_from_object,
        &grasps,
        gripper,
        &params.labels.label_params(body.as_ref()),
        params.seed,
    )?)
}

/// The main job in its three stages: [`render_scene`] (the object at rest and the views' depth),
/// the planner's plan over the views, and [`check_grasp`] on the best grasp.
///
/// # Errors
/// An object with no stable pose, or an error of the renderer, the network or the checks.
pub fn plan_grasp(
    renderer: &Renderer,
    mesh: &TriangleMesh,
    planner: &Planner,
    params: &PlanParams,
) -> Result<PlanReport> {
    let object = GraspObject::new(mesh.clone())?;
    let gripper = &params.labels.gripper;
    let started = Instant::now();
    let scene = render_scene(renderer, &object, params)?;
    let render_s = started.elapsed().as_secs_f64();

    let planned = params
        .plan_views
        .map_or(scene.views.len(), |n| n.max(1).min(scene.views.len()));
    let views = &scene.views[..planned];
    let started = Instant::now();
    let fusion = params.fusion.as_ref().and_then(|f| Fusion::build(views, f));
    let fuse_s = started.elapsed().as_secs_f64();
    let plan = planner.plan_checked(
        views,
        fusion.as_ref(),
        gripper,
        params.hand_check,
        TOP_KEPT,
        params.seed,
    )?;
    let plan_s = started.elapsed().as_secs_f64();

    let started = Instant::now();
    let best = plan.best().copied();
    let label = best
        .map(|best| check_grasp(&object, &scene.table_from_object, &best, gripper, params))
        .transpose()?;
    let check_s = started.elapsed().as_secs_f64();
    // Every view, planned in or not (a view only predicting depth has no candidate).
    let summaries = scene
        .views
        .iter()
        .enumerate()
        .map(|(i, view)| ViewSummary {
            elevation_deg: view.theta_rad().to_degrees(),
            candidates: plan.candidates_per_view.get(i).copied().unwrap_or(0),
            best_quality: plan.best_in_view(i).map(|c| c.quality),
        })
        .collect();
    Ok(PlanReport {
        stable_pose: scene.stable_pose,
        stable_pose_probability: scene.stable_pose_probability,
        views: summaries,
        cameras: scene.views.iter().map(|v| v.camera).collect(),
        table_from_object: scene.table_from_object,
        best_paper: best.map(|b| b.grasp.to_paper()),
        best,
        top: plan.candidates.iter().take(TOP_KEPT).copied().collect(),
        rejections: plan.rejections,
        candidates: plan.candidates,
        analytic: label.map(|l| AnalyticCheck {
            robust_epsilon: l.quality.robust_epsilon,
            collision_free: l.collision_free,
            robust: l.robust,
        }),
        physics: label.and_then(|l| l.physics),
        timings: PlanTimings {
            render_s,
            depth_s: scene.depth_s,
            fuse_s,
            plan_s,
            check_s,
        },
        scene_views: scene.views,
        rgb_views: scene.rgb,
    })
}
