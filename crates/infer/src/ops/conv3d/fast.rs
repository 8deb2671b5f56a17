//! The fast 3-D convolution: each image is unfolded into a `[C * k0 * k1 * k2, positions]`
//! column matrix (vol2col) a band of output slices at a time, and one faer product with the
//! weight, read as `[out_C, C * k0 * k1 * k2]`, writes the band's outputs in place; a 3x3x3
//! "same" convolution of few channels runs row by row instead ([`super::rows`]).

use std::ops::Range;

use rayon::prelude::*;

use super::geometry::{Conv3dParams, Geometry, Kind};
use crate::error::Result;
use crate::gemm::{Rhs, matmul_rows};
use crate::ops::check::valid_outputs;
use crate::ops::stretch;
use crate::parallel::Parallelism;
use crate::tensor::Tensor;

/// 3-D convolution of an `[N, C, D, H, W]` batch with an `[out_C, C, k0, k1, k2]` weight
/// (torch's layout) and an optional `[out_C]` bias, into a new `[N, out_C, od, oh, ow]` tensor.
///
/// # Errors
/// As [`conv3d_into`].
pub fn conv3d(
    input: &Tensor,
    weight: &Tensor,
    bias: Option<&Tensor>,
    params: Conv3dParams,
    par: Parallelism,
) -> Result<Tensor> {
    let mut out = Tensor::default();
    conv3d_into(input, weight, bias, params, &mut out, &mut Vec::new(), par)?;
    Ok(out)
}

/// [`conv3d`] into `out`, resized to `[N, out_C, od, oh, ow]`, with `scratch` for the column
/// matrices; both keep their allocations from call to call. The images run one after the
/// other, each product split among `par`'s threads (the Learnt Stereo Machine convolves one
/// grid at a time); every value is the same whatever the split.
///
/// # Errors
/// [`InferError::ShapeMismatch`](crate::InferError::ShapeMismatch) when `input` is not
/// `[N, C, D, H, W]`, `weight` not `[out_C, C, k0, k1, k2]` with every side at least 1, `bias`
/// not `[out_C]`, or the kernel does not fit the padded input;
/// [`InferError::InvalidParameter`](crate::InferError::InvalidParameter) for a zero stride.
pub fn conv3d_into(
    input: &Tensor,
    weight: &Tensor,
    bias: Option<&Tensor>,
    params: Conv3dParams,
    out: &mut Tensor,
    scratch: &mut Vec<f32>,
    par: Parallelism,
) -> Result<()> {
    let (g, bias) = Geometry::new(Kind::Direct, input, weight, bias, params)?;
    out.resize(&g.output_shape());
    let (in_len, out_len) = (g.input_len(), g.output_len());
    if g.n == 0 || out_len == 0 {
        return Ok(());
    }
    if super::rows::applies(&g) {
        let (x, k) = (input.data(), weight.data());
        for (i, y) in out.data_mut().chunks_exact_mut(out_len).enumerate() {
            super::rows::image(&g, &x[i * in_len..(i + 1) * in_len], k, bias, y, par);
        }
        return Ok(());
    }
    let band = band_slices(&g);
    let slice = g.output[1] * g.output[2];
    let col = stretch(scratch, g.c * g.taps() * band * slice);
    let (x, k) = (input.data(), weight.data());
    for (i, y) in out.data_mut().chunks_exact_mut(out_len).enumerate() {
        image(&g, &x[i * in_len..(i + 1) * in_len], k, bias, y, col, par)?;
    }
    Ok(())
}

/// The most values of a band's column matrix (1 MiB, as the 2-D convolution's bands).
const BAND_VALUES: usize = 1 << 18;

/// The output slices (along depth) unfolded and multiplied at a time, fixed by the geometry
/// alone so that every value is the same whatever the threads.
fn band_slices(g: &Geometry) -> usize {
    let per_slice = g.c * g.taps() * g.output[1] * g.output[2];
    (BAND_VALUES / per_slice.max(1)).clamp(1, g.output[0].max(1))
}

/// One image: `y [oc, positions] = weight [oc, c * taps] · columns [c * taps, positions]`
/// (+ bias), the columns made and multiplied a band of output slices at a time.
fn image(
    g: &Geometry,
    x: &[f32],
    weight: &[f32],
    bias: Option<&[f32]>,
    y: &mut [f32],
    col: &mut [f32],
    par: Parallelism,
) -> Result<()> {
    let slice = g.output[1] * g.output[2];
    let positions = g.output[0] * slice;
    if let Some(bias) = bias {
        for (row, &b) in y.chunks_exact_mut(positions).zip(bias) {
            row.fill(b);
        }
    }
    let rows = g.c * g.taps();
    let band = band_slices(g);
    for start in (0..g.output[0]).step_by(band) {
        let slices = start..(start + band).min(g.output[0]);
        let n = slices.len() * slice;
        let col = &mut col[..rows * n];
        unfold_all(g, x, col, &slices, par);
        matmul_rows(
            "conv3d",
            &mut y[start * slice..],
            positions,
            weight,
            col,
            [g.oc, rows, n],
            Rhs::RowMajor,
            bias.is_some(),
            par,
        )?;
    }
    Ok(())
}

/// Whether the convolution has stride 1 and an output the shape of its input (a "same"
/// convolution: `k = 2 p + 1` along every axis), the case [`unfold_row_same_shape`] handles.
fn is_same_shape(g: &Geometry) -> bool {
    g.stride == [1; 3] && g.output == g.input
}

/// The column matrix of output slices `band` (`col`: `[C * taps, positions]`), its rows made
/// on `par`'s threads (each row on its own: the values are the same whatever the split).
fn unfold_all(g: &Geometry, x: &[f32], col: &mut [f32], band: &Range<usize>, par: Parallelism) {
    let positions = band.len() * g.output[1] * g.output[2];
    let volume = g.input.iter().product::<usize>();
    let same = is_same_shape(g);
    let [_, k1, k2] = g.kernel;
    let fill = |(r, row): (usize, &mut [f32])| {
        let (c, t) = (r / g.taps(), r % g.taps());
        let tap = [t / (k1 * k2), (t / k2) % k1, t % k2];
        let volume = &x[c * volume..(c + 1) * volume];
        if same {
            unfold_row_same_shape(g, volume, row, band, tap);
        } else {
            unfold_row(g, volume, row, band, tap);
        }
    };
    if par.threads() > 1 {
        col.par_chunks_mut(positions).enumerate().for_each(fill);
    } else {
        col.chunks_mut(positions).enumerate().for_each(fill);
    }
}

/// [`unfold_row`] for [`is_same_shape`] convolutions. Output position `p` of row
/// `(c, kz, ky, kx)` then reads input value `p + shift` of volume `c`, with
/// `shift = (kz - pz) h w + (ky - py) w + kx - px`: the row is the volume shifted, one copy
/// per row of `col` instead of one per output row, after which only the slices and rows off
/// the input and the `|kx - px|` columns of each row that the shift wraps round from a
/// neighbouring row are zeroed. The values are those [`unfold_row`] writes.
fn unfold_row_same_shape(
    g: &Geometry,
    volume: &[f32],
    row: &mut [f32],
    band: &Range<usize>,
    [kz, ky, kx]: [usize; 3],
) {
    let [d, h, w] = g.input;
    let hw = h * w;
    let [pz, py, px] = g.padding.map(|p| p as isize);
    let base = band.start * hw;
    let (dz, dy, dx) = (kz as isize - pz, ky as isize - py, kx as isize - px);
    // Output slices whose input slice oz + dz lies inside.
    let (start, end) = (band.start as isize, band.end as isize);
    let z_lo = (-dz).clamp(start, end);
    let z_hi = (d as isize - dz).clamp(z_lo, end);
    let (lo, hi) = (z_lo as usize * hw, z_hi as usize * hw);
    row[..lo - base].fill(0.0);
    row[hi - base..].fill(0.0);
    if lo >= hi {
        return;
    }
    // Positions whose input index falls off the volume are in wrapped rows or columns,
    // zeroed below.
    let shift = dz * hw as isize + dy * w as isize + dx;
    let first = lo.max((-shift).max(0) as usize);
    let last = hi.min(((d * hw) as isize - shift).max(0) as usize);
    if first < last {
        let from = (first as isize + shift) as usize;
        row[first - base..last - base].copy_from_slice(&volume[from..from + (last - first)]);
    }
    let y_lo = ((-dy).max(0) as usize).min(h);
    let y_hi = ((h as isize - dy).clamp(0, h as isize) as usize).max(y_lo);
    let x_lo = ((-dx).max(0) as usize).min(w);
    let x_hi = ((w as isize - dx).clamp(0, w as isize) as usize).max(x_lo);
    for slice in row[lo - base..hi - base].chunks_exact_mut(hw) {
        // Rows oy + dy off the input, then columns ox + dx off it.
        slice[..y_lo * w].fill(0.0);
        slice[y_hi * w..].fill(0.0);
        if x_lo > 0 || x_hi < w {
            for out_row in slice.chunks_exact_mut(w) {
                zero_few(&mut out_row[..x_lo]);
                zero_few(&mut out_row[x_hi..]);
            }
        }
    }
}

/// Zeroes `values`, usually one or none (a 3 x 3 x 3 kernel's wrapped column): a store each,
/// not a `memset` call each (`memset` fell from 4.3% to 2.3% of the LSM's profile).
#[inline(always)]
fn zero_few(values: &mut [f32]) {
    match values {
        [] => {}
        [v] => *v = 0.0,
        _ => values.fill(0.0),
    }
}

/// vol2col, one row: row `(c, kz, ky, kx)` of the column matrix holds, for every output
/// position of the band, the input value that kernel tap meets there (zero in the padding).
fn unfold_row(
    g: &Geometry,
    volume: &[f32],
    row: &mut [f32],
    band: &Range<usize>,
    [kz, ky, kx]: [usize; 3],
) {
    let [d, h, w] = g.input;
    let [_, oh, ow] = g.output;
    let [s0, s1, s2] = g.stride;
    let [p0, p1, p2] = g.padding;
    let (lo, hi) = valid_outputs(w, ow, s2, p2, kx);
    let mut out_rows = row.chunks_exact_mut(ow);
    for oz in band.clone() {
        let iz = (oz * s0 + kz).checked_sub(p0).filter(|&i| i < d);
        for oy in 0..oh {
            let Some(out_row) = out_rows.next() else {
                return;
            };
            let iy = (oy * s1 + ky).checked_sub(p1).filter(|&i| i < h);
            let (Some(iz), Some(iy)) = (iz, iy) else {
                out_row.fill(0.0);
                continue;
            };
            out_row[..lo].fill(0.0);
            out_row[hi..].fill(0.0);
            if lo == hi {
                continue;
            }
            let in_row = &volume[(iz * h + iy) * w..(iz * h + iy + 1) * w];
            let first = lo * s2 + kx - p2;
            if s2 == 1 {
                out_row[lo..hi].copy_from_slice(&in_row[first..first + (hi - lo)]);
            } else {
                let taps = in_row[first..].iter().step_by(s2);
                for (v, &xv) in out_row[lo..hi].iter_mut().zip(taps) {
                    *v = xv;
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
    fn same_shape_columns_are_the_general_ones() {
        let mut rng = Rng::new(44);
        // [c, d, h, w], kernel, padding with k = 2 p + 1; bands of every size.
        for ([c, d, h, w], kernel, padding) in [
            ([2, 5, 4, 6], [3, 3, 3], [1, 1, 1]),
            ([1, 3, 3, 3], [5, 5, 5], [2, 2, 2]),
            ([3, 4, 2, 5], [1, 3, 5], [0, 1, 2]),
            ([1, 2, 6, 1], [3, 1, 3], [1, 0, 1]),
        ] {
            let input = rng.tensor(&[1, c, d, h, w]);
            let weight = Tensor::zeros(&[1, c, kernel[0], kernel[1], kernel[2]]);
            let params = Conv3dParams {
                stride: [1; 3],
                padding,
            };
            let (g, _) = Geometry::new(Kind::Direct, &input, &weight, None, params).unwrap();
            assert!(is_same_shape(&g));
            for band in [d, 1, 2] {
                for start in (0..d).step_by(band) {
                    let slices = start..(start + band).min(d);
                    let len = c * g.taps() * slices.len() * h * w;
                    let (mut fast, mut general) = (vec![f32::NAN; len], vec![f32::NAN; len]);
                    let rows = |same: bool, col: &mut [f32]| {
                        let n = slices.len() * h * w;
                        for (r, row) in col.chunks_mut(n).enumerate() {
                            let (ch, t) = (r / g.taps(), r % g.taps());
                            let [_, k1, k2] = g.kernel;
                            let tap = [t / (k1 * k2), (t / k2) % k1, t % k2];
                            let volume = &input.data()[ch * d * h * w..(ch + 1) * d * h * w];
                            if same {
                                unfold_row_same_shape(&g, volume, row, &slices, tap);
                            } else {
                                unfold_row(&g, volume, row, &slices, tap);
                            }
                        }
                    };
                    rows(true, &mut fast);
                    rows(false, &mut general);
                    assert_eq!(
                        fast, general,
                        "{c}x{d}x{h}x{w} kernel {kernel:?} {slices:?}"
                    );
                }
            }
        }
    }
}
