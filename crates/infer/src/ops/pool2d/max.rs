//! Max pooling: the largest value under each window, padding counting as `-inf`.

use super::params::{Geometry, Pool2dParams};
use crate::error::Result;
use crate::tensor::Tensor;

/// Max pooling of an `[N, C, H, W]` tensor into a new `[N, C, oh, ow]` one (torch's
/// `nn.MaxPool2d` in floor mode: a NaN under a window wins, as in torch).
///
/// # Errors
/// As [`max_pool2d_into`].
pub fn max_pool2d(input: &Tensor, params: Pool2dParams) -> Result<Tensor> {
    let mut out = Tensor::default();
    max_pool2d_into(input, params, &mut out)?;
    Ok(out)
}

/// [`max_pool2d`] into `out`, which is resized to `[N, C, oh, ow]` and keeps its allocation.
///
/// # Errors
/// [`InferError::ShapeMismatch`](crate::InferError::ShapeMismatch) when `input` is not
/// `[N, C, H, W]` or the window does not fit the padded input;
/// [`InferError::InvalidParameter`](crate::InferError::InvalidParameter) for a zero kernel or
/// stride, or padding over half the kernel.
pub fn max_pool2d_into(input: &Tensor, params: Pool2dParams, out: &mut Tensor) -> Result<()> {
    let g = Geometry::new("max_pool2d", input, params)?;
    out.resize(&g.output_shape());
    let planes = input.data().chunks_exact(g.h * g.w);
    for (plane, out_plane) in planes.zip(out.data_mut().chunks_exact_mut(g.oh * g.ow)) {
        let mut y = out_plane.iter_mut();
        for oy in 0..g.oh {
            let rows = g.span(0, oy);
            for ox in 0..g.ow {
                let cols = g.span(1, ox);
                let mut m = f32::NEG_INFINITY;
                for iy in rows.clone() {
                    for &v in &plane[iy * g.w + cols.start..iy * g.w + cols.end] {
                        if v > m || v.is_nan() {
                            m = v;
                        }
                    }
                }
                if let Some(y) = y.next() {
                    *y = m;
                }
            }
        }
    }
    Ok(())
}
