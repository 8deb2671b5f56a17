//! Cans and cylinders: a can with a bevelled base, a rolled rim and a recessed top, or a plain
//! rounded cylinder (a jar, a tin, a toy block).

use parry3d::math::Vec3;
use serde::Serialize;

use crate::error::Result;
use crate::objects::profile::revolve;
use crate::objects::sampling::Sampler;
use crate::objects::sdf::Sdf;

/// The shape parameters of a can (metres).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CanParams {
    /// Radius, 25-37 mm.
    pub radius_m: f32,
    /// Height, 50-160 mm.
    pub height_m: f32,
    /// Whether it has rims and a recessed top (70 %) or is a plain rounded cylinder.
    pub rimmed: bool,
    /// Plain cylinder: edge rounding, 2-8 mm. Can: rounding of the profile's corners, 1 mm.
    pub rounding_m: f32,
    /// Can: how much the base is bevelled inwards, 3-6 mm.
    pub base_bevel_m: f32,
    /// Can: how much narrower the top rim is than the body, 2-5 mm.
    pub top_inset_m: f32,
    /// Can: radial width of the top rim, 3.5-5 mm.
    pub rim_width_m: f32,
    /// Can: depth of the recessed lid inside the rim, 2-4 mm.
    pub recess_m: f32,
}

pub(crate) fn sample(s: &mut Sampler) -> CanParams {
    let rimmed = s.chance(0.7);
    CanParams {
        radius_m: s.length_m(0.025, 0.037),
        height_m: s.length_m(0.05, 0.16),
        rimmed,
        rounding_m: if rimmed {
            0.001
        } else {
            s.length_m(0.002, 0.008)
        },
        base_bevel_m: s.length_m(0.003, 0.006),
        top_inset_m: s.length_m(0.002, 0.005),
        rim_width_m: s.length_m(0.0035, 0.005),
        recess_m: s.length_m(0.002, 0.004),
    }
}

pub(crate) fn build(p: &CanParams) -> Result<Sdf> {
    let (r, h) = (p.radius_m, p.height_m);
    if !p.rimmed {
        return Ok(Sdf::rounded_cylinder(
            Vec3::ZERO,
            Vec3::new(0.0, 0.0, h),
            r,
            p.rounding_m,
        ));
    }
    // The profile is drawn `rho` inside the final surface, then grown by `rho`.
    let rho = p.rounding_m;
    let (r_in, h_in) = (r - rho, h - rho);
    let bevel_h = 2.0 * p.base_bevel_m;
    let r_top = r_in - p.top_inset_m;
    let neck_h = 2.5 * p.top_inset_m;
    let rim_in = r_top - p.rim_width_m + 2.0 * rho;
    Ok(revolve(&[
        [0.0, rho],
        [r_in - p.base_bevel_m, rho],
        [r_in, rho + bevel_h],
        [r_in, h_in - neck_h],
        [r_top, h_in - 0.3 * neck_h],
        [r_top, h_in],
        [rim_in, h_in],
        [rim_in, h_in - p.recess_m],
        [0.0, h_in - p.recess_m],
    ])?
    .offset(rho))
}
