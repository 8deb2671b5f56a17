//! The 3x3x3 "same" convolution (stride 1, padding 1) of few channels row by row: each output
//! row's values for every output channel are summed in a small buffer from the input rows they
//! read, 27 taps x channels scaled rows added in turn, with no column matrix. A cost volume's
//! regulariser (8 channels in and out over 100k voxels) spent most of its time writing and
//! reading the column matrix of the general path ([`super::fast`]); this one reads each input
//! row where it lies.

use rayon::prelude::*;

use super::geometry::Geometry;
use crate::parallel::Parallelism;

/// Whether the row-by-row form applies: a 3x3x3 kernel, stride 1, padding 1, and few enough
/// channels that the products are too thin for a matrix product to pay (`c * oc <= 256`).
pub(super) fn applies(g: &Geometry) -> bool {
    g.kernel == [3; 3] && g.stride == [1; 3] && g.padding == [1; 3] && g.c * g.oc <= 256
}

/// One image `x` `[c, d, h, w]` into `y` `[oc, d, h, w]` (`weight` `[oc, c, 3, 3, 3]`), the
/// output slices shared among `par`'s threads (every value the same whatever the split: each
/// is summed in one fixed order).
pub(super) fn image(
    g: &Geometry,
    x: &[f32],
    weight: &[f32],
    bias: Option<&[f32]>,
    y: &mut [f32],
    par: Parallelism,
) {
    let [d, h, w] = g.input;
    let plane = h * w;
    let volume = d * plane;
    // Output-major by slice: [d][oc][h][w] while summing, then moved to [oc][d][h][w].
    let slice_len = g.oc * plane;
    let mut by_slice = vec![0.0f32; d * slice_len];
    let run = |(z, out): (usize, &mut [f32])| slice(g, x, weight, bias, z, out, volume);
    if par.threads() > 1 {
        by_slice.par_chunks_mut(slice_len).enumerate().for_each(run);
    } else {
        by_slice.chunks_mut(slice_len).enumerate().for_each(run);
    }
    for (z, out) in by_slice.chunks_exact(slice_len).enumerate() {
        for (o, rows) in out.chunks_exact(plane).enumerate() {
            y[o * volume + z * plane..o * volume + (z + 1) * plane].copy_from_slice(rows);
        }
    }
}

/// Output slice `z` (`out` `[oc, h, w]`): with AVX2 where the CPU has it (the same values:
/// each is summed in the same order, and nothing is fused).
fn slice(
    g: &Geometry,
    x: &[f32],
    weight: &[f32],
    bias: Option<&[f32]>,
    z: usize,
    out: &mut [f32],
    volume: usize,
) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2 (checked just above), the one requirement of
        // `slice_avx2`.
        #[allow(unsafe_code)]
        unsafe {
            slice_avx2(g, x, weight, bias, z, out, volume);
        }
        return;
    }
    slice_portable(g, x, weight, bias, z, out, volume);
}

/// [`slice_portable`] compiled for AVX2.
///
/// # Safety
/// The CPU must have AVX2.
#[cfg(target_arch = "x86_64")]
#[allow(unsafe_code)]
#[target_feature(enable = "avx2")]
unsafe fn slice_avx2(
    g: &Geometry,
    x: &[f32],
    weight: &[f32],
    bias: Option<&[f32]>,
    z: usize,
    out: &mut [f32],
    volume: usize,
) {
    slice_portable(g, x, weight, bias, z, out, volume);
}

#[inline(always)]
fn slice_portable(
    g: &Geometry,
    x: &[f32],
    weight: &[f32],
    bias: Option<&[f32]>,
    z: usize,
    out: &mut [f32],
    volume: usize,
) {
    let [d, h, w] = g.input;
    let plane = h * w;
    // One padded input row (w + 2 values, zeros at both ends).
    let mut row = vec![0.0f32; w + 2];
    let mut acc = vec![0.0f32; g.oc * w];
    for yy in 0..h {
        for (o, a) in acc.chunks_exact_mut(w).enumerate() {
            a.fill(bias.map_or(0.0, |b| b[o]));
        }
        for dz in 0..3 {
            let Some(zi) = (z + dz).checked_sub(1).filter(|&zi| zi < d) else {
                continue;
            };
            for dy in 0..3 {
                let Some(yi) = (yy + dy).checked_sub(1).filter(|&yi| yi < h) else {
                    continue;
                };
                for ci in 0..g.c {
                    let start = ci * volume + zi * plane + yi * w;
                    row[1..=w].copy_from_slice(&x[start..start + w]);
                    for (o, a) in acc.chunks_exact_mut(w).enumerate() {
                        let taps = &weight[((o * g.c + ci) * 3 + dz) * 9 + dy * 3..][..3];
                        accumulate(a, &row, taps);
                    }
                }
            }
        }
        for (o, a) in acc.chunks_exact(w).enumerate() {
            out[o * plane + yy * w..o * plane + (yy + 1) * w].copy_from_slice(a);
        }
    }
}

/// `acc[x] += taps[0] row[x] + taps[1] row[x + 1] + taps[2] row[x + 2]`, in that order
/// (`row` is `acc.len() + 2` long).
#[inline(always)]
fn accumulate(acc: &mut [f32], row: &[f32], taps: &[f32]) {
    let (t0, t1, t2) = (taps[0], taps[1], taps[2]);
    let n = acc.len();
    let (r0, r1, r2) = (&row[..n], &row[1..=n], &row[2..n + 2]);
    for (((a, &p), &q), &r) in acc.iter_mut().zip(r0).zip(r1).zip(r2) {
        *a += t0 * p + t1 * q + t2 * r;
    }
}
