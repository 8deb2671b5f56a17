//! The windowed zero-mean normalised cross-correlation of the sweep, from box sums.
//!
//! Per pixel, the sums over its `(2 r + 1)^2` window of six terms of the pixels known in both
//! images (count, a, b, a^2, b^2, ab; the three channels together): horizontal sums first
//! ([`sum_across`]), then vertical ones ([`sum_down`]), each adding its taps in order from the
//! first. A band's terms are laid out with `r` columns of zeros on each side and `r` rows
//! above and below (zeros beyond the swept box), so that every window has all its taps: a
//! zero tap adds nothing, and the sums are those of the window clipped at the box's border,
//! bit for bit.

use std::ops::Range;

/// Colour variance (per channel value, 0 to 255 squared) below which a window has no texture to
/// correlate: its cost is 1 (no evidence) rather than noise divided by nothing.
const MIN_VARIANCE: f32 = 4.0;

/// A row's horizontal sums: `out[i]` the sum of `terms[i..=i + 2 r]`. Terms must be at least
/// zero (never -0: the first tap is not added to 0).
pub(super) fn sum_across(terms: &[f32], out: &mut [f32], r: usize) {
    add_taps(out, 2 * r + 1, |k| &terms[k..]);
}

/// A centre row's vertical sums over the columns `span`: `out[i]` the sum of the horizontal
/// sums `across` (rows `cols` wide) in the `2 r + 1` rows from `first`, column `span.start + i`.
pub(super) fn sum_down(
    across: &[f32],
    (cols, first, span): (usize, usize, Range<usize>),
    out: &mut [f32],
    r: usize,
) {
    add_taps(out, 2 * r + 1, |k| {
        &across[(first + k) * cols + span.start..]
    });
}

/// `out[i] = tap(0)[i] + tap(1)[i] + ...` over `taps` taps (each at least as long as `out`),
/// added in that order.
fn add_taps<'t>(out: &mut [f32], taps: usize, tap: impl Fn(usize) -> &'t [f32]) {
    // The usual windows with all their taps in one pass, the others a tap at a time.
    match taps {
        3 => add_fixed(out, std::array::from_fn::<_, 3, _>(&tap)),
        5 => add_fixed(out, std::array::from_fn::<_, 5, _>(&tap)),
        7 => add_fixed(out, std::array::from_fn::<_, 7, _>(&tap)),
        _ => {
            for (k, tap) in (0..taps).map(tap).enumerate() {
                for (sum, value) in out.iter_mut().zip(tap) {
                    *sum = if k == 0 { *value } else { *sum + value };
                }
            }
        }
    }
}

/// [`add_taps`] for `N` taps, at least two.
#[inline]
fn add_fixed<const N: usize>(out: &mut [f32], taps: [&[f32]; N]) {
    let n = out.len();
    let taps = taps.map(|tap| &tap[..n]);
    for (i, sum) in out.iter_mut().enumerate() {
        let mut s = taps[0][i] + taps[1][i];
        for tap in &taps[2..] {
            s += tap[i];
        }
        *sum = s;
    }
}

/// The mean and variance of one image's values in a window, from the count `n` and the sums of
/// the values and of their squares.
#[inline]
pub(super) fn moments(n: f32, sum: f32, squares: f32) -> [f32; 2] {
    let mean = sum / n;
    [mean, squares / n - mean.powi(2)]
}

/// One minus the zero-mean normalised cross-correlation of a window: `n` the count (three a
/// pixel known in both), the reference's mean and variance ([`moments`]), and the sums of the
/// other image's b, b^2 and of ab. A window without texture in either image costs 1
/// ([`MIN_VARIANCE`]). Without branches, so that loops of it vectorise.
#[inline]
pub(super) fn correlation_cost(n: f32, [mean_a, va]: [f32; 2], [sb, sbb, sab]: [f32; 3]) -> f32 {
    let [mean_b, vb] = moments(n, sb, sbb);
    let covariance = sab / n - mean_a * mean_b;
    let cost = 1.0 - (covariance / (va * vb).sqrt()).clamp(-1.0, 1.0);
    if va < MIN_VARIANCE || vb < MIN_VARIANCE {
        1.0
    } else {
        cost
    }
}
