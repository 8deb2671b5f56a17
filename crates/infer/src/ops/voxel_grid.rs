//! Between images and a voxel grid through pinhole cameras: the Learnt Stereo Machine's
//! unprojection (image features sampled at every voxel's projection) and ray projection (grid
//! features sampled along every pixel's ray). Cameras are plain matrices; the runtime knows no
//! geometry beyond `u = fx x / z + cx` (pixel centres at integers, OpenCV camera frames).

use crate::error::{InferError, Result};
use crate::ops::check::{positive, shape_error};
use crate::tensor::Tensor;

/// A pinhole camera as two matrices.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraMatrices {
    /// Intrinsics at the resolution of the image the camera is used with, row-major.
    pub k: [[f32; 3]; 3],
    /// World to camera, row-major (rotation and translation; last row `0 0 0 1`).
    pub camera_from_world: [[f32; 4]; 4],
}

impl CameraMatrices {
    /// A world point in the camera's frame.
    fn to_camera(self, p: [f32; 3]) -> [f32; 3] {
        let m = &self.camera_from_world;
        std::array::from_fn(|r| m[r][0] * p[0] + m[r][1] * p[1] + m[r][2] * p[2] + m[r][3])
    }

    /// A camera-frame point in the world.
    fn to_world(self, p: [f32; 3]) -> [f32; 3] {
        let m = &self.camera_from_world;
        let q = [p[0] - m[0][3], p[1] - m[1][3], p[2] - m[2][3]];
        std::array::from_fn(|c| m[0][c] * q[0] + m[1][c] * q[1] + m[2][c] * q[2])
    }

    /// The camera's centre in the world and its optical axis (unit, world frame).
    fn centre_and_axis(&self) -> ([f64; 3], [f64; 3]) {
        let centre = self.to_world([0.0; 3]).map(f64::from);
        let m = &self.camera_from_world;
        let axis = [m[2][0], m[2][1], m[2][2]].map(f64::from);
        let norm = axis
            .iter()
            .map(|v| v * v)
            .sum::<f64>()
            .sqrt()
            .max(f64::MIN_POSITIVE);
        (centre, axis.map(|v| v / norm))
    }

    /// Checks the matrices are finite, the intrinsics' focal lengths positive.
    fn check(&self, op: &'static str) -> Result<()> {
        let finite = self
            .k
            .iter()
            .flatten()
            .chain(self.camera_from_world.iter().flatten());
        if finite.clone().any(|v| !v.is_finite()) || self.k[0][0] <= 0.0 || self.k[1][1] <= 0.0 {
            return Err(InferError::InvalidParameter {
                op,
                name: "camera",
                value: format!("{self:?}"),
                expected: "finite matrices with positive focal lengths",
            });
        }
        Ok(())
    }
}

/// A cube of `size`^3 voxels of side `side_m` centred on `centre` (world frame, metres), its
/// features `[C, size, size, size]` indexed `[z][y][x]` (torch's depth, height, width).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VoxelGrid {
    /// The cube's centre.
    pub centre: [f32; 3],
    /// The cube's side, metres.
    pub side_m: f32,
    /// Voxels along each side.
    pub size: usize,
}

impl VoxelGrid {
    /// The grid centred where `cameras` look: the point nearest all their optical axes, least
    /// squares (solved in f64).
    ///
    /// # Errors
    /// [`InferError::InvalidParameter`] when the axes do not pin a point down (fewer than two
    /// cameras, or all axes parallel) or a camera is not finite.
    pub fn centred_on(cameras: &[CameraMatrices], side_m: f32, size: usize) -> Result<Self> {
        const OP: &str = "voxel_grid";
        let mut a = [[0.0f64; 3]; 3];
        let mut b = [0.0f64; 3];
        for camera in cameras {
            camera.check(OP)?;
            let (c, axis) = camera.centre_and_axis();
            for r in 0..3 {
                for col in 0..3 {
                    let projector = f64::from(u8::from(r == col)) - axis[r] * axis[col];
                    a[r][col] += projector;
                    b[r] += projector * c[col];
                }
            }
        }
        let centre = solve3(a, b).ok_or_else(|| InferError::InvalidParameter {
            op: OP,
            name: "cameras",
            value: format!("{} cameras", cameras.len()),
            expected: "at least two cameras whose optical axes are not parallel",
        })?;
        Ok(Self {
            centre: centre.map(|v| v as f32),
            side_m,
            size,
        })
    }

    fn check(&self, op: &'static str) -> Result<()> {
        positive(op, "grid size", self.size)?;
        if !(self.side_m.is_finite() && self.side_m > 0.0)
            || self.centre.iter().any(|v| !v.is_finite())
        {
            return Err(InferError::InvalidParameter {
                op,
                name: "grid",
                value: format!("{self:?}"),
                expected: "a finite centre and a positive side",
            });
        }
        Ok(())
    }

    /// The world position of voxel `[z, y, x]`'s centre.
    fn voxel(&self, z: usize, y: usize, x: usize) -> [f32; 3] {
        let step = self.side_m / self.size as f32;
        let offset = |i: usize| (i as f32 + 0.5) * step - self.side_m / 2.0;
        [
            offset(x) + self.centre[0],
            offset(y) + self.centre[1],
            offset(z) + self.centre[2],
        ]
    }

    /// The radius of the sphere around the cube.
    pub fn radius_m(&self) -> f32 {
        self.side_m * 3f32.sqrt() / 2.0
    }

    /// The depths at which [`project_rays`] samples a camera's rays: `samples` evenly over the
    /// grid's bounding sphere around the depth of its centre (`centre ± radius`).
    pub fn ray_depths(&self, camera: &CameraMatrices, samples: usize) -> Vec<f32> {
        let centre_depth = camera.to_camera(self.centre)[2];
        let radius = self.radius_m();
        (0..samples)
            .map(|j| {
                let t = if samples > 1 {
                    -1.0 + 2.0 * j as f32 / (samples - 1) as f32
                } else {
                    -1.0
                };
                centre_depth + radius * t
            })
            .collect()
    }

    /// The depth of the grid's centre in `camera`.
    pub fn centre_depth(&self, camera: &CameraMatrices) -> f32 {
        camera.to_camera(self.centre)[2]
    }
}

/// `a x = b` for a 3x3 system by Gaussian elimination with partial pivoting; `None` when it is
/// (near) singular: a pivot below 1e-6 of the largest entry (two optical axes 0.06 degrees
/// apart, or one axis alone).
fn solve3(mut a: [[f64; 3]; 3], mut b: [f64; 3]) -> Option<[f64; 3]> {
    let scale = a.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    for col in 0..3 {
        let pivot = (col..3).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[pivot][col].abs() <= 1e-6 * scale.max(f64::MIN_POSITIVE) {
            return None;
        }
        a.swap(col, pivot);
        b.swap(col, pivot);
        for row in col + 1..3 {
            let f = a[row][col] / a[col][col];
            let pivot_row = a[col];
            for (v, p) in a[row][col..].iter_mut().zip(&pivot_row[col..]) {
                *v -= f * p;
            }
            b[row] -= f * b[col];
        }
    }
    let mut x = [0.0; 3];
    for row in (0..3).rev() {
        let rest: f64 = (row + 1..3).map(|c| a[row][c] * x[c]).sum();
        x[row] = (b[row] - rest) / a[row][row];
    }
    Some(x)
}

/// Unprojection: every voxel of `grid` samples one view's `features` (`[C, h, w]`, the camera's
/// `k` at that resolution) bilinearly at its projection, and gets its depth in the camera
/// (relative to the grid centre's, over `depth_scale_m`) and a mask appended: `[C + 2, S, S, S]`.
/// The mask is 1 where the voxel lies in front of the camera and projects inside the image
/// (pixel centres `0..=w-1`, `0..=h-1`), else the voxel's every channel is 0: samples are never
/// clamped to the border, and every tap read is inside the image.
///
/// # Errors
/// [`InferError::ShapeMismatch`] for features not `[C, h >= 1, w >= 1]`;
/// [`InferError::InvalidParameter`] for a camera or grid that is not finite or positive.
pub fn unproject(
    features: &Tensor,
    camera: &CameraMatrices,
    grid: &VoxelGrid,
    depth_scale_m: f32,
) -> Result<Tensor> {
    const OP: &str = "unproject";
    let &[c, h, w] = features.shape() else {
        return Err(shape_error(
            OP,
            "[channels, height, width]",
            features.shape(),
        ));
    };
    if h == 0 || w == 0 {
        return Err(shape_error(
            OP,
            "[channels, height >= 1, width >= 1]",
            features.shape(),
        ));
    }
    camera.check(OP)?;
    grid.check(OP)?;
    let s = grid.size;
    let voxels = s * s * s;
    let mut out = Tensor::zeros(&[c + 2, s, s, s]);
    let centre_depth = grid.centre_depth(camera);
    let (x, y) = (features.data(), out.data_mut());
    let k = &camera.k;
    let (max_u, max_v) = ((w - 1) as f32, (h - 1) as f32);
    for z in 0..s {
        for yy in 0..s {
            for xx in 0..s {
                let v_index = (z * s + yy) * s + xx;
                let p = camera.to_camera(grid.voxel(z, yy, xx));
                if p[2] <= 1e-6 {
                    continue;
                }
                let u = k[0][0] * p[0] / p[2] + k[0][2];
                let v = k[1][1] * p[1] / p[2] + k[1][2];
                if !(u >= 0.0 && u <= max_u && v >= 0.0 && v <= max_v) {
                    continue;
                }
                // Inside: the four taps, the far ones weighted 0 on the last row or column.
                let (u0, v0) = ((u as usize).min(w - 1), (v as usize).min(h - 1));
                let (u1, v1) = ((u0 + 1).min(w - 1), (v0 + 1).min(h - 1));
                let (fu, fv) = (u - u0 as f32, v - v0 as f32);
                let weights = [
                    (v0, u0, (1.0 - fu) * (1.0 - fv)),
                    (v0, u1, fu * (1.0 - fv)),
                    (v1, u0, (1.0 - fu) * fv),
                    (v1, u1, fu * fv),
                ];
                for channel in 0..c {
                    let plane = &x[channel * h * w..(channel + 1) * h * w];
                    y[channel * voxels + v_index] = weights
                        .iter()
                        .map(|&(r, col, wt)| wt * plane[r * w + col])
                        .sum();
                }
                y[c * voxels + v_index] = (p[2] - centre_depth) / depth_scale_m;
                y[(c + 1) * voxels + v_index] = 1.0;
            }
        }
    }
    Ok(out)
}

/// Ray projection: the grid's features (`[C, S, S, S]`) sampled trilinearly along every pixel's
/// ray of `camera` (`k` at `height` x `width`) at the depths of [`VoxelGrid::ray_depths`], zero
/// outside the grid (each of the 8 taps on its own, as torch's `grid_sample` with zero padding
/// and `align_corners=False`): `[C * samples, height, width]`, channel `c * samples + j` the
/// `j`-th sample of channel `c`.
///
/// # Errors
/// [`InferError::ShapeMismatch`] for features not `[C, S, S, S]` of the grid's size;
/// [`InferError::InvalidParameter`] for zero samples or sizes, or a camera or grid that is not
/// finite or positive.
pub fn project_rays(
    features: &Tensor,
    camera: &CameraMatrices,
    grid: &VoxelGrid,
    samples: usize,
    height: usize,
    width: usize,
) -> Result<Tensor> {
    const OP: &str = "project_rays";
    let s = grid.size;
    let &[c, d0, d1, d2] = features.shape() else {
        return Err(shape_error(
            OP,
            format!("[channels, {s}, {s}, {s}]"),
            features.shape(),
        ));
    };
    if [d0, d1, d2] != [s; 3] {
        return Err(shape_error(
            OP,
            format!("[channels, {s}, {s}, {s}]"),
            features.shape(),
        ));
    }
    positive(OP, "samples", samples)?;
    positive(OP, "height", height)?;
    positive(OP, "width", width)?;
    camera.check(OP)?;
    grid.check(OP)?;
    let depths = grid.ray_depths(camera, samples);
    let plane = height * width;
    let voxels = s * s * s;
    let mut out = Tensor::zeros(&[c * samples, height, width]);
    // Channels last, so that a tap reads its voxel's channels from one place.
    let mut last = vec![0.0f32; voxels * c];
    for (channel, volume) in features.data().chunks_exact(voxels).enumerate() {
        for (i, &v) in volume.iter().enumerate() {
            last[i * c + channel] = v;
        }
    }
    let y = out.data_mut();
    let mut values = vec![0.0f32; c];
    let k = &camera.k;
    let inv_step = s as f32 / grid.side_m;
    let half = s as f32 / 2.0 - 0.5;
    for row in 0..height {
        for col in 0..width {
            let ray = [
                (col as f32 - k[0][2]) / k[0][0],
                (row as f32 - k[1][2]) / k[1][1],
                1.0,
            ];
            for (j, &depth) in depths.iter().enumerate() {
                let world = camera.to_world(ray.map(|r| r * depth));
                // Voxel coordinates: voxel centres at integers.
                let g: [f32; 3] =
                    std::array::from_fn(|a| (world[a] - grid.centre[a]) * inv_step + half);
                let [gx, gy, gz] = g;
                let (x0, y0, z0) = (gx.floor(), gy.floor(), gz.floor());
                let (fx, fy, fz) = (gx - x0, gy - y0, gz - z0);
                let (x0, y0, z0) = (x0 as isize, y0 as isize, z0 as isize);
                let mut taps = [(0usize, 0.0f32); 8];
                let mut count = 0;
                for (dz, wz) in [(0, 1.0 - fz), (1, fz)] {
                    for (dy, wy) in [(0, 1.0 - fy), (1, fy)] {
                        for (dx, wx) in [(0, 1.0 - fx), (1, fx)] {
                            let (iz, iy, ix) = (z0 + dz, y0 + dy, x0 + dx);
                            let inside = [iz, iy, ix].iter().all(|&i| i >= 0 && (i as usize) < s);
                            if inside {
                                let index = ((iz as usize * s) + iy as usize) * s + ix as usize;
                                taps[count] = (index, wz * wy * wx);
                                count += 1;
                            }
                        }
                    }
                }
                if count == 0 {
                    continue;
                }
                values.fill(0.0);
                for &(i, wt) in &taps[..count] {
                    for (v, &f) in values.iter_mut().zip(&last[i * c..(i + 1) * c]) {
                        *v += wt * f;
                    }
                }
                for (channel, &value) in values.iter().enumerate() {
                    y[(channel * samples + j) * plane + row * width + col] = value;
                }
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    /// A camera `distance` above the origin looking straight down (x right, y down in the
    /// image: camera x = world x, camera y = -world y, camera z = -world z).
    fn top_down(distance: f32, f: f32, c: f32) -> CameraMatrices {
        CameraMatrices {
            k: [[f, 0.0, c], [0.0, f, c], [0.0, 0.0, 1.0]],
            camera_from_world: [
                [1.0, 0.0, 0.0, 0.0],
                [0.0, -1.0, 0.0, 0.0],
                [0.0, 0.0, -1.0, distance],
                [0.0, 0.0, 0.0, 1.0],
            ],
        }
    }

    /// A camera on the +x axis at `distance` looking at the origin (camera x = world y,
    /// camera y = -world z, camera z = -world x).
    fn side(distance: f32) -> CameraMatrices {
        CameraMatrices {
            k: [[10.0, 0.0, 3.5], [0.0, 10.0, 3.5], [0.0, 0.0, 1.0]],
            camera_from_world: [
                [0.0, 1.0, 0.0, 0.0],
                [0.0, 0.0, -1.0, 0.0],
                [-1.0, 0.0, 0.0, distance],
                [0.0, 0.0, 0.0, 1.0],
            ],
        }
    }

    #[test]
    fn the_grid_centres_where_the_axes_meet() {
        let grid = VoxelGrid::centred_on(&[top_down(0.6, 10.0, 3.5), side(0.5)], 0.3, 4).unwrap();
        assert!(
            grid.centre.iter().all(|v| v.abs() < 1e-6),
            "{:?}",
            grid.centre
        );
        let err = VoxelGrid::centred_on(&[top_down(0.6, 10.0, 3.5)], 0.3, 4).unwrap_err();
        assert!(err.to_string().contains("at least two cameras"), "{err}");
    }

    #[test]
    fn unprojection_samples_where_voxels_project_and_masks_the_rest() {
        // Features: channel 0 = u, channel 1 = v, so a voxel's sample is its own projection.
        let (w, h) = (8usize, 8usize);
        let data: Vec<f32> = (0..2 * h * w)
            .map(|i| {
                if i < h * w {
                    (i % w) as f32
                } else {
                    ((i / w) % h) as f32
                }
            })
            .collect();
        let features = Tensor::new(&[2, h, w], data).unwrap();
        let camera = top_down(1.0, 20.0, 3.5);
        let grid = VoxelGrid {
            centre: [0.0, 0.0, 0.0],
            side_m: 0.8,
            size: 4,
        };
        let out = unproject(&features, &camera, &grid, 0.4).unwrap();
        assert_eq!(out.shape(), [4, 4, 4, 4]);
        let voxels = 64;
        let mut inside = 0;
        for z in 0..4 {
            for y in 0..4 {
                for x in 0..4 {
                    let i = (z * 4 + y) * 4 + x;
                    let p = camera.to_camera(grid.voxel(z, y, x));
                    let u = 20.0 * p[0] / p[2] + 3.5;
                    let v = 20.0 * p[1] / p[2] + 3.5;
                    let mask = out.data()[3 * voxels + i];
                    if (0.0..=7.0).contains(&u) && (0.0..=7.0).contains(&v) {
                        inside += 1;
                        assert_eq!(mask, 1.0);
                        assert!((out.data()[i] - u).abs() < 1e-4, "u {u}");
                        assert!((out.data()[voxels + i] - v).abs() < 1e-4, "v {v}");
                        let depth = (p[2] - 1.0) / 0.4;
                        assert!((out.data()[2 * voxels + i] - depth).abs() < 1e-6);
                    } else {
                        assert_eq!(mask, 0.0);
                        assert!((0..3).all(|c| out.data()[c * voxels + i] == 0.0));
                    }
                }
            }
        }
        assert!(
            inside > 0 && inside < 64,
            "{inside} voxels inside: both cases tested"
        );
        // Behind the camera: every voxel masked.
        let behind = top_down(-1.0, 20.0, 3.5);
        let out = unproject(&features, &behind, &grid, 0.4).unwrap();
        assert!(out.data().iter().all(|&v| v == 0.0));
    }

    #[test]
    fn rays_sample_where_they_pass() {
        // Features linear in the voxel coordinates (channel 0: x index, channel 1: z index):
        // trilinear sampling returns a point's own coordinates wherever its 8 taps are inside.
        let s = 4;
        let grid = VoxelGrid {
            centre: [0.0, 0.0, 0.0],
            side_m: 0.4,
            size: s,
        };
        let mut features = Tensor::zeros(&[2, s, s, s]);
        for z in 0..s {
            for y in 0..s {
                for x in 0..s {
                    let i = (z * s + y) * s + x;
                    features.data_mut()[i] = x as f32;
                    features.data_mut()[s * s * s + i] = z as f32;
                }
            }
        }
        let camera = top_down(1.0, 8.0, 3.5);
        let samples = 9;
        let out = project_rays(&features, &camera, &grid, samples, 8, 8).unwrap();
        assert_eq!(out.shape(), [2 * samples, 8, 8]);
        let depths = grid.ray_depths(&camera, samples);
        assert!((depths[4] - 1.0).abs() < 1e-6);
        assert!((depths[8] - depths[0] - 2.0 * grid.radius_m()).abs() < 1e-5);
        let at = |c: usize, j: usize, r: usize, col: usize| {
            out.data()[((c * samples + j) * 8 + r) * 8 + col]
        };
        for (j, r, col) in [(4, 3, 3), (4, 4, 4), (3, 3, 4), (5, 4, 3)] {
            let d = depths[j];
            // World x = (col - 3.5) / 8 * d, world z = 1 - d; voxel index = world / 0.1 + 1.5.
            let gx = (col as f32 - 3.5) / 8.0 * d * 10.0 + 1.5;
            let gz = (1.0 - d) * 10.0 + 1.5;
            assert!((at(0, j, r, col) - gx).abs() < 1e-4, "x at {j} {r} {col}");
            assert!((at(1, j, r, col) - gz).abs() < 1e-4, "z at {j} {r} {col}");
        }
        // Past the cube along the ray (the sphere's ends lie outside it): zero.
        for c in 0..2 {
            assert_eq!(at(c, 0, 3, 3), 0.0);
            assert_eq!(at(c, 8, 3, 3), 0.0);
        }
        let wrong = Tensor::zeros(&[1, s, s, s + 1]);
        assert!(project_rays(&wrong, &camera, &grid, 4, 8, 8).is_err());
    }
}
