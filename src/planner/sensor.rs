//! Planning on a sensor's depth image: the depth, the camera's intrinsics and, when known, its
//! pose and the object's mask, read from files; the table fitted in the image (always: it
//! finds the object when there is no mask, and gives the world frame when there is no pose);
//! the policy's plan over the view with the hand check. No mesh: nothing is simulated.

use std::path::{Path, PathBuf};
use std::time::Instant;

use mvgrasp_geometry::{Camera, Intrinsics, read_camera_pose};
use mvgrasp_planner::{
    DepthImage, GqcnnPolicy, Mask, Rejections, ScoredGrasp, TableFit, TableFitParams, View,
    fit_table, objects_above, read_depth, read_mask,
};
use serde::Serialize;

use crate::error::{Error, Result};

/// The best candidates a report lists (and the hand check makes sure of).
const TOP_KEPT: usize = 10;

/// The files of one view.
#[derive(Clone, Debug, Default)]
pub struct SensorFiles {
    /// Depth: `.npy` float32 metres or 16-bit PNG millimetres.
    pub depth: PathBuf,
    /// Intrinsics: a Berkeley `.intr`, or a JSON with `K`, `width` and `height`.
    pub intrinsics: PathBuf,
    /// The camera's pose: a Berkeley `.tf` (camera to world) or a JSON `world_from_camera`.
    /// `None`: the world frame is put on the table fitted in the image.
    pub camera_pose: Option<PathBuf>,
    /// The object's pixels (non-zero in a PNG). `None`: what stands on the fitted table.
    pub mask: Option<PathBuf>,
}

/// What [`plan_on_sensor_depth`] does besides the policy's own settings.
#[derive(Clone, Debug)]
pub struct SensorPlanParams {
    /// The table fit and the object found on it.
    pub table: TableFitParams,
    /// Check the open hand against the observed depth (and the contacts against the mask).
    pub hand_check: bool,
    /// Seeds the sampler.
    pub seed: u64,
}

impl Default for SensorPlanParams {
    fn default() -> Self {
        Self {
            table: TableFitParams::default(),
            hand_check: true,
            seed: 0,
        }
    }
}

/// Where the object's pixels came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ObjectSource {
    /// The mask file.
    MaskFile,
    /// What stands on the fitted table ([`objects_above`]).
    AboveTheTable,
}

/// What [`plan_on_sensor_depth`] found.
#[derive(Clone, Debug, Serialize)]
pub struct SensorPlanReport {
    /// The camera: its intrinsics, and its pose in the world (given, or on the fitted table).
    pub camera: Camera,
    /// Whether the camera's pose was estimated from the table (no pose file).
    pub pose_estimated: bool,
    /// The table fitted in the image (the camera's frame), with how well it fit.
    pub table: TableFit,
    /// The angle between the optical axis and the table, degrees (90: straight down).
    pub camera_elevation_deg: f32,
    /// Where the object's pixels came from, and how many there are.
    pub object: ObjectSource,
    /// See `object`.
    pub object_pixels: usize,
    /// Candidates sampled and scored.
    pub candidates: usize,
    /// The best grasp that survived the hand check.
    pub best: Option<ScoredGrasp>,
    /// The best ten, best first.
    pub top: Vec<ScoredGrasp>,
    /// Candidates rejected before the best was chosen, by reason.
    pub rejections: Rejections,
    /// Seconds: reading the files, fitting the table, planning (not in the JSON).
    #[serde(skip)]
    pub timings: [f64; 3],
}

/// Plans a grasp on the depth image of `files`.
///
/// # Errors
/// A file that cannot be read or does not fit the others (each error names its file), no
/// table in the image, nothing on it (without a mask), or a network error.
pub fn plan_on_sensor_depth(
    policy: &GqcnnPolicy,
    gripper: &mvgrasp_grasp::Gripper,
    files: &SensorFiles,
    params: &SensorPlanParams,
) -> Result<SensorPlanReport> {
    let started = Instant::now();
    let view = read_view(files)?;
    let read_s = started.elapsed().as_secs_f64();

    let started = Instant::now();
    let table = fit_table(&view.depth, view.mask.as_ref(), &params.table)?;
    let pose_estimated = files.camera_pose.is_none();
    let mut view = view;
    if pose_estimated {
        view.camera = table.camera(view.camera.intrinsics)?;
    }
    let object = if view.mask.is_some() {
        ObjectSource::MaskFile
    } else {
        let objects = objects_above(&view.depth, &table, &params.table)?;
        view = view.with_mask(objects)?;
        ObjectSource::AboveTheTable
    };
    let object_pixels = view.mask.as_ref().map_or(0, Mask::count);
    let table_s = started.elapsed().as_secs_f64();

    let started = Instant::now();
    let views = [view];
    let mut plan = policy.plan(&views, params.seed)?;
    if params.hand_check {
        plan.reject_colliding(&views, gripper, TOP_KEPT);
    }
    let plan_s = started.elapsed().as_secs_f64();
    let [view] = views;
    Ok(SensorPlanReport {
        camera: view.camera,
        pose_estimated,
        camera_elevation_deg: table.theta_rad().to_degrees(),
        table,
        object,
        object_pixels,
        candidates: plan.candidates_per_view.iter().sum(),
        best: plan.best().copied(),
        top: plan.candidates.iter().take(TOP_KEPT).copied().collect(),
        rejections: plan.rejections,
        timings: [read_s, table_s, plan_s],
    })
}

/// The view of `files`: its depth with its intrinsics, posed by the pose file (else at the
/// identity, until the table says where it is), with the mask file's pixels.
///
/// # Errors
/// See [`plan_on_sensor_depth`].
pub fn read_view(files: &SensorFiles) -> Result<View> {
    let depth = read_depth(&files.depth)?;
    let intrinsics = Intrinsics::from_file(&files.intrinsics)?;
    if (intrinsics.width, intrinsics.height) != (depth.width, depth.height) {
        return Err(mismatch(
            &files.intrinsics,
            format!(
                "the intrinsics are for a {} x {} image, {} is {} x {}",
                intrinsics.width,
                intrinsics.height,
                files.depth.display(),
                depth.width,
                depth.height
            ),
        ));
    }
    let world_from_camera = match &files.camera_pose {
        Some(path) => read_camera_pose(path)?,
        None => mvgrasp_geometry::Pose3::IDENTITY,
    };
    let camera = Camera {
        intrinsics,
        world_from_camera,
    };
    let view = View::new(0, camera, DepthImage::new(intrinsics, depth.depth_m)?)?;
    match &files.mask {
        Some(path) => Ok(view.with_mask(read_mask(path, intrinsics.width, intrinsics.height)?)?),
        None => Ok(view),
    }
}

fn mismatch(path: &Path, detail: String) -> Error {
    Error::Planning(mvgrasp_planner::PlannerError::File {
        path: path.to_path_buf(),
        detail,
    })
}
