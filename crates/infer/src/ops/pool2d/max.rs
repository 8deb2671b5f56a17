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
    let two_by_two = Pool2dParams::new([2, 2]);
    for (plane, out_plane) in planes.zip(out.data_mut().chunks_exact_mut(g.oh * g.ow)) {
        if params == two_by_two {
            pool_2x2(plane, g.w, out_plane, g.ow);
            continue;
        }
        let mut y = out_plane.iter_mut();
        for oy in 0..g.oh {
            let rows = g.span(0, oy);
            for ox in 0..g.ow {
                let cols = g.span(1, ox);
                let mut m = f32::NEG_INFINITY;
                for iy in rows.clone() {
                    for &v in &plane[iy * g.w + cols.start..iy * g.w + cols.end] {
                        m = larger(m, v);
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

/// The running maximum `m` after `v`: `v` when larger or NaN (torch's rule), without a branch.
#[inline]
fn larger(m: f32, v: f32) -> f32 {
    if v > m || v.is_nan() { v } else { m }
}

/// The 2x2 window with stride 2 and no padding (the GQ-CNN's): each output the fold of
/// [`larger`] over its window in row-major order, as the general loop computes it.
fn pool_2x2(plane: &[f32], w: usize, out: &mut [f32], ow: usize) {
    for (rows, y) in plane.chunks_exact(2 * w).zip(out.chunks_exact_mut(ow)) {
        let (top, bottom) = rows.split_at(w);
        let pairs = top.chunks_exact(2).zip(bottom.chunks_exact(2));
        for (y, (t, b)) in y.iter_mut().zip(pairs) {
            // larger(-inf, t[0]) is t[0] itself, so the fold starts there.
            *y = larger(larger(larger(t[0], t[1]), b[0]), b[1]);
        }
    }
}
