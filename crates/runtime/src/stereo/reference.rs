//! A plain version of the sweep of a reference view's box, that the fast one ([`super::band`])
//! is tested against bit for bit: one plane at a time over the whole box, each point located
//! and sampled on its own (its four pixels clamped at the image's border, the mask looked up at
//! each), window sums clipped at the box's border, and a pixel's best views kept by insertion,
//! as the sweep was first written. Only where points land is shared with the fast sweep
//! ([`super::project::BoxRays::pixel`]).

use super::band::{Best, NO_PLANE};
use super::sweep::ViewSweep;
use super::{MAX_BEST_VIEWS, RULED_OUT, RgbView};

/// A point located in a view's image: its four surrounding pixels (indices: top-left,
/// top-right, bottom-left, bottom-right, clamped at the border) and its offset from the first.
struct Pixel {
    corners: [usize; 4],
    fraction: (f32, f32),
}

/// The plain sweep of `sweep`'s box, whose targets' images are `images` (smoothed): per box
/// pixel, its cheapest plane and the first plane that carving leaves it.
pub(super) fn sweep(sweep: &ViewSweep<'_>, images: &[&RgbView]) -> (Vec<Best>, Vec<u32>) {
    let n = sweep.area.w * sweep.area.h;
    let mut best = vec![(RULED_OUT, usize::MAX, RULED_OUT, RULED_OUT); n];
    let mut hull = vec![usize::MAX; n];
    let mut slices: [Vec<f32>; 3] = std::array::from_fn(|_| vec![RULED_OUT; n]);
    for p in 0..=sweep.planes.len() {
        if let Some(&depth) = sweep.planes.get(p) {
            let raw = plane_costs(sweep, images, depth);
            for (i, c) in raw.iter().enumerate() {
                if c.is_finite() && hull[i] == usize::MAX {
                    hull[i] = p;
                }
            }
            slices.rotate_left(1);
            slices[2] = raw;
        } else {
            slices.rotate_left(1);
            slices[2].fill(RULED_OUT);
        }
        if p == 0 {
            continue;
        }
        let (before, at, after) = (&slices[0], &slices[1], &slices[2]);
        for i in 0..n {
            if at[i] < best[i].0 {
                let left = if p >= 2 { before[i] } else { RULED_OUT };
                best[i] = (at[i], p - 1, left, after[i]);
            }
        }
    }
    let plane = |p: usize| if p == usize::MAX { NO_PLANE } else { p as u32 };
    let best = best
        .into_iter()
        .map(|(cost, p, before, after)| Best {
            cost,
            plane: plane(p),
            before,
            after,
        })
        .collect();
    (best, hull.into_iter().map(plane).collect())
}

/// Whether the plane at depth `d` meets the visual hull at a box pixel: its point inside the
/// mask of every other view that sees it, and seen by one at least.
pub(super) fn meets_hull(sweep: &ViewSweep<'_>, images: &[&RgbView], d: f32) -> bool {
    (0..sweep.area.w * sweep.area.h).any(|i| {
        if !is_object(sweep, i) {
            return false;
        }
        let mut seen = false;
        for (t, image) in images.iter().enumerate() {
            if let Some(at) = locate(sweep, (t, image), d, i) {
                if !inside(image, &at) {
                    return false;
                }
                seen = true;
            }
        }
        seen
    })
}

/// Whether box pixel `i` is the reference's object.
fn is_object(sweep: &ViewSweep<'_>, i: usize) -> bool {
    let area = &sweep.area;
    let w = sweep.reference.camera.intrinsics.width as usize;
    let image = (i / area.w + area.v0) * w + i % area.w + area.u0;
    sweep.reference.mask.as_ref().is_none_or(|m| m[image])
}

/// Where box pixel `i`'s point on the plane at depth `d` lands in target `t` (`image` its
/// view), `None` outside the image or behind the camera.
fn locate(sweep: &ViewSweep<'_>, (t, image): (usize, &RgbView), d: f32, i: usize) -> Option<Pixel> {
    let [u, v] = sweep.rays.pixel(sweep.targets[t], d, i)?;
    let k = &image.camera.intrinsics;
    let (w, h) = (k.width as usize, k.height as usize);
    if !(u >= 0.0 && v >= 0.0 && u <= (w - 1) as f32 && v <= (h - 1) as f32) {
        return None;
    }
    let (u0, v0) = (u.floor() as usize, v.floor() as usize);
    Some(Pixel {
        corners: [
            v0 * w + u0,
            v0 * w + (u0 + 1).min(w - 1),
            (v0 + 1).min(h - 1) * w + u0,
            (v0 + 1).min(h - 1) * w + (u0 + 1).min(w - 1),
        ],
        fraction: (u - u0 as f32, v - v0 as f32),
    })
}

/// Whether a located point lies inside the mask (true without one): any of its four pixels.
fn inside(image: &RgbView, at: &Pixel) -> bool {
    image
        .mask
        .as_ref()
        .is_none_or(|m| at.corners.iter().any(|&i| m[i]))
}

/// The colour at a located point, bilinear.
fn colour(image: &RgbView, at: &Pixel) -> [f32; 3] {
    let [a, b, c, d] = at.corners.map(|i| image.rgb[i].map(f32::from));
    let (fu, fv) = at.fraction;
    std::array::from_fn(|ch| {
        (a[ch] * (1.0 - fu) + b[ch] * fu) * (1.0 - fv) + (c[ch] * (1.0 - fu) + d[ch] * fu) * fv
    })
}

/// Each box pixel's cost on the plane at depth `d`: [`RULED_OUT`] where a mask carves its point
/// away or no view sees it, else the mean of its `best_views` smallest costs in the views.
fn plane_costs(sweep: &ViewSweep<'_>, images: &[&RgbView], d: f32) -> Vec<f32> {
    let (w, h) = (sweep.area.w, sweep.area.h);
    let reference = sweep.reference;
    let image_w = reference.camera.intrinsics.width as usize;
    let own: Vec<[f32; 3]> = (0..w * h)
        .map(|i| {
            let image = (i / w + sweep.area.v0) * image_w + i % w + sweep.area.u0;
            if is_object(sweep, i) {
                reference.rgb[image].map(f32::from)
            } else {
                [f32::NAN; 3]
            }
        })
        .collect();
    let on_hull: Vec<bool> = (0..w * h)
        .map(|i| {
            is_object(sweep, i)
                && !images.iter().enumerate().any(|(t, image)| {
                    locate(sweep, (t, image), d, i).is_some_and(|at| !inside(image, &at))
                })
        })
        .collect();
    let per_target: Vec<Vec<f32>> = images
        .iter()
        .enumerate()
        .map(|(t, image)| {
            let theirs: Vec<[f32; 3]> = (0..w * h)
                .map(|i| {
                    let at = on_hull[i]
                        .then(|| locate(sweep, (t, image), d, i))
                        .flatten();
                    at.map_or([f32::NAN; 3], |at| colour(image, &at))
                })
                .collect();
            window_costs(&own, &theirs, (w, h), sweep.radius)
        })
        .collect();
    let best_views = sweep.best_views;
    (0..w * h)
        .map(|i| {
            if !on_hull[i] {
                return RULED_OUT;
            }
            let mut best = [f32::INFINITY; MAX_BEST_VIEWS];
            let mut seen = 0;
            for costs in &per_target {
                let cost = costs[i];
                if !cost.is_finite() {
                    continue;
                }
                seen += 1;
                let kept = &mut best[..best_views];
                if cost < kept[best_views - 1] {
                    let at = kept.partition_point(|&c| c <= cost);
                    kept[at..].rotate_right(1);
                    kept[at] = cost;
                }
            }
            if seen == 0 {
                return RULED_OUT;
            }
            let k = best_views.min(seen);
            best[..k].iter().sum::<f32>() / k as f32
        })
        .collect()
}

/// Per pixel, one minus the zero-mean normalised cross-correlation of `own` and `theirs` over
/// the `(2 r + 1)^2` window (clipped at the borders) of pixels where both are known (not NaN),
/// the three channels as three samples each; NaN where the pixel itself is unknown in either.
fn window_costs(
    own: &[[f32; 3]],
    theirs: &[[f32; 3]],
    (w, h): (usize, usize),
    r: usize,
) -> Vec<f32> {
    let terms: Vec<[f32; 6]> = own
        .iter()
        .zip(theirs)
        .map(|(a, b)| {
            if a[0].is_nan() || b[0].is_nan() {
                return [0.0; 6];
            }
            let mut t = [3.0, 0.0, 0.0, 0.0, 0.0, 0.0];
            for c in 0..3 {
                t[1] += a[c];
                t[2] += b[c];
                t[3] += a[c] * a[c];
                t[4] += b[c] * b[c];
                t[5] += a[c] * b[c];
            }
            t
        })
        .collect();
    let window = window_sums(&window_sums(&terms, (w, h), r, true), (w, h), r, false);
    terms
        .iter()
        .zip(window)
        .map(|(t, [n, sa, sb, saa, sbb, sab])| {
            if t[0] == 0.0 {
                return f32::NAN;
            }
            let va = saa / n - (sa / n).powi(2);
            let vb = sbb / n - (sb / n).powi(2);
            if va < 4.0 || vb < 4.0 {
                return 1.0;
            }
            let covariance = sab / n - (sa / n) * (sb / n);
            1.0 - (covariance / (va * vb).sqrt()).clamp(-1.0, 1.0)
        })
        .collect()
}

/// Sums of `values` over each pixel's `2 r + 1` neighbours along one axis (clipped at the
/// borders), in order.
fn window_sums(
    values: &[[f32; 6]],
    (w, h): (usize, usize),
    r: usize,
    horizontal: bool,
) -> Vec<[f32; 6]> {
    let mut out = vec![[0.0f32; 6]; w * h];
    for y in 0..h {
        for x in 0..w {
            let (lo, hi) = if horizontal {
                (x.saturating_sub(r), (x + r + 1).min(w))
            } else {
                (y.saturating_sub(r), (y + r + 1).min(h))
            };
            let sum = &mut out[y * w + x];
            for t in lo..hi {
                let v = &values[if horizontal { y * w + t } else { t * w + x }];
                for (s, v) in sum.iter_mut().zip(v) {
                    *s += v;
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::super::band::sweep_band;
    use super::super::project::Target;
    use super::super::sweep::plan_view;
    use super::super::tests_support::views_with;
    use super::super::{SweepParams, look_at_point, smooth};
    use super::*;
    use mvgrasp_geometry::{Intrinsics, IntrinsicsPreset};

    /// The test box's views, a third of the PhoXi's size (small enough for the plain sweep).
    fn small_views(count: usize, masks: bool) -> Vec<RgbView> {
        let k = Intrinsics {
            fx: 552.5 / 3.0,
            fy: 552.5 / 3.0,
            cx: 85.5,
            cy: 64.0,
            width: 172,
            height: 129,
            ..Intrinsics::preset(IntrinsicsPreset::PhoxiS)
        };
        let (mut views, _) = views_with(count, 0.5, k);
        for view in &mut views {
            view.rgb = smooth(&view.rgb, &view.camera);
            if !masks {
                view.mask = None;
            }
        }
        views
    }

    /// Every view's box swept in bands of `band_rows` rows against the plain sweep.
    fn bands_match(views: &[RgbView], params: &SweepParams, band_rows: usize) {
        let targets: Vec<Target> = views.iter().map(Target::of).collect();
        let look_at = look_at_point(views);
        for r in 0..views.len() {
            let (_, Some(sweep)) = plan_view((views, &targets), r, params, look_at) else {
                panic!("view {r}: nothing to sweep");
            };
            let images: Vec<&RgbView> = (0..views.len())
                .filter(|&j| j != r)
                .map(|j| &views[j])
                .collect();
            let (best, hull) = super::sweep(&sweep, &images);
            assert!(
                best.iter().any(|b| b.plane != NO_PLANE),
                "view {r}: no winner"
            );
            let w = sweep.area.w;
            for start in (0..sweep.area.h).step_by(band_rows) {
                let rows = start..(start + band_rows).min(sweep.area.h);
                let band = sweep_band(&sweep, rows.clone());
                let box_rows = rows.start * w..rows.end * w;
                assert!(
                    band.best == best[box_rows.clone()] && band.hull == hull[box_rows],
                    "view {r}, rows {rows:?}, {params:?}"
                );
            }
        }
    }

    #[test]
    fn the_bands_sweep_as_the_plain_sweep_does_with_masks() {
        let views = small_views(5, true);
        for (radius, best_views, band_rows) in [(2, 2, 7), (1, 1, 3), (3, 3, 40), (4, 2, 11)] {
            let params = SweepParams {
                planes: 24,
                window_radius: radius,
                best_views,
                ..SweepParams::default()
            };
            bands_match(&views, &params, band_rows);
        }
    }

    #[test]
    fn the_bands_sweep_as_the_plain_sweep_does_without_masks() {
        let views = small_views(3, false);
        let params = SweepParams {
            planes: 8,
            ..SweepParams::default()
        };
        bands_match(&views, &params, 50);
    }

    #[test]
    fn the_coarse_test_finds_the_hull_as_the_plain_one_does() {
        let views = small_views(5, true);
        let targets: Vec<Target> = views.iter().map(Target::of).collect();
        let params = SweepParams {
            planes: 64,
            ..SweepParams::default()
        };
        for r in 0..views.len() {
            let (_, Some(sweep)) = plan_view((&views, &targets), r, &params, look_at_point(&views))
            else {
                panic!("view {r}: nothing to sweep");
            };
            let images: Vec<&RgbView> = (0..views.len())
                .filter(|&j| j != r)
                .map(|j| &views[j])
                .collect();
            let object: Vec<bool> = (0..sweep.area.w * sweep.area.h)
                .map(|i| is_object(&sweep, i))
                .collect();
            // Planes around the hull's: in front of it, through it and behind it.
            let (near, far) = (sweep.planes[0], sweep.planes[63]);
            let depths = (0..48).map(|p| near - 0.05 + p as f32 * (far - near + 0.1) / 47.0);
            let mut met = [0, 0];
            for d in depths {
                let plain = meets_hull(&sweep, &images, d);
                assert_eq!(sweep.plane_meets_hull(d, &object), plain, "view {r}, {d} m");
                met[usize::from(plain)] += 1;
            }
            assert!(met[0] > 0 && met[1] > 0, "view {r}: {met:?}");
        }
    }
}
