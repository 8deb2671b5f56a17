//! The depth Learnt Stereo Machine (Kar, Haene and Malik 2017) as `training/mvgrasp_training/
//! lsm.py` builds it: a few RGB views with their cameras in, a metric depth map per view out.
//!
//! 1. a 2-D encoder per view (shared weights; instance norm): features at full and half
//!    resolution;
//! 2. unprojection of each view's half-resolution features into a voxel grid centred where the
//!    cameras look ([`VoxelGrid::centred_on`]), fused view by view by a 3-D convolutional GRU;
//! 3. a 3-D U-Net refiner (one level: down by a strided convolution, up by a transposed one);
//! 4. ray projection of the grid back into each view and a 2-D decoder with skips from the
//!    encoder, to `centre depth + radius * tanh(out)` metres.

use std::path::Path;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{InferError, Result};
use crate::model::weights::{Weights, beside, parse_description, read_description};
use crate::ops::{
    CameraMatrices, Conv2dParams, Conv3dParams, ConvGru3d, ConvGruScratch, InstanceNorm, VoxelGrid,
    concat, conv_transpose3d, conv2d, conv3d, instance_norm, project_rays, relu, resize_bilinear,
    tanh, unproject,
};
use crate::parallel::Parallelism;
use crate::tensor::Tensor;

/// The format tag of an LSM description.
pub const LSM_FORMAT: &str = "mvgrasp-lsm/1";

/// The network's sizes (`LsmArchitecture` of the training code).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct LsmArchitecture {
    /// Input images' width, pixels.
    pub image_width: usize,
    /// Input images' height, pixels.
    pub image_height: usize,
    /// Channels of the encoder at half resolution (at full resolution: half as many, at least 4).
    pub features: usize,
    /// Voxels along each side of the grid.
    pub grid_size: usize,
    /// The grid's side, metres.
    pub grid_side_m: f32,
    /// Channels of the GRU and the refiner.
    pub gru_channels: usize,
    /// Samples along each ray when the grid is projected back into a view.
    pub ray_samples: usize,
}

impl LsmArchitecture {
    fn check(&self) -> std::result::Result<(), String> {
        let sizes = [
            ("image_width", self.image_width),
            ("image_height", self.image_height),
            ("features", self.features),
            ("grid_size", self.grid_size),
            ("gru_channels", self.gru_channels),
            ("ray_samples", self.ray_samples),
        ];
        if let Some((name, _)) = sizes.iter().find(|(_, v)| *v == 0) {
            return Err(format!("architecture: {name} is 0"));
        }
        let sizes = [self.image_width, self.image_height, self.grid_size];
        if !sizes.iter().all(|s| s.is_multiple_of(2)) {
            return Err(format!(
                "architecture: image {}x{} and grid {} must be even (halved and doubled back)",
                self.image_width, self.image_height, self.grid_size
            ));
        }
        if !(self.grid_side_m.is_finite() && self.grid_side_m > 0.0) {
            return Err(format!(
                "architecture: grid_side_m {} is not positive",
                self.grid_side_m
            ));
        }
        Ok(())
    }

    /// Channels of the encoder at full resolution.
    fn full_features(&self) -> usize {
        (self.features / 2).max(4)
    }
}

/// `NAME.json` of an LSM export.
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct LsmDescription {
    /// [`LSM_FORMAT`].
    pub format: String,
    /// The weights file, beside the JSON.
    pub weights: String,
    /// The sizes.
    pub architecture: LsmArchitecture,
    /// What the training recorded (data, config, figures); free-form.
    #[serde(default)]
    pub training: serde_json::Value,
}

/// A convolution (2-D or 3-D) followed by an affine instance norm and ReLU: `conv2d` and
/// `conv3d` of the training code.
#[derive(Debug)]
struct ConvBlock {
    weight: Tensor,
    bias: Tensor,
    norm_weight: Tensor,
    norm_bias: Tensor,
    stride: usize,
}

impl ConvBlock {
    fn take(
        w: &mut Weights,
        name: &str,
        cin: usize,
        cout: usize,
        dims: usize,
        stride: usize,
    ) -> Result<Self> {
        let mut shape = vec![cout, cin];
        shape.extend(std::iter::repeat_n(3, dims));
        Ok(Self {
            weight: w.take(&format!("{name}.0.weight"), &shape)?,
            bias: w.take(&format!("{name}.0.bias"), &[cout])?,
            norm_weight: w.take(&format!("{name}.1.weight"), &[cout])?,
            norm_bias: w.take(&format!("{name}.1.bias"), &[cout])?,
            stride,
        })
    }

    fn run(&self, x: &Tensor, par: Parallelism) -> Result<Tensor> {
        let mut y = if self.weight.rank() == 4 {
            let params = Conv2dParams {
                stride: [self.stride; 2],
                padding: [1; 2],
                ..Conv2dParams::default()
            };
            conv2d(x, &self.weight, Some(&self.bias), params, par)?
        } else {
            conv3d(
                x,
                &self.weight,
                Some(&self.bias),
                Conv3dParams::cubic(self.stride, 1),
                par,
            )?
        };
        let norm = InstanceNorm {
            weight: Some(&self.norm_weight),
            bias: Some(&self.norm_bias),
            eps: 1e-5,
        };
        instance_norm(&mut y, &norm)?;
        relu(&mut y);
        Ok(y)
    }
}

/// A loaded LSM: `(images [V, 3, H, W] in [0, 1], V cameras at H x W) -> depth [V, H, W]`.
#[derive(Debug)]
pub struct Lsm {
    description: LsmDescription,
    encode_full: [ConvBlock; 2],
    encode_half: [ConvBlock; 2],
    gates_weight: Tensor,
    gates_bias: Tensor,
    candidate_weight: Tensor,
    candidate_bias: Tensor,
    refine_in: ConvBlock,
    refine_down: ConvBlock,
    refine_up_weight: Tensor,
    refine_up_bias: Tensor,
    refine_out: ConvBlock,
    from_rays: ConvBlock,
    decode_half: ConvBlock,
    decode_full: ConvBlock,
    out_weight: Tensor,
    out_bias: Tensor,
    parallelism: Parallelism,
}

impl Lsm {
    /// Loads `NAME.json` and the weights it names (beside it), every tensor's name and shape
    /// checked against the architecture.
    ///
    /// # Errors
    /// [`InferError::Model`] naming the JSON for an unreadable or malformed description, another
    /// format or impossible sizes; [`InferError::Model`] or [`InferError::Weight`] naming the
    /// weights file and tensor for missing, misshapen, extra or non-f32 tensors.
    pub fn load(json: &Path) -> Result<Self> {
        let description = Self::parse_description(&read_description(json)?, json)?;
        let weights = Weights::load(&beside(json, &description.weights))?;
        Self::build(description, weights)
    }

    /// [`Lsm::load`] from the JSON's text and the safetensors bytes held in memory (weights
    /// compiled into a program); `json` names the pair in errors.
    ///
    /// # Errors
    /// As [`Lsm::load`].
    pub fn from_bytes(json_text: &str, weights: &[u8], json: &Path) -> Result<Self> {
        let description = Self::parse_description(json_text, json)?;
        let weights = Weights::from_bytes(weights, &beside(json, &description.weights))?;
        Self::build(description, weights)
    }

    fn parse_description(text: &str, json: &Path) -> Result<LsmDescription> {
        let description: LsmDescription =
            parse_description(text, json, "an LSM", LSM_FORMAT, |d: &LsmDescription| {
                &d.format
            })?;
        description
            .architecture
            .check()
            .map_err(|detail| InferError::Model {
                detail,
                path: json.to_path_buf(),
            })?;
        Ok(description)
    }

    fn build(description: LsmDescription, mut w: Weights) -> Result<Self> {
        w.flush_subnormals();
        let a = description.architecture;
        let (f, half, g) = (a.features, a.full_features(), a.gru_channels);
        let net = Self {
            encode_full: [
                ConvBlock::take(&mut w, "encode_full.0", 3, half, 2, 1)?,
                ConvBlock::take(&mut w, "encode_full.1", half, half, 2, 1)?,
            ],
            encode_half: [
                ConvBlock::take(&mut w, "encode_half.0", half, f, 2, 2)?,
                ConvBlock::take(&mut w, "encode_half.1", f, f, 2, 1)?,
            ],
            gates_weight: w.take("gru.gates.weight", &[2 * g, f + 2 + g, 3, 3, 3])?,
            gates_bias: w.take("gru.gates.bias", &[2 * g])?,
            candidate_weight: w.take("gru.candidate.weight", &[g, f + 2 + g, 3, 3, 3])?,
            candidate_bias: w.take("gru.candidate.bias", &[g])?,
            refine_in: ConvBlock::take(&mut w, "refine_in", g, g, 3, 1)?,
            refine_down: ConvBlock::take(&mut w, "refine_down", g, 2 * g, 3, 2)?,
            refine_up_weight: w.take("refine_up.weight", &[2 * g, g, 4, 4, 4])?,
            refine_up_bias: w.take("refine_up.bias", &[g])?,
            refine_out: ConvBlock::take(&mut w, "refine_out", g, g, 3, 1)?,
            from_rays: ConvBlock::take(&mut w, "from_rays", g * a.ray_samples, f, 2, 1)?,
            decode_half: ConvBlock::take(&mut w, "decode_half", 2 * f, f, 2, 1)?,
            decode_full: ConvBlock::take(&mut w, "decode_full.0", f + half, half, 2, 1)?,
            out_weight: w.take("decode_full.1.weight", &[1, half, 3, 3])?,
            out_bias: w.take("decode_full.1.bias", &[1])?,
            description,
            parallelism: Parallelism::Sequential,
        };
        let left = w.remaining();
        if !left.is_empty() {
            return Err(InferError::Model {
                detail: format!("tensors the architecture does not use: {}", left.join(", ")),
                path: w.path().to_path_buf(),
            });
        }
        Ok(net)
    }

    /// The same network running its convolutions on `par`'s threads.
    #[must_use]
    pub fn with_parallelism(mut self, par: Parallelism) -> Self {
        self.parallelism = par;
        self
    }

    /// The description it was loaded from.
    pub fn description(&self) -> &LsmDescription {
        &self.description
    }

    /// The sizes.
    pub fn architecture(&self) -> &LsmArchitecture {
        &self.description.architecture
    }

    /// The depth of every view, metres along each camera's optical axis: `images` `[V, 3, H, W]`
    /// (RGB in `[0, 1]`, at the architecture's size), `cameras` the V cameras with `k` at that
    /// size, in the world frame the grid is placed in (the table frame: the grid's cube is
    /// axis-aligned there). Returns `[V, H, W]`.
    ///
    /// # Errors
    /// [`InferError::ShapeMismatch`] for images not `[V, 3, H, W]` at the architecture's size or
    /// a camera count other than V; [`InferError::InvalidParameter`] for cameras that do not
    /// place the grid (fewer than two, parallel axes, not finite).
    pub fn predict(&self, images: &Tensor, cameras: &[CameraMatrices]) -> Result<Tensor> {
        let a = self.description.architecture;
        let grid = VoxelGrid::centred_on(cameras, a.grid_side_m, a.grid_size)?;
        self.predict_in(images, cameras, grid.centre)
    }

    /// [`Lsm::predict`] with the grid centred on `centre` (world frame) instead of where the
    /// cameras' axes meet: what one view needs, whose axis alone does not place the grid.
    ///
    /// # Errors
    /// As [`Lsm::predict`], and [`InferError::InvalidParameter`] for no camera or a centre that
    /// is not finite.
    pub fn predict_in(
        &self,
        images: &Tensor,
        cameras: &[CameraMatrices],
        centre: [f32; 3],
    ) -> Result<Tensor> {
        let a = self.description.architecture;
        let (h, w) = (a.image_height, a.image_width);
        let views = cameras.len();
        if images.shape() != [views, 3, h, w] {
            return Err(crate::ops::check::shape_error(
                "lsm",
                format!("images [{views} views, 3, {h}, {w}]"),
                images.shape(),
            ));
        }
        if views == 0 {
            return Err(InferError::InvalidParameter {
                op: "lsm",
                name: "cameras",
                value: "0 cameras".into(),
                expected: "at least one view",
            });
        }
        let par = self.parallelism;
        let mut full = images.clone();
        for block in &self.encode_full {
            full = block.run(&full, par)?;
        }
        let mut half = full.clone();
        for block in &self.encode_half {
            half = block.run(&half, par)?;
        }
        let (hh, hw) = (half.shape()[2], half.shape()[3]);
        let half_cameras: Vec<CameraMatrices> = cameras
            .iter()
            .map(|c| scale_intrinsics(c, hw as f32 / w as f32, hh as f32 / h as f32))
            .collect();
        let grid = VoxelGrid {
            centre,
            side_m: a.grid_side_m,
            size: a.grid_size,
        };
        let s = a.grid_size;
        let g = a.gru_channels;
        let f = a.features;
        let mut state = Tensor::zeros(&[1, g, s, s, s]);
        let cell = ConvGru3d {
            gates_weight: &self.gates_weight,
            gates_bias: Some(&self.gates_bias),
            candidate_weight: &self.candidate_weight,
            candidate_bias: Some(&self.candidate_bias),
        };
        let mut scratch = ConvGruScratch::default();
        let plane = f * hh * hw;
        for (view, camera) in half_cameras.iter().enumerate() {
            let features = Tensor::new(
                &[f, hh, hw],
                half.data()[view * plane..(view + 1) * plane].to_vec(),
            )?;
            let mut x = unproject(&features, camera, &grid, a.grid_side_m / 2.0)?;
            x.reshape(&[1, f + 2, s, s, s])?;
            cell.step(&x, &mut state, &mut scratch, par)?;
        }
        let x = self.refine_in.run(&state, par)?;
        let down = self.refine_down.run(&x, par)?;
        let mut up = conv_transpose3d(
            &down,
            &self.refine_up_weight,
            Some(&self.refine_up_bias),
            Conv3dParams::cubic(2, 1),
            par,
        )?;
        for (u, &v) in up.data_mut().iter_mut().zip(x.data()) {
            *u += v;
        }
        let mut grid_features = self.refine_out.run(&up, par)?;
        grid_features.reshape(&[g, s, s, s])?;
        // Each view's rays and the first decoder layer over them, one view at a time (a view's
        // rays are 7 MB; all views' at once were tens of megabytes allocated and page-faulted
        // afresh on every call), the views shared among `par`'s threads. Each view's values are
        // the same whatever the split (the layer's instance norm is per image).
        let from_rays = |camera: &CameraMatrices, par: Parallelism| -> Result<Tensor> {
            let mut rays = project_rays(&grid_features, camera, &grid, a.ray_samples, hh, hw)?;
            rays.reshape(&[1, g * a.ray_samples, hh, hw])?;
            self.from_rays.run(&rays, par)
        };
        let decoded: Vec<Tensor> = if par.threads() > 1 {
            half_cameras
                .par_iter()
                .map(|camera| from_rays(camera, Parallelism::Sequential))
                .collect::<Result<_>>()?
        } else {
            half_cameras
                .iter()
                .map(|camera| from_rays(camera, par))
                .collect::<Result<_>>()?
        };
        let y = concat(&decoded.iter().collect::<Vec<_>>(), 0)?;
        let y = self.decode_half.run(&concat(&[&y, &half], 1)?, par)?;
        let y = resize_bilinear(&y, h, w)?;
        let y = self.decode_full.run(&concat(&[&y, &full], 1)?, par)?;
        let params = Conv2dParams {
            padding: [1; 2],
            ..Conv2dParams::default()
        };
        let mut out = conv2d(&y, &self.out_weight, Some(&self.out_bias), params, par)?;
        tanh(&mut out);
        let radius = grid.radius_m();
        for (view, depth) in out.data_mut().chunks_exact_mut(h * w).enumerate() {
            let centre = grid.centre_depth(&cameras[view]);
            for d in depth {
                *d = centre + radius * *d;
            }
        }
        out.reshape(&[views, h, w])?;
        Ok(out)
    }
}

/// `camera` for an image resized by `sx` x `sy`, pixel centres at integers
/// (`u' = (u + 0.5) sx - 0.5`), as the training code's `scale_intrinsics`.
pub fn scale_intrinsics(camera: &CameraMatrices, sx: f32, sy: f32) -> CameraMatrices {
    let mut out = *camera;
    out.k[0][0] = camera.k[0][0] * sx;
    out.k[1][1] = camera.k[1][1] * sy;
    out.k[0][2] = (camera.k[0][2] + 0.5) * sx - 0.5;
    out.k[1][2] = (camera.k[1][2] + 0.5) * sy - 0.5;
    out
}
