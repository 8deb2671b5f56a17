//! Pooling windows and the checked sizes every pooling form works from.

use crate::error::{InferError, Result};
use crate::ops::check::{nchw, positive, shape_error, window_output};
use crate::tensor::Tensor;

/// A pooling window, each field `[along height, along width]` as torch takes them. Padding is
/// symmetric and at most half the kernel (torch's rule, which keeps every window on the input).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Pool2dParams {
    /// Window size; at least 1.
    pub kernel: [usize; 2],
    /// Step between windows; at least 1.
    pub stride: [usize; 2],
    /// Added before and after each axis: `-inf` for max pooling, zeros for average pooling.
    pub padding: [usize; 2],
}

impl Pool2dParams {
    /// A `kernel` window with stride equal to the kernel and no padding (torch's defaults).
    pub fn new(kernel: [usize; 2]) -> Self {
        Self {
            kernel,
            stride: kernel,
            padding: [0, 0],
        }
    }

    /// The same window with another stride.
    pub fn with_stride(self, stride: [usize; 2]) -> Self {
        Self { stride, ..self }
    }

    /// The same window with another padding.
    pub fn with_padding(self, padding: [usize; 2]) -> Self {
        Self { padding, ..self }
    }
}

/// What an average-pooling window's sum is divided by.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum AvgPoolDivisor {
    /// The whole window, padding included: torch's default, `count_include_pad=True`.
    #[default]
    Window,
    /// The window's values that lie on the input: `count_include_pad=False`.
    InputOnly,
}

/// The sizes of one pooling, checked: input `[n, c, h, w]`, output `[n, c, oh, ow]`.
#[derive(Clone, Copy, Debug)]
pub(super) struct Geometry {
    pub n: usize,
    pub c: usize,
    pub h: usize,
    pub w: usize,
    pub oh: usize,
    pub ow: usize,
    pub params: Pool2dParams,
}

impl Geometry {
    /// Checks the input's shape and the window.
    pub(super) fn new(op: &'static str, input: &Tensor, params: Pool2dParams) -> Result<Self> {
        let [n, c, h, w] = nchw(op, input)?;
        if h == 0 || w == 0 {
            return Err(shape_error(
                op,
                "[batch, channels, height >= 1, width >= 1]",
                input.shape(),
            ));
        }
        for (name, value) in [
            ("kernel[0]", params.kernel[0]),
            ("kernel[1]", params.kernel[1]),
            ("stride[0]", params.stride[0]),
            ("stride[1]", params.stride[1]),
        ] {
            positive(op, name, value)?;
        }
        for (name, pad, kernel) in [
            ("padding[0]", params.padding[0], params.kernel[0]),
            ("padding[1]", params.padding[1], params.kernel[1]),
        ] {
            if pad > kernel / 2 {
                return Err(InferError::InvalidParameter {
                    op,
                    name,
                    value: pad.to_string(),
                    expected: "at most half the kernel size",
                });
            }
        }
        let [kh, kw] = params.kernel;
        let [sh, sw] = params.stride;
        let [ph, pw] = params.padding;
        let (Some(oh), Some(ow)) = (
            window_output(h, kh, sh, ph, 1),
            window_output(w, kw, sw, pw, 1),
        ) else {
            return Err(shape_error(
                op,
                format!(
                    "[batch, channels, height >= {}, width >= {}] for a {kh}x{kw} window with padding {:?}",
                    kh.saturating_sub(2 * ph),
                    kw.saturating_sub(2 * pw),
                    params.padding,
                ),
                input.shape(),
            ));
        };
        Ok(Self {
            n,
            c,
            h,
            w,
            oh,
            ow,
            params,
        })
    }

    /// The output shape `[n, c, oh, ow]`.
    pub(super) fn output_shape(&self) -> [usize; 4] {
        [self.n, self.c, self.oh, self.ow]
    }

    /// The input rows (or columns, `axis` 1) under output row (column) `o`, clipped to the
    /// input.
    pub(super) fn span(&self, axis: usize, o: usize) -> std::ops::Range<usize> {
        let size = [self.h, self.w][axis];
        let start = o * self.params.stride[axis];
        let lo = start.saturating_sub(self.params.padding[axis]).min(size);
        let hi = (start + self.params.kernel[axis])
            .saturating_sub(self.params.padding[axis])
            .min(size);
        lo..hi.max(lo)
    }
}
