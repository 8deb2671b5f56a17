//! The JSON that travels with a GQ-CNN's weights (written by `training/mvgrasp_training/export.py`).

use serde::Deserialize;

/// The format tag of a GQ-CNN description.
pub const GQCNN_FORMAT: &str = "mvgrasp-gqcnn/1";

/// `NAME.json`.
#[derive(Clone, Debug, Deserialize)]
pub struct GqcnnDescription {
    /// [`GQCNN_FORMAT`].
    pub format: String,
    /// The weights file, beside the JSON.
    pub weights: String,
    /// The layers.
    pub architecture: Architecture,
    /// Input statistics of the training set.
    pub normalisation: Normalisation,
    /// What the training recorded (data, config, figures); free-form.
    #[serde(default)]
    pub training: serde_json::Value,
}

/// The layers of a GQ-CNN (see the training code's `Architecture`).
#[derive(Clone, Debug, Deserialize)]
pub struct Architecture {
    /// A name ("dexnet2", "small", ...).
    pub name: String,
    /// Side of the input crop, pixels.
    pub image_size_px: usize,
    /// The image stream's convolutions.
    pub convs: Vec<ConvSpec>,
    /// Width of the image stream's fully-connected layer.
    pub image_fc: usize,
    /// 1 (grasp depth) or 2 (grasp depth, theta).
    pub pose_inputs: usize,
    /// Width of the pose stream's layer.
    pub pose_fc: usize,
    /// Width of the merged layer.
    pub merge_fc: usize,
    /// LRN window, channels.
    pub lrn_size: usize,
    /// LRN alpha (torch's: divided by the window).
    pub lrn_alpha: f32,
    /// LRN beta.
    pub lrn_beta: f32,
    /// LRN k.
    pub lrn_k: f32,
}

/// One convolution: "same" padding, stride 1, ReLU, then LRN and max pooling if asked.
#[derive(Clone, Copy, Debug, Deserialize)]
pub struct ConvSpec {
    /// Output channels.
    pub filters: usize,
    /// Square kernel side (odd).
    pub kernel: usize,
    /// Local response normalisation after the activation.
    pub lrn: bool,
    /// Max-pool window and stride (1: none).
    pub pool: usize,
}

/// Input statistics: `(x - mean) / std`.
#[derive(Clone, Debug, Deserialize)]
pub struct Normalisation {
    /// Depth crop mean, metres.
    pub image_mean: f32,
    /// Depth crop standard deviation, metres.
    pub image_std: f32,
    /// Pose input means.
    pub pose_mean: Vec<f32>,
    /// Pose input standard deviations.
    pub pose_std: Vec<f32>,
}
