//! The learned multi-view stereo network's geometry: each reference pixel's stretch of ray
//! inside the workspace, depth hypotheses along it, the group-wise correlation cost volume of
//! a reference view's features with its sources' ([`correlation_volume`]) and the soft argmax
//! that turns a volume of logits into depth and confidence. `training/mvgrasp_training/mvs.py`
//! defines them; the tests hold each to its torch form through `tests/mvs_parity.rs`.
//!
//! Cameras are [`CameraMatrices`] (OpenCV frames, pixel centres at integers); depth is along
//! the optical axis, metres.

use rayon::prelude::*;

use crate::error::{InferError, Result};
use crate::ops::CameraMatrices;
use crate::ops::check::shape_error;
use crate::parallel::Parallelism;
use crate::tensor::Tensor;

/// The nearest depth a hypothesis may have, metres (`MIN_DEPTH_M` of the training code).
pub const MIN_DEPTH_M: f32 = 0.05;
/// A ray that misses the workspace spans this far either side of its centre's depth.
pub const MISS_HALF_RANGE_M: f32 = 0.3;
/// The workspace reaches this far below the table.
pub const BELOW_TABLE_M: f32 = 0.01;

/// The box the hypotheses live in: `half_side_m` around `centre` in x and y (world frame),
/// from [`BELOW_TABLE_M`] below the table (z = 0) to `height_m` above it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Workspace {
    /// Where the cameras look (the least-squares point of their optical axes), world frame.
    pub centre: [f32; 3],
    /// Half the box's side in x and y, metres.
    pub half_side_m: f32,
    /// The box's top above the table, metres.
    pub height_m: f32,
}

impl Workspace {
    /// The depth of [`Workspace::centre`] in `camera`.
    pub fn centre_depth(&self, camera: &CameraMatrices) -> f32 {
        let m = &camera.camera_from_world;
        let c = self.centre;
        m[2][0] * c[0] + m[2][1] * c[1] + m[2][2] * c[2] + m[2][3]
    }
}

/// Pixel `(u, v)`'s ray at depth 1 in the camera frame: `K^-1 [u, v, 1]`.
fn pixel_ray(k: &[[f32; 3]; 3], u: f32, v: f32) -> [f32; 3] {
    [(u - k[0][2]) / k[0][0], (v - k[1][2]) / k[1][1], 1.0]
}

/// Each pixel's stretch of ray inside `workspace`, as depths `(near, far)` (`[height, width]`
/// each, row-major): the ray cut by the box (slabs), the near end at least [`MIN_DEPTH_M`]; a
/// ray that misses the box spans [`MISS_HALF_RANGE_M`] either side of the centre's depth.
pub fn depth_range(
    camera: &CameraMatrices,
    workspace: &Workspace,
    height: usize,
    width: usize,
) -> (Vec<f32>, Vec<f32>) {
    let m = &camera.camera_from_world;
    let t = [m[0][3], m[1][3], m[2][3]];
    // The camera's centre in the world: -R^T t.
    let origin: [f32; 3] =
        std::array::from_fn(|c| -(m[0][c] * t[0] + m[1][c] * t[1] + m[2][c] * t[2]));
    let c = workspace.centre;
    let lo = [
        c[0] - workspace.half_side_m,
        c[1] - workspace.half_side_m,
        -BELOW_TABLE_M,
    ];
    let hi = [
        c[0] + workspace.half_side_m,
        c[1] + workspace.half_side_m,
        workspace.height_m,
    ];
    let centre_depth = workspace.centre_depth(camera);
    let miss_near = (centre_depth - MISS_HALF_RANGE_M).max(MIN_DEPTH_M);
    let miss_far = centre_depth + MISS_HALF_RANGE_M;
    let mut near = vec![0.0; height * width];
    let mut far = vec![0.0; height * width];
    for y in 0..height {
        for x in 0..width {
            let ray = pixel_ray(&camera.k, x as f32, y as f32);
            // World direction: R^T ray (its parameter is the depth).
            let dir: [f32; 3] =
                std::array::from_fn(|c| ray[0] * m[0][c] + ray[1] * m[1][c] + ray[2] * m[2][c]);
            let (mut enter, mut leave) = (f32::NEG_INFINITY, f32::INFINITY);
            for axis in 0..3 {
                let (o, d) = (origin[axis], dir[axis]);
                let (a, b) = if d.abs() < 1e-9 {
                    if o < lo[axis] || o > hi[axis] {
                        (f32::INFINITY, f32::NEG_INFINITY)
                    } else {
                        (f32::NEG_INFINITY, f32::INFINITY)
                    }
                } else {
                    let t0 = (lo[axis] - o) / d;
                    let t1 = (hi[axis] - o) / d;
                    (t0.min(t1), t0.max(t1))
                };
                enter = enter.max(a);
                leave = leave.min(b);
            }
            let enter = enter.max(MIN_DEPTH_M);
            let i = y * width + x;
            if leave <= enter + 1e-3 {
                (near[i], far[i]) = (miss_near, miss_far);
            } else {
                (near[i], far[i]) = (enter, leave);
            }
        }
    }
    (near, far)
}

/// `planes` depths from `near` to `far` per pixel, uniform in inverse depth:
/// `[planes, pixels]` as one row-major tensor's data.
pub fn inverse_depth_planes(near: &[f32], far: &[f32], planes: usize) -> Vec<f32> {
    let mut out = vec![0.0; planes * near.len()];
    for i in 0..planes {
        // torch.linspace(0, 1, planes): i * step from the start for the first half, from the
        // end for the second.
        let step = 1.0 / (planes.max(2) - 1) as f32;
        let t = if i < planes / 2 {
            i as f32 * step
        } else {
            1.0 - (planes - 1 - i) as f32 * step
        };
        for (p, (&n, &f)) in near.iter().zip(far).enumerate() {
            let inverse = 1.0 / n + (1.0 / f - 1.0 / n) * t;
            out[i * near.len() + p] = 1.0 / inverse;
        }
    }
    out
}

/// Checks `[V, C, h, w]` features, `cameras.len() == V`, `reference < V`, `depths` `[D, h, w]`
/// and `C` divisible by `groups`; returns `(V, C, h, w, D)`.
fn check_volume(
    op: &'static str,
    features: &Tensor,
    cameras: &[CameraMatrices],
    reference: usize,
    depths: &Tensor,
    groups: usize,
) -> Result<(usize, usize, usize, usize, usize)> {
    let &[v, c, h, w] = features.shape() else {
        return Err(shape_error(
            op,
            "features [views, channels, height, width]",
            features.shape(),
        ));
    };
    if cameras.len() != v || reference >= v || v < 2 {
        return Err(InferError::InvalidParameter {
            op,
            name: "cameras",
            value: format!(
                "{} cameras for {v} views, reference {reference}",
                cameras.len()
            ),
            expected: "one camera a view, at least 2 views, the reference among them",
        });
    }
    let &[d, dh, dw] = depths.shape() else {
        return Err(shape_error(
            op,
            format!("depths [planes, {h}, {w}]"),
            depths.shape(),
        ));
    };
    if (dh, dw) != (h, w) || d == 0 {
        return Err(shape_error(
            op,
            format!("depths [planes, {h}, {w}]"),
            depths.shape(),
        ));
    }
    if groups == 0 || c % groups != 0 {
        return Err(InferError::InvalidParameter {
            op,
            name: "groups",
            value: format!("{groups} for {c} channels"),
            expected: "a divisor of the channel count",
        });
    }
    Ok((v, c, h, w, d))
}

/// `source_from_reference` for two cameras' `camera_from_world` (rigid: the inverse is
/// `[R^T, -R^T t]`), in f64.
fn source_from_reference(source: &CameraMatrices, reference: &CameraMatrices) -> [[f32; 4]; 3] {
    let r = reference.camera_from_world.map(|row| row.map(f64::from));
    let s = source.camera_from_world.map(|row| row.map(f64::from));
    // world_from_reference = [R^T | -R^T t].
    let mut inv = [[0.0f64; 4]; 3];
    for i in 0..3 {
        for j in 0..3 {
            inv[i][j] = r[j][i];
        }
        inv[i][3] = -(0..3).map(|j| r[j][i] * r[j][3]).sum::<f64>();
    }
    std::array::from_fn(|i| {
        std::array::from_fn(|j| {
            let mut v: f64 = (0..3).map(|l| s[i][l] * inv[l][j]).sum();
            if j == 3 {
                v += s[i][3];
            }
            v as f32
        })
    })
}

/// Where a reference ray's point at depth `depth` falls in a source view of `w` x `h`:
/// `Some((u, v))` inside the image in front of the camera, else `None`.
#[inline]
fn project(
    rel: &[[f32; 4]; 3],
    k: &[[f32; 3]; 3],
    ray: [f32; 3],
    depth: f32,
    w: usize,
    h: usize,
) -> Option<(f32, f32)> {
    let p = ray.map(|r| r * depth);
    let q: [f32; 3] =
        std::array::from_fn(|i| rel[i][0] * p[0] + rel[i][1] * p[1] + rel[i][2] * p[2] + rel[i][3]);
    if q[2] <= 1e-6 {
        return None;
    }
    let u = k[0][0] * q[0] / q[2] + k[0][2];
    let v = k[1][1] * q[1] / q[2] + k[1][2];
    let inside = u >= 0.0 && u <= (w - 1) as f32 && v >= 0.0 && v <= (h - 1) as f32;
    inside.then_some((u, v))
}

/// The cost volume of view `reference` against every other view: `features` `[V, C, h, w]`
/// (`cameras` with `k` at that resolution), `depths` `[D, h, w]` the hypotheses of each
/// reference pixel. Each source's features are sampled bilinearly where the hypothesis' point
/// falls (nothing outside its image or behind it) and correlated with the reference's, the
/// mean product over each of `groups` groups of channels: `[2 groups, D, h, w]`, the first
/// `groups` channels the mean over the sources that see the point, the last `groups` the
/// maximum over them (both 0 where none sees it). The reference's rows run on `par`'s threads.
///
/// # Errors
/// [`InferError::ShapeMismatch`] or [`InferError::InvalidParameter`] for inputs that do not
/// fit together.
pub fn correlation_volume(
    features: &Tensor,
    cameras: &[CameraMatrices],
    reference: usize,
    depths: &Tensor,
    groups: usize,
    par: Parallelism,
) -> Result<Tensor> {
    const OP: &str = "correlation_volume";
    let (views, c, h, w, planes) = check_volume(OP, features, cameras, reference, depths, groups)?;
    let pixels = h * w;
    let per_group = c / groups;
    let data = features.data();
    // Every view's features pixel-major ([h, w, C]): a bilinear tap reads C values in a row.
    let interleaved: Vec<Vec<f32>> = (0..views)
        .map(|view| {
            let plane = &data[view * c * pixels..(view + 1) * c * pixels];
            let mut out = vec![0.0; c * pixels];
            for ch in 0..c {
                for p in 0..pixels {
                    out[p * c + ch] = plane[ch * pixels + p];
                }
            }
            out
        })
        .collect();
    let reference_camera = &cameras[reference];
    let sources: Vec<(usize, [[f32; 4]; 3])> = (0..views)
        .filter(|&s| s != reference)
        .map(|s| (s, source_from_reference(&cameras[s], reference_camera)))
        .collect();
    let hypotheses = depths.data();
    let scale = 1.0 / per_group as f32;
    // Each reference row on its own (pixel-major: [w][2 groups][D]), the rows shared among
    // `par`'s threads; every value is the same whatever the split.
    let row_len = w * 2 * groups * planes;
    let mut rows = vec![0.0f32; h * row_len];
    let run = |(y, row): (usize, &mut [f32])| {
        let mut sample = vec![0.0f32; c];
        let mut total = vec![0.0f32; groups];
        let mut best = vec![0.0f32; groups];
        for x in 0..w {
            let p = y * w + x;
            let ray = pixel_ray(&reference_camera.k, x as f32, y as f32);
            let own = &interleaved[reference][p * c..(p + 1) * c];
            let cell = &mut row[x * 2 * groups * planes..(x + 1) * 2 * groups * planes];
            for d in 0..planes {
                let depth = hypotheses[d * pixels + p];
                total.iter_mut().for_each(|t| *t = 0.0);
                best.iter_mut().for_each(|b| *b = f32::NEG_INFINITY);
                let mut seen = 0u32;
                for (s, rel) in &sources {
                    let Some((u, v)) = project(rel, &cameras[*s].k, ray, depth, w, h) else {
                        continue;
                    };
                    seen += 1;
                    bilinear(&interleaved[*s], c, w, h, u, v, &mut sample);
                    for (g, (t, b)) in total.iter_mut().zip(&mut best).enumerate() {
                        let range = g * per_group..(g + 1) * per_group;
                        let dot: f32 = sample[range.clone()]
                            .iter()
                            .zip(&own[range])
                            .map(|(a, b)| a * b)
                            .sum();
                        let correlation = dot * scale;
                        *t += correlation;
                        *b = b.max(correlation);
                    }
                }
                let norm = 1.0 / seen.max(1) as f32;
                for (g, (t, b)) in total.iter().zip(&best).enumerate() {
                    cell[g * planes + d] = t * norm;
                    cell[(groups + g) * planes + d] = if seen > 0 { *b } else { 0.0 };
                }
            }
        }
    };
    if par.threads() > 1 {
        rows.par_chunks_mut(row_len).enumerate().for_each(run);
    } else {
        rows.chunks_mut(row_len).enumerate().for_each(run);
    }
    let mut out = vec![0.0f32; 2 * groups * planes * pixels];
    for (p, cell) in rows.chunks_exact(2 * groups * planes).enumerate() {
        for (i, &value) in cell.iter().enumerate() {
            out[i * pixels + p] = value;
        }
    }
    Tensor::new(&[2 * groups, planes, h, w], out)
}

/// The bilinear sample at `(u, v)` (inside the image) of pixel-major features `[h, w, C]`:
/// taps past the last row or column weigh nothing (they are never read).
#[inline]
fn bilinear(features: &[f32], c: usize, w: usize, h: usize, u: f32, v: f32, out: &mut [f32]) {
    let (x0, y0) = (u.floor(), v.floor());
    let (fx, fy) = (u - x0, v - y0);
    let (x0, y0) = (x0 as usize, y0 as usize);
    out.iter_mut().for_each(|o| *o = 0.0);
    for (dy, wy) in [(0, 1.0 - fy), (1, fy)] {
        let yy = y0 + dy;
        if yy >= h || wy == 0.0 {
            continue;
        }
        for (dx, wx) in [(0, 1.0 - fx), (1, fx)] {
            let xx = x0 + dx;
            if xx >= w || wx == 0.0 {
                continue;
            }
            let weight = wy * wx;
            let tap = &features[(yy * w + xx) * c..(yy * w + xx + 1) * c];
            for (o, &t) in out.iter_mut().zip(tap) {
                *o += weight * t;
            }
        }
    }
}

/// [`correlation_volume`] as its definition reads: per source, per hypothesis, per channel,
/// from the channel-major features; the reference the fast form is tested against.
///
/// # Errors
/// As [`correlation_volume`].
pub fn correlation_volume_reference(
    features: &Tensor,
    cameras: &[CameraMatrices],
    reference: usize,
    depths: &Tensor,
    groups: usize,
) -> Result<Tensor> {
    const OP: &str = "correlation_volume";
    let (views, c, h, w, planes) = check_volume(OP, features, cameras, reference, depths, groups)?;
    let pixels = h * w;
    let per_group = c / groups;
    let data = features.data();
    let at = |view: usize, ch: usize, y: isize, x: isize| -> f32 {
        if y < 0 || x < 0 || y >= h as isize || x >= w as isize {
            0.0
        } else {
            data[(view * c + ch) * pixels + y as usize * w + x as usize]
        }
    };
    let mut total = vec![0.0f32; groups * planes * pixels];
    let mut best = vec![f32::NEG_INFINITY; groups * planes * pixels];
    let mut seen = vec![0.0f32; planes * pixels];
    for source in (0..views).filter(|&s| s != reference) {
        let rel = source_from_reference(&cameras[source], &cameras[reference]);
        for d in 0..planes {
            for y in 0..h {
                for x in 0..w {
                    let p = y * w + x;
                    let ray = pixel_ray(&cameras[reference].k, x as f32, y as f32);
                    let depth = depths.data()[d * pixels + p];
                    let Some((u, v)) = project(&rel, &cameras[source].k, ray, depth, w, h) else {
                        continue;
                    };
                    seen[d * pixels + p] += 1.0;
                    let (x0, y0) = (u.floor(), v.floor());
                    let (fx, fy) = (u - x0, v - y0);
                    let (x0, y0) = (x0 as isize, y0 as isize);
                    for g in 0..groups {
                        let mut sum = 0.0;
                        for ch in g * per_group..(g + 1) * per_group {
                            let value = (1.0 - fy) * (1.0 - fx) * at(source, ch, y0, x0)
                                + (1.0 - fy) * fx * at(source, ch, y0, x0 + 1)
                                + fy * (1.0 - fx) * at(source, ch, y0 + 1, x0)
                                + fy * fx * at(source, ch, y0 + 1, x0 + 1);
                            sum += value * at(reference, ch, y as isize, x as isize);
                        }
                        let correlation = sum / per_group as f32;
                        total[(g * planes + d) * pixels + p] += correlation;
                        let b = &mut best[(g * planes + d) * pixels + p];
                        *b = b.max(correlation);
                    }
                }
            }
        }
    }
    for g in 0..groups {
        for i in 0..planes * pixels {
            total[g * planes * pixels + i] /= seen[i].max(1.0);
            if seen[i] == 0.0 {
                best[g * planes * pixels + i] = 0.0;
            }
        }
    }
    total.extend(best);
    Tensor::new(&[2 * groups, planes, h, w], total)
}

/// Each pixel's feature vector of `[N, C, h, w]` scaled to unit length (torch's
/// `F.normalize(x, dim=1)`: divided by `max(norm, 1e-12)`), in place.
///
/// # Errors
/// [`InferError::ShapeMismatch`] for a tensor not of rank 4.
pub fn normalise_channels(x: &mut Tensor) -> Result<()> {
    let &[n, c, h, w] = x.shape() else {
        return Err(shape_error(
            "normalise_channels",
            "[batch, channels, height, width]",
            x.shape(),
        ));
    };
    let pixels = h * w;
    for image in x.data_mut().chunks_exact_mut(c * pixels.max(1)).take(n) {
        for p in 0..pixels {
            let norm = (0..c)
                .map(|ch| image[ch * pixels + p] * image[ch * pixels + p])
                .sum::<f32>()
                .sqrt()
                .max(1e-12);
            for ch in 0..c {
                image[ch * pixels + p] /= norm;
            }
        }
    }
    Ok(())
}

/// The softmax over hypotheses of `logits` `[D, h, w]` and its expectation over `depths`
/// `[D, h, w]`: `(depth, confidence)`, each `[h * w]`; the confidence is the probability mass
/// of the 4 hypotheses around the expected index (`floor - 1` to `floor + 2`; MVSNet's).
///
/// # Errors
/// [`InferError::ShapeMismatch`] for tensors of other shapes.
pub fn soft_argmax(logits: &Tensor, depths: &Tensor) -> Result<(Vec<f32>, Vec<f32>)> {
    const OP: &str = "soft_argmax";
    let &[planes, h, w] = logits.shape() else {
        return Err(shape_error(
            OP,
            "logits [planes, height, width]",
            logits.shape(),
        ));
    };
    if depths.shape() != logits.shape() || planes == 0 {
        return Err(shape_error(
            OP,
            format!("depths {:?}", logits.shape()),
            depths.shape(),
        ));
    }
    let pixels = h * w;
    let (l, hyp) = (logits.data(), depths.data());
    let mut depth = vec![0.0; pixels];
    let mut confidence = vec![0.0; pixels];
    let mut p = vec![0.0f32; planes];
    for i in 0..pixels {
        let max = (0..planes)
            .map(|d| l[d * pixels + i])
            .fold(f32::NEG_INFINITY, f32::max);
        let mut sum = 0.0;
        for (d, q) in p.iter_mut().enumerate() {
            *q = (l[d * pixels + i] - max).exp();
            sum += *q;
        }
        let (mut expected, mut index) = (0.0, 0.0);
        for (d, q) in p.iter_mut().enumerate() {
            *q /= sum;
            expected += *q * hyp[d * pixels + i];
            index += *q * d as f32;
        }
        let first = index.floor() as isize - 1;
        confidence[i] = (first..first + 4)
            .filter(|&d| d >= 0 && (d as usize) < planes)
            .map(|d| p[d as usize])
            .sum();
        depth[i] = expected;
    }
    Ok((depth, confidence))
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;
    use crate::testing::Rng;

    /// A camera `distance` from the origin at `elevation` and `azimuth`, looking at it.
    pub(crate) fn looking_at_origin(
        distance: f32,
        elevation: f32,
        azimuth: f32,
        k: [[f32; 3]; 3],
    ) -> CameraMatrices {
        let c = [
            distance * elevation.cos() * azimuth.cos(),
            distance * elevation.cos() * azimuth.sin(),
            distance * elevation.sin(),
        ];
        let norm = |v: [f32; 3]| {
            let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
            v.map(|x| x / n)
        };
        let cross = |a: [f32; 3], b: [f32; 3]| {
            [
                a[1] * b[2] - a[2] * b[1],
                a[2] * b[0] - a[0] * b[2],
                a[0] * b[1] - a[1] * b[0],
            ]
        };
        let z = norm(c.map(|v| -v));
        let x = norm(cross(z, [0.0, 0.0, 1.0]));
        let y = cross(z, x);
        let r = [x, y, z];
        let t: [f32; 3] =
            std::array::from_fn(|i| -(r[i][0] * c[0] + r[i][1] * c[1] + r[i][2] * c[2]));
        CameraMatrices {
            k,
            camera_from_world: [
                [x[0], x[1], x[2], t[0]],
                [y[0], y[1], y[2], t[1]],
                [z[0], z[1], z[2], t[2]],
                [0.0, 0.0, 0.0, 1.0],
            ],
        }
    }

    const K: [[f32; 3]; 3] = [[40.0, 0.0, 15.5], [0.0, 40.0, 11.5], [0.0, 0.0, 1.0]];

    fn workspace() -> Workspace {
        Workspace {
            centre: [0.0, 0.0, 0.03],
            half_side_m: 0.2,
            height_m: 0.3,
        }
    }

    #[test]
    fn a_top_down_ray_spans_the_box_from_its_top_to_below_the_table() {
        let camera = looking_at_origin(0.5, 1.5, 0.3, K);
        let (near, far) = depth_range(&camera, &workspace(), 24, 32);
        // The centre pixel's ray goes (almost) straight down from 0.5 m.
        let i = 12 * 32 + 16;
        let cos = 1.5f32.sin();
        assert!((near[i] - (0.5 - 0.3) / cos).abs() < 0.01, "{}", near[i]);
        assert!(
            (far[i] - (0.5 + BELOW_TABLE_M) / cos).abs() < 0.01,
            "{}",
            far[i]
        );
        assert!(
            near.iter()
                .zip(&far)
                .all(|(n, f)| n < f && *n >= MIN_DEPTH_M)
        );
    }

    #[test]
    fn planes_are_uniform_in_inverse_depth_from_near_to_far() {
        let planes = inverse_depth_planes(&[0.2, 0.4], &[0.6, 0.5], 5);
        assert!((planes[0] - 0.2).abs() < 1e-6 && (planes[8] - 0.6).abs() < 1e-6);
        assert!((planes[1] - 0.4).abs() < 1e-6 && (planes[9] - 0.5).abs() < 1e-6);
        let inverse: Vec<f32> = (0..5).map(|d| 1.0 / planes[d * 2]).collect();
        for pair in inverse.windows(2) {
            assert!((pair[0] - pair[1] - (inverse[0] - inverse[1])).abs() < 1e-3);
        }
    }

    fn random_setup(rng: &mut Rng) -> (Tensor, Vec<CameraMatrices>, Tensor) {
        let cameras: Vec<CameraMatrices> = (0..3)
            .map(|i| looking_at_origin(0.5, 1.0 + 0.2 * i as f32, 1.9 * i as f32, K))
            .collect();
        let features = rng.tensor(&[3, 4, 24, 32]);
        let (near, far) = depth_range(&cameras[1], &workspace(), 24, 32);
        let depths = Tensor::new(&[6, 24, 32], inverse_depth_planes(&near, &far, 6)).unwrap();
        (features, cameras, depths)
    }

    #[test]
    fn the_fast_correlation_equals_its_definition() {
        let mut rng = Rng::new(3);
        let (features, cameras, depths) = random_setup(&mut rng);
        for groups in [1, 2, 4] {
            let fast = correlation_volume(
                &features,
                &cameras,
                1,
                &depths,
                groups,
                Parallelism::Sequential,
            )
            .unwrap();
            let split = correlation_volume(
                &features,
                &cameras,
                1,
                &depths,
                groups,
                Parallelism::Rayon { threads: 3 },
            )
            .unwrap();
            assert_eq!(fast, split, "the same bits whatever the threads");
            let plain =
                correlation_volume_reference(&features, &cameras, 1, &depths, groups).unwrap();
            assert_eq!(fast.shape(), [2 * groups, 6, 24, 32]);
            let worst = fast
                .data()
                .iter()
                .zip(plain.data())
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f32::max);
            assert!(worst < 1e-5, "groups {groups}: {worst}");
        }
    }

    #[test]
    fn a_point_seen_by_no_source_costs_nothing() {
        let mut rng = Rng::new(4);
        let (features, cameras, _) = random_setup(&mut rng);
        // Behind every camera: no source sees it.
        let depths = Tensor::full(&[2, 24, 32], -1.0);
        let volume =
            correlation_volume(&features, &cameras, 0, &depths, 2, Parallelism::Sequential)
                .unwrap();
        assert!(volume.data().iter().all(|&v| v == 0.0));
    }

    #[test]
    fn bad_inputs_are_refused() {
        let mut rng = Rng::new(5);
        let (features, cameras, depths) = random_setup(&mut rng);
        let seq = Parallelism::Sequential;
        assert!(correlation_volume(&features, &cameras[..2], 0, &depths, 2, seq).is_err());
        assert!(correlation_volume(&features, &cameras, 3, &depths, 2, seq).is_err());
        assert!(correlation_volume(&features, &cameras, 0, &depths, 3, seq).is_err());
        let small = Tensor::zeros(&[6, 12, 32]);
        assert!(correlation_volume(&features, &cameras, 0, &small, 2, seq).is_err());
    }

    #[test]
    fn soft_argmax_of_a_sharp_peak_is_its_depth_with_full_confidence() {
        let mut logits = Tensor::full(&[8, 1, 2], -30.0);
        logits.data_mut()[3 * 2] = 30.0;
        logits.data_mut()[6 * 2 + 1] = 30.0;
        let depths =
            Tensor::new(&[8, 1, 2], (0..16).map(|i| (i / 2) as f32 * 0.01).collect()).unwrap();
        let (depth, confidence) = soft_argmax(&logits, &depths).unwrap();
        assert!((depth[0] - 0.03).abs() < 1e-6 && (depth[1] - 0.06).abs() < 1e-6);
        assert!(confidence.iter().all(|&c| (c - 1.0).abs() < 1e-6));
        // Flat logits: the middle depth, and 4 of 8 hypotheses' mass.
        let (depth, confidence) = soft_argmax(&Tensor::zeros(&[8, 1, 2]), &depths).unwrap();
        assert!((depth[0] - 0.035).abs() < 1e-6);
        assert!((confidence[0] - 0.5).abs() < 1e-6);
    }
}
