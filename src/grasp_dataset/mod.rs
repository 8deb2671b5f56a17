//! Grasp datasets for the GQ-CNN and the multi-view GQ-CNN (Dex-Net 2.0's datapoints, from any
//! meshes, gripper and camera).
//!
//! A datapoint is a depth crop centred on a grasp and turned so that its axis runs along the
//! crop's rows ([`mvgrasp_planner::crop`]), the grasp's depth, the view's angle to the table (theta), Dex-Net
//! 2.0's robust label, and for a share of them a rapier trial. Per object: its most probable
//! stable poses; per pose, antipodal axes sampled and scored once (robust Ferrari-Canny, which
//! does not depend on the approach), cameras drawn from the configured distribution, depth
//! rendered (optionally with Dex-Net's noise), and every axis that a view sees across (its
//! approach along the optical axis within `max_tilt_deg`) becomes a datapoint, labelled
//! positive when robust and collision-free along that approach.
//!
//! Output folder:
//! ```text
//! dataset.json                manifest: format, config, crop size, objects (id, name, source),
//!                             finished shards with their counts, and the totals (written
//!                             at the start and at the end of a run)
//! shard_NNNNN.safetensors     datapoints of objects [N*k, N*k + k) (k = objects_per_shard)
//! shard_NNNNN.json            that shard's counts (written before the shard)
//! ```
//! Tensors are listed in [`shard`]. Shards are written atomically and a rerun skips those
//! that are finished, so an interrupted run loses at most the shards in progress; every
//! random choice is seeded from the config's seed and the object's name, so the same config
//! gives the same bytes for any thread count and any split of the shards across machines
//! ([`generate_shard`] makes one shard alone).

pub mod cameras;
pub mod clutter;
pub mod config;
pub mod noise;
pub(crate) mod object;
pub mod preview;
pub mod shard;

pub use clutter::ClutterParams;
pub use config::{
    CameraDistribution, CropParams, GraspDatasetConfig, MultiViewCameras, NoiseParams,
    TopDownCameras,
};
pub use shard::{COLUMNS, Counts, Datapoint, ShardColumn, ShardRecord, read_shard};

use std::path::Path;
use std::sync::{Arc, OnceLock};

use indicatif::{ProgressBar, ProgressStyle};
use mvgrasp_render::Renderer;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::dataset::{ObjectSource, name_hash, splitmix};
use crate::error::{Error, Result, RuntimeError};
use object::{Resolved, object_datapoints};
use shard::{finished_shard, write_atomically, write_shard};

/// Mixed into an object's seed to draw its neighbours.
const CLUTTER_SEED: u64 = 0x636c_7574_7465_7200;

/// The manifest's format tag.
pub const FORMAT: &str = "mvgrasp-grasp-dataset/1";

/// One object of a dataset.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ManifestObject {
    /// Index: `object_id` in the shards.
    pub id: u32,
    /// Unique name.
    pub name: String,
    /// Where it came from.
    pub source: String,
}

/// `dataset.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    /// [`FORMAT`].
    pub format: String,
    /// The config that made it.
    pub config: GraspDatasetConfig,
    /// The gripper, resolved.
    pub gripper: mvgrasp_grasp::Gripper,
    /// The intrinsics, resolved.
    pub intrinsics: mvgrasp_geometry::Intrinsics,
    /// Every object, in id order.
    pub objects: Vec<ManifestObject>,
    /// How many shards the objects make.
    pub num_shards: usize,
    /// Finished shards, by index.
    pub shards: Vec<ShardRecord>,
    /// Sums over the finished shards.
    pub totals: Counts,
}

/// What a run did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GenerateSummary {
    /// Shards made in this run.
    pub written: usize,
    /// Shards an earlier run had finished.
    pub skipped: usize,
    /// The manifest's totals after the run.
    pub totals: Counts,
}

/// A dataset's objects, in id order, and the resolved config.
pub struct DatasetPlan {
    objects: Vec<(ManifestObject, ObjectSource)>,
    config: GraspDatasetConfig,
    resolved: Resolved,
    /// See [`DatasetPlan::hash`].
    hash: String,
    /// Each object as a neighbour, built the first time clutter asks for it (`None`: it cannot
    /// be one); shared by every object it clutters.
    as_neighbour: Vec<OnceLock<Option<Arc<clutter::Neighbour>>>>,
}

impl DatasetPlan {
    /// Checks the config and names the objects (ids in the order given).
    ///
    /// # Errors
    /// An invalid config ([`GraspDatasetConfig::validate`]), [`Error::NoObjects`], or
    /// [`Error::DuplicateObject`] for two objects with one name.
    pub fn new(sources: &[ObjectSource], config: &GraspDatasetConfig) -> Result<Self> {
        config.validate()?;
        if sources.is_empty() {
            return Err(Error::NoObjects);
        }
        let names = unique_names(sources)?;
        let objects: Vec<(ManifestObject, ObjectSource)> = sources
            .iter()
            .zip(names)
            .enumerate()
            .map(|(id, (source, name))| {
                (
                    ManifestObject {
                        id: id as u32,
                        name,
                        source: source.describe(),
                    },
                    source.clone(),
                )
            })
            .collect();
        let listed: Vec<&ManifestObject> = objects.iter().map(|(o, _)| o).collect();
        // The format names the code's version of the bytes: shards written by code that
        // writes other bytes are refused too.
        let text = serde_json::to_string(&(FORMAT, config, listed)).map_err(|e| {
            Error::from(RuntimeError::ConfigValue {
                key: "config",
                value: e.to_string(),
                expected: "a config that serialises to JSON",
            })
        })?;
        Ok(Self {
            as_neighbour: objects.iter().map(|_| OnceLock::new()).collect(),
            objects,
            resolved: Resolved {
                gripper: config.gripper()?,
                intrinsics: config.intrinsics()?,
            },
            config: config.clone(),
            hash: format!("{:016x}", name_hash(&text)),
        })
    }

    /// A hash of the format ([`FORMAT`]), the config and the object list (FNV-1a of their
    /// JSON, hex): every shard records it, and a shard made with another is refused.
    pub fn hash(&self) -> &str {
        &self.hash
    }

    /// The record of shard `index` when it is finished in `out` and made by this plan.
    ///
    /// # Errors
    /// [`Error::ForeignShard`] when a finished shard there was made with another config or
    /// other objects (or by a version of mvgrasp that did not record it).
    fn finished(&self, out: &Path, index: usize) -> Result<Option<ShardRecord>> {
        let Some(record) = finished_shard(out, index) else {
            return Ok(None);
        };
        if record.plan_hash != self.hash() {
            return Err(Error::ForeignShard {
                index,
                found: record.plan_hash,
                expected: self.hash.clone(),
                path: out.join(shard::shard_file(index)),
            });
        }
        Ok(Some(record))
    }

    /// The neighbours that clutter object `index` (seeded with `object_seed`): as many of the
    /// other objects as the clutter config may place, drawn without repeats; one that cannot
    /// be loaded or has no stable pose is left out. None without clutter.
    fn neighbours_of(&self, index: usize, object_seed: u64) -> Vec<Arc<clutter::Neighbour>> {
        let Some(params) = &self.config.clutter else {
            return Vec::new();
        };
        let others: Vec<usize> = (0..self.objects.len()).filter(|&i| i != index).collect();
        let mut rng = ChaCha8Rng::seed_from_u64(splitmix(object_seed ^ CLUTTER_SEED));
        clutter::draw_without_repeats(others, params.neighbours[1], &mut rng)
            .into_iter()
            .filter_map(|i| {
                self.as_neighbour[i]
                    .get_or_init(|| {
                        let mesh = self.objects[i].1.load().ok()?;
                        clutter::Neighbour::new(mesh).ok().map(Arc::new)
                    })
                    .clone()
            })
            .collect()
    }

    /// How many shards the objects make.
    pub fn num_shards(&self) -> usize {
        self.objects.len().div_ceil(self.config.objects_per_shard)
    }

    fn manifest(&self, shards: Vec<ShardRecord>) -> Manifest {
        let mut totals = Counts::default();
        for s in &shards {
            totals += s.counts;
        }
        Manifest {
            format: FORMAT.into(),
            config: self.config.clone(),
            gripper: self.resolved.gripper.clone(),
            intrinsics: self.resolved.intrinsics,
            objects: self.objects.iter().map(|(o, _)| o.clone()).collect(),
            num_shards: self.num_shards(),
            shards,
            totals,
        }
    }

    /// Writes the manifest from the shards finished in `out`; returns it.
    ///
    /// # Errors
    /// [`Error::Io`] when it cannot be written; [`Error::ForeignShard`] when a finished shard
    /// there was made with another config or other objects.
    pub fn write_manifest(&self, out: &Path) -> Result<Manifest> {
        let mut shards = Vec::new();
        for i in 0..self.num_shards() {
            shards.extend(self.finished(out, i)?);
        }
        self.write_manifest_of(out, shards)
    }

    /// Writes the manifest of `shards` (finished, in index order); returns it.
    fn write_manifest_of(&self, out: &Path, shards: Vec<ShardRecord>) -> Result<Manifest> {
        let manifest = self.manifest(shards);
        let path = out.join("dataset.json");
        let text = serde_json::to_string_pretty(&manifest).map_err(Error::json(
            "write",
            "grasp-dataset manifest",
            &path,
        ))? + "\n";
        write_atomically(&path, text.as_bytes())?;
        Ok(manifest)
    }

    /// Refuses a folder that holds a dataset of another config or other objects.
    fn check_existing(&self, out: &Path) -> Result<()> {
        let path = out.join("dataset.json");
        let Ok(text) = std::fs::read_to_string(&path) else {
            return Ok(());
        };
        let existing: Manifest = serde_json::from_str(&text).map_err(Error::json(
            "read",
            "grasp-dataset manifest",
            &path,
        ))?;
        let fresh = self.manifest(Vec::new());
        let reason = if existing.format != fresh.format {
            format!(
                "by another version of mvgrasp (format {:?}; this one writes {:?})",
                existing.format, fresh.format
            )
        } else if existing.config != fresh.config {
            "with another config".to_string()
        } else if existing.objects != fresh.objects {
            "from other objects".to_string()
        } else {
            return Ok(());
        };
        Err(Error::ForeignDataset { path, reason })
    }
}

/// Makes shard `index` of the dataset in `out` unless it is finished; its record.
///
/// Objects of the shard run in parallel on rayon's pool. An object that cannot be used (a
/// mesh that fails to load, no stable pose) gives no datapoints and is listed, with the
/// error, in the record's `empty_objects`.
///
/// # Errors
/// [`Error::NoSuchShard`] for an index beyond the plan; write errors; a renderer error.
pub fn generate_shard(
    renderer: &Renderer,
    plan: &DatasetPlan,
    out: &Path,
    index: usize,
) -> Result<ShardRecord> {
    if index >= plan.num_shards() {
        return Err(Error::NoSuchShard {
            index,
            num_shards: plan.num_shards(),
        });
    }
    if let Some(record) = plan.finished(out, index)? {
        return Ok(record);
    }
    std::fs::create_dir_all(out).map_err(Error::io("create", out))?;
    make_shard(renderer, plan, out, index)
}

/// Makes shard `index` in `out` (which exists), finished or not.
fn make_shard(
    renderer: &Renderer,
    plan: &DatasetPlan,
    out: &Path,
    index: usize,
) -> Result<ShardRecord> {
    let k = plan.config.objects_per_shard;
    let objects = &plan.objects[index * k..((index + 1) * k).min(plan.objects.len())];
    let results: Vec<(u32, Result<Vec<Datapoint>>)> = objects
        .par_iter()
        .map(|(object, source)| {
            let object_seed = splitmix(plan.config.seed ^ name_hash(&object.name));
            let neighbours = plan.neighbours_of(object.id as usize, object_seed);
            let points = source.load().and_then(|mesh| {
                object_datapoints(
                    renderer,
                    &mesh,
                    object.id,
                    object_seed,
                    &plan.config,
                    &plan.resolved,
                    &neighbours,
                )
            });
            (object.id, points)
        })
        .collect();
    let mut record = ShardRecord {
        index,
        file: shard::shard_file(index),
        objects: objects.iter().map(|(o, _)| o.id).collect(),
        plan_hash: plan.hash.clone(),
        ..ShardRecord::default()
    };
    let mut points = Vec::new();
    for (id, result) in results {
        match result {
            Ok(p) if p.is_empty() => record.empty_objects.push((id, "no datapoints".into())),
            Ok(p) => points.extend(p),
            Err(e @ Error::Runtime(RuntimeError::Render(_))) => return Err(e),
            Err(e) => record.empty_objects.push((id, e.to_string())),
        }
    }
    record.counts = Counts::of(&points);
    write_shard(out, &points, plan.config.crop.size_px as usize, &mut record)?;
    Ok(record)
}

/// Makes every unfinished shard of `sources` in `out`, and the manifest at the start (the
/// shards an earlier run finished) and at the end. A shard is finished when its file is there;
/// an interrupted run's manifest is rewritten by the next.
///
/// # Errors
/// [`Error::ForeignDataset`] when `out` holds a dataset of another config; the errors of
/// [`DatasetPlan::new`] and [`generate_shard`].
pub fn generate(
    renderer: &Renderer,
    sources: &[ObjectSource],
    config: &GraspDatasetConfig,
    out: &Path,
    progress: bool,
) -> Result<GenerateSummary> {
    let plan = DatasetPlan::new(sources, config)?;
    std::fs::create_dir_all(out).map_err(Error::io("create", out))?;
    plan.check_existing(out)?;
    remove_temporary_files(out)?;
    // The shards an earlier run finished, each read and checked once.
    let mut finished: std::collections::BTreeMap<usize, ShardRecord> = plan
        .write_manifest(out)?
        .shards
        .into_iter()
        .map(|record| (record.index, record))
        .collect();
    let bar = if progress {
        ProgressBar::new(sources.len() as u64)
    } else {
        ProgressBar::hidden()
    };
    bar.set_style(
        ProgressStyle::with_template("{bar:30} {pos}/{len} objects, {per_sec}, {eta} left, {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let mut summary = GenerateSummary::default();
    let mut shards = Vec::with_capacity(plan.num_shards());
    let mut datapoints = 0;
    for index in 0..plan.num_shards() {
        let record = match finished.remove(&index) {
            Some(record) => {
                summary.skipped += 1;
                record
            }
            None => {
                summary.written += 1;
                make_shard(renderer, &plan, out, index)?
            }
        };
        datapoints += record.counts.datapoints;
        bar.inc(record.objects.len() as u64);
        bar.set_message(format!("{datapoints} datapoints"));
        shards.push(record);
    }
    bar.finish_and_clear();
    summary.totals = plan.write_manifest_of(out, shards)?.totals;
    Ok(summary)
}

/// Reads `dir/dataset.json`.
///
/// # Errors
/// [`Error::Io`], [`Error::Json`] or [`Error::Format`] naming the file when it is missing or
/// not a grasp-dataset manifest.
pub fn read_manifest(dir: &Path) -> Result<Manifest> {
    let path = dir.join("dataset.json");
    let text = std::fs::read_to_string(&path).map_err(Error::io("read", &path))?;
    let manifest: Manifest = serde_json::from_str(&text).map_err(Error::json(
        "read",
        "grasp-dataset manifest",
        &path,
    ))?;
    if manifest.format != FORMAT {
        return Err(Error::from(RuntimeError::Format {
            found: manifest.format,
            expected: FORMAT,
            path,
        }));
    }
    Ok(manifest)
}

/// Removes the `.tmp` files an interrupted run left (never a finished shard).
fn remove_temporary_files(out: &Path) -> Result<()> {
    let entries = std::fs::read_dir(out).map_err(Error::io("read", out))?;
    for entry in entries.flatten() {
        let path = entry.path();
        if path.extension().is_some_and(|e| e == "tmp") {
            std::fs::remove_file(&path).map_err(Error::io("remove", &path))?;
        }
    }
    Ok(())
}

/// Each object's name: its own ([`ObjectSource::name`]), or for files whose stems repeat the
/// file name with its extension (`bottle.obj`, `bottle.stl`), then prefixed by as many parent
/// folders as it takes (`pybullet/cube.obj`, `toys/cube.obj`).
fn unique_names(sources: &[ObjectSource]) -> Result<Vec<String>> {
    let name_with_parents = |source: &ObjectSource, parents: usize| match source {
        ObjectSource::File(path) if parents > 0 => {
            // One level up is the file name with its extension (bottle.obj, bottle.stl),
            // then its folders.
            let mut parts: Vec<String> = path
                .components()
                .rev()
                .take(parents)
                .map(|c| c.as_os_str().to_string_lossy().into_owned())
                .collect();
            parts.reverse();
            parts.join("/")
        }
        _ => source.name(),
    };
    let mut depth = vec![0usize; sources.len()];
    let mut clash = String::new();
    for _ in 0..8 {
        let names: Vec<String> = sources
            .iter()
            .zip(&depth)
            .map(|(s, &d)| name_with_parents(s, d))
            .collect();
        let mut clashing = false;
        for i in 0..names.len() {
            if names.iter().filter(|n| **n == names[i]).count() > 1 {
                depth[i] += 1;
                clashing = true;
                clash.clone_from(&names[i]);
            }
        }
        if !clashing {
            return Ok(names);
        }
    }
    Err(Error::DuplicateObject { name: clash })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    #[test]
    fn the_plan_hash_changes_with_the_config_and_the_objects() {
        let sources = |names: &[&str]| -> Vec<ObjectSource> {
            names
                .iter()
                .map(|f| ObjectSource::File(PathBuf::from(f)))
                .collect()
        };
        let config = GraspDatasetConfig::default();
        let plan = DatasetPlan::new(&sources(&["a.obj", "b.obj"]), &config).unwrap();
        let same = DatasetPlan::new(&sources(&["a.obj", "b.obj"]), &config).unwrap();
        assert_eq!(plan.hash(), same.hash());
        let other_objects = DatasetPlan::new(&sources(&["a.obj", "c.obj"]), &config).unwrap();
        assert_ne!(plan.hash(), other_objects.hash());
        let other_config = GraspDatasetConfig {
            grasps_per_pose: config.grasps_per_pose + 1,
            ..config.clone()
        };
        let changed = DatasetPlan::new(&sources(&["a.obj", "b.obj"]), &other_config).unwrap();
        assert_ne!(plan.hash(), changed.hash());
    }

    #[test]
    fn repeated_stems_are_told_apart_by_extension_then_folders() {
        let files = [
            "a/meshes/bottle.obj",
            "a/meshes/bottle.stl",
            "b/toys/cube.obj",
            "b/cube.obj",
            "c/mug.obj",
        ];
        let sources: Vec<ObjectSource> = files
            .iter()
            .map(|f| ObjectSource::File(PathBuf::from(f)))
            .collect();
        let names = unique_names(&sources).unwrap();
        assert_eq!(
            names,
            [
                "bottle.obj",
                "bottle.stl",
                "toys/cube.obj",
                "b/cube.obj",
                "mug"
            ]
        );
        let twice = [sources[4].clone(), sources[4].clone()];
        assert!(unique_names(&twice).is_err());
    }
}
