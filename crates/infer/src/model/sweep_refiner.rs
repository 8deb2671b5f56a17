//! The plane sweep's learned refinement as `training/mvgrasp_training/sweep_refiner.py` builds
//! it: a stack of 3 x 3 convolutions with growing dilation (a context-aggregation network)
//! over the per-pixel summary of a view's plane sweep (its winner, the winner's cost, whether
//! another view confirmed it, the visual hull, the colours), giving per pixel a correction to
//! the sweep's depth (in `step_m` units) and a confidence logit. Every layer but the last is
//! followed by a ReLU; padding keeps the image's size.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::{InferError, Result};
use crate::model::weights::{Weights, beside, parse_description, read_description};
use crate::ops::{Conv2dParams, conv2d, relu};
use crate::parallel::Parallelism;
use crate::tensor::Tensor;

/// The format tag of a sweep refiner description.
pub const SWEEP_REFINER_FORMAT: &str = "mvgrasp-sweep-refiner/1";

/// The network's sizes (`RefinerArchitecture` of the training code).
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SweepRefinerArchitecture {
    /// Input channels (the feature builder's, checked by the caller).
    pub inputs: usize,
    /// Channels of every hidden layer.
    pub channels: usize,
    /// The hidden layers' dilations, in order (each a 3 x 3 convolution).
    pub dilations: Vec<usize>,
    /// The output's depth unit, metres.
    pub step_m: f32,
}

impl SweepRefinerArchitecture {
    fn check(&self) -> std::result::Result<(), String> {
        if self.inputs == 0 || self.channels == 0 || self.dilations.is_empty() {
            return Err(format!(
                "architecture: inputs {}, channels {} and {} dilations must all be at least 1",
                self.inputs,
                self.channels,
                self.dilations.len()
            ));
        }
        if let Some(d) = self.dilations.iter().find(|&&d| d == 0 || d > 64) {
            return Err(format!("architecture: dilation {d} (expected 1 to 64)"));
        }
        if !(self.step_m.is_finite() && self.step_m > 0.0 && self.step_m < 1.0) {
            return Err(format!(
                "architecture: step_m {} (expected metres between 0 and 1)",
                self.step_m
            ));
        }
        Ok(())
    }
}

/// `NAME.json` of a sweep refiner export.
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct SweepRefinerDescription {
    /// [`SWEEP_REFINER_FORMAT`].
    pub format: String,
    /// The weights file, beside the JSON.
    pub weights: String,
    /// The sizes.
    pub architecture: SweepRefinerArchitecture,
    /// What the training recorded (data, config, figures); free-form.
    #[serde(default)]
    pub training: serde_json::Value,
}

/// What [`SweepRefiner::predict`] returns, each `[H, W]`.
#[derive(Clone, Debug)]
pub struct RefinedSweep {
    /// The correction to add to the sweep's depth, metres.
    pub correction_m: Tensor,
    /// Confidence in `[0, 1]` that the corrected depth is within the training's tolerance.
    pub confidence: Tensor,
}

/// A loaded sweep refiner.
#[derive(Debug)]
pub struct SweepRefiner {
    description: SweepRefinerDescription,
    /// Per layer: weight `[out, in, 3, 3]` (1 x 1 for the last), bias, dilation.
    layers: Vec<(Tensor, Tensor, usize)>,
    parallelism: Parallelism,
}

impl SweepRefiner {
    /// Loads `NAME.json` and the weights it names (beside it), every tensor's name and shape
    /// checked against the architecture.
    ///
    /// # Errors
    /// [`InferError::Model`] naming the JSON for an unreadable or malformed description,
    /// another format or impossible sizes; [`InferError::Model`] or [`InferError::Weight`]
    /// naming the weights file and tensor for missing, misshapen, extra or non-f32 tensors.
    pub fn load(json: &Path) -> Result<Self> {
        let description = Self::parse_description(&read_description(json)?, json)?;
        let weights = Weights::load(&beside(json, &description.weights))?;
        Self::build(description, weights)
    }

    /// [`SweepRefiner::load`] from the JSON's text and the safetensors bytes held in memory;
    /// `json` names the pair in errors.
    ///
    /// # Errors
    /// As [`SweepRefiner::load`].
    pub fn from_bytes(json_text: &str, weights: &[u8], json: &Path) -> Result<Self> {
        let description = Self::parse_description(json_text, json)?;
        let weights = Weights::from_bytes(weights, &beside(json, &description.weights))?;
        Self::build(description, weights)
    }

    fn parse_description(text: &str, json: &Path) -> Result<SweepRefinerDescription> {
        let description: SweepRefinerDescription = parse_description(
            text,
            json,
            "a sweep refiner",
            SWEEP_REFINER_FORMAT,
            |d: &SweepRefinerDescription| &d.format,
        )?;
        description
            .architecture
            .check()
            .map_err(|detail| InferError::Model {
                detail,
                path: json.to_path_buf(),
            })?;
        Ok(description)
    }

    fn build(description: SweepRefinerDescription, mut w: Weights) -> Result<Self> {
        w.flush_subnormals();
        let a = &description.architecture;
        let mut layers = Vec::with_capacity(a.dilations.len() + 1);
        let mut cin = a.inputs;
        for (i, &dilation) in a.dilations.iter().enumerate() {
            let weight = w.take(&format!("layers.{i}.weight"), &[a.channels, cin, 3, 3])?;
            let bias = w.take(&format!("layers.{i}.bias"), &[a.channels])?;
            layers.push((weight, bias, dilation));
            cin = a.channels;
        }
        let last = a.dilations.len();
        let weight = w.take(&format!("layers.{last}.weight"), &[2, cin, 1, 1])?;
        let bias = w.take(&format!("layers.{last}.bias"), &[2])?;
        layers.push((weight, bias, 1));
        let left = w.remaining();
        if !left.is_empty() {
            return Err(InferError::Model {
                detail: format!("tensors the architecture does not use: {}", left.join(", ")),
                path: w.path().to_path_buf(),
            });
        }
        Ok(Self {
            description,
            layers,
            parallelism: Parallelism::Sequential,
        })
    }

    /// The same network running its convolutions on `par`'s threads.
    #[must_use]
    pub fn with_parallelism(mut self, par: Parallelism) -> Self {
        self.parallelism = par;
        self
    }

    /// The description it was loaded from.
    pub fn description(&self) -> &SweepRefinerDescription {
        &self.description
    }

    /// The sizes.
    pub fn architecture(&self) -> &SweepRefinerArchitecture {
        &self.description.architecture
    }

    /// The correction and confidence of one view's features `[1, inputs, H, W]`.
    ///
    /// # Errors
    /// [`InferError::ShapeMismatch`] for features not `[1, inputs, H, W]` with H and W at least 1.
    pub fn predict(&self, features: &Tensor) -> Result<RefinedSweep> {
        let a = self.architecture();
        let shape = features.shape();
        if shape.len() != 4
            || shape[0] != 1
            || shape[1] != a.inputs
            || shape[2] == 0
            || shape[3] == 0
        {
            return Err(InferError::ShapeMismatch {
                op: "sweep_refiner",
                expected: format!("[1, {}, H, W] with H, W >= 1", a.inputs),
                got: shape.to_vec(),
            });
        }
        let (h, w) = (shape[2], shape[3]);
        let mut x = features.clone();
        let hidden = self.layers.len() - 1;
        for (i, (weight, bias, dilation)) in self.layers.iter().enumerate() {
            let pad = if i < hidden { *dilation } else { 0 };
            let params = Conv2dParams {
                padding: [pad; 2],
                dilation: [*dilation; 2],
                ..Conv2dParams::default()
            };
            x = conv2d(&x, weight, Some(bias), params, self.parallelism)?;
            if i < hidden {
                relu(&mut x);
            }
        }
        let out = x.data();
        let correction_m: Vec<f32> = out[..h * w].iter().map(|&o| o * a.step_m).collect();
        let confidence: Vec<f32> = out[h * w..]
            .iter()
            .map(|&o| 1.0 / (1.0 + (-o).exp()))
            .collect();
        Ok(RefinedSweep {
            correction_m: Tensor::new(&[h, w], correction_m)?,
            confidence: Tensor::new(&[h, w], confidence)?,
        })
    }
}
