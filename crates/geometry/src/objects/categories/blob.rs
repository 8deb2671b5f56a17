//! Blobs: a smooth union of random spheres, rippled by low-frequency waves.

use parry3d::math::{Rot3, Vec3};
use serde::Serialize;

use crate::error::Result;
use crate::objects::sampling::Sampler;
use crate::objects::sdf::Sdf;

/// One sphere of a blob (metres).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BlobSphere {
    /// Centre.
    pub center_m: [f32; 3],
    /// Radius, 17-24 mm.
    pub radius_m: f32,
}

/// One plane wave added to a blob's distance.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BlobWave {
    /// Wave vector, radians per metre (length 40-120: wavelengths of 5-16 cm).
    pub wave_vector: [f32; 3],
    /// Amplitude, 0-1.2 mm.
    pub amplitude_m: f32,
    /// Phase, radians.
    pub phase_rad: f32,
}

/// The shape parameters of a blob (metres, radians).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BlobParams {
    /// Two to five overlapping spheres, mostly in the x-z plane (y within 4 mm).
    pub spheres: Vec<BlobSphere>,
    /// Size of the fillets between spheres, 8-20 mm.
    pub blend_m: f32,
    /// Three waves.
    pub waves: Vec<BlobWave>,
    /// Rotation about y applied last, radians.
    pub tilt_rad: f32,
}

pub(crate) fn sample(s: &mut Sampler) -> BlobParams {
    // A tree of overlapping spheres, so the blob is one piece: each sphere after the first
    // hangs off an earlier one, 0.45-0.85 of their radii apart (0.6 or more for the second,
    // so the blob is never tiny), in the x-z plane with a little y.
    let n = s.int(2, 5) as usize;
    let mut spheres: Vec<BlobSphere> = Vec::with_capacity(n);
    spheres.push(BlobSphere {
        center_m: [0.0; 3],
        radius_m: s.length_m(0.017, 0.024),
    });
    for i in 1..n {
        let parent = spheres[s.pick(i)].clone();
        let radius_m = s.length_m(0.017, 0.024);
        let spacing = s.uniform(if i == 1 { 0.6 } else { 0.45 }, 0.85);
        let angle = s.uniform(0.0, std::f32::consts::TAU);
        let dist = spacing * (parent.radius_m + radius_m);
        let [px, py, pz] = parent.center_m;
        spheres.push(BlobSphere {
            center_m: [
                round_mm10(px + dist * angle.cos()),
                (py + s.length_m(-0.002, 0.002)).clamp(-0.004, 0.004),
                round_mm10(pz + dist * angle.sin()),
            ],
            radius_m,
        });
    }
    let waves = (0..3)
        .map(|_| {
            let dir = Vec3::new(
                s.uniform(-1.0, 1.0),
                s.uniform(-1.0, 1.0),
                s.uniform(-1.0, 1.0),
            )
            .normalize_or(Vec3::X);
            let k = dir * s.uniform(40.0, 120.0);
            BlobWave {
                wave_vector: [k.x, k.y, k.z].map(|c| (c * 10.0).round() / 10.0),
                amplitude_m: s.length_m(0.0, 0.0012),
                phase_rad: s.ratio(0.0, std::f32::consts::TAU),
            }
        })
        .collect();
    BlobParams {
        spheres,
        blend_m: s.length_m(0.008, 0.02),
        waves,
        tilt_rad: s.ratio(0.0, std::f32::consts::PI),
    }
}

/// `x` rounded to 0.1 mm.
fn round_mm10(x: f32) -> f32 {
    (x * 1e4).round() / 1e4
}

pub(crate) fn build(p: &BlobParams) -> Result<Sdf> {
    let mut blob: Option<Sdf> = None;
    for sphere in &p.spheres {
        let next = Sdf::sphere(Vec3::from_array(sphere.center_m), sphere.radius_m);
        blob = Some(match blob {
            None => next,
            Some(b) => b.smooth_union(next, p.blend_m),
        });
    }
    let Some(blob) = blob else {
        return Ok(Sdf::sphere(Vec3::ZERO, 0.03));
    };
    let waves: Vec<(Vec3, f32, f32)> = p
        .waves
        .iter()
        .map(|w| (Vec3::from_array(w.wave_vector), w.amplitude_m, w.phase_rad))
        .collect();
    let max_abs: f32 = waves.iter().map(|w| w.1).sum();
    let rippled = blob.displace(max_abs, move |q: Vec3| {
        waves
            .iter()
            .map(|(k, a, phase)| a * (k.dot(q) + phase).sin())
            .sum()
    });
    Ok(rippled.rotate_about(Vec3::ZERO, Rot3::from_rotation_y(p.tilt_rad)))
}
