//! Parameters of a 3-D convolution and the checked sizes every form works from.

use crate::error::Result;
use crate::ops::check::{optional_vector, positive, shape_error};
use crate::tensor::Tensor;

/// Stride and padding of a 3-D convolution, each `[along depth, height, width]`, as torch's
/// `nn.Conv3d` and `nn.ConvTranspose3d` take them (no dilation, no output padding, one group).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Conv3dParams {
    /// Step between windows (a transposed convolution: between the input's footprints); at
    /// least 1.
    pub stride: [usize; 3],
    /// Zeros added before and after each axis (a transposed convolution: removed from the
    /// output's borders).
    pub padding: [usize; 3],
}

impl Default for Conv3dParams {
    /// Stride 1, no padding: torch's defaults.
    fn default() -> Self {
        Self {
            stride: [1; 3],
            padding: [0; 3],
        }
    }
}

impl Conv3dParams {
    /// The same stride and padding along every axis.
    pub fn cubic(stride: usize, padding: usize) -> Self {
        Self {
            stride: [stride; 3],
            padding: [padding; 3],
        }
    }
}

/// The checked sizes of one 3-D convolution: input `[n, c, d, h, w]`, kernel `[k0, k1, k2]`,
/// output `[n, oc, od, oh, ow]`.
#[derive(Clone, Copy, Debug)]
pub(super) struct Geometry {
    pub n: usize,
    pub c: usize,
    pub input: [usize; 3],
    pub oc: usize,
    pub kernel: [usize; 3],
    pub output: [usize; 3],
    pub stride: [usize; 3],
    pub padding: [usize; 3],
}

/// Which convolution a [`Geometry`] is for: the weight layouts and output sizes differ.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Kind {
    /// `nn.Conv3d`: weight `[out_C, C, k0, k1, k2]`.
    Direct,
    /// `nn.ConvTranspose3d`: weight `[C, out_C, k0, k1, k2]`.
    Transposed,
}

impl Geometry {
    /// Checks every shape and parameter; returns the sizes and the bias values.
    pub(super) fn new<'a>(
        kind: Kind,
        input: &Tensor,
        weight: &Tensor,
        bias: Option<&'a Tensor>,
        params: Conv3dParams,
    ) -> Result<(Self, Option<&'a [f32]>)> {
        let op = match kind {
            Kind::Direct => "conv3d",
            Kind::Transposed => "conv_transpose3d",
        };
        let &[n, c, d, h, w] = input.shape() else {
            return Err(shape_error(
                op,
                "[batch, channels, depth, height, width]",
                input.shape(),
            ));
        };
        let &[w0, w1, k0, k1, k2] = weight.shape() else {
            return Err(shape_error(op, "a weight of rank 5", weight.shape()));
        };
        let (wc, oc) = match kind {
            Kind::Direct => (w1, w0),
            Kind::Transposed => (w0, w1),
        };
        if wc != c || k0 * k1 * k2 == 0 {
            let expected = match kind {
                Kind::Direct => format!("weight [out_channels, {c}, k0 >= 1, k1 >= 1, k2 >= 1]"),
                Kind::Transposed => {
                    format!("weight [{c}, out_channels, k0 >= 1, k1 >= 1, k2 >= 1]")
                }
            };
            return Err(shape_error(op, expected, weight.shape()));
        }
        let bias = optional_vector(op, "bias", bias, oc)?;
        for (name, value) in [
            ("stride[0]", params.stride[0]),
            ("stride[1]", params.stride[1]),
            ("stride[2]", params.stride[2]),
        ] {
            positive(op, name, value)?;
        }
        let input_size = [d, h, w];
        let kernel = [k0, k1, k2];
        let mut output = [0; 3];
        for axis in 0..3 {
            let (i, k, s, p) = (
                input_size[axis],
                kernel[axis],
                params.stride[axis],
                params.padding[axis],
            );
            let size = match kind {
                Kind::Direct => (i + 2 * p).checked_sub(k).map(|span| span / s + 1),
                Kind::Transposed => ((i.max(1) - 1) * s + k).checked_sub(2 * p),
            };
            match size {
                Some(size) if size > 0 && i > 0 => output[axis] = size,
                _ => {
                    return Err(shape_error(
                        op,
                        format!(
                            "[batch, {c}, depth, height, width] with every axis non-empty and fitting a {kernel:?} kernel with padding {:?}",
                            params.padding
                        ),
                        input.shape(),
                    ));
                }
            }
        }
        Ok((
            Self {
                n,
                c,
                input: input_size,
                oc,
                kernel,
                output,
                stride: params.stride,
                padding: params.padding,
            },
            bias,
        ))
    }

    /// The output shape `[n, oc, od, oh, ow]`.
    pub(super) fn output_shape(&self) -> [usize; 5] {
        let [od, oh, ow] = self.output;
        [self.n, self.oc, od, oh, ow]
    }

    /// Values of one input image.
    pub(super) fn input_len(&self) -> usize {
        self.c * self.input.iter().product::<usize>()
    }

    /// Values of one output image.
    pub(super) fn output_len(&self) -> usize {
        self.oc * self.output.iter().product::<usize>()
    }

    /// Kernel taps per channel.
    pub(super) fn taps(&self) -> usize {
        self.kernel.iter().product()
    }
}
