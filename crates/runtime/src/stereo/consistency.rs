//! The multi-view consistency check of swept depths (Merrell et al.'s visibility-based fusion,
//! as MVSNet and COLMAP filter their depth maps): a pixel's depth stands when another view
//! sees the same surface there, and no more views see through it than agree with it.
//!
//! A pixel's point is projected into every other view with a depth at that place:
//! - **agrees** when its depth in that view is within the tolerance of what that view found;
//! - **is seen through** when it lies in front of what that view found (by more than the
//!   tolerance): that view's ray passes through empty space where the point would be;
//! - otherwise it lies behind that view's surface (occluded there): no evidence either way.
//!
//! A depth with no agreeing view is a guess of one view's photo-consistency (the inside of a
//! cup that only the top-down view sees, a face aliased in every view): the caller replaces it
//! (with the visual hull's depth, which never lies beyond the surface, or with nothing).

use mvgrasp_geometry::rounding::rounded_index;
use mvgrasp_geometry::{Camera, Pose3};
use rayon::prelude::*;

/// The settings of [`consistent_pixels`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Consistency {
    /// Two depths of one point agree within this, metres, ...
    pub tolerance_m: f32,
    /// ... or within this share of the depth, whichever is larger.
    pub relative_tolerance: f32,
    /// A depth stands with at least this many agreeing views, and at least as many agreeing as
    /// seeing through it.
    pub min_agreeing: usize,
}

impl Default for Consistency {
    fn default() -> Self {
        Self {
            tolerance_m: 0.003,
            relative_tolerance: 0.005,
            min_agreeing: 1,
        }
    }
}

/// Per view and pixel, whether its depth stands (see the module docs); pixels without depth
/// (0) are `false`. `depths[i]` is camera `i`'s depth image, metres along its optical axis.
pub fn consistent_pixels(
    cameras: &[Camera],
    depths: &[Vec<f32>],
    params: &Consistency,
) -> Vec<Vec<bool>> {
    consistent_where(cameras, depths, params, |_, _| true)
}

/// [`consistent_pixels`] of the pixels `wanted(view, pixel)` only (the others `false`).
pub(super) fn consistent_where(
    cameras: &[Camera],
    depths: &[Vec<f32>],
    params: &Consistency,
    wanted: impl Fn(usize, usize) -> bool + Sync,
) -> Vec<Vec<bool>> {
    let camera_from_world: Vec<Pose3> = cameras
        .iter()
        .map(|c| c.world_from_camera.inverse())
        .collect();
    // Pixel by pixel in parallel, whatever the number of views.
    (0..cameras.len())
        .map(|r| {
            let k = &cameras[r].intrinsics;
            let w = k.width as usize;
            depths[r]
                .par_iter()
                .enumerate()
                .with_min_len(1024)
                .map(|(i, &d)| {
                    if d <= 0.0 || !wanted(r, i) {
                        return false;
                    }
                    let p = cameras[r].unproject((i % w) as f32, (i / w) as f32, d);
                    let (mut agreeing, mut seen_through) = (0, 0);
                    for (j, camera) in cameras.iter().enumerate() {
                        if j == r {
                            continue;
                        }
                        let q = camera_from_world[j].transform_point(p);
                        let Some(found) =
                            depth_at(camera, &depths[j], q.z, camera.intrinsics.project(q))
                        else {
                            continue;
                        };
                        let tolerance = params.tolerance_m.max(params.relative_tolerance * q.z);
                        if (q.z - found).abs() <= tolerance {
                            agreeing += 1;
                        } else if q.z < found - tolerance {
                            seen_through += 1;
                        }
                    }
                    agreeing >= params.min_agreeing && agreeing >= seen_through
                })
                .collect()
        })
        .collect()
}

/// The depth a view found at the pixel nearest `uv` (`None` outside its image, without depth
/// there, or for a point behind the camera).
fn depth_at(camera: &Camera, depth: &[f32], z: f32, uv: Option<[f32; 2]>) -> Option<f32> {
    let [u, v] = uv?;
    let k = &camera.intrinsics;
    let (Some(u), Some(v), true) = (
        rounded_index(u, k.width as usize),
        rounded_index(v, k.height as usize),
        z > 0.0,
    ) else {
        return None;
    };
    let found = depth[v * k.width as usize + u];
    (found > 0.0).then_some(found)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)] // tests may fail loudly

    use super::super::tests_support::views;
    use super::*;

    #[test]
    fn true_depths_stand_and_a_floating_patch_falls() {
        let (views, truth) = views(5);
        let cameras: Vec<Camera> = views.iter().map(|v| v.camera).collect();
        let params = Consistency::default();
        let standing = consistent_pixels(&cameras, &truth, &params);
        // The true depth of the top-down view: confirmed wherever another view sees it.
        let mask = views[0].mask.as_ref().unwrap();
        let top: Vec<usize> = (0..mask.len()).filter(|&i| mask[i]).collect();
        let confirmed = top.iter().filter(|&&i| standing[0][i]).count();
        assert!(
            confirmed * 20 > top.len() * 19,
            "{confirmed} of {}",
            top.len()
        );
        // The box's top raised 3 cm in the top-down view: the other views see through it.
        let mut wrong = truth.clone();
        for &i in &top {
            wrong[0][i] -= 0.03;
        }
        let standing = consistent_pixels(&cameras, &wrong, &params);
        let kept = top.iter().filter(|&&i| standing[0][i]).count();
        assert!(kept * 50 < top.len(), "{kept} of {} kept", top.len());
        // Without depth, nothing stands.
        let mut none = truth;
        none[0].fill(0.0);
        assert!(
            !consistent_pixels(&cameras, &none, &params)[0]
                .iter()
                .any(|&s| s)
        );
    }
}
