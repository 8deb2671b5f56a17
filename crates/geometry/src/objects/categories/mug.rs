//! Mugs: a hollow, open-topped, possibly tapered cup with a round, oval or square handle.

use parry3d::math::Vec3;
use serde::Serialize;

use crate::error::Result;
use crate::objects::profile::revolve;
use crate::objects::sampling::Sampler;
use crate::objects::sdf::Sdf;

/// The outline of a mug's handle.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum HandleStyle {
    /// A half circle.
    Round,
    /// A half ellipse, taller than it reaches.
    Oval,
    /// A rounded rectangle ("D" handle).
    Square,
}

/// The shape parameters of a mug (metres).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MugParams {
    /// Outer radius at the bottom, 30-37 mm.
    pub bottom_radius_m: f32,
    /// Outer radius at the rim, within 8 % of the bottom radius and at most 37 mm.
    pub top_radius_m: f32,
    /// Height, 75-110 mm.
    pub height_m: f32,
    /// Wall thickness, 4.5-7 mm.
    pub wall_m: f32,
    /// Thickness of the bottom, 6-12 mm.
    pub bottom_m: f32,
    /// Radius of the rounded rim and bottom edges.
    pub rounding_m: f32,
    /// Handle outline.
    pub handle_style: HandleStyle,
    /// Radius of the handle's round cross-section, 4-6.5 mm.
    pub handle_thickness_m: f32,
    /// Vertical distance between the handle's attachment points (centre lines).
    pub handle_span_m: f32,
    /// How far the handle's centre line reaches out from the wall, 16-30 mm.
    pub handle_reach_m: f32,
    /// Height of the handle's centre.
    pub handle_center_m: f32,
}

pub(crate) fn sample(s: &mut Sampler) -> MugParams {
    let bottom_radius_m = s.length_m(0.030, 0.037);
    let taper = s.ratio(-0.08, 0.08);
    let top_radius_m = (bottom_radius_m * (1.0 + taper)).min(0.037);
    let height_m = s.length_m(0.075, 0.11);
    let wall_m = s.length_m(0.0045, 0.007);
    let handle_thickness_m = s.length_m(0.004, 0.0065);
    let handle_style = [HandleStyle::Round, HandleStyle::Oval, HandleStyle::Square][s.pick(3)];
    let handle_reach_m = s.length_m(0.016, 0.03);
    let span_lo = 0.45 * height_m;
    let span_hi = (0.75 * height_m).min(height_m - 2.0 * handle_thickness_m - 0.012);
    let handle_span_m = match handle_style {
        // A round handle's span is twice its reach.
        HandleStyle::Round => (2.0 * handle_reach_m).clamp(span_lo, span_hi.max(span_lo)),
        HandleStyle::Oval | HandleStyle::Square => s.length_m(span_lo, span_hi.max(span_lo)),
    };
    // Keep the handle between the bottom and 6 mm below the rim.
    let half = 0.5 * handle_span_m + handle_thickness_m;
    let lo = half + 0.004;
    let hi = (height_m - half - 0.006).max(lo);
    let handle_center_m = s.length_m(lo, hi);
    MugParams {
        bottom_radius_m,
        top_radius_m,
        height_m,
        wall_m,
        bottom_m: s.length_m(0.006, 0.012),
        rounding_m: (0.4 * wall_m).min(0.0025),
        handle_style,
        handle_thickness_m,
        handle_span_m,
        handle_reach_m,
        handle_center_m,
    }
}

/// Size of the fillet between handle and body, metres.
const FILLET_M: f32 = 0.003;

pub(crate) fn build(p: &MugParams) -> Result<Sdf> {
    let (r0, r1, h, w, b) = (
        p.bottom_radius_m,
        p.top_radius_m,
        p.height_m,
        p.wall_m,
        p.bottom_m,
    );
    let rho = p.rounding_m.min(0.45 * w);
    // The wall's cross-section shrunk by `rho`, then grown back: rounded rim and edges.
    let inner = |z: f32| r0 + (r1 - r0) * (z / h) - w;
    let body = revolve(&[
        [0.0, rho],
        [r0 - rho, rho],
        [r1 - rho, h - rho],
        [inner(h) + rho, h - rho],
        [inner(b) + rho, b + rho],
        [0.0, b + rho],
    ])?
    .offset(rho);
    // The cavity, grown by more than the fillet so the fillet never bulges into it; the
    // handle's ends still reach into the wall (at least 4.5 mm thick).
    let cavity = revolve(&[
        [0.0, b],
        [inner(b), b],
        [inner(h + 0.02), h + 0.02],
        [0.0, h + 0.02],
    ])?;
    let wall_x = |z: f32| r0 + (r1 - r0) * (z / h) - 0.5 * w;
    let path = handle_path(p, wall_x);
    let handle = Sdf::tube(&path, p.handle_thickness_m).subtract(cavity.offset(FILLET_M + 0.0005));
    Ok(body.smooth_union(handle, FILLET_M))
}

/// The handle's centre line in the x-z plane, from the top attachment to the bottom one.
fn handle_path(p: &MugParams, wall_x: impl Fn(f32) -> f32) -> Vec<Vec3> {
    const N: usize = 24;
    let zc = p.handle_center_m;
    let half = 0.5 * p.handle_span_m;
    let (z_top, z_bot) = (zc + half, zc - half);
    let x_top = wall_x(z_top);
    let x_bot = wall_x(z_bot);
    let x_out = wall_x(zc) + 0.5 * p.wall_m + p.handle_reach_m;
    let mut pts = Vec::with_capacity(N + 3);
    match p.handle_style {
        HandleStyle::Round | HandleStyle::Oval => {
            for i in 0..=N {
                let a = std::f32::consts::PI * (0.5 - i as f32 / N as f32);
                let z = zc + half * a.sin();
                let x0 = wall_x(z);
                pts.push(Vec3::new(x0 + (x_out - x0) * a.cos(), 0.0, z));
            }
        }
        HandleStyle::Square => {
            let c = (0.5 * half).min(0.6 * (x_out - x_top)).max(0.0);
            pts.push(Vec3::new(x_top, 0.0, z_top));
            let quarter = |cx: f32, cz: f32, from: f32, pts: &mut Vec<Vec3>| {
                for i in 0..=6 {
                    let a = from - std::f32::consts::FRAC_PI_2 * (i as f32 / 6.0);
                    pts.push(Vec3::new(cx + c * a.cos(), 0.0, cz + c * a.sin()));
                }
            };
            quarter(x_out - c, z_top - c, std::f32::consts::FRAC_PI_2, &mut pts);
            quarter(x_out - c, z_bot + c, 0.0, &mut pts);
            pts.push(Vec3::new(x_bot, 0.0, z_bot));
        }
    }
    pts
}
