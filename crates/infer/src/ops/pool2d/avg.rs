//! Average pooling: the mean under each window, padding counting as zeros.

use super::params::{AvgPoolDivisor, Geometry, Pool2dParams};
use crate::error::Result;
use crate::tensor::Tensor;

/// Average pooling of an `[N, C, H, W]` tensor into a new `[N, C, oh, ow]` one (torch's
/// `nn.AvgPool2d` in floor mode; `divisor` is its `count_include_pad`).
///
/// # Errors
/// As [`avg_pool2d_into`].
pub fn avg_pool2d(input: &Tensor, params: Pool2dParams, divisor: AvgPoolDivisor) -> Result<Tensor> {
    let mut out = Tensor::default();
    avg_pool2d_into(input, params, divisor, &mut out)?;
    Ok(out)
}

/// [`avg_pool2d`] into `out`, which is resized to `[N, C, oh, ow]` and keeps its allocation.
///
/// # Errors
/// [`InferError::ShapeMismatch`](crate::InferError::ShapeMismatch) when `input` is not
/// `[N, C, H, W]` or the window does not fit the padded input;
/// [`InferError::InvalidParameter`](crate::InferError::InvalidParameter) for a zero kernel or
/// stride, or padding over half the kernel.
pub fn avg_pool2d_into(
    input: &Tensor,
    params: Pool2dParams,
    divisor: AvgPoolDivisor,
    out: &mut Tensor,
) -> Result<()> {
    let g = Geometry::new("avg_pool2d", input, params)?;
    out.resize(&g.output_shape());
    let window = (params.kernel[0] * params.kernel[1]) as f32;
    let planes = input.data().chunks_exact(g.h * g.w);
    for (plane, out_plane) in planes.zip(out.data_mut().chunks_exact_mut(g.oh * g.ow)) {
        let mut y = out_plane.iter_mut();
        for oy in 0..g.oh {
            let rows = g.span(0, oy);
            for ox in 0..g.ow {
                let cols = g.span(1, ox);
                let mut sum = 0.0;
                for iy in rows.clone() {
                    sum += plane[iy * g.w + cols.start..iy * g.w + cols.end]
                        .iter()
                        .sum::<f32>();
                }
                let count = match divisor {
                    AvgPoolDivisor::Window => window,
                    AvgPoolDivisor::InputOnly => (rows.len() * cols.len()) as f32,
                };
                if let Some(y) = y.next() {
                    *y = sum / count;
                }
            }
        }
    }
    Ok(())
}
