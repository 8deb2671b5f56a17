//! The fast convolution: each image is unfolded into a `[C * kh * kw, oh * ow]` column matrix
//! (im2col), and one faer product with the weight, read as `[out_C, C * kh * kw]`, writes the
//! image's `[out_C, oh * ow]` output in place. Where the column matrix would outgrow a core's
//! cache, it is made and multiplied a band of output rows at a time.

use std::ops::Range;

use rayon::prelude::*;

use super::geometry::{Conv2dParams, Geometry};
use crate::error::Result;
use crate::gemm::{Rhs, matmul, matmul_rows};
use crate::ops::check::valid_outputs;
use crate::ops::stretch;
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
    } else if is_tap_split(&g) {
        tap_split_len(&g)
    } else {
        g.c * g.kh * g.kw * band_rows(&g) * g.ow
    };
    let (x, k, y) = (input.data(), weight.data(), out.data_mut());
    if g.n == 0 || out_len == 0 {
        return Ok(());
    }
    let tasks = par.threads().min(g.n);
    let input_image = |i: usize| &x[i * in_len..(i + 1) * in_len];
    if tasks <= 1 {
        // One image at a time; a lone image (or a single-thread run) lets faer split the product.
        let col = stretch(scratch, col_len);
        for (i, yi) in y.chunks_exact_mut(out_len).enumerate() {
            image(&g, input_image(i), k, bias, yi, col, par)?;
        }
        return Ok(());
    }
    // A batch: `tasks` contiguous runs of images, each with its own stretch of `scratch`
    // (chunks of at least one value, so that every task gets one when no columns are needed).
    let per_task = g.n.div_ceil(tasks);
    let tasks = g.n.div_ceil(per_task);
    let cols = stretch(scratch, tasks * col_len.max(1));
    y.par_chunks_mut(per_task * out_len)
        .zip(cols.par_chunks_mut(col_len.max(1)))
        .enumerate()
        .try_for_each(|(t, (ys, col))| {
            let col = &mut col[..col_len];
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

/// Whether the convolution runs tap by tap ([`image_tap_split`]): stride 1, no dilation, a
/// kernel wider than one value, and at least four input channels an output channel. Unfolding
/// such an input copies every value once per tap into a matrix with few output rows (the
/// Learnt Stereo Machine's first layer over the rays: 576 channels in, 16 out, 64 MB of
/// columns a view, multiplied a row of 64 positions at a time); splitting by tap moves the
/// copies to the far smaller output side instead.
fn is_tap_split(g: &Geometry) -> bool {
    g.stride == [1, 1] && g.dilation == [1, 1] && g.kh * g.kw > 1 && g.c >= 4 * g.oc
}

/// The scratch values of [`image_tap_split`]: the weight by tap, and every tap's products.
fn tap_split_len(g: &Geometry) -> usize {
    let taps = g.kh * g.kw;
    taps * g.oc * (g.c + g.h * g.w)
}

/// One image by taps: one product `per_tap [taps * oc, h * w] = weight [taps * oc, c] ·
/// x [c, h * w]` with the input as it lies, then each tap's products added to the outputs they
/// reach, shifted by the tap's offset (zero padding: the positions off the input get nothing).
/// `y` already holds the bias (or zeros); every value is the same whatever `par`.
fn image_tap_split(
    g: &Geometry,
    x: &[f32],
    weight: &[f32],
    y: &mut [f32],
    scratch: &mut [f32],
    par: Parallelism,
) -> Result<()> {
    let taps = g.kh * g.kw;
    let plane = g.h * g.w;
    let (by_tap, per_tap) = scratch.split_at_mut(taps * g.oc * g.c);
    let per_tap = &mut per_tap[..taps * g.oc * plane];
    // weight [oc, c, taps] -> by_tap [taps, oc, c].
    for (o, kernel) in weight.chunks_exact(g.c * taps).enumerate() {
        for (c, values) in kernel.chunks_exact(taps).enumerate() {
            for (t, &v) in values.iter().enumerate() {
                by_tap[(t * g.oc + o) * g.c + c] = v;
            }
        }
    }
    let shape = [taps * g.oc, g.c, plane];
    matmul(
        "conv2d",
        per_tap,
        by_tap,
        x,
        shape,
        Rhs::RowMajor,
        false,
        par,
    )?;
    let [ph, pw] = g.padding;
    let positions = g.oh * g.ow;
    for (t, products) in per_tap.chunks_exact(g.oc * plane).enumerate() {
        let (ky, kx) = (t / g.kw, t % g.kw);
        let (lo, hi) = valid_outputs(g.w, g.ow, 1, pw, kx);
        if lo == hi {
            continue;
        }
        for (out, from) in y
            .chunks_exact_mut(positions)
            .zip(products.chunks_exact(plane))
        {
            for oy in 0..g.oh {
                let Some(iy) = (oy + ky).checked_sub(ph).filter(|&iy| iy < g.h) else {
                    continue;
                };
                let ix = lo + kx - pw;
                let src = &from[iy * g.w + ix..iy * g.w + ix + (hi - lo)];
                let dst = &mut out[oy * g.ow + lo..oy * g.ow + hi];
                for (d, &v) in dst.iter_mut().zip(src) {
                    *d += v;
                }
            }
        }
    }
    Ok(())
}

/// The most values of a band's column matrix: 1 MiB, half a core's L2 cache on the machines
/// the benchmarks ran on, so that the product reads its columns from there.
const BAND_VALUES: usize = 1 << 18;

/// The output rows unfolded and multiplied at a time: all of them unless that outgrows
/// [`BAND_VALUES`] (Dex-Net's second convolution, 6.5 MB of columns, goes in bands of 5 rows
/// of 32). Fixed by the geometry alone, so every value is the same whatever the threads.
fn band_rows(g: &Geometry) -> usize {
    let per_row = g.c * g.kh * g.kw * g.ow;
    (BAND_VALUES / per_row.max(1)).clamp(1, g.oh.max(1))
}

/// One image: `y [oc, oh * ow] = weight [oc, c * kh * kw] · columns [c * kh * kw, oh * ow]`
/// (+ bias), the columns made and multiplied a band of output rows at a time.
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
    let taps = g.c * g.kh * g.kw;
    if is_pointwise(g) {
        let shape = [g.oc, taps, positions];
        return matmul(
            "conv2d",
            y,
            weight,
            x,
            shape,
            Rhs::RowMajor,
            bias.is_some(),
            par,
        );
    }
    if is_tap_split(g) {
        if bias.is_none() {
            y.fill(0.0);
        }
        return image_tap_split(g, x, weight, y, col, par);
    }
    let band = band_rows(g);
    for start in (0..g.oh).step_by(band) {
        let rows = start..(start + band).min(g.oh);
        let n = rows.len() * g.ow;
        let col = &mut col[..taps * n];
        if is_same_width(g) {
            unfold_same_width(g, x, col, rows);
        } else {
            unfold(g, x, col, rows);
        }
        // Output rows start.. of every channel: a block of columns of y [oc, positions].
        let dst = &mut y[start * g.ow..];
        let shape = [g.oc, taps, n];
        let accumulate = bias.is_some();
        matmul_rows(
            "conv2d",
            dst,
            positions,
            weight,
            col,
            shape,
            Rhs::RowMajor,
            accumulate,
            par,
        )?;
    }
    Ok(())
}

/// im2col of output rows `band`: row `(c, ky, kx)` of `col` holds, for every output position
/// of the band, the input value that kernel tap meets there (zero in the padding).
fn unfold(g: &Geometry, x: &[f32], col: &mut [f32], band: Range<usize>) {
    let [sh, sw] = g.stride;
    let [ph, pw] = g.padding;
    let [dh, dw] = g.dilation;
    let positions = band.len() * g.ow;
    let mut rows = col.chunks_exact_mut(positions);
    for c in 0..g.c {
        let plane = &x[c * g.h * g.w..(c + 1) * g.h * g.w];
        for ky in 0..g.kh {
            for kx in 0..g.kw {
                let Some(row) = rows.next() else { return };
                let (lo, hi) = valid_outputs(g.w, g.ow, sw, pw, kx * dw);
                for (oy, out_row) in band.clone().zip(row.chunks_exact_mut(g.ow)) {
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

/// Whether the convolution has stride 1, no dilation and an output as wide as its input (a
/// "same" width: `kw = 2 * pw + 1`), the case [`unfold_same_width`] handles.
fn is_same_width(g: &Geometry) -> bool {
    g.stride == [1, 1] && g.dilation == [1, 1] && g.ow == g.w
}

/// [`unfold`] for [`is_same_width`] convolutions. Output position `p = oy * w + ox` of row
/// `(c, ky, kx)` then reads input value `p + (ky - ph) * w + kx - pw` of plane `c`: the row is
/// the plane shifted, one copy, after which only the output rows off the input and the
/// `|kx - pw|` columns of each row that the shift wraps round from a neighbouring input row are
/// zeroed. The values are those [`unfold`] writes; small images make many short rows, where a
/// copy per output row costs more than the copying.
fn unfold_same_width(g: &Geometry, x: &[f32], col: &mut [f32], band: Range<usize>) {
    let (h, w) = (g.h, g.w);
    let [ph, pw] = g.padding;
    // Positions are global (p = oy * w + ox); the band's start at `base` of each row of col.
    let base = band.start * w;
    let mut rows = col.chunks_exact_mut(band.len() * w);
    for plane in x.chunks_exact(h * w).take(g.c) {
        for ky in 0..g.kh {
            // Output rows top..bottom of the band read input rows oy + ky - ph inside 0..h.
            let top = ph.saturating_sub(ky).clamp(band.start, band.end);
            let bottom = (h + ph).saturating_sub(ky).clamp(top, band.end);
            for kx in 0..g.kw {
                let Some(row) = rows.next() else { return };
                row[..top * w - base].fill(0.0);
                row[bottom * w - base..].fill(0.0);
                let (lo, hi) = valid_outputs(w, g.ow, 1, pw, kx);
                // Input index = p + shift; positions whose index falls off the plane are in the
                // wrapped columns, zeroed below.
                let shift = (ky as isize - ph as isize) * w as isize + kx as isize - pw as isize;
                let first = (top * w).max((-shift).max(0) as usize);
                let last = (bottom * w).min(((h * w) as isize - shift).max(0) as usize);
                if first < last {
                    let from = (first as isize + shift) as usize;
                    let to = &mut row[first - base..last - base];
                    to.copy_from_slice(&plane[from..from + (last - first)]);
                }
                // Column by column (a few values a row), so that no call is made per row.
                let inside = &mut row[top * w - base..bottom * w - base];
                for ox in (0..lo).chain(hi..w) {
                    for v in inside.iter_mut().skip(ox).step_by(w) {
                        *v = 0.0;
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;
    use crate::testing::Rng;

    #[test]
    fn same_width_columns_are_the_general_ones() {
        let mut rng = Rng::new(9);
        // [c, h, w], kernel [kh, kw], padding [ph, pw] with kw = 2 pw + 1; taller and shorter
        // outputs, and kernels wider than the image.
        for ([c, h, w], [kh, kw], [ph, pw]) in [
            ([1, 32, 32], [5, 5], [2, 2]),
            ([3, 8, 8], [3, 3], [1, 1]),
            ([2, 6, 5], [5, 3], [1, 1]),
            ([2, 4, 6], [3, 3], [2, 1]),
            ([1, 2, 2], [7, 7], [3, 3]),
            ([2, 1, 3], [1, 1], [0, 0]),
        ] {
            let input = rng.tensor(&[1, c, h, w]);
            let weight = Tensor::zeros(&[1, c, kh, kw]);
            let params = Conv2dParams {
                padding: [ph, pw],
                ..Conv2dParams::default()
            };
            let (g, _) = Geometry::new(&input, &weight, None, params).unwrap();
            assert!(is_same_width(&g));
            // The whole image, and bands of one and of three output rows.
            for band in [g.oh, 1, 3] {
                for start in (0..g.oh).step_by(band) {
                    let rows = start..(start + band).min(g.oh);
                    let len = c * kh * kw * rows.len() * g.ow;
                    let (mut fast, mut general) = (vec![f32::NAN; len], vec![f32::NAN; len]);
                    unfold_same_width(&g, input.data(), &mut fast, rows.clone());
                    unfold(&g, input.data(), &mut general, rows.clone());
                    let case = format!("{c}x{h}x{w} kernel {kh}x{kw} padding {ph},{pw} {rows:?}");
                    assert_eq!(fast, general, "{case}");
                }
            }
        }
    }
}
