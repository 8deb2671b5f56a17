//! Toy cars: a rounded body, a cabin with sloped windscreens, four wheels, sometimes a spoiler.

use parry3d::math::Vec3;
use serde::Serialize;

use crate::error::Result;
use crate::objects::sampling::Sampler;
use crate::objects::sdf::Sdf;

/// The shape parameters of a toy car (metres, angles in radians; x forward, y left).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ToyCarParams {
    /// Body length, 80-160 mm.
    pub length_m: f32,
    /// Body width, 40-62 mm.
    pub width_m: f32,
    /// Body height, 16-30 mm.
    pub body_height_m: f32,
    /// Radius of the body's rounded edges, 3-7 mm.
    pub body_rounding_m: f32,
    /// Wheel radius, 9-16 mm.
    pub wheel_radius_m: f32,
    /// Wheel width, 7-12 mm.
    pub wheel_width_m: f32,
    /// How far the wheels stick out of the body's sides, 0-3 mm.
    pub wheel_protrusion_m: f32,
    /// Distance from the body's ends to the axles, beyond the wheel radius, 4-12 mm.
    pub axle_inset_m: f32,
    /// Height of the body's underside above the ground as a fraction of the wheel radius.
    pub clearance_fraction: f32,
    /// Cabin length as a fraction of the body length, 0.35-0.6.
    pub cabin_length_fraction: f32,
    /// Cabin height as a fraction of the body height, 0.6-1.0.
    pub cabin_height_fraction: f32,
    /// Cabin width as a fraction of the body width, 0.75-0.92.
    pub cabin_width_fraction: f32,
    /// Cabin centre offset along x as a fraction of the body length, -0.15 to 0.1.
    pub cabin_offset_fraction: f32,
    /// Slope of the windscreens from the vertical, 0.25-0.7 rad (less on short, tall cabins).
    pub windscreen_slope_rad: f32,
    /// Whether the car has a rear spoiler (30 %).
    pub spoiler: bool,
}

pub(crate) fn sample(s: &mut Sampler) -> ToyCarParams {
    let mut p = ToyCarParams {
        length_m: s.length_m(0.08, 0.16),
        width_m: s.length_m(0.04, 0.062),
        body_height_m: s.length_m(0.016, 0.03),
        body_rounding_m: s.length_m(0.003, 0.007),
        wheel_radius_m: s.length_m(0.009, 0.016),
        wheel_width_m: s.length_m(0.007, 0.012),
        wheel_protrusion_m: s.length_m(0.0, 0.003),
        axle_inset_m: s.length_m(0.004, 0.012),
        clearance_fraction: s.ratio(0.5, 0.8),
        cabin_length_fraction: s.ratio(0.35, 0.6),
        cabin_height_fraction: s.ratio(0.6, 1.0),
        cabin_width_fraction: s.ratio(0.75, 0.92),
        cabin_offset_fraction: s.ratio(-0.15, 0.1),
        windscreen_slope_rad: s.ratio(0.25, 0.7),
        spoiler: s.chance(0.3),
    };
    // Keep at least 30 % of the cabin's length as a roof.
    let hc = p.cabin_height_fraction * p.body_height_m;
    let lc = p.cabin_length_fraction * p.length_m;
    let steepest = (0.35 * lc / hc).atan();
    p.windscreen_slope_rad = p.windscreen_slope_rad.min((steepest * 1e3).floor() / 1e3);
    p
}

pub(crate) fn build(p: &ToyCarParams) -> Result<Sdf> {
    let (l, w, hb) = (p.length_m, p.width_m, p.body_height_m);
    let wr = p.wheel_radius_m;
    let z_body = p.clearance_fraction * wr;
    let body = Sdf::rounded_box(
        Vec3::new(0.0, 0.0, z_body + 0.5 * hb),
        Vec3::new(0.5 * l, 0.5 * w, 0.5 * hb),
        p.body_rounding_m,
    );
    // Cabin: a rounded box on the body, with its front and back cut by sloped planes.
    let hc = p.cabin_height_fraction * hb;
    let lc = p.cabin_length_fraction * l;
    let xc = p.cabin_offset_fraction * l;
    let z_top = z_body + hb;
    let cabin_box = Sdf::rounded_box(
        Vec3::new(xc, 0.0, z_top + 0.5 * hc - 0.004),
        Vec3::new(0.5 * lc, 0.5 * p.cabin_width_fraction * w, 0.5 * hc + 0.004),
        (0.35 * hc).min(0.006),
    );
    let (sin, cos) = p.windscreen_slope_rad.sin_cos();
    let front = Sdf::half_space(
        Vec3::new(xc + 0.5 * lc, 0.0, z_top),
        Vec3::new(cos, 0.0, sin),
    );
    let back = Sdf::half_space(
        Vec3::new(xc - 0.5 * lc, 0.0, z_top),
        Vec3::new(-cos, 0.0, sin),
    );
    let cabin = cabin_box.intersect(front).intersect(back);
    let mut car = body.smooth_union(cabin, 0.004);
    if p.spoiler {
        let x = -0.5 * l + 0.012;
        let post = Sdf::rounded_box(
            Vec3::new(x, 0.0, z_top + 0.006),
            Vec3::new(0.004, 0.004, 0.007),
            0.0015,
        );
        let wing = Sdf::rounded_box(
            Vec3::new(x - 0.002, 0.0, z_top + 0.0135),
            Vec3::new(0.009, 0.42 * w, 0.003),
            0.0015,
        );
        car = car.smooth_union(post.union(wing), 0.002);
    }
    let wx = 0.5 * l - wr - p.axle_inset_m;
    let wy = 0.5 * w + p.wheel_protrusion_m - 0.5 * p.wheel_width_m;
    let ww = p.wheel_width_m;
    for (sx, sy) in [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)] {
        let c = Vec3::new(sx * wx, sy * wy, wr);
        let half = Vec3::new(0.0, 0.5 * ww, 0.0);
        let wheel = Sdf::rounded_cylinder(c - half, c + half, wr, 0.002);
        car = car.union(wheel);
    }
    Ok(car)
}
