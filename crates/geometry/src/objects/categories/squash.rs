//! Squashes and gourds: a bulb, often a neck or a second bulb, ribs, a slight bend and a stem.

use parry3d::math::Vec3;
use serde::Serialize;

use crate::error::Result;
use crate::objects::sampling::Sampler;
use crate::objects::sdf::Sdf;

/// The overall form of a squash.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SquashStyle {
    /// One oblate, ribbed bulb (acorn squash, small pumpkin).
    Round,
    /// A bulb with a long, thick neck (butternut).
    Butternut,
    /// Two bulbs with a narrow waist (bottle gourd).
    Gourd,
}

/// The shape parameters of a squash (metres, radians).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SquashParams {
    /// Overall form (a third each).
    pub style: SquashStyle,
    /// Radius of the lower bulb, 25-35 mm.
    pub bulb_radius_m: f32,
    /// Half height of the lower bulb: 0.6-0.9 of its radius (round), else 0.8-1.15.
    pub bulb_half_height_m: f32,
    /// Radius of the neck or upper bulb: 0.45-0.65 (butternut) or 0.5-0.8 (gourd) of the bulb
    /// radius; 0 for round squashes.
    pub top_radius_m: f32,
    /// Half length of the neck or upper bulb: 30-60 mm (butternut), 0.9-1.2 of its radius
    /// (gourd); 0 for round squashes.
    pub top_half_length_m: f32,
    /// Size of the fillet between bulb and top, 8-20 mm.
    pub blend_m: f32,
    /// Number of ribs: 6-12 on round squashes, otherwise 0 (70 %) or 6-10.
    pub ribs: u32,
    /// Depth of the ribs' grooves, 1-3 mm.
    pub rib_depth_m: f32,
    /// Sideways offset of the top caused by a bend, 0-15 mm (0 for round squashes).
    pub bend_m: f32,
    /// Length of the stem, 8-22 mm.
    pub stem_length_m: f32,
    /// Radius of the stem, 4-6 mm.
    pub stem_radius_m: f32,
    /// Tilt of the stem from vertical, 0-0.4 rad.
    pub stem_tilt_rad: f32,
    /// How much of the bottom is flattened so it stands, 2-6 mm.
    pub flat_m: f32,
}

pub(crate) fn sample(s: &mut Sampler) -> SquashParams {
    let style = [
        SquashStyle::Round,
        SquashStyle::Butternut,
        SquashStyle::Gourd,
    ][s.pick(3)];
    let r1 = s.length_m(0.025, 0.035);
    let (h_lo, h_hi) = if style == SquashStyle::Round {
        (0.6, 0.9)
    } else {
        (0.8, 1.15)
    };
    let bulb_half_height_m = s.length_m(h_lo * r1, h_hi * r1);
    let (top_radius_m, top_half_length_m) = match style {
        SquashStyle::Round => (0.0, 0.0),
        SquashStyle::Butternut => (s.length_m(0.45 * r1, 0.65 * r1), s.length_m(0.03, 0.06)),
        SquashStyle::Gourd => {
            let r2 = s.length_m(0.5 * r1, 0.8 * r1);
            (r2, s.length_m(0.9 * r2, 1.2 * r2))
        }
    };
    let ribs = if style == SquashStyle::Round {
        s.int(6, 12)
    } else if s.chance(0.3) {
        s.int(6, 10)
    } else {
        0
    };
    SquashParams {
        style,
        bulb_radius_m: r1,
        bulb_half_height_m,
        top_radius_m,
        top_half_length_m,
        blend_m: s.length_m(0.008, 0.02),
        ribs,
        rib_depth_m: s.length_m(0.001, 0.003),
        bend_m: if style == SquashStyle::Round {
            0.0
        } else {
            s.length_m(0.0, 0.015)
        },
        stem_length_m: s.length_m(0.008, 0.022),
        stem_radius_m: s.length_m(0.004, 0.006),
        stem_tilt_rad: s.ratio(0.0, 0.4),
        flat_m: s.length_m(0.002, 0.006),
    }
}

pub(crate) fn build(p: &SquashParams) -> Result<Sdf> {
    let (r1, h1) = (p.bulb_radius_m, p.bulb_half_height_m);
    let bulb = Sdf::ellipsoid(Vec3::new(0.0, 0.0, h1), Vec3::new(r1, r1, h1));
    let (r2, l2) = (p.top_radius_m, p.top_half_length_m);
    let (mut body, z_top) = match p.style {
        SquashStyle::Round => (bulb, 2.0 * h1),
        SquashStyle::Butternut | SquashStyle::Gourd => {
            let z_t = if p.style == SquashStyle::Butternut {
                1.6 * h1 + 0.8 * l2
            } else {
                1.75 * h1 + 0.85 * l2
            };
            let top = Sdf::ellipsoid(Vec3::new(0.0, 0.0, z_t), Vec3::new(r2, r2, l2));
            (bulb.smooth_union(top, p.blend_m), z_t + l2)
        }
    };
    if p.ribs > 0 {
        let (n, depth) = (p.ribs as f32, p.rib_depth_m);
        let fade = 0.5 * r1;
        body = body.displace(depth, move |q: Vec3| {
            let r = (q.x * q.x + q.y * q.y).sqrt();
            let theta = q.y.atan2(q.x);
            depth * (0.5 - 0.5 * (n * theta).cos()) * (r / fade).min(1.0)
        });
    }
    let (sin, cos) = p.stem_tilt_rad.sin_cos();
    let stem_base = Vec3::new(0.0, 0.0, z_top - 0.5 * p.stem_radius_m - p.rib_depth_m);
    let stem_tip = stem_base + Vec3::new(sin, 0.0, cos) * p.stem_length_m;
    let stem = Sdf::capsule(stem_base, stem_tip, p.stem_radius_m);
    let mut squash = body.smooth_union(stem, 0.004);
    let height = stem_tip.z + p.stem_radius_m;
    if p.bend_m > 0.0 && height > 0.0 {
        let bend = p.bend_m;
        let (lo, hi) = squash.bounds();
        squash = squash.warp(lo, hi + Vec3::X * bend, move |q: Vec3| {
            let u = (q.z / height).clamp(0.0, 1.0);
            q - Vec3::X * (bend * u * u)
        });
    }
    let floor = Sdf::half_space(Vec3::new(0.0, 0.0, p.flat_m), -Vec3::Z);
    Ok(squash.intersect(floor))
}
