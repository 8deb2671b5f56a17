//! Antipodal grasp candidates from a depth image alone (Dex-Net 2.0's depth-image sampler).
//!
//! Depth edges are where the depth steps by more than a threshold between a pixel's
//! neighbours; an edge's outward normal, in the image, is its depth gradient (towards the
//! farther side). From an edge pixel, the sampler walks into the surface along the reversed
//! normal turned by a random angle within the friction cone, and takes the first edge pixel
//! whose outward normal lies within the cone of the walk: the two are the jaws' contacts seen
//! from the camera. The grasp centre is their midpoint, the closing axis their direction, and
//! the depth is sampled below the shallowest point between them (the fingers close around
//! what sticks up). The network decides which of these is a good grasp.

use mvgrasp_grasp::ImageGrasp;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::depth_image::{DepthImage, MASK_MARGIN_PX, Mask};

/// Parameters of [`sample_image_grasps`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ImageSamplerParams {
    /// Candidates wanted (before the depths per candidate).
    pub num_grasps: usize,
    /// Edge pixels tried at most.
    pub max_tries: usize,
    /// A change of depth between a pixel's two neighbours (along u or v) above this marks an
    /// edge, metres.
    pub edge_threshold_m: f32,
    /// Coulomb friction coefficient: the half-angle of the cone is atan(mu).
    pub friction_coef: f32,
    /// Narrowest grasp, metres.
    pub min_width_m: f32,
    /// The grasp depth is the shallowest depth between the contacts plus an offset in this
    /// range, metres.
    pub depth_offset_m: [f32; 2],
    /// Depths per contact pair, spread evenly over `depth_offset_m`.
    pub depths_per_grasp: usize,
    /// Candidates closer than this (pixels) with an angle within `min_angle_rad` of an
    /// earlier one are dropped.
    pub min_distance_px: f32,
    /// See `min_distance_px`.
    pub min_angle_rad: f32,
}

impl Default for ImageSamplerParams {
    fn default() -> Self {
        Self {
            num_grasps: 200,
            max_tries: 5000,
            edge_threshold_m: 0.0025,
            friction_coef: 0.5,
            min_width_m: 0.005,
            depth_offset_m: [0.005, 0.035],
            depths_per_grasp: 3,
            min_distance_px: 2.0,
            min_angle_rad: 0.2,
        }
    }
}

/// An edge pixel's outward normal in the image (unit), if the pixel is on an edge.
struct EdgeMap {
    normals: Vec<Option<[f32; 2]>>,
    width: usize,
    height: usize,
}

impl EdgeMap {
    fn new(depth: &DepthImage, threshold: f32) -> Self {
        let (width, height) = (depth.width() as usize, depth.height() as usize);
        let at = |u: usize, v: usize| depth.at(u as i64, v as i64);
        let mut normals = vec![None; width * height];
        for v in 1..height.saturating_sub(1) {
            for u in 1..width.saturating_sub(1) {
                if at(u, v) <= 0.0 {
                    continue;
                }
                let (l, r, t, b) = (at(u - 1, v), at(u + 1, v), at(u, v - 1), at(u, v + 1));
                if l <= 0.0 || r <= 0.0 || t <= 0.0 || b <= 0.0 {
                    continue;
                }
                let g = [r - l, b - t];
                let norm = g[0].hypot(g[1]);
                if norm > threshold {
                    normals[v * width + u] = Some([g[0] / norm, g[1] / norm]);
                }
            }
        }
        Self {
            normals,
            width,
            height,
        }
    }

    fn at(&self, [u, v]: [f32; 2]) -> Option<[f32; 2]> {
        let (u, v) = (u.round(), v.round());
        if u < 0.0 || v < 0.0 || u >= self.width as f32 || v >= self.height as f32 {
            return None;
        }
        self.normals[v as usize * self.width + u as usize]
    }

    /// Every edge pixel (row-major index) with its normal.
    fn pixels(&self) -> Vec<(usize, [f32; 2])> {
        self.normals
            .iter()
            .enumerate()
            .filter_map(|(i, n)| n.map(|n| (i, n)))
            .collect()
    }
}

/// Grasp candidates in `depth` for a gripper that opens `max_width_m`; deterministic from
/// `seed`. An image with no edges gives none. Missing pixels (0) are never edges: an edge
/// needs all four neighbours seen. With a `mask`, only edges on the object (within
/// 2 pixels of it) start or end a candidate.
pub fn sample_image_grasps(
    depth: &DepthImage,
    mask: Option<&Mask>,
    max_width_m: f32,
    params: &ImageSamplerParams,
    seed: u64,
) -> Vec<ImageGrasp> {
    let intrinsics = depth.intrinsics();
    let w = depth.width() as usize;
    if depth.width() < 3 || depth.height() < 3 {
        return Vec::new();
    }
    let mut edges = EdgeMap::new(depth, params.edge_threshold_m);
    if let Some(mask) = mask {
        let near = mask.dilated(MASK_MARGIN_PX);
        for (i, normal) in edges.normals.iter_mut().enumerate() {
            if !near.at((i % w) as i64, (i / w) as i64) {
                *normal = None;
            }
        }
    }
    let mut pixels = edges.pixels();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let cone = params.friction_coef.atan();
    let cos_cone = cone.cos();
    let focal = intrinsics.fx.min(intrinsics.fy);
    let mut found: Vec<ImageGrasp> = Vec::new();
    let tries = params.max_tries.min(pixels.len());
    for t in 0..tries {
        if found.len() >= params.num_grasps * params.depths_per_grasp.max(1) {
            break;
        }
        // A partial Fisher-Yates shuffle: edge pixels in a seeded random order.
        let pick = rng.random_range(t..pixels.len());
        pixels.swap(t, pick);
        let (index, n1) = pixels[t];
        let p1 = [(index % w) as f32, (index / w) as f32];
        let turn = rng.random_range(-cone..=cone);
        let (sin, cos) = turn.sin_cos();
        let dir = [-(n1[0] * cos - n1[1] * sin), -(n1[0] * sin + n1[1] * cos)];
        let z1 = depth.as_slice()[index];
        let max_px = max_width_m * focal / z1;
        let Some(p2) = walk_to_contact(&edges, p1, dir, max_px, cos_cone, params.min_distance_px)
        else {
            continue;
        };
        let Some(top) = shallowest_between(depth, p1, p2) else {
            continue;
        };
        let span_px = (p2[0] - p1[0]).hypot(p2[1] - p1[1]);
        let width_m = span_px * top / focal;
        if width_m < params.min_width_m || width_m > max_width_m {
            continue;
        }
        let center = [(p1[0] + p2[0]) / 2.0, (p1[1] + p2[1]) / 2.0];
        let angle = dir[1].atan2(dir[0]);
        if found.iter().any(|g| {
            (g.center_px[0] - center[0]).hypot(g.center_px[1] - center[1]) < params.min_distance_px
                && axis_angle_between(g.angle_rad, angle) < params.min_angle_rad
        }) {
            continue;
        }
        let n = params.depths_per_grasp.max(1);
        let [lo, hi] = params.depth_offset_m;
        for k in 0..n {
            let offset = lo + (hi - lo) * (k as f32 + 0.5) / n as f32;
            found.push(ImageGrasp {
                center_px: center,
                angle_rad: angle,
                depth_m: top + offset,
                width_m,
            });
        }
    }
    found
}

/// From `p1`, along `dir`, the first edge pixel farther than `min_px` and at most `max_px`
/// away whose outward normal is within the cone around `dir`.
fn walk_to_contact(
    edges: &EdgeMap,
    p1: [f32; 2],
    dir: [f32; 2],
    max_px: f32,
    cos_cone: f32,
    min_px: f32,
) -> Option<[f32; 2]> {
    let steps = max_px.floor() as usize;
    (1..=steps).find_map(|s| {
        let p = [p1[0] + dir[0] * s as f32, p1[1] + dir[1] * s as f32];
        let n = edges.at(p)?;
        (s as f32 > min_px && n[0] * dir[0] + n[1] * dir[1] >= cos_cone)
            .then(|| [p[0].round(), p[1].round()])
    })
}

/// The smallest non-empty depth on the segment from `a` to `b`.
fn shallowest_between(depth: &DepthImage, a: [f32; 2], b: [f32; 2]) -> Option<f32> {
    let steps = (b[0] - a[0]).abs().max((b[1] - a[1]).abs()).ceil().max(1.0) as usize;
    (0..=steps)
        .map(|s| {
            let t = s as f32 / steps as f32;
            let (u, v) = (
                (a[0] + (b[0] - a[0]) * t).round(),
                (a[1] + (b[1] - a[1]) * t).round(),
            );
            depth.at(u as i64, v as i64)
        })
        .filter(|&d| d > 0.0)
        .min_by(f32::total_cmp)
}

/// The angle between two grasp axes (an axis and its reverse are the same grasp), radians.
fn axis_angle_between(a: f32, b: f32) -> f32 {
    let d = (a - b).rem_euclid(std::f32::consts::PI);
    d.min(std::f32::consts::PI - d)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_scenes::box_on_table;
    use mvgrasp_geometry::{Intrinsics, IntrinsicsPreset};

    /// A 4 cm x 12 cm box, 5 cm tall, under a camera 0.7 m above the table (PhoXi S).
    fn box_image() -> (DepthImage, Intrinsics) {
        let k = Intrinsics::preset(IntrinsicsPreset::PhoxiS);
        (box_on_table(k, [0.02, 0.06], None), k)
    }

    #[test]
    fn grasps_on_a_box_close_across_its_narrow_side() {
        let (depth, k) = box_image();
        let grasps = sample_image_grasps(&depth, None, 0.08, &ImageSamplerParams::default(), 7);
        assert!(grasps.len() >= 30, "{} candidates", grasps.len());
        for g in &grasps {
            // Across the 4 cm side (the 12 cm side is wider than the gripper): the axis is
            // horizontal in the image, the width about 4 cm, the centre on the box's middle
            // column, the depth below the box top.
            assert!(
                axis_angle_between(g.angle_rad, 0.0) <= 0.5f32.atan() + 1e-3,
                "{g:?}"
            );
            assert!((0.035..=0.05).contains(&g.width_m), "{g:?}");
            assert!((g.center_px[0] - k.cx).abs() < 3.0, "{g:?}");
            assert!(g.depth_m > 0.65 && g.depth_m < 0.69, "{g:?}");
        }
    }

    #[test]
    fn the_same_seed_gives_the_same_grasps_and_a_flat_image_none() {
        let (depth, k) = box_image();
        let params = ImageSamplerParams::default();
        assert_eq!(
            sample_image_grasps(&depth, None, 0.08, &params, 3),
            sample_image_grasps(&depth, None, 0.08, &params, 3)
        );
        let flat = DepthImage::new(k, vec![0.7f32; depth.as_slice().len()]).unwrap();
        assert!(sample_image_grasps(&flat, None, 0.08, &params, 3).is_empty());
    }

    #[test]
    fn a_mask_keeps_the_candidates_on_the_object() {
        // Two 4 cm boxes side by side, 10 cm apart; the mask covers the left one.
        let k = Intrinsics::preset(IntrinsicsPreset::PhoxiS);
        let (w, h) = (k.width as usize, k.height as usize);
        let x_of = |u: usize| (u as f32 - k.cx) * 0.65 / k.fx;
        let y_of = |v: usize| (v as f32 - k.cy) * 0.65 / k.fy;
        let on_box = |x: f32, y: f32, cx: f32| (x - cx).abs() < 0.02 && y.abs() < 0.02;
        let mut depth = Vec::with_capacity(w * h);
        let mut mask = Vec::with_capacity(w * h);
        for v in 0..h {
            for u in 0..w {
                let (x, y) = (x_of(u), y_of(v));
                let left = on_box(x, y, -0.05);
                depth.push(if left || on_box(x, y, 0.05) {
                    0.65
                } else {
                    0.7
                });
                mask.push(left);
            }
        }
        let depth = DepthImage::new(k, depth).unwrap();
        let mask = Mask::new(k.width, k.height, mask).unwrap();
        let params = ImageSamplerParams::default();
        let all = sample_image_grasps(&depth, None, 0.08, &params, 5);
        let left_x = |g: &ImageGrasp| x_of(g.center_px[0].round() as usize) < 0.0;
        assert!(all.iter().any(left_x) && !all.iter().all(left_x));
        let masked = sample_image_grasps(&depth, Some(&mask), 0.08, &params, 5);
        assert!(masked.len() >= 30, "{} candidates", masked.len());
        assert!(masked.iter().all(left_x));
    }

    #[test]
    fn a_box_wider_than_the_gripper_has_no_grasp() {
        let (depth, _) = box_image();
        let params = ImageSamplerParams::default();
        assert!(sample_image_grasps(&depth, None, 0.03, &params, 1).is_empty());
    }
}
