//! Depth from calibrated RGB views without learning: the classical baseline that the Learnt
//! Stereo Machine is measured against, and the depth the default run plans on.
//!
//! Silhouette carving, then a plane sweep inside the hull, then a consistency check across the
//! views ([`sweep_depths`]):
//!
//! 1. **Planes.** Each reference view sweeps `planes` fronto-parallel planes (uniform in
//!    inverse depth) over the depths where its object pixels' rays cross the workspace: the
//!    slab from the table (world z = 0) up to `max_height_m`, within `reach_m` of the depth of
//!    the point the cameras look at.
//! 2. **Photo-consistency.** Each pixel's point on a plane is projected into every other view.
//!    A view's cost for the pixel is one minus the zero-mean normalised cross-correlation of
//!    the reference's `(2 r + 1)^2` window around it with the colours that view shows at the
//!    window's points (bilinear; the three channels together): the correlation forgives the
//!    gain and offset that shading puts on one surface seen from two directions (the renderer's
//!    light moves with its camera; a real lamp lights a face differently for each lens). The
//!    pixel's cost on the plane is the mean of its `best_views` smallest costs, so that views
//!    which do not see the point (occluded) do not count.
//! 3. **Carving.** With masks, a point that projects outside the object's mask of any view that
//!    has it in its image is not on the object: the plane is ruled out for that pixel. The
//!    nearest plane that survives is the visual hull's depth ([`SweptDepth::hull_m`]).
//! 4. **Winner.** Each object pixel takes its cheapest plane, refined between its neighbours by
//!    a parabola; a winner costing more than `max_cost` is left missing (0). Without a mask
//!    every pixel is swept; with one, the others see the table plane (`table`) or nothing.
//! 5. **Consistency** ([`consistency`]). A winner that no other view's depth confirms (or that
//!    more views see through than confirm) is a guess: it is left missing, or with masks and
//!    `hull_where_unconfirmed` it takes the visual hull's depth, which never lies beyond the
//!    surface.
//!
//! Colours are compared after a 3 x 3 binomial blur: the datasets' random face colours change
//! from one pixel to the next and alias differently in each view.
//!
//! Limits, measured on a textured box seen by 5 views 0.5 m away (the unit test, which prints
//! them): from above, every top pixel to about 0.1 mm (median); from the side, the faces that
//! a second view confirms to a millimetre or two, the rest missing. A face that
//! only one view sees has no second view to confirm it (the inside of a cup seen from above),
//! and a face seen at a grazing angle aliases. Missing is what the planner's fused model
//! treats as unknown space, which the hand may not enter.
//!
//! The cameras' world must be the table frame (z up, the table at z = 0), as `render` writes
//! them; every view needs its pose.

use mvgrasp_geometry::{Camera, Vec3};
use rayon::prelude::*;

use crate::error::{Error, Result};

mod consistency;

pub use consistency::{Consistency, consistent_pixels};

/// One calibrated RGB view.
#[derive(Clone, Debug)]
pub struct RgbView {
    /// Its camera, posed in the table frame.
    pub camera: Camera,
    /// Row-major RGB pixels, `width * height`.
    pub rgb: Vec<[u8; 3]>,
    /// The object's pixels, if known.
    pub mask: Option<Vec<bool>>,
}

/// The plane sweep's settings ([`sweep_depths`]).
#[derive(Clone, Debug, PartialEq)]
pub struct SweepParams {
    /// Depth planes per reference view.
    pub planes: usize,
    /// Half side of the cost window, pixels.
    pub window_radius: usize,
    /// A point's cost: the mean over this many of the other views that agree best.
    pub best_views: usize,
    /// The workspace's height above the table, metres.
    pub max_height_m: f32,
    /// A winning plane costing more than this (one minus the correlation, 0 to 2) leaves the
    /// pixel missing.
    pub max_cost: f32,
    /// With masks: pixels off the object get the table plane's depth (else nothing).
    pub table: bool,
    /// The depths swept stay within this distance of the depth of the point the cameras look
    /// at (the least-squares point of their optical axes), metres.
    pub reach_m: f32,
    /// The multi-view consistency check of the swept depths ([`consistency`]); `None` keeps
    /// every winner.
    pub consistency: Option<Consistency>,
    /// With masks: an object pixel whose depth fails the check takes the visual hull's depth
    /// (never beyond the surface, so the hand keeps clear of it); else (the default) it is left
    /// missing. The hull is tight around an object seen from all sides and loose around objects
    /// seen by a few low cameras (the real shelf-bin photographs: 261 mm median error with it,
    /// 12 mm on the confirmed pixels without); a network that plans in one view and needs
    /// every pixel wants it ([`crate::planner::DepthPredictor::for_one_view`]).
    pub hull_where_unconfirmed: bool,
}

impl Default for SweepParams {
    fn default() -> Self {
        Self {
            planes: 160,
            window_radius: 2,
            best_views: 2,
            max_height_m: 0.3,
            max_cost: 1.0,
            table: true,
            reach_m: 0.3,
            consistency: Some(Consistency::default()),
            hull_where_unconfirmed: false,
        }
    }
}

/// One view's depth from [`sweep_depths`], metres along the optical axis, 0 where unknown.
#[derive(Clone, Debug, PartialEq)]
pub struct SweptDepth {
    /// The plane sweep's depth (carved by the masks when there are masks).
    pub depth_m: Vec<f32>,
    /// The visual hull's depth (the nearest plane inside every mask; 0 without masks).
    pub hull_m: Vec<f32>,
    /// The cheapest plane's depth, refined, before `max_cost` and the consistency check (0
    /// where no plane survived carving): what [`crate::sweep_refiner`] learns to trust or not.
    pub winner_m: Vec<f32>,
    /// That plane's cost (one minus the correlation, 0 to 2; 0 where `winner_m` is 0).
    pub cost: Vec<f32>,
}

/// A cost that rules a plane out.
const RULED_OUT: f32 = f32::INFINITY;

/// The depth of every view from all the others (see the module docs).
///
/// # Errors
/// [`Error::Stereo`] for fewer than two views, an image or mask whose size is not its
/// camera's, or bad parameters.
pub fn sweep_depths(views: &[RgbView], params: &SweepParams) -> Result<Vec<SweptDepth>> {
    check(views, params)?;
    // The depths swept are bounded around where the cameras look.
    let look_at = look_at_point(views);
    let smoothed: Vec<RgbView> = views
        .par_iter()
        .map(|view| RgbView {
            camera: view.camera,
            rgb: smooth(&view.rgb, &view.camera),
            mask: view.mask.clone(),
        })
        .collect();
    let mut swept: Vec<SweptDepth> = (0..views.len())
        .into_par_iter()
        .map(|r| sweep_view(&smoothed, r, params, look_at))
        .collect();
    if let Some(consistency) = &params.consistency {
        let cameras: Vec<Camera> = views.iter().map(|v| v.camera).collect();
        let depths: Vec<Vec<f32>> = swept.iter().map(|s| s.depth_m.clone()).collect();
        let standing = consistent_pixels(&cameras, &depths, consistency);
        for ((view, swept), standing) in views.iter().zip(&mut swept).zip(standing) {
            for (i, depth) in swept.depth_m.iter_mut().enumerate() {
                let object = view.mask.as_ref().is_none_or(|m| m[i]);
                if object && *depth > 0.0 && !standing[i] {
                    let hull = swept.hull_m[i];
                    *depth = if params.hull_where_unconfirmed && hull > 0.0 {
                        hull
                    } else {
                        0.0
                    };
                }
            }
        }
    }
    Ok(swept)
}

/// The image under a [1 2 1] x [1 2 1] / 16 binomial filter (the borders clamped): colours
/// that change from one pixel to the next (the datasets' random face colours at a millimetre
/// a pixel) alias differently in each view, and compare better slightly blurred.
fn smooth(rgb: &[[u8; 3]], camera: &Camera) -> Vec<[u8; 3]> {
    let (w, h) = (
        camera.intrinsics.width as usize,
        camera.intrinsics.height as usize,
    );
    let at = |x: isize, y: isize| {
        let x = x.clamp(0, w as isize - 1) as usize;
        let y = y.clamp(0, h as isize - 1) as usize;
        rgb[y * w + x].map(u32::from)
    };
    (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as isize, (i / w) as isize);
            let mut sum = [0u32; 3];
            for (dy, wy) in [(-1, 1), (0, 2), (1, 1)] {
                for (dx, wx) in [(-1, 1), (0, 2), (1, 1)] {
                    let p = at(x + dx, y + dy);
                    for c in 0..3 {
                        sum[c] += p[c] * wx * wy;
                    }
                }
            }
            sum.map(|s| ((s + 8) / 16) as u8)
        })
        .collect()
}

fn check(views: &[RgbView], params: &SweepParams) -> Result<()> {
    let bad = |problem: String| Err(Error::Stereo { problem });
    if views.len() < 2 {
        return bad(format!("{} view(s): stereo needs at least 2", views.len()));
    }
    for (i, view) in views.iter().enumerate() {
        let k = &view.camera.intrinsics;
        let pixels = k.width as usize * k.height as usize;
        if view.rgb.len() != pixels {
            return bad(format!(
                "view {i}: {} RGB pixels, but its camera is {} x {}",
                view.rgb.len(),
                k.width,
                k.height
            ));
        }
        if view.mask.as_ref().is_some_and(|m| m.len() != pixels) {
            return bad(format!("view {i}: the mask is not the image's size"));
        }
        if !view.camera.world_from_camera.is_finite() {
            return bad(format!("view {i}: the camera pose is not finite"));
        }
    }
    let tolerances_ok = params
        .consistency
        .is_none_or(|c| c.tolerance_m >= 0.0 && c.relative_tolerance >= 0.0);
    let positive = params.max_height_m > 0.0 && params.max_cost > 0.0 && params.reach_m > 0.0;
    if params.planes < 2
        || !(1..=MAX_BEST_VIEWS).contains(&params.best_views)
        || !(positive && tolerances_ok)
    {
        return bad(format!(
            "parameters {params:?}: need 2 or more planes, 1 to {MAX_BEST_VIEWS} best views, a \
             positive height, cost and reach, and tolerances of 0 or more"
        ));
    }
    Ok(())
}

/// Per pixel of `camera` (row-major), the depth at which its ray meets the table plane (world
/// z = 0), if ahead of the camera.
pub(crate) fn table_depth(camera: &Camera) -> Vec<Option<f32>> {
    let rays = Rays::of(camera);
    (0..rays.ray.len())
        .map(|i| rays.depth_at_height(i, 0.0))
        .collect()
}

/// The world point seen at pixel (u, v) at depth `d`: `origin + d * ray`.
struct Rays {
    origin: Vec3,
    /// Per pixel, the world displacement for one metre of depth.
    ray: Vec<Vec3>,
}

impl Rays {
    fn of(camera: &Camera) -> Self {
        let k = &camera.intrinsics;
        let pose = &camera.world_from_camera;
        let ray = (0..k.height)
            .flat_map(|v| (0..k.width).map(move |u| (u, v)))
            .map(|(u, v)| pose.transform_vector(k.unproject(u as f32, v as f32, 1.0)))
            .collect();
        Self {
            origin: pose.translation,
            ray,
        }
    }

    /// The depth at which pixel `i`'s ray reaches world height `z`, if ahead of the camera.
    fn depth_at_height(&self, i: usize, z: f32) -> Option<f32> {
        let dz = self.ray[i].z;
        let d = (z - self.origin.z) / dz;
        (dz != 0.0 && d.is_finite() && d > 0.0).then_some(d)
    }
}

/// A view, ready to be sampled from another's points.
struct Target<'a> {
    view: &'a RgbView,
    camera_from_world: mvgrasp_geometry::Pose3,
}

impl Target<'_> {
    /// Where world point `p` projects, `None` outside the image or behind the camera.
    fn locate(&self, p: Vec3) -> Option<Pixel> {
        let k = &self.view.camera.intrinsics;
        let [u, v] = k.project(self.camera_from_world.transform_point(p))?;
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

    /// Whether a located point lies inside the mask (true without one): when any of the four
    /// pixels around it is the object's, as a surface point on the silhouette may fall a
    /// fraction of a pixel outside the mask.
    fn inside(&self, at: &Pixel) -> bool {
        self.view
            .mask
            .as_ref()
            .is_none_or(|m| at.corners.iter().any(|&i| m[i]))
    }

    /// The colour at a located point, bilinear.
    fn colour(&self, at: &Pixel) -> [f32; 3] {
        let [a, b, c, d] = at.corners.map(|i| self.view.rgb[i].map(f32::from));
        let (fu, fv) = at.fraction;
        std::array::from_fn(|ch| {
            (a[ch] * (1.0 - fu) + b[ch] * fu) * (1.0 - fv) + (c[ch] * (1.0 - fu) + d[ch] * fu) * fv
        })
    }
}

/// A point located in a view's image: its four surrounding pixels (indices: top-left,
/// top-right, bottom-left, bottom-right, clamped at the border) and its offset from the first.
struct Pixel {
    corners: [usize; 4],
    fraction: (f32, f32),
}

/// The pixels a reference view sweeps: its mask's bounding box grown by the window (the whole
/// image without a mask), as (u0, v0, u1, v1), exclusive ends.
fn sweep_box(view: &RgbView, margin: usize) -> Option<(usize, usize, usize, usize)> {
    let k = &view.camera.intrinsics;
    let (w, h) = (k.width as usize, k.height as usize);
    let Some(mask) = &view.mask else {
        return Some((0, 0, w, h));
    };
    let (mut u0, mut v0, mut u1, mut v1) = (w, h, 0, 0);
    for (i, _) in mask.iter().enumerate().filter(|(_, m)| **m) {
        let (u, v) = (i % w, i / w);
        (u0, v0, u1, v1) = (u0.min(u), v0.min(v), u1.max(u + 1), v1.max(v + 1));
    }
    (u0 < u1).then(|| {
        (
            u0.saturating_sub(margin),
            v0.saturating_sub(margin),
            (u1 + margin).min(w),
            (v1 + margin).min(h),
        )
    })
}

/// The point nearest every camera's optical axis (least squares), if the axes pin one down.
fn look_at_point(views: &[RgbView]) -> Option<Vec3> {
    let mut a = [[0.0f64; 3]; 3];
    let mut b = [0.0f64; 3];
    for view in views {
        let c = view.camera.position().to_array().map(f64::from);
        let axis = view
            .camera
            .optical_axis()
            .normalize()
            .to_array()
            .map(f64::from);
        for r in 0..3 {
            for col in 0..3 {
                let projector = f64::from(u8::from(r == col)) - axis[r] * axis[col];
                a[r][col] += projector;
                b[r] += projector * c[col];
            }
        }
    }
    // Cramer's rule; near-parallel axes leave the point undetermined.
    let det = |m: &[[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det(&a);
    if d.abs() < 1e-9 {
        return None;
    }
    let solved: [f64; 3] = std::array::from_fn(|col| {
        let mut m = a;
        for (row, value) in m.iter_mut().zip(b) {
            row[col] = value;
        }
        det(&m) / d
    });
    let p = Vec3::new(solved[0] as f32, solved[1] as f32, solved[2] as f32);
    p.is_finite().then_some(p)
}

fn sweep_view(
    views: &[RgbView],
    r: usize,
    params: &SweepParams,
    look_at: Option<Vec3>,
) -> SweptDepth {
    let reference = &views[r];
    let k = &reference.camera.intrinsics;
    let (w, h) = (k.width as usize, k.height as usize);
    let rays = Rays::of(&reference.camera);
    let mut depth_m = vec![0.0f32; w * h];
    let mut hull_m = vec![0.0f32; w * h];
    let mut winner_m = vec![0.0f32; w * h];
    let mut cost_of = vec![0.0f32; w * h];
    if let (true, Some(mask)) = (params.table, &reference.mask) {
        for (i, d) in depth_m.iter_mut().enumerate() {
            if !mask[i] {
                *d = rays.depth_at_height(i, 0.0).unwrap_or(0.0);
            }
        }
    }
    let Some((bu0, bv0, bu1, bv1)) = sweep_box(reference, params.window_radius) else {
        return SweptDepth {
            depth_m,
            hull_m,
            winner_m,
            cost: cost_of,
        };
    };
    let (bw, bh) = (bu1 - bu0, bv1 - bv0);
    let is_object = |i: usize| reference.mask.as_ref().is_none_or(|m| m[i]);
    // The depth range: where the object pixels' rays cross the workspace slab (from the
    // camera's near limit when the camera is inside it).
    let inside_slab = (0.0..=params.max_height_m).contains(&rays.origin.z);
    let (mut near, mut far) = if inside_slab {
        (k.z_near_m, 0.0f32)
    } else {
        (f32::INFINITY, 0.0f32)
    };
    for v in bv0..bv1 {
        for u in bu0..bu1 {
            let i = v * w + u;
            if !is_object(i) {
                continue;
            }
            for z in [0.0, params.max_height_m] {
                if let Some(d) = rays.depth_at_height(i, z) {
                    near = near.min(d);
                    far = far.max(d);
                }
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
    if !(near.is_finite() && far > near) {
        return SweptDepth {
            depth_m,
            hull_m,
            winner_m,
            cost: cost_of,
        };
    }
    let targets: Vec<Target<'_>> = views
        .iter()
        .enumerate()
        .filter(|(j, _)| *j != r)
        .map(|(_, view)| Target {
            view,
            camera_from_world: view.camera.world_from_camera.inverse(),
        })
        .collect();
    let best_views = params.best_views.min(targets.len());
    let sweep_box = (bu0, bv0, bw, bh);
    // With masks, a coarse pass finds the depths the hull spans, and the fine planes cover
    // only those.
    if reference.mask.is_some() {
        let coarse = inverse_depth_planes(near, far, COARSE_PLANES);
        let inside: Vec<usize> = (0..COARSE_PLANES)
            .filter(|&p| plane_meets_hull(reference, &rays, &targets, coarse[p], sweep_box))
            .collect();
        let (Some(&first), Some(&last)) = (inside.first(), inside.last()) else {
            return SweptDepth {
                depth_m,
                hull_m,
                winner_m,
                cost: cost_of,
            };
        };
        // Two coarse planes of margin: a ray may cross a sliver of the hull between two.
        near = coarse[first.saturating_sub(2)];
        far = coarse[(last + 2).min(COARSE_PLANES - 1)];
    }
    let planes = inverse_depth_planes(near, far, params.planes);
    // The reference's colour per box pixel, NaN off the object.
    let own: Vec<[f32; 3]> = (0..bw * bh)
        .map(|i| {
            box_point(reference, &rays, 1.0, sweep_box, i).map_or([f32::NAN; 3], |(image, _)| {
                reference.rgb[image].map(f32::from)
            })
        })
        .collect();
    // Per box pixel: the best cost, its plane, its neighbours' costs, the hull's plane.
    let n = bw * bh;
    let mut best = vec![(RULED_OUT, usize::MAX, RULED_OUT, RULED_OUT); n];
    let mut hull = vec![usize::MAX; n];
    let mut slices: [Vec<f32>; 3] = std::array::from_fn(|_| vec![RULED_OUT; n]);
    for p in 0..=params.planes {
        if let Some(&depth) = planes.get(p) {
            let raw = plane_costs(
                reference,
                &rays,
                &targets,
                depth,
                (sweep_box, &own),
                best_views,
                params.window_radius,
            );
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
        // Plane p - 1 is now complete with both neighbours.
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
    for v in 0..bh {
        for u in 0..bw {
            let (i, image) = (v * bw + u, (v + bv0) * w + (u + bu0));
            if !is_object(image) {
                continue;
            }
            if hull[i] != usize::MAX && reference.mask.is_some() {
                hull_m[image] = planes[hull[i]];
            }
            let (cost, plane, left, right) = best[i];
            if plane == usize::MAX {
                continue;
            }
            let refined = refine(&planes, plane, cost, left, right);
            winner_m[image] = refined;
            cost_of[image] = cost;
            if cost <= params.max_cost {
                depth_m[image] = refined;
            }
        }
    }
    SweptDepth {
        depth_m,
        hull_m,
        winner_m,
        cost: cost_of,
    }
}

/// Planes before the sweep that find the depths the visual hull spans.
const COARSE_PLANES: usize = 64;

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

/// The most views a pixel's cost averages ([`SweepParams::best_views`]).
const MAX_BEST_VIEWS: usize = 8;

/// The world point of box pixel `i` on the plane at depth `d`, if it is an object pixel of the
/// reference view (every pixel without a mask), with its index in the image.
fn box_point(
    reference: &RgbView,
    rays: &Rays,
    d: f32,
    (bu0, bv0, bw, _): (usize, usize, usize, usize),
    i: usize,
) -> Option<(usize, Vec3)> {
    let w = reference.camera.intrinsics.width as usize;
    let image = (i / bw + bv0) * w + (i % bw + bu0);
    // Off the object in its own view: not on the hull.
    let object = reference.mask.as_ref().is_none_or(|m| m[image]);
    object.then(|| (image, rays.origin + rays.ray[image] * d))
}

/// Whether the plane at depth `d` meets the visual hull at some box pixel: its point inside the
/// mask of every other view that sees it, and seen by one at least.
fn plane_meets_hull(
    reference: &RgbView,
    rays: &Rays,
    targets: &[Target<'_>],
    d: f32,
    area: (usize, usize, usize, usize),
) -> bool {
    (0..area.2 * area.3).into_par_iter().any(|i| {
        box_point(reference, rays, d, area, i).is_some_and(|(_, point)| {
            let mut seen = false;
            for target in targets {
                if let Some(at) = target.locate(point) {
                    if !target.inside(&at) {
                        return false;
                    }
                    seen = true;
                }
            }
            seen
        })
    })
}

/// Each box pixel's cost on the plane at depth `d` ([`RULED_OUT`] when the point leaves a
/// mask or no other view sees it): the mean of its `best_views` smallest costs in the other
/// views, a view's cost being one minus the zero-mean normalised cross-correlation of the
/// reference's window around the pixel with what that view shows of the window's points (the
/// three channels together; [`window_costs`]). The correlation forgives the gain and offset
/// that a light fixed to each camera puts on one surface seen from two of them. A window's
/// points that a mask carves away are not on the object at this depth and count in no view's
/// correlation. `own`: the reference's colour per box pixel, NaN off the object.
fn plane_costs(
    reference: &RgbView,
    rays: &Rays,
    targets: &[Target<'_>],
    d: f32,
    (area, own): ((usize, usize, usize, usize), &[[f32; 3]]),
    best_views: usize,
    radius: usize,
) -> Vec<f32> {
    let (bw, bh) = (area.2, area.3);
    // Per box pixel, its point on the plane if no mask carves it away (and it is the object's).
    let on_hull: Vec<Option<Vec3>> = (0..own.len())
        .into_par_iter()
        .with_min_len(512)
        .map(|i| {
            let (_, point) = box_point(reference, rays, d, area, i)?;
            let carved = targets
                .iter()
                .any(|t| t.locate(point).is_some_and(|at| !t.inside(&at)));
            (!carved).then_some(point)
        })
        .collect();
    // Per target: its cost at every box pixel (NaN where it does not see the point).
    let per_target: Vec<Vec<f32>> = targets
        .par_iter()
        .map(|target| {
            let theirs: Vec<[f32; 3]> = on_hull
                .iter()
                .map(|point| {
                    point
                        .and_then(|p| target.locate(p))
                        .map_or([f32::NAN; 3], |at| target.colour(&at))
                })
                .collect();
            window_costs(own, &theirs, bw, bh, radius)
        })
        .collect();
    (0..own.len())
        .map(|i| {
            if on_hull[i].is_none() {
                return RULED_OUT;
            }
            // The smallest costs so far, ascending.
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

/// Colour variance (per channel value, 0 to 255 squared) below which a window has no texture to
/// correlate: its cost is 1 (no evidence) rather than noise divided by nothing.
const MIN_VARIANCE: f32 = 4.0;

/// Per pixel, one minus the zero-mean normalised cross-correlation of `own` and `theirs` over
/// the `(2 r + 1)^2` window (clipped at the borders) of pixels where both are known (not NaN),
/// the three channels as three samples each; NaN where the pixel itself is unknown in either.
fn window_costs(own: &[[f32; 3]], theirs: &[[f32; 3]], w: usize, h: usize, r: usize) -> Vec<f32> {
    // Per pixel: count, sum a, sum b, sum a^2, sum b^2, sum ab (over both known, channels summed).
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
    let window = window_sums(&window_sums(&terms, w, h, r, true), w, h, r, false);
    terms
        .iter()
        .zip(window)
        .map(|(t, [n, sa, sb, saa, sbb, sab])| {
            if t[0] == 0.0 {
                return f32::NAN;
            }
            let va = saa / n - (sa / n).powi(2);
            let vb = sbb / n - (sb / n).powi(2);
            if va < MIN_VARIANCE || vb < MIN_VARIANCE {
                return 1.0;
            }
            let covariance = sab / n - (sa / n) * (sb / n);
            1.0 - (covariance / (va * vb).sqrt()).clamp(-1.0, 1.0)
        })
        .collect()
}

/// Sums of `values` over each pixel's `2 r + 1` neighbours along one axis (clipped at the
/// borders), in a fixed order.
fn window_sums(
    values: &[[f32; 6]],
    w: usize,
    h: usize,
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
pub(crate) mod tests_support {
    #![allow(clippy::unwrap_used, clippy::expect_used)] // tests may fail loudly

    use super::*;
    use mvgrasp_geometry::{HemisphereLayout, Intrinsics, IntrinsicsPreset};

    /// A colour that varies at the millimetre scale, as the datasets' random face colours do.
    fn texture(p: Vec3) -> [u8; 3] {
        let cell = |x: f32| (x * 200.0).floor() as i64;
        let hash = (cell(p.x) * 73_856_093) ^ (cell(p.y) * 19_349_663) ^ (cell(p.z) * 83_492_791);
        let h = (hash as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 40;
        [
            (h & 255) as u8,
            ((h >> 8) & 255) as u8,
            ((h >> 16) & 255) as u8,
        ]
    }

    /// A box 6 x 4 x 5 cm standing on a textured table, seen by `camera`: RGB, mask, true
    /// depth (ray-cast against the box and the table).
    fn look(camera: &Camera) -> (Vec<[u8; 3]>, Vec<bool>, Vec<f32>) {
        let rays = Rays::of(camera);
        let (lo, hi) = (Vec3::new(-0.03, -0.02, 0.0), Vec3::new(0.03, 0.02, 0.05));
        let mut out = (Vec::new(), Vec::new(), Vec::new());
        for ray in &rays.ray {
            let (o, d) = (rays.origin, *ray);
            // Slab test against the box.
            let (mut t0, mut t1) = (0.0f32, f32::INFINITY);
            for a in 0..3 {
                let (ta, tb) = ((lo[a] - o[a]) / d[a], (hi[a] - o[a]) / d[a]);
                t0 = t0.max(ta.min(tb));
                t1 = t1.min(ta.max(tb));
            }
            let table = -o.z / d.z;
            let (t, on_box) = if t0 <= t1 { (t0, true) } else { (table, false) };
            out.0.push(texture(o + d * t));
            out.1.push(on_box);
            out.2.push(t);
        }
        out
    }

    pub(crate) fn views(count: usize) -> (Vec<RgbView>, Vec<Vec<f32>>) {
        views_at(count, 0.5)
    }

    /// `count` of the paper's test views (the first top-down) `radius_m` from the box.
    pub(super) fn views_at(count: usize, radius_m: f32) -> (Vec<RgbView>, Vec<Vec<f32>>) {
        let k = Intrinsics::preset(IntrinsicsPreset::PhoxiS);
        let layout = HemisphereLayout {
            count,
            radius_m,
            ..HemisphereLayout::paper_test()
        };
        let cameras = layout.cameras(k, Vec3::new(0.0, 0.0, 0.025), 1).unwrap();
        let mut rgb_views = Vec::new();
        let mut truth = Vec::new();
        for camera in cameras {
            let (rgb, mask, depth) = look(&camera);
            rgb_views.push(RgbView {
                camera,
                rgb,
                mask: Some(mask),
            });
            truth.push(depth);
        }
        (rgb_views, truth)
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)] // tests may fail loudly

    use super::tests_support::{views, views_at};
    use super::*;

    /// Per view: the object pixels, those with a depth, and the median error of those, metres.
    fn object_errors(
        views: &[RgbView],
        depths: &[SweptDepth],
        truth: &[Vec<f32>],
    ) -> Vec<(usize, usize, f32)> {
        views
            .iter()
            .zip(depths.iter().zip(truth))
            .map(|(view, (swept, truth))| {
                let mask = view.mask.as_ref().unwrap();
                let mut errors: Vec<f32> = (0..mask.len())
                    .filter(|&i| mask[i] && swept.depth_m[i] > 0.0)
                    .map(|i| (swept.depth_m[i] - truth[i]).abs())
                    .collect();
                errors.sort_by(f32::total_cmp);
                let median = errors
                    .get(errors.len() / 2)
                    .copied()
                    .unwrap_or(f32::INFINITY);
                (mask.iter().filter(|m| **m).count(), errors.len(), median)
            })
            .collect()
    }

    #[test]
    fn each_view_lit_differently_still_gives_the_top_to_a_fraction_of_a_millimetre() {
        // A lamp moving with each camera, as the renderer's: the same face is darker or
        // brighter, with an offset, from each view. Absolute colour differences would match
        // nothing; the correlation does not see gain and offset.
        let (mut views, truth) = views(5);
        for (i, view) in views.iter_mut().enumerate() {
            let (gain, offset) = (0.4 + 0.15 * i as f32, 10.0 * i as f32);
            for p in &mut view.rgb {
                *p = p.map(|c| (f32::from(c) * gain + offset).min(255.0) as u8);
            }
        }
        let depths = sweep_depths(&views, &SweepParams::default()).unwrap();
        let (object, found, median) = object_errors(&views, &depths, &truth)[0];
        assert!(found * 20 > object * 19, "{found} of {object}");
        assert!(median < 0.3e-3, "median error {median} m from above");
    }

    #[test]
    fn a_camera_just_above_the_workspace_still_finds_the_object() {
        // A low view 0.7 m away whose camera is 5 mm above the workspace's top: its rays cross
        // the top a centimetre ahead, and planes swept from there in inverse depth would be
        // decimetres apart at the object. The reach around where the cameras look bounds them.
        let (views, truth) = views_at(5, 0.7);
        let (low, height) = views
            .iter()
            .map(|v| v.camera.position().z)
            .enumerate()
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .unwrap();
        let params = SweepParams {
            max_height_m: height - 0.005,
            consistency: None,
            ..SweepParams::default()
        };
        let depths = sweep_depths(&views, &params).unwrap();
        let (object, found, median) = object_errors(&views, &depths, &truth)[low];
        assert!(found * 2 > object, "view {low}: {found} of {object}");
        assert!(median < 5e-3, "view {low}: median error {median} m");
    }

    #[test]
    fn a_textured_box_is_recovered_to_a_millimetre_and_the_hull_contains_it() {
        let (views, truth) = views(5);
        let depths = sweep_depths(&views, &SweepParams::default()).unwrap();
        for (r, (swept, true_depth)) in depths.iter().zip(&truth).enumerate() {
            let mask = views[r].mask.as_ref().unwrap();
            let object = mask.iter().filter(|m| **m).count();
            let mut errors: Vec<f32> = (0..mask.len())
                .filter(|&i| mask[i] && swept.depth_m[i] > 0.0)
                .map(|i| (swept.depth_m[i] - true_depth[i]).abs())
                .collect();
            errors.sort_by(f32::total_cmp);
            let q = |f: f32| errors[((errors.len() - 1) as f32 * f) as usize];
            let p = views[r].camera.world_from_camera.translation;
            let elevation = (p.z - 0.025).atan2(p.x.hypot(p.y)).to_degrees();
            eprintln!(
                "view {r} ({elevation:.0} deg): {} of {object} object pixels, error median {:.2} mm, p90 {:.2} mm",
                errors.len(),
                1e3 * q(0.5),
                1e3 * q(0.9)
            );
            // From above, the whole top to a fraction of a millimetre; from the side, what
            // two other views agree on (faces that one view alone sees are left missing, and
            // the grazing top face's colours alias: the module docs' limits).
            if elevation > 89.0 {
                assert!(
                    errors.len() as f32 > 0.95 * object as f32,
                    "view {r}: missing"
                );
                assert!(q(0.5) < 0.3e-3, "view {r}: median error {} m", q(0.5));
            }
            assert!(
                errors.len() as f32 > 0.3 * object as f32,
                "view {r}: too many missing"
            );
            assert!(q(0.5) < 3.0e-3, "view {r}: median error {} m", q(0.5));
            // The hull holds the box: it never reaches behind the true surface.
            let behind = (0..mask.len())
                .filter(|&i| mask[i] && swept.hull_m[i] > true_depth[i] + 3.0e-3)
                .count();
            assert!(
                behind < object / 10,
                "view {r}: hull behind the surface at {behind}"
            );
            // Off the object, the table plane.
            for i in (0..mask.len()).filter(|&i| !mask[i]).step_by(97) {
                assert!((swept.depth_m[i] - true_depth[i]).abs() < 1.0e-4);
            }
        }
    }

    #[test]
    fn without_masks_no_depth_strays_beyond_the_workspace_around_where_the_cameras_look() {
        let (mut views, truth) = views(5);
        for view in &mut views {
            view.mask = None;
        }
        let params = SweepParams::default();
        let depths = sweep_depths(&views, &params).unwrap();
        let centre = look_at_point(&views).unwrap();
        // The cameras look at the box's centre, 2.5 cm above the table.
        assert!(
            (centre - Vec3::new(0.0, 0.0, 0.025)).length() < 1e-3,
            "{centre}"
        );
        for (view, (swept, truth)) in views.iter().zip(depths.iter().zip(&truth)) {
            let reach = view
                .camera
                .world_from_camera
                .inverse_transform_point(centre)
                .z;
            let kept = swept.depth_m.iter().filter(|&&d| d > 0.0);
            assert!(
                kept.clone()
                    .all(|&d| (d - reach).abs() <= params.reach_m + 1e-4),
                "a depth beyond the reach"
            );
            // What lies within the reach is still found, the table included, to a few
            // millimetres: 96% from above; the low views see the table at a grazing angle
            // (about half found).
            let within: Vec<(f32, f32)> = swept
                .depth_m
                .iter()
                .zip(truth)
                .filter(|&(_, &t)| (t - reach).abs() < params.reach_m - 0.01)
                .map(|(&d, &t)| (d, t))
                .collect();
            let good = within
                .iter()
                .filter(|&&(d, t)| d > 0.0 && (d - t).abs() < 5e-3)
                .count();
            assert!(good * 10 > within.len() * 4, "{good} of {}", within.len());
        }
    }

    #[test]
    fn one_view_or_a_wrong_size_is_refused() {
        let (mut views, _) = views(2);
        assert!(sweep_depths(&views[..1], &SweepParams::default()).is_err());
        let too_many = SweepParams {
            best_views: MAX_BEST_VIEWS + 1,
            ..SweepParams::default()
        };
        let message = sweep_depths(&views, &too_many).unwrap_err().to_string();
        assert!(message.contains("best views"), "{message}");
        views[1].rgb.pop();
        let message = sweep_depths(&views, &SweepParams::default())
            .unwrap_err()
            .to_string();
        assert!(message.contains("view 1"), "{message}");
    }
}
