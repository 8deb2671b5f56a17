//! Planning on a sensor's depth image: the depth, the camera's intrinsics and, when known, its
//! pose and the object's mask, read from files; the table fitted in the image (always: it
//! finds the object when there is no mask, and gives the world frame when there is no pose);
//! the planner's plan over the view with the hand check. No mesh: nothing is simulated.

use std::path::{Path, PathBuf};
use std::time::Instant;

use mvgrasp_geometry::{Camera, Intrinsics, one_line, read_camera_pose};
use mvgrasp_planner::{
    DepthImage, Fusion, FusionParams, Mask, Plan, Planner, Rejections, ScoredGrasp, TableFit,
    TableFitParams, View, fit_table, objects_above,
};

/// With the views fused, the world's z must be within this of the fitted table's normal,
/// degrees.
const MAX_WORLD_TILT_DEG: f32 = 10.0;

use crate::sensor_files::{read_depth_in_units, read_mask_of};
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

/// What [`plan_on_sensor_depth`] does besides the planner's own settings.
#[derive(Clone, Debug)]
pub struct SensorPlanParams {
    /// The table fit and the object found on it.
    pub table: TableFitParams,
    /// Check the open hand against the observed depth (and the contacts against the mask).
    pub hand_check: bool,
    /// Seeds the sampler.
    pub seed: u64,
    /// Fuse the views (see [`crate::planner::PlanParams::fusion`]); the table's height is the
    /// first view's fitted table, in the world frame (whose z must point up from it).
    pub fusion: Option<FusionParams>,
}

impl Default for SensorPlanParams {
    fn default() -> Self {
        Self {
            table: TableFitParams::default(),
            hand_check: true,
            seed: 0,
            fusion: None,
        }
    }
}

/// Where the object's pixels came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ObjectSource {
    /// The view's own mask (a mask file, or one given with an in-memory view).
    MaskFile,
    /// What stands on the fitted table ([`objects_above`]).
    AboveTheTable,
}

/// What [`plan_on_sensor_depth`] found (`grasps.json`, [`crate::grasps_file`], is its
/// serialised form).
#[derive(Clone, Debug)]
pub struct SensorPlanReport {
    /// The view as planned: its camera posed in the world (given, or on the fitted table) and
    /// its object mask (given, or found on the table).
    pub view: View,
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
    /// Seconds: reading the files, fitting the table, planning.
    pub timings: [f64; 3],
}

/// Plans a grasp on the depth image of `files` ([`read_view`], then [`plan_on_view`]).
///
/// # Errors
/// A file that cannot be read or does not fit the others (each error names its file), no
/// table in the image, nothing on it (without a mask), or a network error.
pub fn plan_on_sensor_depth(
    planner: &Planner,
    gripper: &mvgrasp_grasp::Gripper,
    files: &SensorFiles,
    params: &SensorPlanParams,
) -> Result<SensorPlanReport> {
    let started = Instant::now();
    let view = read_view(files)?;
    let read_s = started.elapsed().as_secs_f64();
    let mut report = plan_on_view(planner, gripper, view, files.camera_pose.is_some(), params)?;
    report.timings[0] = read_s;
    Ok(report)
}

/// Plans a grasp on one view held in memory (a robot's depth stream, no files): its depth, its
/// camera's intrinsics and, when `pose_given`, its pose in the world (else the world is put on
/// the table fitted in the image, and the view's pose is ignored), and its object mask if it
/// has one (else the object is what stands on the table).
///
/// # Errors
/// No table in the image, nothing on it (without a mask), or a network error.
pub fn plan_on_view(
    planner: &Planner,
    gripper: &mvgrasp_grasp::Gripper,
    view: View,
    pose_given: bool,
    params: &SensorPlanParams,
) -> Result<SensorPlanReport> {
    let started = Instant::now();
    let located = locate(view, pose_given, params)?;
    let table_s = started.elapsed().as_secs_f64();
    let started = Instant::now();
    let views = [located.view];
    let plan = plan_views(planner, gripper, &views, &[located.table], params)?;
    let plan_s = started.elapsed().as_secs_f64();
    let [view] = views;
    Ok(SensorPlanReport {
        object_pixels: view.mask.as_ref().map_or(0, Mask::count),
        view,
        pose_estimated: !pose_given,
        camera_elevation_deg: located.table.theta_rad().to_degrees(),
        table: located.table,
        object: located.object,
        candidates: plan.candidates_per_view.iter().sum(),
        best: plan.best().copied(),
        top: plan.candidates.iter().take(TOP_KEPT).copied().collect(),
        rejections: plan.rejections,
        timings: [0.0, table_s, plan_s],
    })
}

/// A view with its table fitted, posed on it unless `pose_given`, and its object found on it
/// when it has no mask.
struct Located {
    view: View,
    table: TableFit,
    object: ObjectSource,
}

fn locate(view: View, pose_given: bool, params: &SensorPlanParams) -> Result<Located> {
    let table = fit_table(&view.depth, view.mask.as_ref(), &params.table)?;
    let mut view = view;
    if !pose_given {
        view.camera = table.camera(view.camera.intrinsics)?;
    }
    let object = if view.mask.is_some() {
        ObjectSource::MaskFile
    } else {
        let objects = objects_above(&view.depth, &table, &params.table)?;
        view = view.with_mask(objects)?;
        ObjectSource::AboveTheTable
    };
    Ok(Located {
        view,
        table,
        object,
    })
}

/// The planner's plan over `views`, hand-checked against all of them unless told not to.
fn plan_views(
    planner: &Planner,
    gripper: &mvgrasp_grasp::Gripper,
    views: &[View],
    tables: &[TableFit],
    params: &SensorPlanParams,
) -> Result<Plan> {
    let fusion = match &params.fusion {
        Some(fusion_params) => {
            let table_z_m = table_height_in_world(&views[0], &tables[0])?;
            Fusion::build(
                views,
                &FusionParams {
                    table_z_m,
                    ..fusion_params.clone()
                },
            )
        }
        None => None,
    };
    Ok(planner.plan_checked(
        views,
        fusion.as_ref(),
        gripper,
        params.hand_check,
        TOP_KEPT,
        params.seed,
    )?)
}

/// The height of the table fitted in `view` in the world frame, which must have its z axis up
/// from the table (the fused model is built in the table frame).
fn table_height_in_world(view: &View, table: &TableFit) -> Result<f32> {
    let world_from_camera = view.camera.world_from_camera;
    let up = world_from_camera.rotation * table.up();
    let tilt_deg = up.z.clamp(-1.0, 1.0).acos().to_degrees();
    if tilt_deg > MAX_WORLD_TILT_DEG {
        return Err(Error::Planning(mvgrasp_planner::PlannerError::Table(
            format!(
                "the world's z axis is {tilt_deg:.0} degrees from the table's normal: fusing the \
             views needs camera poses in a frame whose z points up from the table"
            ),
        )));
    }
    // The table's point under the camera: normal . p + height = 0.
    let foot = table.up() * -table.camera_height_m;
    Ok(world_from_camera.transform_point(foot).z)
}

/// The view of `files`: its depth with its intrinsics, posed by the pose file (else at the
/// identity, until the table says where it is), with the mask file's pixels. A PNG inside a
/// `render` dataset reads in that dataset's units and mask ids (see [`read_views_dir`]).
///
/// # Errors
/// See [`plan_on_sensor_depth`].
pub fn read_view(files: &SensorFiles) -> Result<View> {
    // A PNG inside a `render` dataset is in its units (0.1 mm), its masks in its ids.
    let (units, object_id) = render_conventions(files.depth.parent().unwrap_or(Path::new(".")))?;
    let depth = read_depth_in_units(&files.depth, units)?;
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
        Some(path) => Ok(view.with_mask(read_mask_of(
            path,
            intrinsics.width,
            intrinsics.height,
            object_id,
        )?)?),
        None => Ok(view),
    }
}

/// The PNG depth units and the object's mask value of the `render` dataset that `dir` is in
/// (its `dataset.json` in `dir` or up to two folders above): `(1000, None)` (millimetres, any
/// non-zero mask pixel) when there is none.
///
/// # Errors
/// A `dataset.json` that cannot be read as JSON (its units would be guessed).
/// The path of `dir/cameras.json` and its cameras (at least one).
///
/// # Errors
/// The file missing or unreadable, not a list of cameras, or empty; naming the file.
pub(crate) fn read_cameras_json(dir: &Path) -> Result<(std::path::PathBuf, Vec<Camera>)> {
    let path = dir.join("cameras.json");
    let text = std::fs::read_to_string(&path)
        .map_err(|e| mismatch(&path, format!("cannot read the cameras: {e}")))?;
    let cameras: Vec<Camera> = serde_json::from_str(&text).map_err(|e| {
        mismatch(
            &path,
            format!("not a list of cameras: {}", one_line(&e.to_string())),
        )
    })?;
    if cameras.is_empty() {
        return Err(mismatch(&path, "no camera".into()));
    }
    Ok((path, cameras))
}

pub(crate) fn render_conventions(dir: &Path) -> Result<(f32, Option<u8>)> {
    let Some(path) = [dir.to_path_buf(), dir.join(".."), dir.join("../..")]
        .into_iter()
        .map(|d| d.join("dataset.json"))
        .find(|p| p.is_file())
    else {
        return Ok((1000.0, None));
    };
    let manifest: serde_json::Value = std::fs::read_to_string(&path)
        .map_err(|e| e.to_string())
        .and_then(|t| serde_json::from_str(&t).map_err(|e| one_line(&e.to_string())))
        .map_err(|e| mismatch(&path, format!("cannot read the dataset's units: {e}")))?;
    let units = manifest["depth_png_units_per_m"]
        .as_f64()
        .map_or(1000.0, |u| u as f32);
    let object_id = manifest["mask_ids"]["object"]
        .as_u64()
        .and_then(|id| u8::try_from(id).ok());
    Ok((units, object_id))
}

pub(crate) fn mismatch(path: &Path, detail: String) -> Error {
    Error::Planning(mvgrasp_planner::PlannerError::File {
        path: path.to_path_buf(),
        detail,
    })
}

/// What [`plan_on_views_dir`] found.
#[derive(Clone, Debug)]
pub struct ViewsPlanReport {
    /// The views as planned (the cameras of `cameras.json`, each view's object mask), in view
    /// order.
    pub views: Vec<View>,
    /// The table fitted in each view (its camera's frame).
    pub tables: Vec<TableFit>,
    /// Where each view's object pixels came from, and how many there are.
    pub objects: Vec<(ObjectSource, usize)>,
    /// Candidates sampled and scored in each view.
    pub candidates_per_view: Vec<usize>,
    /// The best grasp over all views that survived the hand check (against every view).
    pub best: Option<ScoredGrasp>,
    /// The best ten, best first.
    pub top: Vec<ScoredGrasp>,
    /// Candidates rejected before the best was chosen, by reason.
    pub rejections: Rejections,
}

/// The views of a folder: `cameras.json` (a list of cameras, `intrinsics` and
/// `world_from_camera`, as `render` writes them) and for camera `i` the depth
/// `{i:03}_depth.npy` (metres) or `{i:03}_depth.png`, and optionally the mask
/// `{i:03}_mask.png`. A `dataset.json` in the folder or up to two above it (a `render`
/// dataset) gives the PNGs' depth units (`depth_png_units_per_m`) and the object's mask value
/// (`mask_ids.object`); without one, PNG depth is in millimetres and any non-zero mask pixel is
/// the object.
///
/// # Errors
/// A missing or unreadable `cameras.json`, a camera without a depth image, a depth image or
/// mask whose size is not its camera's, or one with no camera; each names its file.
pub fn read_views_dir(dir: &Path) -> Result<Vec<View>> {
    let (cameras_path, cameras) = read_cameras_json(dir)?;
    let (units, object_id) = render_conventions(dir)?;
    // Depth images past the cameras' count: the folder and its cameras disagree.
    let extra = dir.join(format!("{:03}_depth.npy", cameras.len()));
    let extra_png = dir.join(format!("{:03}_depth.png", cameras.len()));
    if let Some(path) = [extra, extra_png].into_iter().find(|p| p.is_file()) {
        return Err(mismatch(
            &path,
            format!(
                "{} lists {} cameras, but this is view {}",
                cameras_path.display(),
                cameras.len(),
                cameras.len()
            ),
        ));
    }
    let mut views = Vec::with_capacity(cameras.len());
    for (i, camera) in cameras.into_iter().enumerate() {
        let npy = dir.join(format!("{i:03}_depth.npy"));
        let png = dir.join(format!("{i:03}_depth.png"));
        let path = if npy.is_file() { npy } else { png };
        if !path.is_file() {
            return Err(mismatch(
                &path,
                format!("view {i} of {} has no depth image", cameras_path.display()),
            ));
        }
        let depth = read_depth_in_units(&path, units)?;
        let k = camera.intrinsics;
        if (k.width, k.height) != (depth.width, depth.height) {
            return Err(mismatch(
                &path,
                format!(
                    "{} x {} pixels, but its camera in {} is {} x {}",
                    depth.width,
                    depth.height,
                    cameras_path.display(),
                    k.width,
                    k.height
                ),
            ));
        }
        let view = View::new(i, camera, DepthImage::new(k, depth.depth_m)?)?;
        let mask = dir.join(format!("{i:03}_mask.png"));
        views.push(if mask.is_file() {
            view.with_mask(read_mask_of(&mask, k.width, k.height, object_id)?)?
        } else {
            view
        });
    }
    Ok(views)
}

/// Plans over every view of the folder `dir` ([`read_views_dir`]; the cameras' poses are
/// given): each view's table fitted (the object, without a mask, is what stands on it), the
/// candidates of all views ranked together, and the hand checked against every view.
///
/// # Errors
/// See [`read_views_dir`]; no table in a view, nothing on it (without a mask), or a network
/// error.
pub fn plan_on_views_dir(
    planner: &Planner,
    gripper: &mvgrasp_grasp::Gripper,
    dir: &Path,
    params: &SensorPlanParams,
) -> Result<ViewsPlanReport> {
    plan_on_views(planner, gripper, read_views_dir(dir)?, params)
}

/// [`plan_on_views_dir`] on views in memory, each with its camera's pose (and its mask, if it
/// has one).
///
/// # Errors
/// No table in a view, nothing on it (without a mask), the world's z not up from the table
/// (with the views fused), or a network error.
pub fn plan_on_views(
    planner: &Planner,
    gripper: &mvgrasp_grasp::Gripper,
    read: Vec<View>,
    params: &SensorPlanParams,
) -> Result<ViewsPlanReport> {
    let mut views = Vec::new();
    let mut tables = Vec::new();
    let mut objects = Vec::new();
    for view in read {
        let located = locate(view, true, params)?;
        objects.push((
            located.object,
            located.view.mask.as_ref().map_or(0, Mask::count),
        ));
        tables.push(located.table);
        views.push(located.view);
    }
    let plan = plan_views(planner, gripper, &views, &tables, params)?;
    Ok(ViewsPlanReport {
        views,
        tables,
        objects,
        candidates_per_view: plan.candidates_per_view.clone(),
        best: plan.best().copied(),
        top: plan.candidates.iter().take(TOP_KEPT).copied().collect(),
        rejections: plan.rejections,
    })
}
