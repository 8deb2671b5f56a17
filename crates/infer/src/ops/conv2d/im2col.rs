//! The fast convolution: each image is unfolded into a `[C * kh * kw, oh * ow]` column matrix
//! (im2col), and one faer product with the weight, read as `[out_C, C * kh * kw]`, writes the
//! image's `[out_C, oh * ow]` output in place.

use rayon::prelude::*;

use super::geometry::{Conv2dParams, Geometry};
use crate::error::Result;
use crate::gemm::{Rhs, matmul};
use crate::parallel::Parallelism;
use crate::tensor::Tensor;

/// 2-D convolution of an `[N, C, H, W]` batch with an `[out_C, C, kh, kw]` weight (torch's
/// layout) and an optional `[out_C]` bias, into a new `[N, out_C, oh, ow]` tensor.
///
/// # Errors
/// As [`conv2d_into`].
pub fn conv2d(
    input: &Tensor,
    weight: &Tensor,
    bias: Option<&Tensor>,
    params: Conv2dParams,
    par: Parallelism,
) -> Result<Tensor> {
    let mut out = Tensor::default();
    conv2d_into(input, weight, bias, params, &mut out, &mut Vec::new(), par)?;
    Ok(out)
}

/// [`conv2d`] into `out`, which is resized to `[N, out_C, oh, ow]`, with `scratch` for the
/// column matrices: both keep their allocations from call to call, so a model that passes the
/// same buffers allocates only on its first call.
///
/// With [`Parallelism::Rayon`] a batch is split across threads image by image; a single image
/// splits its matrix product instead. Each output value is the same whatever the split.
///
/// # Errors
/// [`InferError::ShapeMismatch`](crate::InferError::ShapeMismatch) when `input` is not
/// `[N, C, H, W]`, `weight` not `[out_C, C, kh >= 1, kw >= 1]`, `bias` not `[out_C]`, or the
/// dilated kernel does not fit the padded input;
/// [`InferError::InvalidParameter`](crate::InferError::InvalidParameter) for a zero stride or
/// dilation.
pub fn conv2d_into(
    input: &Tensor,
    weight: &Tensor,
    bias: Option<&Tensor>,
    params: Conv2dParams,
    out: &mut Tensor,
    scratch: &mut Vec<f32>,
    par: Parallelism,
) -> Result<()> {
    let (g, bias) = Geometry::new(input, weight, bias, params)?;
    out.resize(&g.output_shape());
    let in_len = g.c * g.h * g.w;
    let out_len = g.oc * g.oh * g.ow;
    let col_len = if is_pointwise(&g) {
        0
    } else {
        g.c * g.kh * g.kw * g.oh * g.ow
    };
    let (x, k, y) = (input.data(), weight.data(), out.data_mut());
    if g.n == 0 || out_len == 0 {
        return Ok(());
    }
    let tasks = par.threads().min(g.n);
    let input_image = |i: usize| &x[i * in_len..(i + 1) * in_len];
    if tasks <= 1 {
        // One image at a time; a lone image (or a single-thread run) lets faer split the product.
        scratch.resize(col_len, 0.0);
        for (i, yi) in y.chunks_exact_mut(out_len).enumerate() {
            image(&g, input_image(i), k, bias, yi, scratch, par)?;
        }
        return Ok(());
    }
    // A batch: `tasks` contiguous runs of images, each with its own stretch of `scratch`.
    let per_task = g.n.div_ceil(tasks);
    let tasks = g.n.div_ceil(per_task);
    scratch.resize(tasks * col_len, 0.0);
    let mut cols: Vec<&mut [f32]> = scratch.chunks_exact_mut(col_len.max(1)).collect();
    cols.resize_with(tasks, Default::default);
    y.par_chunks_mut(per_task * out_len)
        .zip(cols)
        .enumerate()
        .try_for_each(|(t, (ys, col))| {
            for (j, yi) in ys.chunks_exact_mut(out_len).enumerate() {
                let xi = input_image(t * per_task + j);
                image(&g, xi, k, bias, yi, col, Parallelism::Sequential)?;
            }
            Ok(())
        })
}

/// Whether the convolution reads each input value once per output position unchanged (a 1x1
/// kernel, stride 1, no padding): then the input image already is the column matrix.
fn is_pointwise(g: &Geometry) -> bool {
    g.kh == 1 && g.kw == 1 && g.stride == [1, 1] && g.padding == [0, 0]
}

/// One image: `y [oc, oh * ow] = weight [oc, c * kh * kw] · columns [c * kh * kw, oh * ow]`
/// (+ bias).
fn image(
    g: &Geometry,
    x: &[f32],
    weight: &[f32],
    bias: Option<&[f32]>,
    y: &mut [f32],
    col: &mut [f32],
    par: Parallelism,
) -> Result<()> {
    let positions = g.oh * g.ow;
    if let Some(bias) = bias {
        for (row, &b) in y.chunks_exact_mut(positions).zip(bias) {
            row.fill(b);
        }
    }
    let columns: &[f32] = if is_pointwise(g) {
        x
    } else {
        unfold(g, x, col);
        col
    };
    matmul(
        "conv2d",
        y,
        weight,
        columns,
        [g.oc, g.c * g.kh * g.kw, positions],
        Rhs::RowMajor,
        bias.is_some(),
        par,
    )
}

/// im2col: row `(c, ky, kx)` of `col` holds, for every output position, the input value that
/// kernel tap meets there (zero in the padding).
fn unfold(g: &Geometry, x: &[f32], col: &mut [f32]) {
    let [sh, sw] = g.stride;
    let [ph, pw] = g.padding;
    let [dh, dw] = g.dilation;
    let positions = g.oh * g.ow;
    let mut rows = col.chunks_exact_mut(positions);
    for c in 0..g.c {
        let plane = &x[c * g.h * g.w..(c + 1) * g.h * g.w];
        for ky in 0..g.kh {
            for kx in 0..g.kw {
                let Some(row) = rows.next() else { return };
                let (lo, hi) = valid_outputs(g.w, g.ow, sw, pw, kx * dw);
                for (oy, out_row) in row.chunks_exact_mut(g.ow).enumerate() {
                    let iy = (oy * sh + ky * dh).checked_sub(ph).filter(|&iy| iy < g.h);
                    let Some(iy) = iy else {
                        out_row.fill(0.0);
                        continue;
                    };
                    let in_row = &plane[iy * g.w..(iy + 1) * g.w];
                    out_row[..lo].fill(0.0);
                    out_row[hi..].fill(0.0);
                    if lo == hi {
                        continue;
                    }
                    // Output column ox reads input column ox * sw + kx * dw - pw.
                    let first = lo * sw + kx * dw - pw;
                    if sw == 1 {
                        out_row[lo..hi].copy_from_slice(&in_row[first..first + (hi - lo)]);
                    } else {
                        for (v, &xv) in out_row[lo..hi]
                            .iter_mut()
                            .zip(in_row[first..].iter().step_by(sw))
                        {
                            *v = xv;
                        }
                    }
                }
            }
        }
    }
}

/// The output columns `lo..hi` whose input column `ox * stride + offset - padding` lies in
/// `0..width`.
fn valid_outputs(
    width: usize,
    out_width: usize,
    stride: usize,
    padding: usize,
    offset: usize,
) -> (usize, usize) {
    // ox * stride + offset >= padding
    let lo = padding
        .saturating_sub(offset)
        .div_ceil(stride)
        .min(out_width);
    // ox * stride + offset - padding <= width - 1
    let hi = if width + padding > offset {
        ((width + padding - offset - 1) / stride + 1).min(out_width)
    } else {
        0
    };
    (lo, hi.max(lo))
}
