//! Bowls: a shell of revolution with a rounded rim lip and an optional foot ring.

use parry3d::math::Vec3;
use serde::Serialize;

use crate::error::Result;
use crate::objects::profile::revolve;
use crate::objects::sampling::Sampler;
use crate::objects::sdf::Sdf;

/// The shape parameters of a bowl (metres).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BowlParams {
    /// Radius of the rim (wall centre line), 50-85 mm.
    pub rim_radius_m: f32,
    /// Total height, 40-70 mm.
    pub height_m: f32,
    /// Wall thickness, 4.5-6.5 mm.
    pub wall_m: f32,
    /// Radius of the flat bottom as a fraction of the rim radius, 0.3-0.55.
    pub bottom_fraction: f32,
    /// Wall curve exponent: r grows as height^exponent, 0.35 (round) to 0.8 (conical).
    pub wall_exponent: f32,
    /// Extra radius of the rim lip beyond half the wall, 0-2 mm.
    pub lip_m: f32,
    /// Height of the foot ring, 0 (no foot, 30 %) or 4-8 mm.
    pub foot_height_m: f32,
    /// Radius of the foot ring's centre as a fraction of the bottom radius, 0.75-0.95.
    pub foot_fraction: f32,
}

pub(crate) fn sample(s: &mut Sampler) -> BowlParams {
    let foot = s.chance(0.7);
    BowlParams {
        rim_radius_m: s.length_m(0.05, 0.085),
        height_m: s.length_m(0.04, 0.07),
        wall_m: s.length_m(0.0045, 0.0065),
        bottom_fraction: s.ratio(0.3, 0.55),
        wall_exponent: s.ratio(0.35, 0.8),
        lip_m: s.length_m(0.0, 0.002),
        foot_height_m: if foot { s.length_m(0.004, 0.008) } else { 0.0 },
        foot_fraction: s.ratio(0.75, 0.95),
    }
}

pub(crate) fn build(p: &BowlParams) -> Result<Sdf> {
    const N: usize = 40;
    let t = p.wall_m;
    let lip = 0.5 * t + p.lip_m;
    let rim_r = p.rim_radius_m;
    let rb = p.bottom_fraction * rim_r;
    // Mid-surface of the shell: from the bottom plate's centre line to the rim.
    let z0 = p.foot_height_m + 0.5 * t;
    let z_rim = p.height_m - lip;
    let mut pts: Vec<[f32; 2]> = vec![[0.0, z0], [rb, z0]];
    for i in 1..=N {
        // Sample densely near the bottom, where the wall turns fastest.
        let v = i as f32 / N as f32;
        let u = v * v;
        let r = rb + (rim_r - rb) * u.powf(p.wall_exponent);
        pts.push([r, z0 + (z_rim - z0) * u]);
    }
    // Close well above the rim; the cut below removes this lid.
    let z_lid = z_rim + 0.02;
    pts.push([rim_r, z_lid]);
    pts.push([0.0, z_lid]);
    let solid = revolve(&pts)?;
    let cut = Sdf::half_space(Vec3::new(0.0, 0.0, z_rim), Vec3::Z);
    let shell = solid.shell(t).intersect(cut);
    let rim = Sdf::torus(Vec3::new(0.0, 0.0, z_rim), Vec3::Z, rim_r, lip);
    let mut bowl = shell.smooth_union(rim, 0.002);
    if p.foot_height_m > 0.0 {
        let rf = p.foot_fraction * rb;
        let half_w = 0.5 * t;
        let e = 0.0015f32.min(0.4 * half_w);
        let foot = revolve(&[
            [rf - half_w, z0],
            [rf - half_w, e],
            [rf - half_w + e, 0.0],
            [rf + half_w - e, 0.0],
            [rf + half_w, e],
            [rf + half_w, z0],
        ])?;
        bowl = bowl.smooth_union(foot, 0.002);
    }
    Ok(bowl)
}
