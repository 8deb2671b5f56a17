//! The table under a camera whose pose is unknown: a plane fitted to the depth image's points
//! by RANSAC, what the planner needs from it (the view's angle to the table, a world frame on
//! the table with gravity along -z), and the object as what stands on it.

use mvgrasp_geometry::{Camera, Intrinsics, Pose3, Rot3, Vec3};
use nalgebra::{Matrix3, SymmetricEigen};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::depth_image::{DepthImage, Mask};
use crate::error::{PlannerError, Result};

/// Parameters of [`fit_table`] and [`objects_above`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TableFitParams {
    /// RANSAC hypotheses (three points each).
    pub iterations: usize,
    /// A point within this of the plane is an inlier, metres (a Primesense's noise at 0.7 m is
    /// 1 to 2 mm).
    pub inlier_distance_m: f32,
    /// Every this many pixels along rows and columns are fitted.
    pub stride_px: u32,
    /// What a point more than `inlier_distance_m` under a hypothesis costs it, in inliers.
    /// Nothing lies under a support: the top of a box in a bin has the bin's floor under it
    /// and loses to the floor though it has more inliers. Less than one, because a table
    /// seen past its edge has the floor under part of the image.
    pub below_cost: f32,
    /// Points higher than this above the table are the object's, metres.
    pub object_min_height_m: f32,
    /// Regions of fewer pixels than this share of the image are noise, not objects.
    pub object_min_share: f32,
    /// Neighbouring pixels whose depths differ by less than this lie on one smooth surface,
    /// metres: what is joined that way to something the image's border cuts (a bin's wall,
    /// a floor that curves up into it) is not an object.
    pub smooth_step_m: f32,
    /// Seeds the hypotheses.
    pub seed: u64,
}

impl Default for TableFitParams {
    fn default() -> Self {
        Self {
            iterations: 300,
            inlier_distance_m: 0.004,
            stride_px: 4,
            below_cost: 0.5,
            object_min_height_m: 0.005,
            object_min_share: 0.0005,
            smooth_step_m: 0.003,
            seed: 0,
        }
    }
}

/// A plane fitted to a depth image: the table, in the camera's frame.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct TableFit {
    /// Unit normal in the camera frame, pointing up from the table towards the camera.
    pub normal: [f32; 3],
    /// The camera's height above the plane, metres: a point p (camera frame) stands
    /// `normal . p + camera_height_m` above the table.
    pub camera_height_m: f32,
    /// The share of the fitted points within [`TableFitParams::inlier_distance_m`] of it.
    pub inlier_share: f32,
    /// The root mean square distance of those inliers from it, metres.
    pub rms_residual_m: f32,
    /// Points fitted.
    pub points: usize,
}

impl TableFit {
    /// The normal as a vector.
    pub fn up(&self) -> Vec3 {
        Vec3::from(self.normal)
    }

    /// The height above the table of a point in the camera frame, metres.
    pub fn height_of(&self, camera_point: Vec3) -> f32 {
        self.up().dot(camera_point) + self.camera_height_m
    }

    /// The angle between the optical axis and the table plane (the seed paper's theta): pi/2
    /// looking straight down.
    pub fn theta_rad(&self) -> f32 {
        (-self.up().z).clamp(-1.0, 1.0).asin()
    }

    /// A world frame on the table: z up (gravity along -z), the origin where the optical axis
    /// meets the table (below the camera when it looks straight down), x along the image's
    /// rows as seen on the table.
    ///
    /// # Errors
    /// [`PlannerError::Table`] when the optical axis does not meet the table in front of the
    /// camera.
    pub fn world_from_camera(&self) -> Result<Pose3> {
        let up = self.up();
        // The optical axis t (0, 0, 1) meets the plane where up.z t + height = 0.
        if up.z > -1e-3 {
            return Err(PlannerError::Table(format!(
                "the camera looks {:.0} degrees up from the table: its optical axis does not \
                 meet it",
                self.theta_rad().to_degrees().abs()
            )));
        }
        let origin = Vec3::Z * (-self.camera_height_m / up.z);
        let mut x = Vec3::X - up * up.dot(Vec3::X);
        if x.length() < 1e-3 {
            x = Vec3::Y - up * up.dot(Vec3::Y);
        }
        let x = x.normalize();
        let y = up.cross(x);
        // The world's axes and origin in the camera frame: camera_from_world.
        let rotation = Rot3::from_mat3(&mvgrasp_geometry::Mat3::from_cols(x, y, up)).normalize();
        Ok(Pose3::from_parts(origin, rotation).inverse())
    }

    /// The camera, posed in [`TableFit::world_from_camera`]'s frame.
    ///
    /// # Errors
    /// See [`TableFit::world_from_camera`].
    pub fn camera(&self, intrinsics: Intrinsics) -> Result<Camera> {
        Ok(Camera {
            intrinsics,
            world_from_camera: self.world_from_camera()?,
        })
    }
}

/// Fits the table to `depth`'s points (every `stride_px`-th, leaving out `exclude`'s pixels,
/// e.g. the object's mask): over random three-point hypotheses, the plane with the most
/// inliers less [`TableFitParams::below_cost`] for each point under it (a support has nothing
/// under it), refined by least squares on its inliers; deterministic from `params.seed`.
///
/// # Errors
/// [`PlannerError::Table`] with fewer than 3 usable points, or no plane through them.
pub fn fit_table(
    depth: &DepthImage,
    exclude: Option<&Mask>,
    params: &TableFitParams,
) -> Result<TableFit> {
    let k = depth.intrinsics();
    let stride = params.stride_px.max(1) as usize;
    let mut points = Vec::new();
    for v in (0..depth.height() as usize).step_by(stride) {
        for u in (0..depth.width() as usize).step_by(stride) {
            let (u, v) = (u as i64, v as i64);
            let d = depth.at(u, v);
            if d > 0.0 && !exclude.is_some_and(|m| m.at(u, v)) {
                points.push(k.unproject(u as f32, v as f32, d));
            }
        }
    }
    if points.len() < 3 {
        return Err(PlannerError::Table(format!(
            "{} usable depth points: too few to fit the table",
            points.len()
        )));
    }
    let threshold = params.inlier_distance_m;
    // Inliers less the cost of the points under the plane (the side away from the camera).
    let score = |n: Vec3, h: f32| {
        let (mut inliers, mut below) = (0usize, 0usize);
        for p in &points {
            let r = n.dot(*p) + h;
            if r.abs() < threshold {
                inliers += 1;
            } else if r < 0.0 {
                below += 1;
            }
        }
        inliers as f32 - params.below_cost * below as f32
    };
    let mut rng = ChaCha8Rng::seed_from_u64(params.seed);
    let mut best: Option<(f32, Vec3, f32)> = None;
    for _ in 0..params.iterations {
        let [a, b, c] = [0; 3].map(|_| points[rng.random_range(0..points.len())]);
        let n = (b - a).cross(c - a);
        if n.length() < 1e-9 {
            continue;
        }
        let mut n = n.normalize();
        let mut h = -n.dot(a);
        // Up is towards the camera (at the origin), so that "under" is away from it.
        if h < 0.0 {
            n = -n;
            h = -h;
        }
        let s = score(n, h);
        if best.is_none_or(|(most, ..)| s > most) {
            best = Some((s, n, h));
        }
    }
    let Some((_, n, h)) = best else {
        return Err(PlannerError::Table(
            "every hypothesis was degenerate: the points lie on a line".into(),
        ));
    };
    // Least squares on the inliers: the plane through their centroid normal to the direction
    // of least spread.
    let inliers: Vec<Vec3> = points
        .iter()
        .copied()
        .filter(|p| (n.dot(*p) + h).abs() < threshold)
        .collect();
    let centroid = inliers.iter().copied().sum::<Vec3>() / inliers.len() as f32;
    let mut scatter = Matrix3::<f64>::zeros();
    for p in &inliers {
        let d = *p - centroid;
        let d = nalgebra::Vector3::new(f64::from(d.x), f64::from(d.y), f64::from(d.z));
        scatter += d * d.transpose();
    }
    let eigen = SymmetricEigen::new(scatter);
    let smallest = eigen.eigenvalues.imin();
    let e = eigen.eigenvectors.column(smallest);
    let mut normal = Vec3::new(e[0] as f32, e[1] as f32, e[2] as f32).normalize();
    if normal.dot(n) < 0.0 {
        normal = -normal;
    }
    let mut height = -normal.dot(centroid);
    // Up is towards the camera (at the origin): the camera's height is positive.
    if height < 0.0 {
        normal = -normal;
        height = -height;
    }
    let residuals: Vec<f32> = points
        .iter()
        .map(|p| normal.dot(*p) + height)
        .filter(|r| r.abs() < threshold)
        .collect();
    let rms = (residuals.iter().map(|r| r * r).sum::<f32>() / residuals.len().max(1) as f32).sqrt();
    Ok(TableFit {
        normal: normal.into(),
        camera_height_m: height,
        inlier_share: residuals.len() as f32 / points.len() as f32,
        rms_residual_m: rms,
        points: points.len(),
    })
}

/// The objects on the table: pixels higher than `params.object_min_height_m` above it, in
/// connected regions (4-neighbours) that hold at least `params.object_min_share` of the image.
/// A region the image's border cuts (a robot, a bin's wall) is not an object, nor is what is
/// joined to the border or to the table by a smooth surface (neighbours within
/// `params.smooth_step_m` in depth: a bin's floor that curves up into its walls), nor what
/// lies behind such a surface across a depth edge (under a robot's arm); what is left of such
/// a region, in front of it across depth edges (the objects in a bin, from above), is.
///
/// # Errors
/// [`PlannerError::Table`] when no region qualifies.
pub fn objects_above(
    depth: &DepthImage,
    table: &TableFit,
    params: &TableFitParams,
) -> Result<Mask> {
    let k = depth.intrinsics();
    let (w, h) = (depth.width() as usize, depth.height() as usize);
    let d = depth.as_slice();
    let above: Vec<bool> = (0..w * h)
        .map(|i| {
            let (u, v) = (i % w, i / w);
            d[i] > 0.0
                && table.height_of(k.unproject(u as f32, v as f32, d[i]))
                    > params.object_min_height_m
        })
        .collect();
    let on_border = |i: usize| {
        let (u, v) = (i % w, i / w);
        u == 0 || v == 0 || u + 1 == w || v + 1 == h
    };
    let min_pixels = (params.object_min_share * (w * h) as f32).ceil() as usize;
    let mut label = vec![false; w * h];
    let mut kept = 0;
    let mut keep = |region: &[usize], label: &mut [bool]| {
        if region.len() >= min_pixels {
            kept += 1;
            for &i in region {
                label[i] = true;
            }
        }
    };
    for region in components(&above, w, h) {
        if !region.iter().any(|&i| on_border(i)) {
            keep(&region, &mut label);
            continue;
        }
        // The region less what a smooth surface joins to the border or the table.
        let mut rest = vec![false; w * h];
        for &i in &region {
            rest[i] = true;
        }
        let smooth = |i: usize, j: usize| (d[i] - d[j]).abs() < params.smooth_step_m;
        let mut stack: Vec<usize> = region
            .iter()
            .copied()
            .filter(|&i| {
                on_border(i) || neighbours(i, w, h).any(|j| !above[j] && d[j] > 0.0 && smooth(i, j))
            })
            .collect();
        for &i in &stack {
            rest[i] = false;
        }
        while let Some(i) = stack.pop() {
            for j in neighbours(i, w, h) {
                // Across a depth edge only to what lies behind: under a robot's arm, not an
                // object in front of a bin's wall.
                if rest[j] && (smooth(i, j) || d[j] > d[i]) {
                    rest[j] = false;
                    stack.push(j);
                }
            }
        }
        for part in components(&rest, w, h) {
            keep(&part, &mut label);
        }
    }
    if kept == 0 {
        return Err(PlannerError::Table(format!(
            "nothing stands on the table: no region more than {} mm above it, clear of the \
             image's border, of at least {min_pixels} pixels",
            params.object_min_height_m * 1000.0
        )));
    }
    Mask::new(depth.width(), depth.height(), label)
}

/// The 4-neighbours of pixel `i` of a `w` x `h` image.
fn neighbours(i: usize, w: usize, h: usize) -> impl Iterator<Item = usize> {
    let (u, v) = (i % w, i / w);
    [
        (u > 0).then(|| i - 1),
        (u + 1 < w).then(|| i + 1),
        (v > 0).then(|| i - w),
        (v + 1 < h).then(|| i + w),
    ]
    .into_iter()
    .flatten()
}

/// The connected regions (4-neighbours) of `mask`'s set pixels, each in the order found.
fn components(mask: &[bool], w: usize, h: usize) -> Vec<Vec<usize>> {
    let mut seen = vec![false; w * h];
    let mut regions = Vec::new();
    let mut stack = Vec::new();
    for start in 0..w * h {
        if !mask[start] || seen[start] {
            continue;
        }
        seen[start] = true;
        stack.push(start);
        let mut region = Vec::new();
        while let Some(i) = stack.pop() {
            region.push(i);
            for j in neighbours(i, w, h) {
                if mask[j] && !seen[j] {
                    seen[j] = true;
                    stack.push(j);
                }
            }
        }
        regions.push(region);
    }
    regions
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_scenes::box_on_table;
    use mvgrasp_geometry::IntrinsicsPreset;

    /// A camera `elevation_deg` above the table looking at the origin from 0.7 m, and the
    /// depth it sees of the table plane z = 0 with a box of 4 x 4 x 5 cm at the origin.
    fn tilted_scene(elevation_deg: f32) -> (Camera, DepthImage) {
        let k = Intrinsics::preset(IntrinsicsPreset::Primesense);
        let e = elevation_deg.to_radians();
        let eye = Vec3::new(0.7 * e.cos(), 0.0, 0.7 * e.sin());
        let camera = Camera::look_at(k, eye, Vec3::ZERO, Vec3::Z).unwrap();
        let boxes = [(Vec3::new(-0.02, -0.02, 0.0), Vec3::new(0.02, 0.02, 0.05))];
        let mut depth = Vec::with_capacity((k.width * k.height) as usize);
        for v in 0..k.height {
            for u in 0..k.width {
                let ray = camera.world_from_camera.rotation * k.unproject(u as f32, v as f32, 1.0);
                let o = camera.world_from_camera.translation;
                // The nearest hit along the ray of the table and the box (slab test).
                let mut t_hit = if ray.z < 0.0 {
                    -o.z / ray.z
                } else {
                    f32::INFINITY
                };
                for (lo, hi) in boxes {
                    let (mut t0, mut t1) = (0.0f32, f32::INFINITY);
                    for a in 0..3 {
                        let (ta, tb) = ((lo[a] - o[a]) / ray[a], (hi[a] - o[a]) / ray[a]);
                        t0 = t0.max(ta.min(tb));
                        t1 = t1.min(ta.max(tb));
                    }
                    if t0 <= t1 {
                        t_hit = t_hit.min(t0);
                    }
                }
                // Depth is z in the camera frame: the ray has z = 1 there.
                depth.push(if t_hit.is_finite() { t_hit } else { 0.0 });
            }
        }
        (camera, DepthImage::new(k, depth).unwrap())
    }

    #[test]
    fn the_table_is_found_under_tilted_cameras() {
        for elevation in [20.0f32, 45.0, 80.0, 90.0] {
            let (camera, depth) = tilted_scene(elevation);
            let fit = fit_table(&depth, None, &TableFitParams::default()).unwrap();
            // The true table normal, +z, in the camera frame.
            let truth = camera.world_from_camera.rotation.inverse() * Vec3::Z;
            let error = fit.up().angle_between(truth).to_degrees();
            assert!(error < 0.5, "{elevation} deg: {error} deg off");
            assert!(
                (fit.theta_rad().to_degrees() - elevation).abs() < 0.5,
                "{fit:?}"
            );
            // The camera's height: 0.7 sin(elevation).
            let height = 0.7 * elevation.to_radians().sin();
            assert!((fit.camera_height_m - height).abs() < 1e-3, "{fit:?}");
            assert!(
                fit.inlier_share > 0.9 && fit.rms_residual_m < 1e-3,
                "{fit:?}"
            );
            // The derived world: the camera at its height, looking at the origin of the table,
            // and the box's top 5 cm up.
            let world_from_camera = fit.world_from_camera().unwrap();
            assert!((world_from_camera.translation.z - height).abs() < 1e-3);
            let mask = objects_above(&depth, &fit, &TableFitParams::default()).unwrap();
            assert!(mask.count() > 100, "{}", mask.count());
            let k = depth.intrinsics();
            let top = (0..depth.as_slice().len())
                .filter(|&i| mask.at((i % k.width as usize) as i64, (i / k.width as usize) as i64))
                .map(|i| {
                    let (u, v) = ((i % k.width as usize) as f32, (i / k.width as usize) as f32);
                    world_from_camera
                        .transform_point(k.unproject(u, v, depth.as_slice()[i]))
                        .z
                })
                .fold(0.0f32, f32::max);
            assert!((top - 0.05).abs() < 2e-3, "{elevation} deg: top at {top}");
        }
    }

    #[test]
    fn a_flat_table_has_no_object_and_the_border_is_not_one() {
        let k = Intrinsics::preset(IntrinsicsPreset::PhoxiS);
        let flat = DepthImage::new(k, vec![0.7; (k.width * k.height) as usize]).unwrap();
        let fit = fit_table(&flat, None, &TableFitParams::default()).unwrap();
        assert!((fit.theta_rad().to_degrees() - 90.0).abs() < 0.1);
        let err = objects_above(&flat, &fit, &TableFitParams::default()).unwrap_err();
        assert!(
            err.to_string().contains("nothing stands on the table"),
            "{err}"
        );
        // A box in the middle is an object; the same box cut by the image's edge is not.
        let boxed = box_on_table(k, [0.02, 0.06], None);
        let fit = fit_table(&boxed, None, &TableFitParams::default()).unwrap();
        assert!(objects_above(&boxed, &fit, &TableFitParams::default()).is_ok());
        let w = k.width as usize;
        let shifted: Vec<f32> = (0..boxed.as_slice().len())
            .map(|i| {
                let (u, v) = (i % w, i / w);
                // The box's right half moved to the image's left edge.
                let from = (u + w / 2).min(w - 1);
                boxed.as_slice()[v * w + from]
            })
            .collect();
        let edge = DepthImage::new(k, shifted).unwrap();
        let fit = fit_table(&edge, None, &TableFitParams::default()).unwrap();
        assert!(objects_above(&edge, &fit, &TableFitParams::default()).is_err());
    }

    /// A bin seen from 0.8 m straight above: its floor at 0.8 m rising smoothly into a wall
    /// along the image's left edge (a 12 cm ramp, 3 cm high where the border cuts it), a flat
    /// box 4 cm tall, 50 x 40 cm, covering more of the image than the floor does, and a small
    /// box, its top 5 cm above the floor, standing in the ramp where the ramp is 1 to 2 cm
    /// high (so the two are one region above the table, joined across a depth edge).
    fn bin_scene() -> DepthImage {
        let k = Intrinsics::preset(IntrinsicsPreset::PhoxiS);
        let depth = (0..k.width * k.height)
            .map(|i| {
                let (u, v) = ((i % k.width) as f32, (i / k.width) as f32);
                let (x, y) = ((u - k.cx) * 0.8 / k.fx, (v - k.cy) * 0.8 / k.fy);
                let left = -k.cx * 0.8 / k.fx;
                let ramp = (0.12 - (x - left)).max(0.0) / 0.12 * 0.03;
                let big = (x - (left + 0.41)).abs() < 0.25 && y.abs() < 0.2;
                let small = (x - (left + 0.065)).abs() < 0.015 && y.abs() < 0.02;
                let height = if big {
                    0.04
                } else if small {
                    0.05
                } else {
                    ramp
                };
                // Straight down: depth is 0.8 m less the height (near enough for the test).
                0.8 - height
            })
            .collect();
        DepthImage::new(k, depth).unwrap()
    }

    #[test]
    fn in_a_bin_the_floor_is_the_table_and_the_objects_are_found_against_its_wall() {
        let depth = bin_scene();
        let params = TableFitParams::default();
        let fit = fit_table(&depth, None, &params).unwrap();
        // The wide box's top has more inliers than the floor, but the floor is under it.
        assert!((fit.camera_height_m - 0.8).abs() < 2e-3, "{fit:?}");
        let without_cost = TableFitParams {
            below_cost: 0.0,
            ..params.clone()
        };
        let top = fit_table(&depth, None, &without_cost).unwrap();
        assert!((top.camera_height_m - 0.76).abs() < 2e-3, "{top:?}");
        // The ramp is cut by the border and joins the small box: the box stays an object (a
        // region the border cuts was once dropped whole), the ramp does not.
        let mask = objects_above(&depth, &fit, &params).unwrap();
        let k = depth.intrinsics();
        let at_m = |x: f32, y: f32| {
            let (u, v) = (x * k.fx / 0.8 + k.cx, y * k.fy / 0.8 + k.cy);
            mask.at(u as i64, v as i64)
        };
        let left = -k.cx * 0.8 / k.fx;
        assert!(at_m(left + 0.41, 0.0), "the wide box");
        assert!(at_m(left + 0.065, 0.0), "the small box in the ramp");
        assert!(!at_m(left + 0.03, 0.0), "the ramp");
        assert!(!at_m(left + 0.065, 0.15), "the ramp");
    }

    #[test]
    fn too_few_points_is_an_error() {
        let k = Intrinsics::preset(IntrinsicsPreset::PhoxiS);
        let empty = DepthImage::new(k, vec![0.0; (k.width * k.height) as usize]).unwrap();
        assert!(fit_table(&empty, None, &TableFitParams::default()).is_err());
    }
}
