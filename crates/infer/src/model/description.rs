//! The JSON that travels with a GQ-CNN's weights (written by `training/mvgrasp_training/export.py`).

use serde::{Deserialize, Serialize};

/// The format tag of a GQ-CNN description.
pub const GQCNN_FORMAT: &str = "mvgrasp-gqcnn/1";

/// `NAME.json`.
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct GqcnnDescription {
    /// [`GQCNN_FORMAT`].
    pub format: String,
    /// The weights file, beside the JSON.
    pub weights: String,
    /// The layers.
    pub architecture: Architecture,
    /// Input statistics of the training set.
    pub normalisation: Normalisation,
    /// What the network expects of its inputs (absent from exports made before the training
    /// recorded it).
    #[serde(default)]
    pub input: Option<InputSpec>,
    /// What the training recorded (data, config, figures); free-form.
    #[serde(default)]
    pub training: serde_json::Value,
}

/// The network's input contract, recorded by the training export from the manifest and the
/// crops of the dataset it was trained on: a GQ-CNN only knows crops like those.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct InputSpec {
    /// Side of the window cut around a grasp in the training images, pixels.
    pub crop_window_px: u32,
    /// Side of the crop the network takes, pixels (the window is scaled to it).
    pub crop_size_px: u32,
    /// Focal length of the training camera, pixels: the window spans
    /// `crop_window_px * z / focal_px` metres at depth `z`.
    pub focal_px: f32,
    /// Distances of the training cameras from the object, metres.
    pub camera_distance_m: [f32; 2],
    /// Range of the training crops' grasp depths, metres.
    pub grasp_depth_m: [f32; 2],
    /// Range of the training views' angle to the table, radians (multi-view networks).
    #[serde(default)]
    pub theta_rad: Option<[f32; 2]>,
    /// The pose inputs in order: `grasp_depth_m`, then `theta_rad` for a multi-view network.
    pub pose_inputs: Vec<String>,
}

impl InputSpec {
    /// Checks the contract against the architecture it travels with.
    ///
    /// # Errors
    /// What is inconsistent, in words.
    pub fn check(&self, arch: &Architecture) -> std::result::Result<(), String> {
        if self.crop_size_px as usize != arch.image_size_px {
            return Err(format!(
                "input: crop_size_px {} but the network takes {} x {} crops",
                self.crop_size_px, arch.image_size_px, arch.image_size_px
            ));
        }
        if self.crop_window_px < self.crop_size_px {
            return Err(format!(
                "input: crop_window_px {} is smaller than crop_size_px {}",
                self.crop_window_px, self.crop_size_px
            ));
        }
        if !(self.focal_px.is_finite() && self.focal_px > 0.0) {
            return Err(format!("input: focal_px {} is not positive", self.focal_px));
        }
        let expected = ["grasp_depth_m", "theta_rad"];
        if self.pose_inputs.len() != arch.pose_inputs
            || self
                .pose_inputs
                .iter()
                .zip(expected)
                .any(|(name, want)| name != want)
        {
            return Err(format!(
                "input: pose_inputs {:?}, expected the first {} of {expected:?}",
                self.pose_inputs, arch.pose_inputs
            ));
        }
        Ok(())
    }
}

/// The layers of a GQ-CNN (see the training code's `Architecture`).
#[derive(Clone, Debug, Deserialize, Serialize)]
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
#[derive(Clone, Copy, Debug, Deserialize, Serialize)]
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
#[derive(Clone, Debug, Deserialize, Serialize)]
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

#[cfg(test)]
mod tests {
    use super::*;

    fn arch(pose_inputs: usize) -> Architecture {
        serde_json::from_value(serde_json::json!({
            "name": "small", "image_size_px": 32,
            "convs": [{"filters": 4, "kernel": 3, "lrn": false, "pool": 2}],
            "image_fc": 8, "pose_inputs": pose_inputs, "pose_fc": 4, "merge_fc": 8,
            "lrn_size": 5, "lrn_alpha": 1e-4, "lrn_beta": 0.75, "lrn_k": 1.0,
        }))
        .unwrap()
    }

    fn spec(pose_inputs: &[&str]) -> InputSpec {
        serde_json::from_value(serde_json::json!({
            "crop_window_px": 96, "crop_size_px": 32, "focal_px": 552.5,
            "camera_distance_m": [0.65, 0.75], "grasp_depth_m": [0.6, 0.75],
            "pose_inputs": pose_inputs,
        }))
        .unwrap()
    }

    #[test]
    fn an_input_contract_must_fit_its_network() {
        assert_eq!(spec(&["grasp_depth_m"]).check(&arch(1)), Ok(()));
        assert_eq!(
            spec(&["grasp_depth_m", "theta_rad"]).check(&arch(2)),
            Ok(())
        );
        let err = spec(&["grasp_depth_m"]).check(&arch(2)).unwrap_err();
        assert!(err.contains("pose_inputs"), "{err}");
        let err = spec(&["theta_rad"]).check(&arch(1)).unwrap_err();
        assert!(err.contains("pose_inputs"), "{err}");
        let mut small_window = spec(&["grasp_depth_m"]);
        small_window.crop_window_px = 16;
        assert!(
            small_window
                .check(&arch(1))
                .unwrap_err()
                .contains("crop_window_px")
        );
        let mut other_size = spec(&["grasp_depth_m"]);
        other_size.crop_size_px = 64;
        assert!(
            other_size
                .check(&arch(1))
                .unwrap_err()
                .contains("crop_size_px")
        );
    }
}
