//! Solids of revolution: a 2-D profile in the (r, z) half-plane turned about the z axis.

use std::sync::Arc;

use parry3d::math::Vec3;

use super::sdf::Sdf;
use crate::error::{GeometryError, Result};

/// The solid swept by turning a closed polygon of `(r, z)` points (metres, `r >= 0`) about the
/// z axis. The polygon may run along the axis (a solid cap such as a bottle's) or stay clear of
/// it (a ring such as a bowl's foot); edges that lie on the axis are not part of the surface.
///
/// The distance is exact: for a point at radius `r`, the nearest point of the solid's surface
/// lies in the same half-plane.
///
/// # Errors
/// [`GeometryError::InvalidParameter`] when there are fewer than three points, a coordinate is
/// not finite, or a radius is negative.
pub fn revolve(profile: &[[f32; 2]]) -> Result<Sdf> {
    const OP: &str = "revolve profile";
    if profile.len() < 3 {
        return Err(GeometryError::InvalidParameter {
            op: OP,
            name: "points",
            value: profile.len().to_string(),
            expected: "at least 3 (r, z) points",
        });
    }
    if let Some(bad) = profile
        .iter()
        .find(|q| !q[0].is_finite() || !q[1].is_finite() || q[0] < 0.0)
    {
        return Err(GeometryError::InvalidParameter {
            op: OP,
            name: "point",
            value: format!("({}, {})", bad[0], bad[1]),
            expected: "finite coordinates with r >= 0",
        });
    }
    let points: Arc<[[f32; 2]]> = profile.iter().copied().collect();
    let r_max = points.iter().map(|q| q[0]).fold(0.0f32, f32::max);
    let z_min = points.iter().map(|q| q[1]).fold(f32::INFINITY, f32::min);
    let z_max = points
        .iter()
        .map(|q| q[1])
        .fold(f32::NEG_INFINITY, f32::max);
    Ok(Sdf::new(
        Vec3::new(-r_max, -r_max, z_min),
        Vec3::new(r_max, r_max, z_max),
        move |p| {
            let r = (p.x * p.x + p.y * p.y).sqrt();
            polygon_distance(&points, r, p.z)
        },
    ))
}

/// Signed distance from `(r, z)` (with `r >= 0`) to the closed polygon `points` mirrored about
/// the axis: edges on the axis are skipped, so the mirrored half needs no evaluation.
fn polygon_distance(points: &[[f32; 2]], r: f32, z: f32) -> f32 {
    let mut best = f32::INFINITY;
    let mut inside = false;
    let n = points.len();
    for i in 0..n {
        let [ar, az] = points[i];
        let [br, bz] = points[(i + 1) % n];
        // Even-odd rule with a ray towards +r; the mirrored half lies at r <= 0 and is never hit.
        if (az > z) != (bz > z) {
            let r_cross = ar + (z - az) * (br - ar) / (bz - az);
            if r < r_cross {
                inside = !inside;
            }
        }
        if ar == 0.0 && br == 0.0 {
            continue;
        }
        let (er, ez) = (br - ar, bz - az);
        let (wr, wz) = (r - ar, z - az);
        let len2 = er * er + ez * ez;
        let t = if len2 > 0.0 {
            ((wr * er + wz * ez) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let (dr, dz) = (wr - er * t, wz - ez * t);
        best = best.min(dr * dr + dz * dz);
    }
    let d = best.sqrt();
    if inside { -d } else { d }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn revolved_rectangle_is_a_cylinder() {
        let sdf = revolve(&[[0.0, 0.0], [0.03, 0.0], [0.03, 0.1], [0.0, 0.1]]).unwrap();
        let close = |a: f32, b: f32| (a - b).abs() < 1e-6;
        assert!(close(sdf.eval(Vec3::new(0.0, 0.0, 0.05)), -0.03));
        assert!(close(sdf.eval(Vec3::new(0.0, 0.05, 0.05)), 0.02));
        assert!(close(sdf.eval(Vec3::new(0.0, 0.0, 0.13)), 0.03));
        assert!(close(sdf.eval(Vec3::new(0.01, 0.0, 0.095)), -0.005));
        assert!(close(sdf.eval(Vec3::new(-0.01, 0.0, 0.002)), -0.002));
    }

    #[test]
    fn revolved_ring_has_a_hole() {
        let ring = revolve(&[[0.02, 0.0], [0.03, 0.0], [0.03, 0.01], [0.02, 0.01]]).unwrap();
        assert!(ring.eval(Vec3::new(0.0, 0.0, 0.005)) > 0.019);
        assert!(ring.eval(Vec3::new(0.025, 0.0, 0.005)) < 0.0);
    }

    #[test]
    fn bad_profiles_are_rejected() {
        assert!(revolve(&[[0.0, 0.0], [0.1, 0.0]]).is_err());
        assert!(revolve(&[[0.0, 0.0], [-0.1, 0.0], [0.0, 0.1]]).is_err());
        assert!(revolve(&[[0.0, 0.0], [f32::NAN, 0.0], [0.0, 0.1]]).is_err());
    }
}
