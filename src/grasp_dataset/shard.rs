//! Shards: safetensors files of datapoints, each with a JSON sidecar of its counts, written
//! atomically (temporary file, then rename; the sidecar first, the shard last).
//!
//! Tensors of a shard with `N` datapoints and crops of side `S` (row-major, little-endian):
//!
//! | name | dtype | shape | meaning |
//! |---|---|---|---|
//! | `depth_crops` | F32 | N x S x S | grasp-centred, grasp-aligned depth crop, metres (0 = nothing) |
//! | `grasp_depth_m` | F32 | N | depth of the grasp centre along the optical axis, metres |
//! | `theta_rad` | F32 | N | angle between the optical axis and the table plane |
//! | `angle_rad` | F32 | N | in-image angle of the grasp axis before the crop turned it |
//! | `center_px` | F32 | N x 2 | grasp centre in the full image, pixels (u, v) |
//! | `width_m` | F32 | N | distance between the contacts, metres |
//! | `robust_epsilon` | F32 | N | robust Ferrari-Canny quality (mean over perturbations) |
//! | `robust_label` | U8 | N | Dex-Net 2.0's label: robust_epsilon > threshold and collision-free |
//! | `collision_free` | U8 | N | the open hand misses object and table along its approach |
//! | `force_closure` | U8 | N | the nominal contacts are in force closure |
//! | `physics` | I8 | N | physics label: 1 when at least half the trials held, 0 when not, -1 not run (or every trial's object left its resting pose) |
//! | `physics_rate` | F32 | N | share of the label's perturbed trials that held, of those whose object kept its resting pose until the gripper came; -1 as `physics` |
//! | `physics_stage` | I8 | N | stage most failed trials failed at: 0 settle, 1 approach, 2 close, 3 lift, 4 shake; -1 none |
//! | `object_id` `stable_pose` `view` `grasp` | U32 | N | ids (object index in the manifest; pose, view, axis within it) |
//! | `quality_seed` | U64 | N | seed of the robust-quality evaluation (see the manifest) |
//! | `object_from_gripper` | F32 | N x 4 x 4 | the grasp in the object frame (approach along the view) |
//! | `table_from_object` | F32 | N x 4 x 4 | the stable pose |
//! | `world_from_camera` | F32 | N x 4 x 4 | the camera (world = table frame) |

use std::path::{Path, PathBuf};

use mvgrasp_grasp::physics::{FailureStage, StageCounts};
use safetensors::Dtype;
use safetensors::tensor::TensorView;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result, RuntimeError};

/// One labelled grasp image.
#[derive(Clone, Debug, PartialEq)]
pub struct Datapoint {
    /// The crop, `size * size` values, row-major.
    pub crop: Vec<f32>,
    /// See the module docs for every field.
    pub grasp_depth_m: f32,
    /// See the module docs.
    pub theta_rad: f32,
    /// See the module docs.
    pub angle_rad: f32,
    /// See the module docs.
    pub center_px: [f32; 2],
    /// See the module docs.
    pub width_m: f32,
    /// See the module docs.
    pub robust_epsilon: f32,
    /// See the module docs.
    pub robust_label: bool,
    /// See the module docs.
    pub collision_free: bool,
    /// See the module docs.
    pub force_closure: bool,
    /// See the module docs.
    pub physics: i8,
    /// See the module docs.
    pub physics_rate: f32,
    /// See the module docs.
    pub physics_stage: i8,
    /// See the module docs.
    pub object_id: u32,
    /// See the module docs.
    pub stable_pose: u32,
    /// See the module docs.
    pub view: u32,
    /// See the module docs.
    pub grasp: u32,
    /// See the module docs.
    pub quality_seed: u64,
    /// Row-major 4x4.
    pub object_from_gripper: [[f32; 4]; 4],
    /// Row-major 4x4.
    pub table_from_object: [[f32; 4]; 4],
    /// Row-major 4x4.
    pub world_from_camera: [[f32; 4]; 4],
}

/// A shard's counts, in its sidecar `shard_NNNNN.json`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ShardRecord {
    /// Shard index.
    pub index: usize,
    /// The safetensors file, relative to the dataset folder.
    pub file: String,
    /// Ids of the objects it holds (a contiguous range).
    pub objects: Vec<u32>,
    /// Its counts (flattened into the JSON).
    #[serde(flatten)]
    pub counts: Counts,
    /// Objects that gave no datapoint, with the reason.
    pub empty_objects: Vec<(u32, String)>,
    /// The hash of the config and object list that made it ([`super::DatasetPlan::hash`]):
    /// a rerun into the folder with another config refuses the shard instead of reusing it.
    /// Empty in shards made before it was recorded.
    #[serde(default)]
    pub plan_hash: String,
    /// The SHA-256 of the shard's file (hex): a file that does not match it is not the shard
    /// that was written (changed or damaged), so a rerun makes it again and the training code
    /// refuses it. Empty in shards made before it was recorded.
    #[serde(default)]
    pub sha256: String,
}

/// What a set of datapoints holds; summed over shards for a dataset's totals.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Counts {
    /// Datapoints.
    pub datapoints: usize,
    /// Robust-label positives.
    pub positives: usize,
    /// Collision-free datapoints.
    pub collision_free: usize,
    /// Datapoints with a physics label (each from `physics_trials` trials of the config).
    pub physics_trials: usize,
    /// Physics labels 1 (at least half the trials held).
    pub physics_held: usize,
    /// Physics labels whose trials mostly got as far as the grasp (the object did not topple
    /// while settling).
    pub physics_tested: usize,
    /// Of those, labels that matched the robust label.
    pub physics_agree: usize,
    /// Physics labels 0 by the stage most of their trials failed at.
    pub physics_failures: StageCounts,
}

impl Counts {
    /// The counts of `points`.
    pub fn of(points: &[Datapoint]) -> Self {
        let mut counts = Self {
            datapoints: points.len(),
            ..Self::default()
        };
        for p in points {
            counts.positives += usize::from(p.robust_label);
            counts.collision_free += usize::from(p.collision_free);
            if p.physics < 0 {
                continue;
            }
            counts.physics_trials += 1;
            counts.physics_held += usize::from(p.physics == 1);
            let stage = FailureStage::ALL.get(p.physics_stage as usize).copied();
            if let Some(stage) = stage
                && p.physics == 0
            {
                counts.physics_failures.count(stage);
            }
            // A trial whose object toppled before the gripper came tested the pose, not the
            // grasp.
            if stage != Some(FailureStage::Settle) {
                counts.physics_tested += 1;
                counts.physics_agree += usize::from((p.physics == 1) == p.robust_label);
            }
        }
        counts
    }
}

impl std::ops::AddAssign for Counts {
    fn add_assign(&mut self, other: Self) {
        self.datapoints += other.datapoints;
        self.positives += other.positives;
        self.collision_free += other.collision_free;
        self.physics_trials += other.physics_trials;
        self.physics_held += other.physics_held;
        self.physics_tested += other.physics_tested;
        self.physics_agree += other.physics_agree;
        self.physics_failures += other.physics_failures;
    }
}

/// The shard's file name.
pub fn shard_file(index: usize) -> String {
    format!("shard_{index:05}.safetensors")
}

/// The sidecar's path.
pub fn sidecar_path(dir: &Path, index: usize) -> PathBuf {
    dir.join(format!("shard_{index:05}.json"))
}

fn bytes_f32(values: impl Iterator<Item = f32>) -> Vec<u8> {
    values.flat_map(f32::to_le_bytes).collect()
}

fn bytes_u32(values: impl Iterator<Item = u32>) -> Vec<u8> {
    values.flat_map(u32::to_le_bytes).collect()
}

/// Writes `points` as shard `record.index` in `dir`: the sidecar, then the shard, each through
/// a temporary file and a rename.
///
/// # Errors
/// [`Error::Io`], [`Error::Json`] or [`Error::Safetensors`] naming the file.
pub fn write_shard(
    dir: &Path,
    points: &[Datapoint],
    crop_size: usize,
    record: &mut ShardRecord,
) -> Result<()> {
    let n = points.len();
    let flat4 = |m: &[[f32; 4]; 4]| m.concat();
    let columns: Vec<(&str, Dtype, Vec<usize>, Vec<u8>)> = vec![
        (
            "depth_crops",
            Dtype::F32,
            vec![n, crop_size, crop_size],
            bytes_f32(points.iter().flat_map(|p| p.crop.iter().copied())),
        ),
        (
            "grasp_depth_m",
            Dtype::F32,
            vec![n],
            bytes_f32(points.iter().map(|p| p.grasp_depth_m)),
        ),
        (
            "theta_rad",
            Dtype::F32,
            vec![n],
            bytes_f32(points.iter().map(|p| p.theta_rad)),
        ),
        (
            "angle_rad",
            Dtype::F32,
            vec![n],
            bytes_f32(points.iter().map(|p| p.angle_rad)),
        ),
        (
            "center_px",
            Dtype::F32,
            vec![n, 2],
            bytes_f32(points.iter().flat_map(|p| p.center_px)),
        ),
        (
            "width_m",
            Dtype::F32,
            vec![n],
            bytes_f32(points.iter().map(|p| p.width_m)),
        ),
        (
            "robust_epsilon",
            Dtype::F32,
            vec![n],
            bytes_f32(points.iter().map(|p| p.robust_epsilon)),
        ),
        (
            "robust_label",
            Dtype::U8,
            vec![n],
            points.iter().map(|p| u8::from(p.robust_label)).collect(),
        ),
        (
            "collision_free",
            Dtype::U8,
            vec![n],
            points.iter().map(|p| u8::from(p.collision_free)).collect(),
        ),
        (
            "force_closure",
            Dtype::U8,
            vec![n],
            points.iter().map(|p| u8::from(p.force_closure)).collect(),
        ),
        (
            "physics_stage",
            Dtype::I8,
            vec![n],
            points
                .iter()
                .flat_map(|p| p.physics_stage.to_le_bytes())
                .collect(),
        ),
        (
            "physics",
            Dtype::I8,
            vec![n],
            points
                .iter()
                .flat_map(|p| p.physics.to_le_bytes())
                .collect(),
        ),
        (
            "physics_rate",
            Dtype::F32,
            vec![n],
            bytes_f32(points.iter().map(|p| p.physics_rate)),
        ),
        (
            "object_id",
            Dtype::U32,
            vec![n],
            bytes_u32(points.iter().map(|p| p.object_id)),
        ),
        (
            "stable_pose",
            Dtype::U32,
            vec![n],
            bytes_u32(points.iter().map(|p| p.stable_pose)),
        ),
        (
            "view",
            Dtype::U32,
            vec![n],
            bytes_u32(points.iter().map(|p| p.view)),
        ),
        (
            "grasp",
            Dtype::U32,
            vec![n],
            bytes_u32(points.iter().map(|p| p.grasp)),
        ),
        (
            "quality_seed",
            Dtype::U64,
            vec![n],
            points
                .iter()
                .flat_map(|p| p.quality_seed.to_le_bytes())
                .collect(),
        ),
        (
            "object_from_gripper",
            Dtype::F32,
            vec![n, 4, 4],
            bytes_f32(points.iter().flat_map(|p| flat4(&p.object_from_gripper))),
        ),
        (
            "table_from_object",
            Dtype::F32,
            vec![n, 4, 4],
            bytes_f32(points.iter().flat_map(|p| flat4(&p.table_from_object))),
        ),
        (
            "world_from_camera",
            Dtype::F32,
            vec![n, 4, 4],
            bytes_f32(points.iter().flat_map(|p| flat4(&p.world_from_camera))),
        ),
    ];
    debug_assert!(
        columns
            .iter()
            .map(|(name, dtype, ..)| (*name, *dtype))
            .eq(COLUMNS.iter().map(|(name, dtype, _)| (*name, *dtype))),
        "the columns written are the format's"
    );
    let shard_path = dir.join(shard_file(record.index));
    let views = columns
        .iter()
        .map(|(name, dtype, shape, data)| {
            TensorView::new(*dtype, shape.clone(), data)
                .map(|view| (*name, view))
                .map_err(|source| {
                    Error::from(RuntimeError::Safetensors {
                        op: "write",
                        source,
                        path: shard_path.clone(),
                    })
                })
        })
        .collect::<Result<Vec<_>>>()?;
    // No metadata map: safetensors stores it from a HashMap, whose order would vary the bytes.
    let bytes = safetensors::serialize(views, None).map_err(|source| {
        Error::from(RuntimeError::Safetensors {
            op: "write",
            source,
            path: shard_path.clone(),
        })
    })?;
    record.sha256 = sha256_hex(&bytes);
    let sidecar = sidecar_path(dir, record.index);
    write_atomically(
        &sidecar,
        (serde_json::to_string_pretty(record).map_err(Error::json(
            "write",
            "shard record",
            &sidecar,
        ))? + "\n")
            .as_bytes(),
    )?;
    write_atomically(&shard_path, &bytes)
}

/// Every column of a shard: name, dtype and the shape of one datapoint's entry (`0` stands for
/// the crop side), in the order they are written; the module docs' table.
pub const COLUMNS: [(&str, Dtype, &[usize]); 21] = [
    ("depth_crops", Dtype::F32, &[0, 0]),
    ("grasp_depth_m", Dtype::F32, &[]),
    ("theta_rad", Dtype::F32, &[]),
    ("angle_rad", Dtype::F32, &[]),
    ("center_px", Dtype::F32, &[2]),
    ("width_m", Dtype::F32, &[]),
    ("robust_epsilon", Dtype::F32, &[]),
    ("robust_label", Dtype::U8, &[]),
    ("collision_free", Dtype::U8, &[]),
    ("force_closure", Dtype::U8, &[]),
    ("physics_stage", Dtype::I8, &[]),
    ("physics", Dtype::I8, &[]),
    ("physics_rate", Dtype::F32, &[]),
    ("object_id", Dtype::U32, &[]),
    ("stable_pose", Dtype::U32, &[]),
    ("view", Dtype::U32, &[]),
    ("grasp", Dtype::U32, &[]),
    ("quality_seed", Dtype::U64, &[]),
    ("object_from_gripper", Dtype::F32, &[4, 4]),
    ("table_from_object", Dtype::F32, &[4, 4]),
    ("world_from_camera", Dtype::F32, &[4, 4]),
];

/// One column of a shard read back: raw little-endian bytes with their dtype and shape.
#[derive(Clone, Debug, PartialEq)]
pub struct ShardColumn {
    /// The column's name ([`COLUMNS`]).
    pub name: &'static str,
    /// Its element type.
    pub dtype: Dtype,
    /// Its shape, datapoints first.
    pub shape: Vec<usize>,
    /// Its elements, little-endian, row-major.
    pub data: Vec<u8>,
}

/// Reads the shard at `path` and checks it against the format: every column of [`COLUMNS`]
/// there, of its dtype, with one entry per datapoint of the shape the table gives (square
/// crops). Returns the columns in [`COLUMNS`]' order; other tensors in the file are ignored.
///
/// # Errors
/// [`Error::Shard`] naming the file and the fault (unreadable, not safetensors, a column
/// missing, of another dtype or shape).
pub fn read_shard(path: &Path) -> Result<Vec<ShardColumn>> {
    let fault = |problem: String| Error::Shard {
        problem,
        path: path.to_path_buf(),
    };
    let bytes = std::fs::read(path).map_err(|e| fault(format!("cannot read it: {e}")))?;
    let file = safetensors::SafeTensors::deserialize(&bytes)
        .map_err(|e| fault(format!("not a safetensors file: {e}")))?;
    let crops = file
        .tensor("depth_crops")
        .map_err(|_| fault("no tensor depth_crops".into()))?;
    let (n, side) = match *crops.shape() {
        [n, a, b] if a == b => (n, a),
        ref shape => {
            return Err(fault(format!(
                "depth_crops has shape {shape:?}, expected (N, S, S)"
            )));
        }
    };
    COLUMNS
        .iter()
        .map(|&(name, dtype, entry)| {
            let tensor = file
                .tensor(name)
                .map_err(|_| fault(format!("no tensor {name}")))?;
            let shape: Vec<usize> = std::iter::once(n)
                .chain(entry.iter().map(|&d| if d == 0 { side } else { d }))
                .collect();
            if tensor.dtype() != dtype || tensor.shape() != shape {
                return Err(fault(format!(
                    "{name} is {:?} {:?}, expected {dtype:?} {shape:?}",
                    tensor.dtype(),
                    tensor.shape()
                )));
            }
            Ok(ShardColumn {
                name,
                dtype,
                shape,
                data: tensor.data().to_vec(),
            })
        })
        .collect()
}

/// Writes `bytes` to `path` through `path.tmp` and a rename.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> Result<()> {
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".tmp");
    let tmp = PathBuf::from(tmp);
    std::fs::write(&tmp, bytes).map_err(Error::io("write", &tmp))?;
    std::fs::rename(&tmp, path).map_err(Error::io("rename", &tmp))
}

/// A finished shard's sidecar, if the shard and its sidecar are both there.
pub fn finished_shard(dir: &Path, index: usize) -> Option<ShardRecord> {
    let bytes = std::fs::read(dir.join(shard_file(index))).ok()?;
    let text = std::fs::read_to_string(sidecar_path(dir, index)).ok()?;
    let record: ShardRecord = serde_json::from_str(&text).ok()?;
    // A shard whose bytes are not the ones recorded is made again.
    (record.sha256.is_empty() || record.sha256 == sha256_hex(&bytes)).then_some(record)
}

/// The SHA-256 of `bytes`, lower-case hex.
pub fn sha256_hex(bytes: &[u8]) -> String {
    use sha2::Digest;
    sha2::Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)] // tests may fail loudly

    use super::*;

    fn datapoint(i: u32, crop_size: usize) -> Datapoint {
        let pose = |offset: f32| {
            [0, 1, 2, 3].map(|r| [0, 1, 2, 3].map(|c| (4 * r + c) as f32 + offset + i as f32))
        };
        Datapoint {
            crop: (0..crop_size * crop_size).map(|j| j as f32 * 0.5).collect(),
            grasp_depth_m: 0.6 + i as f32,
            theta_rad: 1.0,
            angle_rad: -0.5,
            center_px: [10.0, 20.0 + i as f32],
            width_m: 0.04,
            robust_epsilon: 0.002,
            robust_label: i.is_multiple_of(2),
            collision_free: true,
            force_closure: !i.is_multiple_of(2),
            physics: -1,
            physics_rate: -1.0,
            physics_stage: 3,
            object_id: 7,
            stable_pose: 1,
            view: i,
            grasp: 2 * i,
            quality_seed: u64::MAX - u64::from(i),
            object_from_gripper: pose(0.0),
            table_from_object: pose(100.0),
            world_from_camera: pose(200.0),
        }
    }

    #[test]
    fn a_shard_reads_back_as_written_and_a_damaged_one_is_named() {
        let dir = tempfile::tempdir().unwrap();
        let points = [datapoint(0, 3), datapoint(1, 3)];
        let mut record = ShardRecord {
            file: shard_file(4),
            index: 4,
            ..ShardRecord::default()
        };
        write_shard(dir.path(), &points, 3, &mut record).unwrap();
        let path = dir.path().join(shard_file(4));
        // The record carries the file's checksum: finished while the bytes match it.
        assert_eq!(record.sha256, sha256_hex(&std::fs::read(&path).unwrap()));
        assert_eq!(finished_shard(dir.path(), 4), Some(record.clone()));
        let columns = read_shard(&path).unwrap();
        assert_eq!(columns.len(), COLUMNS.len());
        let column = |name: &str| columns.iter().find(|c| c.name == name).unwrap();
        assert_eq!(column("depth_crops").shape, [2, 3, 3]);
        assert_eq!(
            column("depth_crops").data[..8],
            bytes_f32([0.0, 0.5].into_iter())
        );
        assert_eq!(column("object_from_gripper").shape, [2, 4, 4]);
        assert_eq!(
            column("quality_seed").data[8..],
            (u64::MAX - 1).to_le_bytes()
        );
        assert_eq!(column("physics_stage").data, [3, 3]);
        assert_eq!(column("robust_label").data, [1, 0]);
        assert_eq!(
            column("world_from_camera").data[64..68],
            201.0f32.to_le_bytes()
        );

        // A shard whose bytes changed is not finished: a rerun makes it again.
        let bytes = std::fs::read(&path).unwrap();
        let mut changed = bytes.clone();
        *changed.last_mut().unwrap() ^= 1;
        std::fs::write(&path, &changed).unwrap();
        assert_eq!(finished_shard(dir.path(), 4), None);
        std::fs::write(&path, &bytes).unwrap();
        // Cut short: the file and the fault named.
        let cut = dir.path().join("cut.safetensors");
        std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
        let message = read_shard(&cut).unwrap_err().to_string();
        assert!(message.contains("cut.safetensors") && message.contains("safetensors"));
        // A column missing.
        let one = safetensors::serialize(
            [(
                "depth_crops",
                TensorView::new(Dtype::F32, vec![1, 1, 1], &[0u8; 4]).unwrap(),
            )],
            None,
        )
        .unwrap();
        let partial = dir.path().join("partial.safetensors");
        std::fs::write(&partial, one).unwrap();
        let message = read_shard(&partial).unwrap_err().to_string();
        assert!(
            message.contains("partial.safetensors") && message.contains("no tensor grasp_depth_m"),
            "{message}"
        );
        let missing = read_shard(&dir.path().join("none.safetensors")).unwrap_err();
        assert!(matches!(missing, Error::Shard { .. }), "{missing}");
    }
}
