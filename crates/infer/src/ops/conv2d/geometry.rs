//! Convolution parameters and the checked sizes both convolution forms work from.

use crate::error::Result;
use crate::ops::check::{nchw, optional_vector, positive, shape_error, window_output};
use crate::tensor::Tensor;

/// Stride, padding and dilation of a 2-D convolution, each `[along height, along width]`, as
/// torch's `nn.Conv2d` takes them. Padding is symmetric (zeros on both sides of each axis).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Conv2dParams {
    /// Step between windows; at least 1.
    pub stride: [usize; 2],
    /// Zeros added before and after each axis.
    pub padding: [usize; 2],
    /// Spacing between kernel taps; at least 1 (1: a plain convolution).
    pub dilation: [usize; 2],
}

impl Default for Conv2dParams {
    /// Stride 1, no padding, no dilation: torch's defaults.
    fn default() -> Self {
        Self {
            stride: [1, 1],
            padding: [0, 0],
            dilation: [1, 1],
        }
    }
}

/// The sizes of one convolution, checked: input `[n, c, h, w]`, weight `[oc, c, kh, kw]`,
/// output `[n, oc, oh, ow]`.
#[derive(Clone, Copy, Debug)]
pub(super) struct Geometry {
    pub n: usize,
    pub c: usize,
    pub h: usize,
    pub w: usize,
    pub oc: usize,
    pub kh: usize,
    pub kw: usize,
    pub oh: usize,
    pub ow: usize,
    pub stride: [usize; 2],
    pub padding: [usize; 2],
    pub dilation: [usize; 2],
}

impl Geometry {
    /// Checks every shape and parameter; returns the sizes and the bias values.
    pub(super) fn new<'a>(
        input: &Tensor,
        weight: &Tensor,
        bias: Option<&'a Tensor>,
        params: Conv2dParams,
    ) -> Result<(Self, Option<&'a [f32]>)> {
        const OP: &str = "conv2d";
        let [n, c, h, w] = nchw(OP, input)?;
        let &[oc, wc, kh, kw] = weight.shape() else {
            return Err(shape_error(
                OP,
                "weight [out_channels, in_channels, kernel_h, kernel_w]",
                weight.shape(),
            ));
        };
        if wc != c || kh == 0 || kw == 0 {
            return Err(shape_error(
                OP,
                format!(
                    "weight [out_channels, {c}, kernel_h >= 1, kernel_w >= 1] for {c} input channels"
                ),
                weight.shape(),
            ));
        }
        let bias = optional_vector(OP, "bias", bias, oc)?;
        for (name, value) in [
            ("stride[0]", params.stride[0]),
            ("stride[1]", params.stride[1]),
            ("dilation[0]", params.dilation[0]),
            ("dilation[1]", params.dilation[1]),
        ] {
            positive(OP, name, value)?;
        }
        let [sh, sw] = params.stride;
        let [ph, pw] = params.padding;
        let [dh, dw] = params.dilation;
        let (Some(oh), Some(ow)) = (
            window_output(h, kh, sh, ph, dh),
            window_output(w, kw, sw, pw, dw),
        ) else {
            return Err(shape_error(
                OP,
                format!(
                    "[batch, {c}, height >= {}, width >= {}] for a {kh}x{kw} kernel with padding {:?} and dilation {:?}",
                    (dh * (kh - 1) + 1).saturating_sub(2 * ph),
                    (dw * (kw - 1) + 1).saturating_sub(2 * pw),
                    params.padding,
                    params.dilation,
                ),
                input.shape(),
            ));
        };
        Ok((
            Self {
                n,
                c,
                h,
                w,
                oc,
                kh,
                kw,
                oh,
                ow,
                stride: params.stride,
                padding: params.padding,
                dilation: params.dilation,
            },
            bias,
        ))
    }

    /// The output shape `[n, oc, oh, ow]`.
    pub(super) fn output_shape(&self) -> [usize; 4] {
        [self.n, self.oc, self.oh, self.ow]
    }
}
