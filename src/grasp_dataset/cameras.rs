//! Sampling the cameras of a stable pose: top-down (Dex-Net 2.0) or anywhere on the hemisphere.

use std::f32::consts::TAU;

use mvgrasp_geometry::{Camera, Intrinsics, Vec3};
pub use mvgrasp_planner::theta_rad;
use rand::RngExt;
use rand_chacha::ChaCha8Rng;

use super::config::CameraDistribution;
use crate::error::Result;

/// Above this elevation a camera's image "up" is a random horizontal direction (world up would
/// be nearly parallel to its view); below it, world up.
const ROLL_FREE_ELEVATION_RAD: f32 = 1.2;

/// One camera from `distribution`, looking at (or near) `target` (the object's centre of mass,
/// table frame).
///
/// # Errors
/// A geometry error for a degenerate camera (a zero radius passes validation only as a range
/// whose both ends are 0, which [`super::GraspDatasetConfig::validate`] rejects).
pub fn sample_camera(
    distribution: &CameraDistribution,
    intrinsics: Intrinsics,
    target: Vec3,
    rng: &mut ChaCha8Rng,
) -> Result<Camera> {
    let uniform = |rng: &mut ChaCha8Rng, [lo, hi]: [f32; 2]| {
        if hi > lo {
            rng.random_range(lo..=hi)
        } else {
            lo
        }
    };
    let (look_at, elevation, radius) = match distribution {
        CameraDistribution::TopDown(t) => {
            let radius = uniform(rng, t.radius_m);
            let polar = uniform(rng, [0.0, t.max_polar_deg.to_radians()]);
            let o = t.planar_offset_m;
            let offset = Vec3::new(uniform(rng, [-o, o]), uniform(rng, [-o, o]), 0.0);
            (target + offset, std::f32::consts::FRAC_PI_2 - polar, radius)
        }
        CameraDistribution::MultiView(m) => {
            let radius = uniform(rng, m.radius_m);
            let e = m.elevation_deg;
            let elevation = uniform(rng, [e[0].to_radians(), e[1].to_radians()]);
            (target, elevation, radius)
        }
    };
    let azimuth: f32 = rng.random_range(0.0..TAU);
    let roll: f32 = rng.random_range(0.0..TAU);
    let (sin_e, cos_e) = elevation.sin_cos();
    let eye = look_at + Vec3::new(cos_e * azimuth.cos(), cos_e * azimuth.sin(), sin_e) * radius;
    let up = if elevation > ROLL_FREE_ELEVATION_RAD {
        Vec3::new(roll.cos(), roll.sin(), 0.0)
    } else {
        Vec3::Z
    };
    Ok(Camera::look_at(intrinsics, eye, look_at, up)?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grasp_dataset::config::{MultiViewCameras, TopDownCameras};
    use rand::SeedableRng;

    #[test]
    fn top_down_cameras_stay_within_their_cone_and_radius() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let dist = CameraDistribution::TopDown(TopDownCameras::default());
        for _ in 0..200 {
            let camera = sample_camera(
                &dist,
                Intrinsics::phoxi_s(),
                Vec3::new(0.0, 0.0, 0.03),
                &mut rng,
            )
            .unwrap();
            let theta = theta_rad(&camera).to_degrees();
            assert!((72.0 - 1e-3..=90.0).contains(&theta), "{theta}");
            let height = camera.position().z - 0.03;
            assert!((0.65 * 72f32.to_radians().sin() - 1e-3..=0.75 + 1e-3).contains(&height));
        }
    }

    #[test]
    fn multi_view_cameras_look_at_the_target_from_their_elevation_range() {
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let dist = CameraDistribution::MultiView(MultiViewCameras {
            radius_m: [0.5, 0.5],
            elevation_deg: [10.0, 40.0],
        });
        let target = Vec3::new(0.01, -0.02, 0.04);
        for _ in 0..200 {
            let camera = sample_camera(&dist, Intrinsics::phoxi_s(), target, &mut rng).unwrap();
            let theta = theta_rad(&camera).to_degrees();
            assert!((10.0 - 1e-3..=40.0 + 1e-3).contains(&theta), "{theta}");
            let to_target = (target - camera.position()).normalize();
            assert!(to_target.dot(camera.optical_axis()) > 1.0 - 1e-5);
            assert!((camera.position().distance(target) - 0.5).abs() < 1e-4);
        }
    }
}
