//! The learned multi-view stereo network as `training/mvgrasp_training/mvs.py` builds it: a
//! few RGB views with their cameras in, a metric depth map and a confidence per view out.
//!
//! 1. a 2-D encoder per view (shared weights): an image-resolution stem, features at 1/2 and
//!    1/4 of the input;
//! 2. per reference view, a coarse cost volume at 1/4 over hypotheses uniform in inverse depth
//!    along each ray's stretch inside the workspace ([`depth_range`]), group-wise correlation of
//!    unit feature vectors with every other view, its mean and maximum over the sources
//!    ([`correlation_volume`]), a 3-D U-Net to logits and a soft argmax ([`soft_argmax`]) to
//!    depth and confidence;
//! 3. a fine cost volume at 1/2 over `fine_planes` hypotheses `fine_step_m` apart around the
//!    coarse depth, the same way;
//! 4. a 2-D refinement at the input's resolution: a residual of at most `fine_step_m`.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::{InferError, Result};
use crate::model::lsm::scale_intrinsics;
use crate::model::weights::{Weights, beside, parse_description, read_description};
use crate::ops::plane_sweep::{
    Workspace, correlation_volume, depth_range, inverse_depth_planes, normalise_channels,
    soft_argmax,
};
use crate::ops::{
    CameraMatrices, Conv2dParams, Conv3dParams, VoxelGrid, concat, conv_transpose3d, conv2d,
    conv3d, relu, resize_bilinear, tanh,
};
use crate::parallel::Parallelism;
use crate::tensor::Tensor;

/// The format tag of a multi-view stereo description.
pub const MVS_FORMAT: &str = "mvgrasp-mvs/1";

/// The network's sizes (`MvsArchitecture` of the training code).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct MvsArchitecture {
    /// Input images' width, pixels (a multiple of 8).
    pub image_width: usize,
    /// Input images' height, pixels (a multiple of 8).
    pub image_height: usize,
    /// Channels of the matching features.
    pub features: usize,
    /// Groups of the group-wise correlation.
    pub groups: usize,
    /// Hypotheses of the coarse stage (even).
    pub coarse_planes: usize,
    /// Hypotheses of the fine stage (even).
    pub fine_planes: usize,
    /// The fine hypotheses' spacing, metres.
    pub fine_step_m: f32,
    /// Channels of the 3-D regulariser.
    pub regulariser: usize,
    /// Half the workspace's side in x and y, metres.
    pub workspace_half_side_m: f32,
    /// The workspace's top above the table, metres.
    pub workspace_height_m: f32,
}

impl MvsArchitecture {
    fn check(&self) -> std::result::Result<(), String> {
        let sizes = [
            ("image_width", self.image_width),
            ("image_height", self.image_height),
            ("features", self.features),
            ("groups", self.groups),
            ("coarse_planes", self.coarse_planes),
            ("fine_planes", self.fine_planes),
            ("regulariser", self.regulariser),
        ];
        if let Some((name, _)) = sizes.iter().find(|(_, v)| *v == 0) {
            return Err(format!("architecture: {name} is 0"));
        }
        if !(self.image_width.is_multiple_of(8) && self.image_height.is_multiple_of(8)) {
            return Err(format!(
                "architecture: image {}x{} must divide by 8",
                self.image_width, self.image_height
            ));
        }
        if !(self.coarse_planes.is_multiple_of(2) && self.fine_planes.is_multiple_of(2)) {
            return Err("architecture: the plane counts must be even".into());
        }
        if !self.features.is_multiple_of(self.groups) {
            return Err(format!(
                "architecture: features {} do not divide into {} groups",
                self.features, self.groups
            ));
        }
        let lengths = [
            self.fine_step_m,
            self.workspace_half_side_m,
            self.workspace_height_m,
        ];
        if !lengths.iter().all(|v| v.is_finite() && *v > 0.0) {
            return Err("architecture: fine_step_m and the workspace must be positive".into());
        }
        Ok(())
    }
}

/// `NAME.json` of a multi-view stereo export.
#[derive(Clone, Debug, Deserialize, Serialize)]
pub struct MvsDescription {
    /// [`MVS_FORMAT`].
    pub format: String,
    /// The weights file, beside the JSON.
    pub weights: String,
    /// The sizes.
    pub architecture: MvsArchitecture,
    /// What the training recorded (data, config, figures); free-form.
    #[serde(default)]
    pub training: serde_json::Value,
}

/// A convolution and its bias, and whether a ReLU follows.
#[derive(Debug)]
struct Conv {
    weight: Tensor,
    bias: Tensor,
    stride: usize,
    relu: bool,
}

impl Conv {
    /// `name.weight`/`name.bias` (a `nn.Conv` alone) or `name.0.*` (a `conv2d`/`conv3d` block
    /// with its ReLU), 3 taps a side.
    fn take(
        w: &mut Weights,
        name: &str,
        cin: usize,
        cout: usize,
        dims: usize,
        stride: usize,
        relu: bool,
    ) -> Result<Self> {
        let mut shape = vec![cout, cin];
        shape.extend(std::iter::repeat_n(3, dims));
        let prefix = if relu {
            format!("{name}.0")
        } else {
            name.to_owned()
        };
        Ok(Self {
            weight: w.take(&format!("{prefix}.weight"), &shape)?,
            bias: w.take(&format!("{prefix}.bias"), &[cout])?,
            stride,
            relu,
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
        if self.relu {
            relu(&mut y);
        }
        Ok(y)
    }
}

/// The 3-D U-Net from a cost volume `[1, 2 G, D, h, w]` to logits `[D, h, w]`.
#[derive(Debug)]
struct Regulariser {
    inp: Conv,
    down: Conv,
    mid: Conv,
    up_weight: Tensor,
    up_bias: Tensor,
    out: Conv,
    logit: Conv,
}

impl Regulariser {
    fn take(w: &mut Weights, name: &str, groups: usize, c: usize) -> Result<Self> {
        Ok(Self {
            inp: Conv::take(w, &format!("{name}.inp"), 2 * groups, c, 3, 1, true)?,
            down: Conv::take(w, &format!("{name}.down"), c, 2 * c, 3, 2, true)?,
            mid: Conv::take(w, &format!("{name}.mid"), 2 * c, 2 * c, 3, 1, true)?,
            up_weight: w.take(&format!("{name}.up.weight"), &[2 * c, c, 4, 4, 4])?,
            up_bias: w.take(&format!("{name}.up.bias"), &[c])?,
            out: Conv::take(w, &format!("{name}.out"), c, c, 3, 1, true)?,
            logit: Conv::take(w, &format!("{name}.logit"), c, 1, 3, 1, false)?,
        })
    }

    fn run(&self, cost: &Tensor, par: Parallelism) -> Result<Tensor> {
        let x = self.inp.run(cost, par)?;
        let down = self.mid.run(&self.down.run(&x, par)?, par)?;
        let mut up = conv_transpose3d(
            &down,
            &self.up_weight,
            Some(&self.up_bias),
            Conv3dParams::cubic(2, 1),
            par,
        )?;
        for (u, &v) in up.data_mut().iter_mut().zip(x.data()) {
            *u += v;
        }
        let mut logits = self.logit.run(&self.out.run(&up, par)?, par)?;
        let shape = logits.shape()[2..].to_vec();
        logits.reshape(&shape)?;
        Ok(logits)
    }
}

/// What [`Mvs::predict`] returns: per view, depth (metres along the optical axis) and
/// confidence (the probability mass near the chosen depth of both stages, upsampled), each
/// `[V, H, W]` at the architecture's size.
#[derive(Clone, Debug)]
pub struct MvsDepth {
    /// Depth, metres.
    pub depth: Tensor,
    /// Confidence in `[0, 1]`.
    pub confidence: Tensor,
}

/// A loaded multi-view stereo network.
#[derive(Debug)]
pub struct Mvs {
    description: MvsDescription,
    stem: Conv,
    encode_half: [Conv; 2],
    encode_quarter: [Conv; 2],
    coarse_features: Conv,
    fine_features: Conv,
    coarse_regulariser: Regulariser,
    fine_regulariser: Regulariser,
    refine: [Conv; 3],
    parallelism: Parallelism,
}

impl Mvs {
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

    /// [`Mvs::load`] from the JSON's text and the safetensors bytes held in memory; `json`
    /// names the pair in errors.
    ///
    /// # Errors
    /// As [`Mvs::load`].
    pub fn from_bytes(json_text: &str, weights: &[u8], json: &Path) -> Result<Self> {
        let description = Self::parse_description(json_text, json)?;
        let weights = Weights::from_bytes(weights, &beside(json, &description.weights))?;
        Self::build(description, weights)
    }

    fn parse_description(text: &str, json: &Path) -> Result<MvsDescription> {
        let description: MvsDescription = parse_description(
            text,
            json,
            "a multi-view stereo network",
            MVS_FORMAT,
            |d: &MvsDescription| &d.format,
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

    fn build(description: MvsDescription, mut w: Weights) -> Result<Self> {
        w.flush_subnormals();
        let a = description.architecture;
        let (f, g, r) = (a.features, a.groups, a.regulariser);
        let net = Self {
            stem: Conv::take(&mut w, "stem", 3, 8, 2, 1, true)?,
            encode_half: [
                Conv::take(&mut w, "encode_half.0", 8, 16, 2, 2, true)?,
                Conv::take(&mut w, "encode_half.1", 16, 16, 2, 1, true)?,
            ],
            encode_quarter: [
                Conv::take(&mut w, "encode_quarter.0", 16, 32, 2, 2, true)?,
                Conv::take(&mut w, "encode_quarter.1", 32, 32, 2, 1, true)?,
            ],
            coarse_features: Conv::take(&mut w, "coarse_features", 32, f, 2, 1, false)?,
            fine_features: Conv::take(&mut w, "fine_features", 16 + 32, f, 2, 1, false)?,
            coarse_regulariser: Regulariser::take(&mut w, "coarse_regulariser", g, r)?,
            fine_regulariser: Regulariser::take(&mut w, "fine_regulariser", g, r)?,
            refine: [
                Conv::take(&mut w, "refine.0", 9, 8, 2, 1, true)?,
                Conv::take(&mut w, "refine.1", 8, 8, 2, 1, true)?,
                Conv::take(&mut w, "refine.2", 8, 1, 2, 1, false)?,
            ],
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
    pub fn description(&self) -> &MvsDescription {
        &self.description
    }

    /// The sizes.
    pub fn architecture(&self) -> &MvsArchitecture {
        &self.description.architecture
    }

    /// Depth and confidence of every view: `images` `[V, 3, H, W]` (RGB in `[0, 1]`, at the
    /// architecture's size), `cameras` the V cameras with `k` at that size, posed in the table
    /// frame (z up, the table at z = 0). The workspace is centred where the cameras' optical
    /// axes meet.
    ///
    /// # Errors
    /// [`InferError::ShapeMismatch`] for images not `[V, 3, H, W]` at the architecture's size or
    /// a camera count other than V; [`InferError::InvalidParameter`] for fewer than two views
    /// or cameras whose axes do not meet (parallel, not finite).
    pub fn predict(&self, images: &Tensor, cameras: &[CameraMatrices]) -> Result<MvsDepth> {
        let a = self.description.architecture;
        let (h, w) = (a.image_height, a.image_width);
        let views = cameras.len();
        if images.shape() != [views, 3, h, w] {
            return Err(crate::ops::check::shape_error(
                "mvs",
                format!("images [{views} views, 3, {h}, {w}]"),
                images.shape(),
            ));
        }
        if views < 2 {
            return Err(InferError::InvalidParameter {
                op: "mvs",
                name: "cameras",
                value: format!("{views} cameras"),
                expected: "at least two views",
            });
        }
        // The grid's centring (least squares of the axes) is the workspace's.
        let centre = VoxelGrid::centred_on(cameras, 1.0, 1)?.centre;
        let workspace = Workspace {
            centre,
            half_side_m: a.workspace_half_side_m,
            height_m: a.workspace_height_m,
        };
        let par = self.parallelism;
        let mut input = images.clone();
        input.data_mut().iter_mut().for_each(|v| *v -= 0.5);
        let stem = self.stem.run(&input, par)?;
        let half = self.encode_half[1].run(&self.encode_half[0].run(&stem, par)?, par)?;
        let quarter = self.encode_quarter[1].run(&self.encode_quarter[0].run(&half, par)?, par)?;
        let mut coarse_features = self.coarse_features.run(&quarter, par)?;
        normalise_channels(&mut coarse_features)?;
        let (h2, w2, h4, w4) = (h / 2, w / 2, h / 4, w / 4);
        let up = resize_bilinear(&quarter, h2, w2)?;
        let mut fine_features = self.fine_features.run(&concat(&[&half, &up], 1)?, par)?;
        normalise_channels(&mut fine_features)?;
        let scaled = |sx: usize, sy: usize| -> Vec<CameraMatrices> {
            cameras
                .iter()
                .map(|c| scale_intrinsics(c, sx as f32 / w as f32, sy as f32 / h as f32))
                .collect()
        };
        let (k2, k4) = (scaled(w2, h2), scaled(w4, h4));
        let offsets: Vec<f32> = (0..a.fine_planes)
            .map(|i| (i as f32 - (a.fine_planes - 1) as f32 / 2.0) * a.fine_step_m)
            .collect();
        let mut depths = Vec::with_capacity(views * h * w);
        let mut confidences = Vec::with_capacity(views * h * w);
        for reference in 0..views {
            let (near, far) = depth_range(&k4[reference], &workspace, h4, w4);
            let planes = Tensor::new(
                &[a.coarse_planes, h4, w4],
                inverse_depth_planes(&near, &far, a.coarse_planes),
            )?;
            let mut cost =
                correlation_volume(&coarse_features, &k4, reference, &planes, a.groups, par)?;
            cost.reshape(&[1, 2 * a.groups, a.coarse_planes, h4, w4])?;
            let logits = self.coarse_regulariser.run(&cost, par)?;
            let (coarse, coarse_confidence) = soft_argmax(&logits, &planes)?;
            let centre_fine = resize_bilinear(&Tensor::new(&[1, 1, h4, w4], coarse)?, h2, w2)?;
            let mut fine_planes = vec![0.0; a.fine_planes * h2 * w2];
            for (d, offset) in offsets.iter().enumerate() {
                for (out, c) in fine_planes[d * h2 * w2..(d + 1) * h2 * w2]
                    .iter_mut()
                    .zip(centre_fine.data())
                {
                    *out = c + offset;
                }
            }
            let planes = Tensor::new(&[a.fine_planes, h2, w2], fine_planes)?;
            let mut cost =
                correlation_volume(&fine_features, &k2, reference, &planes, a.groups, par)?;
            cost.reshape(&[1, 2 * a.groups, a.fine_planes, h2, w2])?;
            let logits = self.fine_regulariser.run(&cost, par)?;
            let (fine, fine_confidence) = soft_argmax(&logits, &planes)?;
            let fine_up = resize_bilinear(&Tensor::new(&[1, 1, h2, w2], fine)?, h, w)?;
            let centre_depth = workspace.centre_depth(&cameras[reference]);
            let mut normalised = fine_up.clone();
            normalised
                .data_mut()
                .iter_mut()
                .for_each(|d| *d = (*d - centre_depth) / 0.1);
            let plane = 8 * h * w;
            let own_stem = Tensor::new(
                &[1, 8, h, w],
                stem.data()[reference * plane..(reference + 1) * plane].to_vec(),
            )?;
            let mut x = concat(&[&own_stem, &normalised], 1)?;
            for conv in &self.refine {
                x = conv.run(&x, par)?;
            }
            tanh(&mut x);
            depths.extend(
                fine_up
                    .data()
                    .iter()
                    .zip(x.data())
                    .map(|(d, r)| d + a.fine_step_m * r),
            );
            let coarse_up =
                resize_bilinear(&Tensor::new(&[1, 1, h4, w4], coarse_confidence)?, h2, w2)?;
            let product: Vec<f32> = coarse_up
                .data()
                .iter()
                .zip(&fine_confidence)
                .map(|(a, b)| a * b)
                .collect();
            let confidence = resize_bilinear(&Tensor::new(&[1, 1, h2, w2], product)?, h, w)?;
            confidences.extend_from_slice(confidence.data());
        }
        Ok(MvsDepth {
            depth: Tensor::new(&[views, h, w], depths)?,
            confidence: Tensor::new(&[views, h, w], confidences)?,
        })
    }
}
