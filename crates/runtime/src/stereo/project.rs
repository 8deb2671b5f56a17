//! Where a reference view's points on a depth plane land in the other views, and what those
//! views show there.
//!
//! A pixel's point on the plane at depth `d` is `origin + ray * d` (the ray in the world, one
//! per pixel of the swept box: [`BoxRays`]); each other view maps it into its camera frame and
//! projects it (pinhole, no distortion). The mapping repeats glam's arithmetic for
//! `Pose3::transform_point` operation for operation (its SSE2 quaternion rotation, which the
//! baseline x86-64 target has without fused multiply-adds), so the points land on the same
//! bits as the pose transform gives, while the loop over a row of points vectorises.

use std::ops::Range;

use mvgrasp_geometry::Pose3;

use super::{Rays, RgbView};

/// A view ready to be sampled at the other views' points: its colours in four lanes (a load
/// each) and its mask grown so that one look-up answers whether a point's four pixels touch the
/// object.
///
/// Both are stored row-major with a stride of `width + 1`, over `height + 1` rows: the extra
/// column and row repeat the last ones, which is the clamped border of bilinear sampling, so a
/// point's four pixels are always `at`, `at + 1`, `at + stride` and `at + stride + 1`. After
/// them comes the sample of the points the view does not see ([`Target::nowhere`]): black
/// around it, and on the object (a point out of sight is carved by no mask), so that sampling
/// needs no branch.
pub(super) struct Target {
    fx: f32,
    fy: f32,
    cx: f32,
    cy: f32,
    /// The largest pixel coordinates a point may have, `width - 1` and `height - 1`.
    last: [f32; 2],
    stride: u32,
    /// The sample of the points not seen.
    nowhere: u32,
    /// `camera_from_world` ([`ToCamera`]).
    to_camera: ToCamera,
    /// Per sample, RGB and a zero.
    colours: Vec<[u8; 4]>,
    /// Per sample: whether the pixel, or its right, lower or lower-right neighbour (clamped at
    /// the border), is the object's (`None` without a mask): a surface point on the silhouette
    /// may fall a fraction of a pixel outside the mask.
    near_object: Option<Vec<bool>>,
}

impl Target {
    /// `view` prepared for sampling (its colours as given: the sweep passes them smoothed).
    pub(super) fn of(view: &RgbView) -> Self {
        let k = &view.camera.intrinsics;
        let (w, h) = (k.width as usize, k.height as usize);
        let stride = w + 1;
        let nowhere = stride * (h + 1);
        // The unseen sample and its three neighbours.
        let beyond = stride + 2;
        // Row v of the padded layout: image row min(v, h - 1), its last pixel repeated.
        let padded_rows = || (0..=h).map(|v| v.min(h - 1) * w..(v.min(h - 1) + 1) * w);
        let mut colours = Vec::with_capacity(nowhere + beyond);
        for row in padded_rows() {
            let row = &view.rgb[row];
            let colour = |&[r, g, b]: &[u8; 3]| [r, g, b, 0];
            colours.extend(row.iter().chain(&row[w - 1..]).map(colour));
        }
        colours.resize(nowhere + beyond, [0; 4]);
        let near_object = view.mask.as_ref().map(|mask| {
            let mut near = Vec::with_capacity(nowhere + beyond);
            let row = |v: usize| &mask[v * w..(v + 1) * w];
            for v in 0..h {
                let (here, below) = (row(v), row((v + 1).min(h - 1)));
                let either: Vec<bool> = here.iter().zip(below).map(|(&a, &b)| a || b).collect();
                let right = |u: usize| either[(u + 1).min(w - 1)];
                near.extend((0..w).map(|u| either[u] || right(u)));
                // The padding column: no point is located there.
                near.push(false);
            }
            near.resize(nowhere, false);
            near.resize(nowhere + beyond, true);
            near
        });
        Self {
            fx: k.fx,
            fy: k.fy,
            cx: k.cx,
            cy: k.cy,
            last: [(w - 1) as f32, (h - 1) as f32],
            stride: stride as u32,
            nowhere: nowhere as u32,
            to_camera: ToCamera::of(&view.camera.world_from_camera.inverse()),
            colours,
            near_object,
        }
    }

    /// The sample of the points this view does not see (behind it or outside its image).
    pub(super) fn nowhere(&self) -> u32 {
        self.nowhere
    }

    /// Where the camera-frame point (x, y, z) projects: its four pixels' top-left sample
    /// ([`Target::nowhere`] behind the camera or outside the image) and its offsets from it.
    #[inline]
    fn locate(&self, x: f32, y: f32, z: f32) -> (u32, f32, f32) {
        let [u, v] = self.project(x, y, z);
        let [umax, vmax] = self.last;
        let seen = z > 0.0 && u >= 0.0 && v >= 0.0 && u <= umax && v <= vmax;
        // Unchanged where seen, and within the image everywhere.
        let (u, v) = (u.max(0.0).min(umax), v.max(0.0).min(vmax));
        let (u0, v0) = (floor(u), floor(v));
        let sample = (v0 * self.stride as i32 + u0) as u32;
        (
            if seen { sample } else { self.nowhere },
            u - u0 as f32,
            v - v0 as f32,
        )
    }

    /// The pixel coordinates (u, v) of the camera-frame point (x, y, z), whether in front of the
    /// camera or not.
    #[inline]
    fn project(&self, x: f32, y: f32, z: f32) -> [f32; 2] {
        [self.fx * x / z + self.cx, self.fy * y / z + self.cy]
    }

    /// Whether the view has a mask (else no point is carved by it).
    pub(super) fn has_mask(&self) -> bool {
        self.near_object.is_some()
    }

    /// Whether the point at sample `at` may lie on the object: one of its four pixels is inside
    /// the mask (always without a mask, and for a point out of sight).
    #[inline]
    pub(super) fn near_object(&self, at: u32) -> bool {
        self.near_object
            .as_ref()
            .is_none_or(|near| near[at as usize])
    }

    /// The colour at a located point: bilinear between the four pixels around sample `at`,
    /// `fraction` the point's offset from it (RGB and a zero).
    #[inline]
    pub(super) fn colour(&self, at: u32, (fu, fv): (f32, f32)) -> [f32; 4] {
        let at = at as usize;
        let stride = self.stride as usize;
        let sample = |i: usize| self.colours[i].map(f32::from);
        let (a, b) = (sample(at), sample(at + 1));
        let (c, d) = (sample(at + stride), sample(at + stride + 1));
        // All four lanes at once, as one vector each.
        let lerp = |p: [f32; 4], q: [f32; 4], t: f32| -> [f32; 4] {
            std::array::from_fn(|l| p[l] * (1.0 - t) + q[l] * t)
        };
        lerp(lerp(a, b, fu), lerp(c, d, fu), fv)
    }
}

/// The world rays of a reference view's pixels (those of its swept box): pixel `i`'s point on
/// the plane at depth `d` is `origin + ray[i] * d`.
pub(super) struct BoxRays {
    origin: [f32; 3],
    /// Per pixel, the ray's three coordinates (structure of arrays).
    ray: [Vec<f32>; 3],
}

/// A camera's `camera_from_world` as glam applies it to a point: its rotation's vector part
/// `v` and scalar part `w`, with `w w - |v|^2` and `2 w`, and its translation.
struct ToCamera {
    v: [f32; 3],
    scale: f32,
    twice_w: f32,
    translation: [f32; 3],
}

impl ToCamera {
    fn of(camera_from_world: &Pose3) -> Self {
        let q = camera_from_world.rotation;
        let [x, y, z, w] = [q.x, q.y, q.z, q.w];
        Self {
            v: [x, y, z],
            scale: w * w - ((x * x + y * y) + z * z),
            twice_w: w * 2.0,
            translation: camera_from_world.translation.to_array(),
        }
    }

    /// `camera_from_world.transform_point(p)`, bit for bit: `p (w w - |v|^2) + v (2 p.v) +
    /// (v x p) 2 w + translation`, each sum and product in glam's order.
    #[inline]
    fn apply(&self, p: [f32; 3]) -> [f32; 3] {
        let ([vx, vy, vz], [px, py, pz]) = (self.v, p);
        let twice_dot = ((px * vx + py * vy) + pz * vz) * 2.0;
        let cross = [vy * pz - py * vz, vz * px - pz * vx, vx * py - px * vy];
        std::array::from_fn(|c| {
            ((p[c] * self.scale + self.v[c] * twice_dot) + cross[c] * self.twice_w)
                + self.translation[c]
        })
    }
}

/// Where points land in a target: per point, the sample at its four pixels' top-left one
/// ([`Target::nowhere`] when not seen) and its offset from it along u and v (0 to 1).
pub(super) struct Located {
    /// The top-left sample, or [`Target::nowhere`].
    pub at: Vec<u32>,
    /// The offsets along u.
    pub fu: Vec<f32>,
    /// The offsets along v.
    pub fv: Vec<f32>,
}

impl Located {
    /// Room for `n` points, none seen by `target`.
    pub(super) fn with_len(n: usize, target: &Target) -> Self {
        Self {
            at: vec![target.nowhere; n],
            fu: vec![0.0; n],
            fv: vec![0.0; n],
        }
    }
}

impl BoxRays {
    /// The rays of pixels `pixels` (image indices, in this order) of the reference whose rays
    /// are `rays`.
    pub(super) fn of(rays: &Rays, pixels: impl Iterator<Item = usize>) -> Self {
        let mut ray: [Vec<f32>; 3] = Default::default();
        for i in pixels {
            for (r, value) in ray.iter_mut().zip(rays.ray[i].to_array()) {
                r.push(value);
            }
        }
        Self {
            origin: rays.origin.to_array(),
            ray,
        }
    }

    /// Where the point of pixel `i` (this order) on the plane at depth `d` projects in
    /// `target`, (u, v), if in front of it: the arithmetic of [`BoxRays::locate`].
    #[cfg(test)]
    pub(super) fn pixel(&self, target: &Target, d: f32, i: usize) -> Option<[f32; 2]> {
        let point = std::array::from_fn(|c| self.origin[c] + self.ray[c][i] * d);
        let [x, y, z] = target.to_camera.apply(point);
        (z > 0.0).then(|| target.project(x, y, z))
    }

    /// Locates the points of pixels `pixels` (this order) on the plane at depth `d` in
    /// `target`, into `at`, `fu` and `fv` (one entry a pixel).
    pub(super) fn locate(
        &self,
        target: &Target,
        d: f32,
        pixels: Range<usize>,
        (at, fu, fv): (&mut [u32], &mut [f32], &mut [f32]),
    ) {
        let [rx, ry, rz] = self.ray.each_ref().map(|r| &r[pixels.clone()]);
        let [ox, oy, oz] = self.origin;
        let (at, fu, fv) = (
            &mut at[..rx.len()],
            &mut fu[..rx.len()],
            &mut fv[..rx.len()],
        );
        for i in 0..rx.len() {
            let point = [ox + rx[i] * d, oy + ry[i] * d, oz + rz[i] * d];
            let [x, y, z] = target.to_camera.apply(point);
            (at[i], fu[i], fv[i]) = target.locate(x, y, z);
        }
    }
}

/// `x.floor()` for `x` in 0 to 2^23, by the bits of `x + 2^23` (whose units are whole numbers):
/// a library call on the baseline x86-64 target otherwise, and a conversion that does not
/// vectorise.
#[inline]
fn floor(x: f32) -> i32 {
    const TWO_23: f32 = 8_388_608.0;
    // Rounded to the nearest whole number by the addition.
    let nearest = (x + TWO_23).to_bits() as i32 - TWO_23.to_bits() as i32;
    nearest - i32::from(nearest as f32 > x)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)] // tests may fail loudly

    use super::{ToCamera, floor};
    use mvgrasp_geometry::{Pose3, Rot3, Vec3};

    #[test]
    fn points_reach_a_camera_as_the_pose_transform_takes_them() {
        // A small generator of values spread over many binades.
        let mut state = 0x9E37_79B9_7F4A_7C15u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0
        };
        for _ in 0..200 {
            let axis = Vec3::new(next(), next(), next()).normalize_or(Vec3::Z);
            let pose = Pose3::from_parts(
                Vec3::new(next(), next(), next()),
                Rot3::from_axis_angle(axis, 3.2 * next()),
            );
            let to_camera = ToCamera::of(&pose);
            for _ in 0..200 {
                let p = Vec3::new(next(), next(), next()) * 0.7;
                let expected = pose.transform_point(p).to_array().map(f32::to_bits);
                assert_eq!(
                    to_camera.apply(p.to_array()).map(f32::to_bits),
                    expected,
                    "{p}"
                );
            }
        }
    }

    #[test]
    fn floor_is_the_floor_over_an_image() {
        let mut xs = vec![
            0.0,
            0.5,
            1.0,
            1.5,
            2.5,
            0.999_999_94,
            1.000_000_1,
            515.0,
            515.999_97,
        ];
        xs.extend((0..100_000).map(|i| i as f32 * 0.005_17));
        for x in xs {
            assert_eq!(floor(x), x.floor() as i32, "{x}");
        }
    }
}
