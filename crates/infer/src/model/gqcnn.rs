//! The GQ-CNN (Dex-Net 2.0) and the multi-view GQ-CNN: loaded from the training code's export,
//! run on the op set with buffers reused across calls.

use std::path::Path;

use crate::error::{InferError, Result};
use crate::model::description::{
    Architecture, ConvSpec, GQCNN_FORMAT, GqcnnDescription, InputSpec,
};
use crate::model::image_stream::{ImageStream, StreamBuffers};
use crate::model::weights::{Weights, beside, parse_description, read_description};
use crate::ops::{LocalResponseNorm, concat_into, linear_into, relu, softmax};
use crate::parallel::Parallelism;
use crate::tensor::Tensor;

/// A weight matrix and its bias.
#[derive(Debug)]
pub(super) struct Dense {
    pub(super) weight: Tensor,
    pub(super) bias: Tensor,
}

/// A loaded GQ-CNN: `(depth crops [N, 1, S, S], pose [N, P]) -> P(robust) [N]`.
#[derive(Debug)]
pub struct Gqcnn {
    description: GqcnnDescription,
    convs: Vec<(ConvSpec, Dense)>,
    image_fc: Dense,
    pose_fc: Dense,
    merge_fc: Dense,
    out: Dense,
    image_mean: f32,
    image_std: f32,
    pose_mean: Vec<f32>,
    pose_std: Vec<f32>,
    lrn: LocalResponseNorm,
    parallelism: Parallelism,
}

/// The intermediate tensors of [`Gqcnn::logits`], kept between calls so that scoring allocates
/// only when the batch grows.
#[derive(Debug, Default)]
pub struct GqcnnWorkspace {
    a: Tensor,
    stream: Vec<StreamBuffers>,
    image: Tensor,
    gathered: Tensor,
    pose_in: Tensor,
    pose: Tensor,
    merged: Tensor,
    hidden: Tensor,
    logits: Tensor,
}

impl Gqcnn {
    /// Loads `NAME.json` and the weights it names (beside it), checking every tensor's name and
    /// shape against the architecture.
    ///
    /// # Errors
    /// [`InferError::Model`] naming the JSON for an unreadable or malformed description, another
    /// format, or an architecture that cannot be built; [`InferError::Model`] or
    /// [`InferError::Weight`] naming the weights file and tensor for missing, misshapen, extra
    /// or non-f32 tensors and truncated files.
    pub fn load(json: &Path) -> Result<Self> {
        let description = Self::parse_description(&read_description(json)?, json)?;
        let weights = Weights::load(&beside(json, &description.weights))?;
        Self::build(description, weights)
    }

    /// Builds the network from a description (the JSON's text) and its safetensors file held
    /// in memory (weights compiled into a program); `json` names the pair in errors, and the
    /// weights are named as the file the description names beside it.
    ///
    /// # Errors
    /// As [`Gqcnn::load`].
    pub fn from_bytes(json_text: &str, weights: &[u8], json: &Path) -> Result<Self> {
        let description = Self::parse_description(json_text, json)?;
        let weights = Weights::from_bytes(weights, &beside(json, &description.weights))?;
        Self::build(description, weights)
    }

    fn parse_description(text: &str, json: &Path) -> Result<GqcnnDescription> {
        let model_error = |detail: String| InferError::Model {
            detail,
            path: json.to_path_buf(),
        };
        let description: GqcnnDescription = parse_description(
            text,
            json,
            "a GQ-CNN",
            GQCNN_FORMAT,
            |d: &GqcnnDescription| &d.format,
        )?;
        check_architecture(&description.architecture).map_err(&model_error)?;
        if let Some(input) = &description.input {
            input
                .check(&description.architecture)
                .map_err(model_error)?;
        }
        Ok(description)
    }

    fn build(description: GqcnnDescription, mut weights: Weights) -> Result<Self> {
        // Subnormal weights cost a microcode assist per product on x86 (see the method).
        weights.flush_subnormals();
        let arch = &description.architecture;
        let mut convs = Vec::with_capacity(arch.convs.len());
        let (mut channels, mut size) = (1, arch.image_size_px);
        for (i, spec) in arch.convs.iter().enumerate() {
            let k = spec.kernel;
            let layer = Dense {
                weight: weights.take(
                    &format!("convs.{i}.weight"),
                    &[spec.filters, channels, k, k],
                )?,
                bias: weights.take(&format!("convs.{i}.bias"), &[spec.filters])?,
            };
            convs.push((*spec, layer));
            channels = spec.filters;
            size /= spec.pool;
        }
        let image_fc = take_dense(
            &mut weights,
            "image_fc",
            arch.image_fc,
            channels * size * size,
        )?;
        let pose_fc = take_dense(&mut weights, "pose_fc", arch.pose_fc, arch.pose_inputs)?;
        let merge_fc = take_dense(
            &mut weights,
            "merge_fc",
            arch.merge_fc,
            arch.image_fc + arch.pose_fc,
        )?;
        let out = take_dense(&mut weights, "out", 2, arch.merge_fc)?;
        let p = arch.pose_inputs;
        let image_mean = weights.take("image_mean", &[1])?.data()[0];
        let image_std = weights.take("image_std", &[1])?.data()[0];
        let pose_mean = weights.take("pose_mean", &[p])?.into_data();
        let pose_std = weights.take("pose_std", &[p])?.into_data();
        let usable = |v: &f32| v.is_finite() && *v > 0.0;
        if !(usable(&image_std) && pose_std.iter().all(usable)) {
            return Err(InferError::Weight {
                name: "image_std / pose_std".into(),
                detail: "a standard deviation is not a finite number > 0".into(),
                path: weights.path().to_path_buf(),
            });
        }
        if let Some(extra) = weights.remaining().first() {
            return Err(InferError::Weight {
                name: (*extra).to_string(),
                detail: "not part of the architecture".into(),
                path: weights.path().to_path_buf(),
            });
        }
        let lrn = LocalResponseNorm {
            size: arch.lrn_size,
            alpha: arch.lrn_alpha,
            beta: arch.lrn_beta,
            k: arch.lrn_k,
        };
        Ok(Self {
            convs,
            image_fc,
            pose_fc,
            merge_fc,
            out,
            image_mean,
            image_std,
            pose_mean,
            pose_std,
            lrn,
            parallelism: Parallelism::default(),
            description,
        })
    }

    /// Runs on `parallelism` (default: one thread): a batch's images split among the threads
    /// through the convolutions, a lone image's matrix products split instead, and the fully
    /// connected layers' products split. Results are the same to the bit whatever it says.
    pub fn with_parallelism(mut self, parallelism: Parallelism) -> Self {
        self.parallelism = parallelism;
        self
    }

    /// The description it was loaded from.
    pub fn description(&self) -> &GqcnnDescription {
        &self.description
    }

    /// The input contract its training recorded, if it did.
    pub fn input_spec(&self) -> Option<&InputSpec> {
        self.description.input.as_ref()
    }

    /// The layers.
    pub fn architecture(&self) -> &Architecture {
        &self.description.architecture
    }

    /// The two logits (not robust, robust) per grasp, in `workspace`'s output buffer.
    ///
    /// # Errors
    /// [`InferError::ShapeMismatch`] when `depth` is not `[N, 1, S, S]` with the network's `S`
    /// or `pose` not `[N, P]` with its `P`.
    pub fn logits<'w>(
        &self,
        depth: &Tensor,
        pose: &Tensor,
        workspace: &'w mut GqcnnWorkspace,
    ) -> Result<&'w Tensor> {
        self.logits_shared(depth, None, pose, workspace)
    }

    /// [`Gqcnn::logits`] for grasps that share crops: grasp `i` (pose row `i`) sees crop
    /// `image_of[i]` of `depth` `[M, 1, S, S]`; each crop goes through the image stream once
    /// (a grasp axis tried at several depths has one crop). `None`: grasp `i` sees crop `i`.
    ///
    /// # Errors
    /// As [`Gqcnn::logits`], and [`InferError::ShapeMismatch`] for an `image_of` whose length is
    /// not the pose rows' or that names a crop past `M`.
    pub fn logits_shared<'w>(
        &self,
        depth: &Tensor,
        image_of: Option<&[usize]>,
        pose: &Tensor,
        workspace: &'w mut GqcnnWorkspace,
    ) -> Result<&'w Tensor> {
        let arch = self.architecture();
        let s = arch.image_size_px;
        let m = depth.shape().first().copied().unwrap_or(0);
        if depth.shape() != [m, 1, s, s] {
            return Err(InferError::ShapeMismatch {
                op: "gqcnn depth",
                expected: format!("[batch, 1, {s}, {s}]"),
                got: depth.shape().to_vec(),
            });
        }
        let n = image_of.map_or(m, <[usize]>::len);
        if pose.shape() != [n, arch.pose_inputs] {
            return Err(InferError::ShapeMismatch {
                op: "gqcnn pose",
                expected: format!("[{n}, {}]", arch.pose_inputs),
                got: pose.shape().to_vec(),
            });
        }
        if let Some(bad) = image_of.and_then(|of| of.iter().find(|&&i| i >= m)) {
            return Err(InferError::ShapeMismatch {
                op: "gqcnn crop index",
                expected: format!("indices below {m} crops"),
                got: vec![*bad],
            });
        }
        let par = self.parallelism;
        let w = workspace;
        let stream = ImageStream {
            convs: &self.convs,
            lrn: self.lrn,
            image_mean: self.image_mean,
            image_std: self.image_std,
        };
        stream.features(depth, &mut w.a, &mut w.stream, par)?;
        linear_into(
            &w.a,
            &self.image_fc.weight,
            Some(&self.image_fc.bias),
            &mut w.image,
            par,
        )?;
        relu(&mut w.image);
        if let Some(image_of) = image_of {
            let features = w.image.shape().get(1).copied().unwrap_or(0);
            w.gathered.resize(&[n, features]);
            let from = w.image.data();
            for (row, &i) in w
                .gathered
                .data_mut()
                .chunks_exact_mut(features.max(1))
                .zip(image_of)
            {
                row.copy_from_slice(&from[i * features..(i + 1) * features]);
            }
            std::mem::swap(&mut w.image, &mut w.gathered);
        }
        w.pose_in.resize(pose.shape());
        let p = arch.pose_inputs;
        for (i, (x, &v)) in w.pose_in.data_mut().iter_mut().zip(pose.data()).enumerate() {
            *x = (v - self.pose_mean[i % p]) / self.pose_std[i % p];
        }
        linear_into(
            &w.pose_in,
            &self.pose_fc.weight,
            Some(&self.pose_fc.bias),
            &mut w.pose,
            par,
        )?;
        relu(&mut w.pose);
        concat_into(&[&w.image, &w.pose], 1, &mut w.merged)?;
        linear_into(
            &w.merged,
            &self.merge_fc.weight,
            Some(&self.merge_fc.bias),
            &mut w.hidden,
            par,
        )?;
        relu(&mut w.hidden);
        linear_into(
            &w.hidden,
            &self.out.weight,
            Some(&self.out.bias),
            &mut w.logits,
            par,
        )?;
        Ok(&w.logits)
    }

    /// The probability that each grasp is robust (softmax of the logits, second class).
    ///
    /// # Errors
    /// As [`Gqcnn::logits`].
    pub fn predict(
        &self,
        depth: &Tensor,
        pose: &Tensor,
        workspace: &mut GqcnnWorkspace,
    ) -> Result<Vec<f32>> {
        self.logits(depth, pose, workspace)?;
        robust_probability(workspace)
    }

    /// [`Gqcnn::predict`] for grasps that share crops (see [`Gqcnn::logits_shared`]).
    ///
    /// # Errors
    /// As [`Gqcnn::logits_shared`].
    pub fn predict_shared(
        &self,
        depth: &Tensor,
        image_of: &[usize],
        pose: &Tensor,
        workspace: &mut GqcnnWorkspace,
    ) -> Result<Vec<f32>> {
        self.logits_shared(depth, Some(image_of), pose, workspace)?;
        robust_probability(workspace)
    }
}

/// The softmax's second class of the logits in `workspace`: P(robust) per grasp.
fn robust_probability(workspace: &mut GqcnnWorkspace) -> Result<Vec<f32>> {
    softmax(&mut workspace.logits)?;
    Ok(workspace
        .logits
        .data()
        .chunks_exact(2)
        .map(|p| p[1])
        .collect())
}

/// `NAME.weight` `[outputs, inputs]` and `NAME.bias` `[outputs]`.
fn take_dense(weights: &mut Weights, name: &str, outputs: usize, inputs: usize) -> Result<Dense> {
    Ok(Dense {
        weight: weights.take(&format!("{name}.weight"), &[outputs, inputs])?,
        bias: weights.take(&format!("{name}.bias"), &[outputs])?,
    })
}

/// What the loader cannot build, in words.
fn check_architecture(arch: &Architecture) -> std::result::Result<(), String> {
    if arch.image_size_px == 0 || arch.convs.is_empty() {
        return Err("architecture: image_size_px and convs must not be empty".into());
    }
    for (i, c) in arch.convs.iter().enumerate() {
        if c.filters == 0 || c.kernel % 2 == 0 || c.pool == 0 {
            return Err(format!(
                "architecture: convs[{i}] needs filters >= 1, an odd kernel and pool >= 1"
            ));
        }
    }
    let shrink: usize = arch.convs.iter().map(|c| c.pool).product();
    if arch.image_size_px / shrink == 0 {
        return Err("architecture: the pools shrink the image to nothing".into());
    }
    if arch.pose_inputs == 0 || arch.image_fc == 0 || arch.pose_fc == 0 || arch.merge_fc == 0 {
        return Err("architecture: every layer width must be at least 1".into());
    }
    if arch.lrn_size == 0 {
        return Err("architecture: lrn_size must be at least 1".into());
    }
    Ok(())
}
