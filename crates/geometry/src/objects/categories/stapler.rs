//! Staplers and hole punches: a base, a hinge at the back and a top arm (lever) that opens
//! towards the front.

use parry3d::math::{Rot3, Vec3};
use serde::Serialize;

use crate::error::Result;
use crate::objects::sampling::Sampler;
use crate::objects::sdf::Sdf;

/// Which of the two office tools.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StaplerStyle {
    /// A long base, a round hinge and a domed arm over the whole length.
    Stapler,
    /// A flat base plate, a punch body at the front, a hinge post at the back and a lever.
    HolePunch,
}

/// The shape parameters of a stapler or hole punch (metres, radians; x forward).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StaplerParams {
    /// Stapler or hole punch (60 % staplers).
    pub style: StaplerStyle,
    /// Base length: 100-170 mm (stapler), 90-140 mm (punch).
    pub length_m: f32,
    /// Base width: 30-50 mm (stapler), 50-70 mm (punch).
    pub width_m: f32,
    /// Base thickness: 8-15 mm (stapler), 6-10 mm (punch plate).
    pub base_height_m: f32,
    /// Hinge radius (stapler) or half the hinge post's length (punch), 7-12 mm.
    pub hinge_radius_m: f32,
    /// Arm length as a fraction of the base length, 0.85-0.97.
    pub arm_length_fraction: f32,
    /// Arm width as a fraction of the base width: 0.75-0.95 (stapler), 0.5-0.75 (punch).
    pub arm_width_fraction: f32,
    /// Arm thickness: 12-22 mm (stapler), 8-14 mm (punch lever).
    pub arm_thickness_m: f32,
    /// How far the arm is raised at the front, 0.03-0.18 rad.
    pub arm_angle_rad: f32,
    /// Punch only: body length as a fraction of the base length, 0.4-0.6.
    pub body_length_fraction: f32,
    /// Punch only: body width as a fraction of the base width, 0.6-0.85.
    pub body_width_fraction: f32,
    /// Punch only: body height, 20-35 mm.
    pub body_height_m: f32,
    /// Punch only: gap between the body's top and the lever at the hinge, 4-10 mm.
    pub gap_m: f32,
}

pub(crate) fn sample(s: &mut Sampler) -> StaplerParams {
    let style = if s.chance(0.6) {
        StaplerStyle::Stapler
    } else {
        StaplerStyle::HolePunch
    };
    let punch = style == StaplerStyle::HolePunch;
    let (len, wid, base, arm_w, arm_t) = if punch {
        (
            (0.09, 0.14),
            (0.05, 0.07),
            (0.006, 0.01),
            (0.5, 0.75),
            (0.008, 0.014),
        )
    } else {
        (
            (0.10, 0.17),
            (0.03, 0.05),
            (0.008, 0.015),
            (0.75, 0.95),
            (0.012, 0.022),
        )
    };
    StaplerParams {
        style,
        length_m: s.length_m(len.0, len.1),
        width_m: s.length_m(wid.0, wid.1),
        base_height_m: s.length_m(base.0, base.1),
        hinge_radius_m: s.length_m(0.007, 0.012),
        arm_length_fraction: s.ratio(0.85, 0.97),
        arm_width_fraction: s.ratio(arm_w.0, arm_w.1),
        arm_thickness_m: s.length_m(arm_t.0, arm_t.1),
        arm_angle_rad: s.ratio(0.03, 0.18),
        body_length_fraction: s.ratio(0.4, 0.6),
        body_width_fraction: s.ratio(0.6, 0.85),
        body_height_m: s.length_m(0.02, 0.035),
        gap_m: s.length_m(0.004, 0.01),
    }
}

pub(crate) fn build(p: &StaplerParams) -> Result<Sdf> {
    let (l, w, hb) = (p.length_m, p.width_m, p.base_height_m);
    let base = Sdf::rounded_box(
        Vec3::new(0.0, 0.0, 0.5 * hb),
        Vec3::new(0.5 * l, 0.5 * w, 0.5 * hb),
        0.003f32.min(0.4 * hb),
    );
    let hr = p.hinge_radius_m;
    let x_back = -0.5 * l;
    let arm_len = p.arm_length_fraction * l;
    let arm_w = p.arm_width_fraction * w;
    let ta = p.arm_thickness_m;
    let (pivot, support) = match p.style {
        StaplerStyle::Stapler => {
            // A round hinge sitting on the base at the back.
            let pivot = Vec3::new(x_back + hr, 0.0, hb + hr);
            let half = Vec3::new(0.0, 0.5 * arm_w * 0.8, 0.0);
            let hinge = Sdf::rounded_cylinder(pivot - half, pivot + half, hr, 0.002);
            let block = Sdf::rounded_box(
                Vec3::new(pivot.x, 0.0, hb + 0.5 * hr),
                Vec3::new(hr, 0.4 * arm_w, 0.5 * hr + 0.002),
                0.002,
            );
            (pivot, hinge.union(block))
        }
        StaplerStyle::HolePunch => {
            let bl = p.body_length_fraction * l;
            let hbody = p.body_height_m;
            let body = Sdf::rounded_box(
                Vec3::new(0.5 * l - 0.004 - 0.5 * bl, 0.0, hb + 0.5 * hbody - 0.002),
                Vec3::new(
                    0.5 * bl,
                    0.5 * p.body_width_fraction * w,
                    0.5 * hbody + 0.002,
                ),
                0.004,
            );
            let z_pivot = hb + hbody + p.gap_m;
            let pivot = Vec3::new(x_back + 0.004 + hr, 0.0, z_pivot);
            let post = Sdf::rounded_box(
                Vec3::new(pivot.x, 0.0, 0.5 * (hb + z_pivot)),
                Vec3::new(hr, 0.5 * arm_w, 0.5 * (z_pivot - hb) + 0.002),
                0.003,
            );
            (pivot, body.union(post))
        }
    };
    // The arm starts over the pivot and is raised about it.
    let arm = Sdf::rounded_box(
        Vec3::new(
            pivot.x - 0.5 * hr + 0.5 * arm_len,
            0.0,
            pivot.z + 0.5 * ta - 0.5 * hr,
        ),
        Vec3::new(0.5 * arm_len, 0.5 * arm_w, 0.5 * ta),
        (0.45 * ta).min(0.008),
    )
    .rotate_about(pivot, Rot3::from_rotation_y(-p.arm_angle_rad));
    Ok(base.union(support).smooth_union(arm, 0.003))
}
