//! One reference view's sweep: its depth range, the coarse pass that finds where the visual
//! hull lies, its planes, and its depths from the bands' results ([`super::band`]).

use std::ops::Range;

use mvgrasp_geometry::Vec3;
use rayon::prelude::*;

use super::band::{BandResult, NO_PLANE, sweep_band};
use super::project::{BoxRays, Located, Target};
use super::{Rays, RgbView, SweepParams, SweptDepth};

/// Planes before the sweep that find the depths the visual hull spans.
const COARSE_PLANES: usize = 64;

/// The rows of a band ([`super::band`]): enough bands for the threads to share, few enough that
/// the rows their windows compute again at the edges stay a small share.
const BAND_ROWS: usize = 48;

/// The pixels a reference view sweeps: its mask's bounding box grown by the window (the whole
/// image without a mask).
#[derive(Clone, Copy, Debug)]
pub(super) struct SweepBox {
    /// The first column.
    pub u0: usize,
    /// The first row.
    pub v0: usize,
    /// Columns.
    pub w: usize,
    /// Rows.
    pub h: usize,
}

impl SweepBox {
    fn of(view: &RgbView, margin: usize) -> Option<Self> {
        let k = &view.camera.intrinsics;
        let (w, h) = (k.width as usize, k.height as usize);
        let Some(mask) = &view.mask else {
            return Some(Self { u0: 0, v0: 0, w, h });
        };
        let (mut u0, mut v0, mut u1, mut v1) = (w, h, 0, 0);
        for (i, _) in mask.iter().enumerate().filter(|(_, m)| **m) {
            let (u, v) = (i % w, i / w);
            (u0, v0, u1, v1) = (u0.min(u), v0.min(v), u1.max(u + 1), v1.max(v + 1));
        }
        (u0 < u1).then(|| {
            let (u0, v0) = (u0.saturating_sub(margin), v0.saturating_sub(margin));
            let (u1, v1) = ((u1 + margin).min(w), (v1 + margin).min(h));
            Self {
                u0,
                v0,
                w: u1 - u0,
                h: v1 - v0,
            }
        })
    }

    /// The image index of box pixel `i` (row-major over the box), in an image `width` wide.
    fn image_index(&self, i: usize, width: usize) -> usize {
        (i / self.w + self.v0) * width + i % self.w + self.u0
    }
}

/// A reference view ready for the sweep of its bands.
pub(super) struct ViewSweep<'a> {
    /// The reference (colours smoothed).
    pub reference: &'a RgbView,
    /// The pixels swept.
    pub area: SweepBox,
    /// The depths swept, nearest first.
    pub planes: Vec<f32>,
    /// The other views, in order.
    pub targets: Vec<&'a Target>,
    /// The box's pixels' rays.
    pub rays: BoxRays,
    /// A point's cost averages this many views' costs.
    pub best_views: usize,
    /// The window's half side.
    pub radius: usize,
}

impl ViewSweep<'_> {
    /// The bands of rows the sweep splits the box into.
    fn bands(&self) -> impl Iterator<Item = Range<usize>> + '_ {
        (0..self.area.h)
            .step_by(BAND_ROWS)
            .map(|v| v..(v + BAND_ROWS).min(self.area.h))
    }

    /// Whether box pixel `i` is the reference's object (every pixel without a mask).
    fn is_object(&self, i: usize) -> bool {
        let w = self.reference.camera.intrinsics.width as usize;
        let image = self.area.image_index(i, w);
        self.reference.mask.as_ref().is_none_or(|m| m[image])
    }

    /// Whether the plane at depth `d` meets the visual hull at a box pixel: its point inside
    /// the mask of every other view that sees it, and seen by one at least. `object`: per box
    /// pixel, whether it is the reference's object.
    pub(super) fn plane_meets_hull(&self, d: f32, object: &[bool]) -> bool {
        let w = self.area.w;
        let mut located = Located::with_len(w, self.targets[0]);
        let (mut on_hull, mut seen) = (vec![false; w], vec![false; w]);
        object.chunks_exact(w).enumerate().any(|(y, row)| {
            on_hull.copy_from_slice(row);
            seen.fill(false);
            for &target in &self.targets {
                // The row's points still on the hull.
                let (Some(lo), Some(hi)) = (
                    on_hull.iter().position(|&h| h),
                    on_hull.iter().rposition(|&h| h),
                ) else {
                    return false;
                };
                let (at, fu, fv) = (
                    &mut located.at[lo..=hi],
                    &mut located.fu[lo..=hi],
                    &mut located.fv[lo..=hi],
                );
                let pixels = y * w + lo..y * w + hi + 1;
                self.rays.locate(target, d, pixels, (&mut *at, fu, fv));
                let points = on_hull[lo..=hi].iter_mut().zip(&mut seen[lo..=hi]);
                for ((h, s), &at) in points.zip(&*at) {
                    *h &= target.near_object(at);
                    *s |= at != target.nowhere();
                }
            }
            on_hull.iter().zip(&seen).any(|(&h, &s)| h && s)
        })
    }

    /// Writes a band's depths into `swept` ([`SweptDepth`]'s fields).
    fn finish(&self, band: &BandResult, params: &SweepParams, swept: &mut SweptDepth) {
        let w = self.reference.camera.intrinsics.width as usize;
        let first = band.rows.start * self.area.w;
        for (k, (best, &hull)) in band.best.iter().zip(&band.hull).enumerate() {
            let i = first + k;
            if !self.is_object(i) {
                continue;
            }
            let image = self.area.image_index(i, w);
            if hull != NO_PLANE && self.reference.mask.is_some() {
                swept.hull_m[image] = self.planes[hull as usize];
            }
            if best.plane == NO_PLANE {
                continue;
            }
            let refined = refine(
                &self.planes,
                best.plane as usize,
                best.cost,
                best.before,
                best.after,
            );
            swept.winner_m[image] = refined;
            swept.cost[image] = best.cost;
            if best.cost <= params.max_cost {
                swept.depth_m[image] = refined;
            }
        }
    }
}

/// Reference view `r`'s depths (before the consistency check): its sweep planned, then its
/// bands swept in parallel (with the other views' bands, as threads come free). `views` hold
/// the smoothed colours, `targets` the same views prepared for sampling.
pub(super) fn sweep_view(
    (views, targets): (&[RgbView], &[Target]),
    r: usize,
    params: &SweepParams,
    look_at: Option<Vec3>,
) -> SweptDepth {
    let (mut swept, sweep) = plan_view((views, targets), r, params, look_at);
    let Some(sweep) = sweep else {
        return swept;
    };
    let bands: Vec<Range<usize>> = sweep.bands().collect();
    let results: Vec<BandResult> = bands
        .into_par_iter()
        .map(|rows| sweep_band(&sweep, rows))
        .collect();
    for result in &results {
        sweep.finish(result, params, &mut swept);
    }
    swept
}

/// Reference view `r`'s depth before the sweep (the table plane off the object, with masks and
/// `table`), and its sweep, if there is anything to sweep. `views` hold the smoothed colours,
/// `targets` the same views prepared for sampling.
pub(super) fn plan_view<'a>(
    (views, targets): (&'a [RgbView], &'a [Target]),
    r: usize,
    params: &SweepParams,
    look_at: Option<Vec3>,
) -> (SweptDepth, Option<ViewSweep<'a>>) {
    let reference = &views[r];
    let k = &reference.camera.intrinsics;
    let pixels = k.width as usize * k.height as usize;
    let rays = Rays::of(&reference.camera);
    let mut swept = SweptDepth {
        depth_m: vec![0.0; pixels],
        hull_m: vec![0.0; pixels],
        winner_m: vec![0.0; pixels],
        cost: vec![0.0; pixels],
    };
    if let (true, Some(mask)) = (params.table, &reference.mask) {
        for (i, d) in swept.depth_m.iter_mut().enumerate() {
            if !mask[i] {
                *d = rays.depth_at_height(i, 0.0).unwrap_or(0.0);
            }
        }
    }
    let Some(area) = SweepBox::of(reference, params.window_radius) else {
        return (swept, None);
    };
    let Some((near, far)) = depth_range(reference, &rays, area, params, look_at) else {
        return (swept, None);
    };
    let box_pixels = || (0..area.w * area.h).map(|i| area.image_index(i, k.width as usize));
    let mut sweep = ViewSweep {
        reference,
        area,
        planes: Vec::new(),
        targets: (0..views.len())
            .filter(|&j| j != r)
            .map(|j| &targets[j])
            .collect(),
        rays: BoxRays::of(&rays, box_pixels()),
        best_views: params.best_views.min(views.len() - 1),
        radius: params.window_radius,
    };
    let (mut near, mut far) = (near, far);
    // With masks, a coarse pass finds the depths the hull spans, and the fine planes cover
    // only those.
    if reference.mask.is_some() {
        let coarse = inverse_depth_planes(near, far, COARSE_PLANES);
        let object: Vec<bool> = (0..area.w * area.h).map(|i| sweep.is_object(i)).collect();
        let meets = |p: usize| sweep.plane_meets_hull(coarse[p], &object);
        // From either end inwards: the planes between are not needed (nor cheap to rule out).
        let (Some(first), Some(last)) = rayon::join(
            || (0..COARSE_PLANES).position(meets),
            || (0..COARSE_PLANES).rposition(meets),
        ) else {
            return (swept, None);
        };
        // Two coarse planes of margin: a ray may cross a sliver of the hull between two.
        near = coarse[first.saturating_sub(2)];
        far = coarse[(last + 2).min(COARSE_PLANES - 1)];
    }
    sweep.planes = inverse_depth_planes(near, far, params.planes);
    (swept, Some(sweep))
}

/// The depths a reference view sweeps, near and far: where its object pixels' rays cross the
/// workspace slab (from the camera's near limit when the camera is inside it), within the
/// reach around the point the cameras look at; `None` if that leaves nothing.
fn depth_range(
    reference: &RgbView,
    rays: &Rays,
    area: SweepBox,
    params: &SweepParams,
    look_at: Option<Vec3>,
) -> Option<(f32, f32)> {
    let k = &reference.camera.intrinsics;
    let inside_slab = (0.0..=params.max_height_m).contains(&rays.origin.z);
    let (mut near, mut far) = if inside_slab {
        (k.z_near_m, 0.0f32)
    } else {
        (f32::INFINITY, 0.0f32)
    };
    for i in (0..area.w * area.h).map(|i| area.image_index(i, k.width as usize)) {
        if !reference.mask.as_ref().is_none_or(|m| m[i]) {
            continue;
        }
        for z in [0.0, params.max_height_m] {
            if let Some(d) = rays.depth_at_height(i, z) {
                near = near.min(d);
                far = far.max(d);
            }
        }
    }
    // Without a mask every pixel's ray counts, and one that grazes the table plane would
    // stretch the planes to kilometres; a camera lower than the workspace is tall would sweep
    // from its near limit, too sparsely for the coarse pass to meet the object: the depths stay
    // within the workspace's reach around the point the cameras look at.
    if let Some(centre) = look_at {
        let depth = reference
            .camera
            .world_from_camera
            .inverse_transform_point(centre)
            .z;
        near = near.max(depth - params.reach_m);
        far = far.min(depth + params.reach_m);
    }
    (near.is_finite() && far > near).then_some((near, far))
}

/// `count` depths from `near` to `far`, evenly spaced in inverse depth (as disparity is).
fn inverse_depth_planes(near: f32, far: f32, count: usize) -> Vec<f32> {
    (0..count)
        .map(|p| {
            let t = p as f32 / (count - 1) as f32;
            1.0 / (1.0 / near + t * (1.0 / far - 1.0 / near))
        })
        .collect()
}

/// The depth of the parabola's minimum through the costs of `plane` and its neighbours, in
/// inverse depth (the planes' spacing).
fn refine(planes: &[f32], plane: usize, cost: f32, left: f32, right: f32) -> f32 {
    let (inv, step) = (1.0 / planes[plane], {
        let other = if plane + 1 < planes.len() {
            plane + 1
        } else {
            plane - 1
        };
        (1.0 / planes[other] - 1.0 / planes[plane]) * if other > plane { 1.0 } else { -1.0 }
    });
    let curvature = left - 2.0 * cost + right;
    let offset = if left.is_finite() && right.is_finite() && curvature > 0.0 {
        (0.5 * (left - right) / curvature).clamp(-0.5, 0.5)
    } else {
        0.0
    };
    1.0 / (inv + offset * step)
}
