//! Boxes: rounded cuboids of varied proportions, some with an overhanging lid.

use parry3d::math::Vec3;
use serde::Serialize;

use crate::error::Result;
use crate::objects::sampling::Sampler;
use crate::objects::sdf::Sdf;

/// The shape parameters of a box (metres).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BoxParams {
    /// Length along x, 50-200 mm.
    pub length_m: f32,
    /// Width along y (the grasp width), 30-68 mm.
    pub width_m: f32,
    /// Height along z, 20-150 mm.
    pub height_m: f32,
    /// Radius of the rounded edges, 2-8 mm (at most 30 % of the smallest side).
    pub rounding_m: f32,
    /// Height of the lid, 0 (no lid, 60 %) or 8-20 mm.
    pub lid_height_m: f32,
    /// How far the lid overhangs the sides, 1.5-3 mm.
    pub lid_overhang_m: f32,
}

pub(crate) fn sample(s: &mut Sampler) -> BoxParams {
    let length_m = s.length_m(0.05, 0.2);
    let width_m = s.length_m(0.03, 0.068);
    let height_m = s.length_m(0.02, 0.15);
    let smallest = length_m.min(width_m).min(height_m);
    let rounding_m = s.length_m(0.002, 0.008f32.min(0.3 * smallest));
    let lid = s.chance(0.4) && height_m > 0.04;
    BoxParams {
        length_m,
        width_m,
        height_m,
        rounding_m,
        lid_height_m: if lid {
            s.length_m(0.008, 0.02f32.min(0.4 * height_m))
        } else {
            0.0
        },
        lid_overhang_m: s.length_m(0.0015, 0.003),
    }
}

pub(crate) fn build(p: &BoxParams) -> Result<Sdf> {
    let half = Vec3::new(p.length_m, p.width_m, p.height_m) * 0.5;
    let body = Sdf::rounded_box(Vec3::new(0.0, 0.0, half.z), half, p.rounding_m);
    if p.lid_height_m <= 0.0 {
        return Ok(body);
    }
    let o = p.lid_overhang_m;
    let lid_half = Vec3::new(half.x + o, half.y + o, 0.5 * p.lid_height_m);
    let lid = Sdf::rounded_box(
        Vec3::new(0.0, 0.0, p.height_m - lid_half.z),
        lid_half,
        p.rounding_m.min(0.45 * p.lid_height_m),
    );
    Ok(body.union(lid))
}
