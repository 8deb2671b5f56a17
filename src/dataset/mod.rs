//! The multi-view RGB-D dataset of the seed paper: per object, 20 training views on the
//! hemisphere (RGB, depth, mask, cameras) and 10 novel test views with novel colouring, the
//! first exactly top-down.
//!
//! Layout of `OUT/` (documented for users in the README):
//! ```text
//! dataset.json                  config, intrinsics, depth units, objects
//! <object>/object.json          source, resting pose (table_from_object), colouring
//! <object>/mesh.obj             the mesh, object frame, metres
//! <object>/{train,test}/cameras.json        [{intrinsics, world_from_camera (4x4 rows)}]
//! <object>/{train,test}/NNN_rgb.png         8-bit RGB
//! <object>/{train,test}/NNN_depth.png       16-bit z in 0.1 mm units, 0 = nothing
//! <object>/{train,test}/NNN_mask.png        8-bit: 0 background, 1 object, 2 table
//! ```
//! Each object is written into `.<object>.partial/` and renamed when complete, so an
//! interrupted run leaves no half object; a rerun skips finished objects.

mod scene;

pub use scene::{ColorMode, PlacedObject, name_hash, splitmix};

use std::path::{Path, PathBuf};

use indicatif::{ProgressBar, ProgressStyle};
use mvgrasp_geometry::objects::{ObjectSpec, generate};
use mvgrasp_geometry::{Camera, HemisphereLayout, Intrinsics, TriangleMesh, load_mesh, write_obj};
use mvgrasp_render::Renderer;
use serde::Serialize;

use crate::convert::render_view;
use crate::error::{Error, Result};
use crate::images::{DEPTH_PNG_UNITS_PER_M, write_depth_png, write_png8};
use crate::scene::{OBJECT_ID, TABLE_ID};

/// Where an object comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum ObjectSource {
    /// The built-in procedural library.
    Builtin(ObjectSpec),
    /// An OBJ, STL or URDF file in metres.
    File(PathBuf),
}

impl ObjectSource {
    /// The object's folder name.
    pub fn name(&self) -> String {
        match self {
            Self::Builtin(spec) => spec.name(),
            Self::File(path) => path
                .file_stem()
                .map_or("mesh".into(), |s| s.to_string_lossy().into_owned()),
        }
    }

    pub(crate) fn describe(&self) -> String {
        match self {
            Self::Builtin(spec) => format!(
                "built-in {} #{} seed {}",
                spec.category, spec.index, spec.seed
            ),
            Self::File(path) => path.display().to_string(),
        }
    }

    pub(crate) fn load(&self) -> Result<TriangleMesh> {
        Ok(match self {
            Self::Builtin(spec) => generate(spec.category, spec.index, spec.seed)?.mesh,
            Self::File(path) => load_mesh(path)?,
        })
    }
}

/// What to render.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DatasetConfig {
    /// Seeds camera layouts and colours (mixed with each object's name).
    pub seed: u64,
    /// The camera.
    pub intrinsics: Intrinsics,
    /// The training views.
    pub training: HemisphereLayout,
    /// The novel test views (the paper's include the exact top-down view).
    pub test: HemisphereLayout,
    /// Render the table plane under the object.
    pub table: bool,
}

impl Default for DatasetConfig {
    fn default() -> Self {
        Self {
            seed: 0,
            intrinsics: Intrinsics::phoxi_s(),
            training: HemisphereLayout::paper_training(),
            test: HemisphereLayout::paper_test(),
            table: true,
        }
    }
}

/// What a run did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DatasetSummary {
    /// Objects rendered in this run.
    pub written: usize,
    /// Objects already complete from an earlier run.
    pub skipped: usize,
    /// Views rendered in this run.
    pub views: usize,
}

#[derive(Serialize)]
struct ObjectRecord<'a> {
    name: &'a str,
    source: String,
    #[serde(with = "mvgrasp_geometry::pose_as_matrix")]
    table_from_object: mvgrasp_geometry::Pose3,
    pose_probability: f32,
    pose_marginal: bool,
    color_mode: ColorMode,
    train_color_seed: u64,
    test_color_seed: u64,
    triangles: usize,
}

#[derive(Serialize)]
struct DatasetRecord {
    seed: u64,
    intrinsics: Intrinsics,
    training_views: usize,
    test_views: usize,
    table: bool,
    depth_png_units_per_m: f32,
    mask_ids: serde_json::Value,
    objects: Vec<String>,
}

/// Renders every object of `sources` into `out` (see the module docs), skipping objects a
/// previous run finished.
///
/// # Errors
/// Duplicate object names, unreadable meshes, render and file errors, each naming its object or
/// file. Objects finished before the error stay finished.
pub fn write_dataset(
    renderer: &Renderer,
    sources: &[ObjectSource],
    config: &DatasetConfig,
    out: &Path,
    progress: bool,
) -> Result<DatasetSummary> {
    let mut names: Vec<String> = sources.iter().map(ObjectSource::name).collect();
    names.sort();
    if let Some(w) = names.windows(2).find(|w| w[0] == w[1]) {
        return Err(Error::DuplicateObject { name: w[0].clone() });
    }
    std::fs::create_dir_all(out).map_err(Error::io("create", out))?;
    claim_folder(out, config)?;
    let bar = if progress {
        ProgressBar::new(sources.len() as u64)
    } else {
        ProgressBar::hidden()
    };
    bar.set_style(
        ProgressStyle::with_template("{bar:30} {pos}/{len} objects, {per_sec}, {eta} left  {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let mut summary = DatasetSummary::default();
    for source in sources {
        let name = source.name();
        bar.set_message(name.clone());
        if out.join(&name).join("object.json").is_file() {
            summary.skipped += 1;
        } else {
            summary.views += write_object(renderer, source, &name, config, out)?;
            summary.written += 1;
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    let record = DatasetRecord {
        seed: config.seed,
        intrinsics: config.intrinsics,
        training_views: config.training.count,
        test_views: config.test.count,
        table: config.table,
        depth_png_units_per_m: DEPTH_PNG_UNITS_PER_M,
        mask_ids: serde_json::json!({ "background": 0, "object": OBJECT_ID, "table": TABLE_ID }),
        objects: sources.iter().map(ObjectSource::name).collect(),
    };
    write_json_atomically(&out.join("dataset.json"), &record)?;
    Ok(summary)
}

/// The version of the RGB-D dataset's files, recorded in `settings.json`: a folder that code
/// writing other bytes started is refused instead of being finished with different bytes.
pub const RGBD_FORMAT: &str = "mvgrasp-rgbd-dataset/1";

/// Records this run's settings in `out/settings.json` when the folder is new, or checks them
/// against the ones recorded there: a resumed run must be the run that started the folder.
///
/// # Errors
/// [`Error::ForeignDataset`] naming `settings.json` when it records other settings or another
/// format, or when the folder holds finished objects but no `settings.json` (an earlier
/// version of mvgrasp made them); [`Error::Io`] or [`Error::Json`] naming the file.
fn claim_folder(out: &Path, config: &DatasetConfig) -> Result<()> {
    let path = out.join("settings.json");
    let settings = serde_json::json!({
        "format": RGBD_FORMAT,
        "config": format!("{config:?}"),
    });
    match std::fs::read_to_string(&path) {
        Ok(text) => {
            let found: serde_json::Value =
                serde_json::from_str(&text).map_err(Error::json("read", "JSON", &path))?;
            let reason = if found.get("format") != settings.get("format") {
                format!(
                    "by another version of mvgrasp (format {}; this one writes {RGBD_FORMAT:?})",
                    found.get("format").unwrap_or(&serde_json::Value::Null)
                )
            } else if found.get("config") != settings.get("config") {
                "with another config".to_string()
            } else {
                return Ok(());
            };
            Err(Error::ForeignDataset { path, reason })
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            let entries = std::fs::read_dir(out).map_err(Error::io("read", out))?;
            let started_before = entries
                .filter_map(std::result::Result::ok)
                .any(|entry| entry.path().join("object.json").is_file());
            if started_before {
                return Err(Error::ForeignDataset {
                    path,
                    reason: "by an earlier version of mvgrasp (its objects have no settings.json)"
                        .to_string(),
                });
            }
            write_json_atomically(&path, &settings)
        }
        Err(e) => Err(Error::io("read", &path)(e)),
    }
}

/// Renders one object into `.NAME.partial/` and renames it to `NAME/`; returns the views.
fn write_object(
    renderer: &Renderer,
    source: &ObjectSource,
    name: &str,
    config: &DatasetConfig,
    out: &Path,
) -> Result<usize> {
    let partial = out.join(format!(".{name}.partial"));
    let done = out.join(name);
    for stale in [&partial, &done] {
        if stale.exists() {
            std::fs::remove_dir_all(stale).map_err(Error::io("remove", stale))?;
        }
    }
    let object_seed = splitmix(config.seed ^ name_hash(name));
    let placed = PlacedObject::new(source.load()?, object_seed)?;
    let com = placed.mesh.mass_facts(1000.0)?.center_of_mass;
    let target = placed.table_from_object.transform_point(com);
    let views_seed = splitmix(object_seed ^ 0x7669_6577);
    let k = config.intrinsics;
    let splits = [
        (
            "train",
            config.training.cameras(k, target, views_seed)?,
            placed.train_color_seed,
        ),
        (
            "test",
            config.test.cameras(k, target, views_seed.wrapping_add(1))?,
            placed.test_color_seed,
        ),
    ];
    let data = placed.scene_data();
    let mut views = 0;
    for (split, cameras, color_seed) in &splits {
        let dir = partial.join(split);
        std::fs::create_dir_all(&dir).map_err(Error::io("create", &dir))?;
        let colors = placed.colors(*color_seed);
        let scene = renderer.upload(&placed.inputs(&data, &colors, config.table))?;
        let render_views: Vec<_> = cameras.iter().map(render_view).collect();
        let frames = renderer.render(&scene, &render_views)?;
        for (i, frame) in frames.iter().enumerate() {
            let (w, h) = (frame.width, frame.height);
            write_png8(&dir.join(format!("{i:03}_rgb.png")), w, h, 3, &frame.rgb)?;
            write_depth_png(&dir.join(format!("{i:03}_depth.png")), w, h, &frame.depth_m)?;
            write_png8(&dir.join(format!("{i:03}_mask.png")), w, h, 1, &frame.mask)?;
        }
        write_json(&dir.join("cameras.json"), &cameras)?;
        views += frames.len();
    }
    write_obj(&placed.mesh, partial.join("mesh.obj"))?;
    let record = ObjectRecord {
        name,
        source: source.describe(),
        table_from_object: placed.table_from_object,
        pose_probability: placed.pose_probability,
        pose_marginal: placed.pose_marginal,
        color_mode: placed.color_mode,
        train_color_seed: placed.train_color_seed,
        test_color_seed: placed.test_color_seed,
        triangles: placed.mesh.triangles().len(),
    };
    write_json(&partial.join("object.json"), &record)?;
    std::fs::rename(&partial, &done).map_err(Error::io("rename", &partial))?;
    Ok(views)
}

fn write_json(path: &Path, value: &impl Serialize) -> Result<()> {
    let text = serde_json::to_string_pretty(value).map_err(Error::json("write", "JSON", path))?;
    std::fs::write(path, text + "\n").map_err(Error::io("write", path))
}

fn write_json_atomically(path: &Path, value: &impl Serialize) -> Result<()> {
    let tmp = path.with_extension("json.tmp");
    write_json(&tmp, value)?;
    std::fs::rename(&tmp, path).map_err(Error::io("rename", &tmp))
}

/// The cameras of a dataset split, read back.
///
/// # Errors
/// [`Error::Io`] or [`Error::Json`] naming the file.
pub fn read_cameras(path: &Path) -> Result<Vec<Camera>> {
    let text = std::fs::read_to_string(path).map_err(Error::io("read", path))?;
    serde_json::from_str(&text).map_err(Error::json("read", "JSON", path))
}
