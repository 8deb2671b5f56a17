//! Cameras on a hemisphere around an object, looking at it: the paper's 20 training views and
//! 10 novel test views (always including the exact top-down view).

use std::f32::consts::{FRAC_PI_2, TAU};

use parry3d::math::Vec3;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::camera::{Camera, Intrinsics};
use crate::error::{GeometryError, Result};

/// Where cameras go: a spherical cap above the table around `target`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct HemisphereLayout {
    /// How many views.
    pub count: usize,
    /// Distance from the target, metres.
    pub radius_m: f32,
    /// Lowest elevation above the table plane, radians (0 = side view).
    pub min_elevation_rad: f32,
    /// Highest elevation, radians (pi/2 = top-down).
    pub max_elevation_rad: f32,
    /// Make the first view the exact top-down one.
    pub include_top_down: bool,
}

impl HemisphereLayout {
    /// The paper's training layout: 20 views, 0.5 m away, elevations 15 to 85 degrees.
    pub fn paper_training() -> Self {
        Self {
            count: 20,
            radius_m: 0.5,
            min_elevation_rad: 15f32.to_radians(),
            max_elevation_rad: 85f32.to_radians(),
            include_top_down: false,
        }
    }

    /// The paper's test layout: 10 novel views, the first exactly top-down.
    pub fn paper_test() -> Self {
        Self {
            count: 10,
            include_top_down: true,
            ..Self::paper_training()
        }
    }

    /// The cameras, deterministic from `seed`: elevation stratified in equal-area bands (so
    /// views cover the cap evenly), azimuth spread by the golden angle, both jittered.
    ///
    /// # Errors
    /// [`GeometryError::InvalidParameter`] for a count of 0, a radius that is not positive, or
    /// elevations outside 0 to pi/2 or in the wrong order.
    pub fn cameras(&self, intrinsics: Intrinsics, target: Vec3, seed: u64) -> Result<Vec<Camera>> {
        self.validate()?;
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let random = self.count - usize::from(self.include_top_down);
        let (lo, hi) = (self.min_elevation_rad.sin(), self.max_elevation_rad.sin());
        let azimuth_offset = rng.random_range(0.0..TAU);
        let golden_angle = TAU * (1.0 - 1.0 / 1.618_034);
        let mut cameras = Vec::with_capacity(self.count);
        if self.include_top_down {
            let eye = target + Vec3::Z * self.radius_m;
            cameras.push(Camera::look_at(intrinsics, eye, target, Vec3::Y)?);
        }
        for i in 0..random {
            let band = (i as f32 + rng.random_range(0.0..1.0)) / random as f32;
            let elevation = (lo + (hi - lo) * band)
                .clamp(-1.0, 1.0)
                .asin()
                .min(FRAC_PI_2 - 1e-3);
            let azimuth = azimuth_offset + golden_angle * i as f32 + rng.random_range(-0.2..0.2);
            let direction = Vec3::new(
                elevation.cos() * azimuth.cos(),
                elevation.cos() * azimuth.sin(),
                elevation.sin(),
            );
            cameras.push(Camera::look_at(
                intrinsics,
                target + direction * self.radius_m,
                target,
                Vec3::Z,
            )?);
        }
        Ok(cameras)
    }

    fn validate(&self) -> Result<()> {
        let invalid = |name, value: String, expected| {
            Err(GeometryError::InvalidParameter {
                op: "hemisphere views",
                name,
                value,
                expected,
            })
        };
        if self.count == 0 || self.count > 10_000 {
            return invalid("count", self.count.to_string(), "1 to 10000");
        }
        if !(self.radius_m.is_finite() && self.radius_m > 0.0) {
            return invalid(
                "radius_m",
                self.radius_m.to_string(),
                "a finite distance > 0",
            );
        }
        let (lo, hi) = (self.min_elevation_rad, self.max_elevation_rad);
        if !(0.0 <= lo && lo <= hi && hi <= FRAC_PI_2) {
            return invalid(
                "min_elevation_rad, max_elevation_rad",
                format!("{lo}, {hi}"),
                "0 <= min <= max <= pi/2",
            );
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn training_views_look_at_the_target_from_the_cap() {
        let layout = HemisphereLayout::paper_training();
        let target = Vec3::new(0.1, -0.2, 0.05);
        let cams = layout.cameras(Intrinsics::phoxi_s(), target, 7).unwrap();
        assert_eq!(cams.len(), 20);
        for cam in &cams {
            let offset = cam.position() - target;
            assert!((offset.length() - 0.5).abs() < 1e-4);
            let elevation = (offset.z / offset.length()).asin().to_degrees();
            assert!((14.9..=85.1).contains(&elevation), "{elevation}");
            assert!((cam.optical_axis() + offset.normalize()).length() < 1e-4);
            let [u, v] = cam.project(target).unwrap();
            assert!((u - 255.5).abs() < 0.05 && (v - 191.75).abs() < 0.05);
        }
        // Every elevation band gets a view.
        let mut elevations: Vec<f32> = cams.iter().map(|c| (c.position() - target).z).collect();
        elevations.sort_by(f32::total_cmp);
        assert!(elevations.windows(2).all(|w| w[1] - w[0] < 0.1));
    }

    #[test]
    fn test_views_start_exactly_top_down_and_differ_from_training() {
        let k = Intrinsics::phoxi_s();
        let test = HemisphereLayout::paper_test()
            .cameras(k, Vec3::ZERO, 1)
            .unwrap();
        assert_eq!(test.len(), 10);
        assert_eq!(test[0].optical_axis(), -Vec3::Z);
        assert_eq!(test[0].position(), Vec3::new(0.0, 0.0, 0.5));
        let train = HemisphereLayout::paper_training()
            .cameras(k, Vec3::ZERO, 0)
            .unwrap();
        assert!(test.iter().all(|t| {
            train
                .iter()
                .all(|c| (c.position() - t.position()).length() > 1e-3)
        }));
    }

    #[test]
    fn same_seed_same_cameras_other_seed_other_cameras() {
        let k = Intrinsics::phoxi_s();
        let layout = HemisphereLayout::paper_training();
        assert_eq!(
            layout.cameras(k, Vec3::ZERO, 3).unwrap(),
            layout.cameras(k, Vec3::ZERO, 3).unwrap()
        );
        assert_ne!(
            layout.cameras(k, Vec3::ZERO, 3).unwrap(),
            layout.cameras(k, Vec3::ZERO, 4).unwrap()
        );
    }

    #[test]
    fn bad_layouts_are_rejected() {
        let k = Intrinsics::phoxi_s();
        let bad = HemisphereLayout {
            min_elevation_rad: 1.0,
            max_elevation_rad: 0.5,
            ..HemisphereLayout::paper_training()
        };
        assert!(bad.cameras(k, Vec3::ZERO, 0).is_err());
        let none = HemisphereLayout {
            count: 0,
            ..HemisphereLayout::paper_training()
        };
        assert!(none.cameras(k, Vec3::ZERO, 0).is_err());
    }
}
