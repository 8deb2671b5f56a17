//! Toy chairs: a seat on four (possibly splayed) legs and a panel or two-post back.

use parry3d::math::{Rot3, Vec3};
use serde::Serialize;

use crate::error::Result;
use crate::objects::sampling::Sampler;
use crate::objects::sdf::Sdf;

/// The back of a toy chair.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ChairBack {
    /// One solid panel.
    Panel,
    /// Two posts continuing the back legs, joined by a top rail and a middle rail.
    Posts,
}

/// The shape parameters of a toy chair (metres, radians; the back is at +y).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ToyChairParams {
    /// Seat width along x, 45-66 mm.
    pub seat_width_m: f32,
    /// Seat depth along y, 45-66 mm.
    pub seat_depth_m: f32,
    /// Seat thickness, 6-11 mm.
    pub seat_thickness_m: f32,
    /// Height of the seat's top above the floor, 35-60 mm.
    pub seat_height_m: f32,
    /// Leg thickness (side or diameter), 6-10 mm.
    pub leg_thickness_m: f32,
    /// Whether the legs are round (40 %) or square.
    pub round_legs: bool,
    /// How far the legs' tops sit in from the seat's edges, 2-6 mm.
    pub leg_inset_m: f32,
    /// Outward splay of the legs, 0-0.07 rad.
    pub leg_splay_rad: f32,
    /// Back style (50 % each).
    pub back: ChairBack,
    /// Height of the back above the seat, 35-65 mm.
    pub back_height_m: f32,
    /// Thickness of the back, 6-10 mm.
    pub back_thickness_m: f32,
    /// Backward tilt of the back, 0-0.2 rad.
    pub back_tilt_rad: f32,
}

pub(crate) fn sample(s: &mut Sampler) -> ToyChairParams {
    ToyChairParams {
        seat_width_m: s.length_m(0.045, 0.066),
        seat_depth_m: s.length_m(0.045, 0.066),
        seat_thickness_m: s.length_m(0.006, 0.011),
        seat_height_m: s.length_m(0.035, 0.06),
        leg_thickness_m: s.length_m(0.006, 0.01),
        round_legs: s.chance(0.4),
        leg_inset_m: s.length_m(0.002, 0.006),
        leg_splay_rad: s.ratio(0.0, 0.07),
        back: if s.chance(0.5) {
            ChairBack::Panel
        } else {
            ChairBack::Posts
        },
        back_height_m: s.length_m(0.035, 0.065),
        back_thickness_m: s.length_m(0.006, 0.01),
        back_tilt_rad: s.ratio(0.0, 0.2),
    }
}

pub(crate) fn build(p: &ToyChairParams) -> Result<Sdf> {
    let (sw, sd, st, sh) = (
        p.seat_width_m,
        p.seat_depth_m,
        p.seat_thickness_m,
        p.seat_height_m,
    );
    let seat = Sdf::rounded_box(
        Vec3::new(0.0, 0.0, sh - 0.5 * st),
        Vec3::new(0.5 * sw, 0.5 * sd, 0.5 * st),
        0.002,
    );
    let lt = p.leg_thickness_m;
    let leg_x = 0.5 * sw - p.leg_inset_m - 0.5 * lt;
    let leg_y = 0.5 * sd - p.leg_inset_m - 0.5 * lt;
    let spread = (sh - st).max(0.0) * p.leg_splay_rad.tan();
    let mut chair = seat;
    for (sx, sy) in [(1.0f32, 1.0f32), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)] {
        // From inside the seat down to just below the floor; the floor cut flattens the feet.
        let top = Vec3::new(sx * leg_x, sy * leg_y, sh - 0.5 * st);
        let foot = Vec3::new(
            sx * (leg_x + spread * std::f32::consts::FRAC_1_SQRT_2),
            sy * (leg_y + spread * std::f32::consts::FRAC_1_SQRT_2),
            -0.003,
        );
        let leg = if p.round_legs {
            Sdf::cylinder(top, foot, 0.5 * lt)
        } else {
            square_leg(top, foot, lt)
        };
        chair = chair.union(leg);
    }
    let back = back(p, leg_x, lt);
    let floor = Sdf::half_space(Vec3::ZERO, -Vec3::Z);
    Ok(chair.smooth_union(back, 0.002).intersect(floor))
}

/// A square leg from `top` to `foot`: a rounded box along z, tilted to join both points.
fn square_leg(top: Vec3, foot: Vec3, side: f32) -> Sdf {
    let axis = top - foot;
    let len = axis.length();
    let mid = 0.5 * (top + foot);
    let upright = Sdf::rounded_box(mid, Vec3::new(0.5 * side, 0.5 * side, 0.5 * len), 0.0015);
    let rotation = Rot3::from_rotation_arc(Vec3::Z, axis.normalize_or(Vec3::Z));
    upright.rotate_about(mid, rotation)
}

/// The back, standing on the seat's +y edge and tilted backwards about it.
fn back(p: &ToyChairParams, leg_x: f32, lt: f32) -> Sdf {
    let (sw, sd, sh) = (p.seat_width_m, p.seat_depth_m, p.seat_height_m);
    let (bh, bt) = (p.back_height_m, p.back_thickness_m);
    let y = 0.5 * sd - 0.5 * bt;
    let bottom = sh - 0.003;
    let shape = match p.back {
        ChairBack::Panel => Sdf::rounded_box(
            Vec3::new(0.0, y, bottom + 0.5 * bh),
            Vec3::new(0.5 * sw, 0.5 * bt, 0.5 * bh),
            0.002,
        ),
        ChairBack::Posts => {
            let post = |x: f32| {
                Sdf::rounded_box(
                    Vec3::new(x, y, bottom + 0.5 * bh),
                    Vec3::new(0.5 * lt, 0.5 * bt, 0.5 * bh),
                    0.0015,
                )
            };
            let rail_h = 0.35 * bh.min(0.03);
            let rail = |z: f32| {
                Sdf::rounded_box(
                    Vec3::new(0.0, y, z),
                    Vec3::new(leg_x + 0.5 * lt, 0.5 * bt, 0.5 * rail_h.max(0.006)),
                    0.0015,
                )
            };
            post(leg_x)
                .union(post(-leg_x))
                .union(rail(sh + bh - 0.5 * rail_h.max(0.006)))
                .union(rail(sh + 0.55 * bh))
        }
    };
    let hinge = Vec3::new(0.0, 0.5 * sd, sh);
    shape.rotate_about(hinge, Rot3::from_rotation_x(-p.back_tilt_rad))
}
