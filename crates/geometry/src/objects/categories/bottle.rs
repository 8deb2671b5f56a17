//! Bottles: a solid of revolution with body, optional waist, shoulder, neck and cap.

use serde::Serialize;

use crate::error::Result;
use crate::objects::profile::revolve;
use crate::objects::sampling::Sampler;
use crate::objects::sdf::Sdf;

/// The shape parameters of a bottle (metres).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BottleParams {
    /// Radius of the body, 22-36 mm.
    pub body_radius_m: f32,
    /// Height of the cylindrical body, 60-130 mm.
    pub body_height_m: f32,
    /// Height of the shoulder between body and neck, 15-50 mm.
    pub shoulder_height_m: f32,
    /// Superellipse exponent of the shoulder: 1 is a cone, larger is rounder (1-3.5).
    pub shoulder_roundness: f32,
    /// Radius of the neck, 9-15 mm (at most 60 % of the body radius).
    pub neck_radius_m: f32,
    /// Height of the bare neck below the cap, 8-35 mm.
    pub neck_height_m: f32,
    /// Radius of the cap, 1-3 mm more than the neck.
    pub cap_radius_m: f32,
    /// Height of the cap, 10-20 mm.
    pub cap_height_m: f32,
    /// Radius of the rounded bottom edge, 2-6 mm.
    pub base_rounding_m: f32,
    /// Depth of a waist (grip groove) around the body, 0 (none, 40 %) to 15 % of the radius.
    pub waist_depth_m: f32,
    /// Height of the waist's centre as a fraction of the body height.
    pub waist_center: f32,
}

pub(crate) fn sample(s: &mut Sampler) -> BottleParams {
    let body_radius_m = s.length_m(0.022, 0.036);
    let neck_radius_m = s.length_m(0.009, (0.6 * body_radius_m).min(0.015));
    let waist = s.chance(0.6);
    BottleParams {
        body_radius_m,
        body_height_m: s.length_m(0.06, 0.13),
        shoulder_height_m: s.length_m(0.015, 0.05),
        shoulder_roundness: s.ratio(1.0, 3.5),
        neck_radius_m,
        neck_height_m: s.length_m(0.008, 0.035),
        cap_radius_m: neck_radius_m + s.length_m(0.001, 0.003),
        cap_height_m: s.length_m(0.01, 0.02),
        base_rounding_m: s.length_m(0.002, 0.006),
        waist_depth_m: if waist {
            s.length_m(0.0, 0.15 * body_radius_m)
        } else {
            0.0
        },
        waist_center: s.ratio(0.35, 0.65),
    }
}

pub(crate) fn build(p: &BottleParams) -> Result<Sdf> {
    const STEP_M: f32 = 0.002;
    let r = p.body_radius_m;
    let rb = p.base_rounding_m.min(0.5 * r);
    let hb = p.body_height_m;
    let mut pts: Vec<[f32; 2]> = vec![[0.0, 0.0]];
    // Rounded bottom edge: a quarter circle from (r - rb, 0) to (r, rb).
    for i in 0..=6 {
        let a = std::f32::consts::FRAC_PI_2 * (i as f32 / 6.0);
        pts.push([r - rb + rb * a.sin(), rb - rb * a.cos()]);
    }
    // Body with an optional smooth waist.
    let zw = p.waist_center * hb;
    let ww = 0.25 * hb;
    let steps = ((hb - rb) / STEP_M).ceil().max(1.0) as usize;
    for i in 1..=steps {
        let z = rb + (hb - rb) * i as f32 / steps as f32;
        let u = ((z - zw) / ww).clamp(-1.0, 1.0);
        let bump = 0.5 + 0.5 * (std::f32::consts::PI * u).cos();
        pts.push([r - p.waist_depth_m * bump, z]);
    }
    // Shoulder: a superellipse from the body radius down to the neck radius.
    let a = p.shoulder_roundness.max(1.0);
    let hs = p.shoulder_height_m;
    let steps = (hs / STEP_M).ceil().max(2.0) as usize;
    for i in 1..=steps {
        let u = i as f32 / steps as f32;
        let g = (1.0 - u.powf(a)).max(0.0).powf(1.0 / a);
        pts.push([p.neck_radius_m + (r - p.neck_radius_m) * g, hb + hs * u]);
    }
    // Neck, then the cap with a rounded top edge.
    let z_cap = hb + hs + p.neck_height_m;
    let top = z_cap + p.cap_height_m;
    let rc = p.cap_radius_m;
    let edge = 0.0015f32.min(0.3 * p.cap_height_m);
    pts.push([p.neck_radius_m, z_cap]);
    pts.push([rc, z_cap]);
    pts.push([rc, top - edge]);
    pts.push([rc - edge, top]);
    pts.push([0.0, top]);
    revolve(&pts)
}
