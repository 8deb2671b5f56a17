//! The networks that ship with mvgrasp (`models/` in the repository, compiled into the
//! program so that a fresh clone plans with no download). Each was produced by the committed
//! training code; `models/README.md` is their training report.

use std::path::Path;

use mvgrasp_infer::{Gqcnn, Lsm, Mvs, SweepRefiner};

use crate::error::Result;

/// A shipped network: its name, files, and the views it plans best with.
#[derive(Clone, Copy, Debug)]
pub struct ShippedModel {
    /// The experiment's name (`training/configs/NAME.toml`).
    pub name: &'static str,
    description: &'static str,
    weights: &'static [u8],
}

/// The views a network plans in, unless told otherwise: how many of the paper's test views
/// and how far away (a GQ-CNN only knows the camera distances it was trained at).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewSetting {
    /// The first this many test views (the first is top-down).
    pub views: usize,
    /// Camera distance from the object, metres.
    pub distance_m: f32,
}

impl ViewSetting {
    /// The setting for a network with `pose_inputs` pose inputs: a top-down GQ-CNN (1) plans
    /// in the top-down view 0.7 m above the object (its training data: 0.65 to 0.75 m); a
    /// multi-view GQ-CNN (2) in all 10 test views 0.65 m away (its data: 0.5 to 0.75 m; at
    /// the edge of that range, 0.5 m, its grasps held less often in `plan_eval`).
    pub fn for_pose_inputs(pose_inputs: usize) -> Self {
        if pose_inputs >= 2 {
            Self {
                views: 10,
                distance_m: 0.65,
            }
        } else {
            Self {
                views: 1,
                distance_m: 0.7,
            }
        }
    }
}

impl ShippedModel {
    /// The network, ready to score.
    ///
    /// # Errors
    /// Only if the shipped files are broken (a test loads every one).
    pub fn load(&self) -> Result<Gqcnn> {
        let path = Path::new("models").join(format!("{}.json", self.name));
        Ok(Gqcnn::from_bytes(self.description, self.weights, &path)?)
    }
}

macro_rules! shipped {
    ($name:literal) => {
        ShippedModel {
            name: $name,
            description: include_str!(concat!("../../../models/", $name, ".json")),
            weights: include_bytes!(concat!("../../../models/", $name, ".safetensors")),
        }
    };
}

/// The GQ-CNN trained on top-down views (Dex-Net 2.0's setting). `plan`'s default: its
/// grasps held most often in physics (`examples/plan_eval.rs`, models/README.md).
pub const GQCNN_TOPDOWN: ShippedModel = shipped!("gqcnn_small_topdown");

/// The multi-view GQ-CNN: trained on views from anywhere on the hemisphere; its pose stream
/// takes the grasp depth and the view's angle to the table.
pub const MVGQCNN: ShippedModel = shipped!("gqcnn_small_multiview");

/// Every shipped network.
pub const ALL: [ShippedModel; 2] = [GQCNN_TOPDOWN, MVGQCNN];

/// The shipped network called `name`.
pub fn shipped(name: &str) -> Option<ShippedModel> {
    ALL.into_iter().find(|m| m.name == name)
}

/// A shipped Learnt Stereo Machine: its name and files.
#[derive(Clone, Copy, Debug)]
pub struct ShippedLsm {
    /// The experiment's name (`training/configs/NAME.toml`).
    pub name: &'static str,
    description: &'static str,
    weights: &'static [u8],
}

impl ShippedLsm {
    /// The network, ready to predict depth.
    ///
    /// # Errors
    /// Only if the shipped files are broken (a test loads them).
    pub fn load(&self) -> Result<Lsm> {
        let path = Path::new("models").join(format!("{}.json", self.name));
        Ok(Lsm::from_bytes(self.description, self.weights, &path)?)
    }
}

/// The Learnt Stereo Machine trained on the built-in objects' RGB-D dataset
/// (`training/configs/lsm_small.toml`): depth from a few RGB views.
pub const LSM: ShippedLsm = ShippedLsm {
    name: "lsm_small",
    description: include_str!("../../../models/lsm_small.json"),
    weights: include_bytes!("../../../models/lsm_small.safetensors"),
};

/// A shipped multi-view stereo network: its name and files.
#[derive(Clone, Copy, Debug)]
pub struct ShippedMvs {
    /// The experiment's name (`training/configs/NAME.toml`).
    pub name: &'static str,
    description: &'static str,
    weights: &'static [u8],
}

impl ShippedMvs {
    /// The network, ready to predict depth.
    ///
    /// # Errors
    /// Only if the shipped files are broken (a test loads them).
    pub fn load(&self) -> Result<Mvs> {
        let path = Path::new("models").join(format!("{}.json", self.name));
        Ok(Mvs::from_bytes(self.description, self.weights, &path)?)
    }
}

/// The learned multi-view stereo network trained on the built-in objects' RGB-D dataset
/// (`training/configs/mvs_small.toml`): depth and confidence from two or more RGB views.
pub const MVS: ShippedMvs = ShippedMvs {
    name: "mvs_small",
    description: include_str!("../../../models/mvs_small.json"),
    weights: include_bytes!("../../../models/mvs_small.safetensors"),
};

/// A shipped sweep refiner: its name and files.
#[derive(Clone, Copy, Debug)]
pub struct ShippedSweepRefiner {
    /// The experiment's name (`training/configs/NAME.toml`).
    pub name: &'static str,
    description: &'static str,
    weights: &'static [u8],
}

impl ShippedSweepRefiner {
    /// The network, ready to refine a plane sweep's depth.
    ///
    /// # Errors
    /// Only if the shipped files are broken (a test loads them).
    pub fn load(&self) -> Result<SweepRefiner> {
        let path = Path::new("models").join(format!("{}.json", self.name));
        Ok(SweepRefiner::from_bytes(
            self.description,
            self.weights,
            &path,
        )?)
    }
}

/// The plane sweep's learned refinement trained on built-in objects seen by random camera
/// rigs (`training/configs/sweep_refiner_small.toml`): a correction and a confidence per
/// pixel of the sweep's depth.
pub const SWEEP_REFINER: ShippedSweepRefiner = ShippedSweepRefiner {
    name: "sweep_refiner_small",
    description: include_str!("../../../models/sweep_refiner_small.json"),
    weights: include_bytes!("../../../models/sweep_refiner_small.safetensors"),
};
