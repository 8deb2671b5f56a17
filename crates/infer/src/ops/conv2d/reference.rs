//! The convolution as its definition reads: seven nested loops, nothing clever.

use super::geometry::{Conv2dParams, Geometry};
use crate::error::Result;
use crate::tensor::Tensor;

/// 2-D convolution (torch's cross-correlation) written as its definition: for every output
/// value, the bias plus the sum over input channels and kernel taps, taps outside the input
/// reading zero. Slow; the reference [`conv2d`](super::conv2d) is tested against.
///
/// `input` is `[N, C, H, W]`, `weight` `[out_C, C, kh, kw]`, `bias` `[out_C]`.
///
/// # Errors
/// [`InferError::ShapeMismatch`](crate::InferError::ShapeMismatch) for a wrong shape,
/// [`InferError::InvalidParameter`](crate::InferError::InvalidParameter) for a zero stride or
/// dilation.
pub fn conv2d_reference(
    input: &Tensor,
    weight: &Tensor,
    bias: Option<&Tensor>,
    params: Conv2dParams,
) -> Result<Tensor> {
    let (g, bias) = Geometry::new(input, weight, bias, params)?;
    let mut out = Tensor::zeros(&g.output_shape());
    let (x, k, y) = (input.data(), weight.data(), out.data_mut());
    let mut i = 0;
    for n in 0..g.n {
        for o in 0..g.oc {
            for oy in 0..g.oh {
                for ox in 0..g.ow {
                    let mut sum = bias.map_or(0.0, |b| b[o]);
                    for c in 0..g.c {
                        for ky in 0..g.kh {
                            for kx in 0..g.kw {
                                let iy = (oy * g.stride[0] + ky * g.dilation[0]) as isize
                                    - g.padding[0] as isize;
                                let ix = (ox * g.stride[1] + kx * g.dilation[1]) as isize
                                    - g.padding[1] as isize;
                                if iy < 0 || ix < 0 || iy >= g.h as isize || ix >= g.w as isize {
                                    continue;
                                }
                                let (iy, ix) = (iy as usize, ix as usize);
                                let xv = x[((n * g.c + c) * g.h + iy) * g.w + ix];
                                let kv = k[((o * g.c + c) * g.kh + ky) * g.kw + kx];
                                sum += xv * kv;
                            }
                        }
                    }
                    y[i] = sum;
                    i += 1;
                }
            }
        }
    }
    Ok(out)
}
