//! Signed distance functions (SDFs): primitives and the operations that compose them.
//!
//! Convention: negative inside, positive outside, metres. Every [`Sdf`] carries an axis-aligned
//! box that contains its surface, so the mesher knows where to sample. Primitives are exact
//! distances; unions, intersections and subtractions are bounds (exact outside for unions), and
//! warps and displacements are only approximately distances, which is all the mesher needs: it
//! uses the sign, and the values only to place vertices along grid edges.

use std::fmt;
use std::sync::Arc;

use parry3d::math::{Rot3, Vec3};

type DistanceFn = dyn Fn(Vec3) -> f32 + Send + Sync;

/// A shape given by its signed distance function and a box that bounds its surface.
#[derive(Clone)]
pub struct Sdf {
    f: Arc<DistanceFn>,
    min: Vec3,
    max: Vec3,
}

impl fmt::Debug for Sdf {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Sdf")
            .field("min", &self.min)
            .field("max", &self.max)
            .finish_non_exhaustive()
    }
}

impl Sdf {
    /// A shape from any distance function `f` whose surface lies inside `[min, max]`.
    pub fn new(min: Vec3, max: Vec3, f: impl Fn(Vec3) -> f32 + Send + Sync + 'static) -> Self {
        Self {
            f: Arc::new(f),
            min: min.min(max),
            max: min.max(max),
        }
    }

    /// The signed distance at `p` (metres; negative inside).
    pub fn eval(&self, p: Vec3) -> f32 {
        (self.f)(p)
    }

    /// The box `(min, max)` that contains the surface (infinite for half-spaces).
    pub fn bounds(&self) -> (Vec3, Vec3) {
        (self.min, self.max)
    }

    // ----- primitives -----

    /// A sphere. Negative radii count as zero.
    pub fn sphere(center: Vec3, radius: f32) -> Self {
        let r = radius.max(0.0);
        Self::new(center - r, center + r, move |p| (p - center).length() - r)
    }

    /// An axis-aligned ellipsoid with semi-axes `radii` (an approximate distance, exact on the
    /// surface; Inigo Quilez's bound).
    pub fn ellipsoid(center: Vec3, radii: Vec3) -> Self {
        let r = radii.max(Vec3::splat(1e-6));
        Self::new(center - r, center + r, move |p| {
            let q = p - center;
            let k0 = (q / r).length();
            let k1 = (q / (r * r)).length();
            if k1 <= f32::MIN_POSITIVE {
                -r.min_element()
            } else {
                k0 * (k0 - 1.0) / k1
            }
        })
    }

    /// An axis-aligned box of half extents `half` whose edges are rounded with radius `rounding`
    /// (clamped to the smallest half extent).
    pub fn rounded_box(center: Vec3, half: Vec3, rounding: f32) -> Self {
        let half = half.max(Vec3::ZERO);
        let r = rounding.clamp(0.0, half.min_element());
        let inner = half - r;
        Self::new(center - half, center + half, move |p| {
            let q = (p - center).abs() - inner;
            q.max(Vec3::ZERO).length() + q.max_element().min(0.0) - r
        })
    }

    /// A capsule: all points within `radius` of the segment `a`-`b`.
    pub fn capsule(a: Vec3, b: Vec3, radius: f32) -> Self {
        let r = radius.max(0.0);
        Self::new(a.min(b) - r, a.max(b) + r, move |p| {
            segment_distance(p, a, b) - r
        })
    }

    /// A solid cylinder of `radius` whose flat caps are centred on `a` and `b`.
    pub fn cylinder(a: Vec3, b: Vec3, radius: f32) -> Self {
        let r = radius.max(0.0);
        let ba = b - a;
        let baba = ba.length_squared().max(1e-12);
        Self::new(a.min(b) - r, a.max(b) + r, move |p| {
            // Inigo Quilez's exact capped cylinder between two points.
            let pa = p - a;
            let paba = pa.dot(ba);
            let x = (pa * baba - ba * paba).length() - r * baba;
            let y = (paba - baba * 0.5).abs() - baba * 0.5;
            let x2 = x * x;
            let y2 = y * y * baba;
            let d = if x.max(y) < 0.0 {
                -x2.min(y2)
            } else {
                (if x > 0.0 { x2 } else { 0.0 }) + (if y > 0.0 { y2 } else { 0.0 })
            };
            d.signum() * d.abs().sqrt() / baba
        })
    }

    /// A cylinder from `a` to `b` of `radius` whose cap edges are rounded with `rounding`
    /// (clamped so the shape keeps its length and radius).
    pub fn rounded_cylinder(a: Vec3, b: Vec3, radius: f32, rounding: f32) -> Self {
        let axis = (b - a).normalize_or_zero();
        let half_len = 0.5 * (b - a).length();
        let r = rounding.clamp(0.0, radius.min(half_len).max(0.0));
        Self::cylinder(a + axis * r, b - axis * r, radius - r).offset(r)
    }

    /// A torus around `axis` (any length but zero) through `center`: ring radius `major`, tube
    /// radius `minor`.
    pub fn torus(center: Vec3, axis: Vec3, major: f32, minor: f32) -> Self {
        let n = axis.normalize_or(Vec3::Z);
        let reach = Vec3::splat(major.abs() + minor.abs());
        Self::new(center - reach, center + reach, move |p| {
            let q = p - center;
            let h = q.dot(n);
            let radial = (q - n * h).length();
            ((radial - major).powi(2) + h * h).sqrt() - minor
        })
    }

    /// A tube of `radius` swept along the polyline `points` (a union of capsules, evaluated in one
    /// pass). An empty polyline gives an empty shape far away.
    pub fn tube(points: &[Vec3], radius: f32) -> Self {
        let r = radius.max(0.0);
        let pts: Arc<[Vec3]> = points.iter().copied().collect();
        let (lo, hi) = points.iter().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), v| (lo.min(*v), hi.max(*v)),
        );
        if points.is_empty() {
            return Self::new(Vec3::ZERO, Vec3::ZERO, |_| f32::MAX);
        }
        Self::new(lo - r, hi + r, move |p| {
            let mut best = f32::INFINITY;
            if pts.len() == 1 {
                best = (p - pts[0]).length();
            }
            for w in pts.windows(2) {
                best = best.min(segment_distance(p, w[0], w[1]));
            }
            best - r
        })
    }

    /// The half-space behind the plane through `point` with outward normal `normal`.
    pub fn half_space(point: Vec3, normal: Vec3) -> Self {
        let n = normal.normalize_or(Vec3::Z);
        Self::new(
            Vec3::splat(f32::NEG_INFINITY),
            Vec3::splat(f32::INFINITY),
            move |p| (p - point).dot(n),
        )
    }

    // ----- operations -----

    /// The union of both shapes.
    pub fn union(self, other: Sdf) -> Self {
        let (min, max) = (self.min.min(other.min), self.max.max(other.max));
        Self::new(min, max, move |p| self.eval(p).min(other.eval(p)))
    }

    /// The union of both shapes with a fillet of size `k` (polynomial smooth minimum).
    pub fn smooth_union(self, other: Sdf, k: f32) -> Self {
        let k = k.max(1e-9);
        let (min, max) = (self.min.min(other.min), self.max.max(other.max));
        Self::new(min - 0.25 * k, max + 0.25 * k, move |p| {
            smooth_min(self.eval(p), other.eval(p), k)
        })
    }

    /// The intersection of both shapes.
    pub fn intersect(self, other: Sdf) -> Self {
        let (min, max) = (self.min.max(other.min), self.max.min(other.max));
        Self::new(min, max.max(min), move |p| self.eval(p).max(other.eval(p)))
    }

    /// This shape with `other` cut away.
    pub fn subtract(self, other: Sdf) -> Self {
        let (min, max) = (self.min, self.max);
        Self::new(min, max, move |p| self.eval(p).max(-other.eval(p)))
    }

    /// A hollow skin of total `thickness` centred on this shape's surface.
    pub fn shell(self, thickness: f32) -> Self {
        let h = 0.5 * thickness.max(0.0);
        let (min, max) = (self.min - h, self.max + h);
        Self::new(min, max, move |p| self.eval(p).abs() - h)
    }

    /// The shape grown by `amount` (shrunk where negative), which also rounds convex edges.
    pub fn offset(self, amount: f32) -> Self {
        let grow = amount.max(0.0);
        let (min, max) = (self.min - grow, self.max + grow);
        Self::new(min, max, move |p| self.eval(p) - amount)
    }

    /// The shape moved by `by`.
    pub fn translate(self, by: Vec3) -> Self {
        let (min, max) = (self.min + by, self.max + by);
        Self::new(min, max, move |p| self.eval(p - by))
    }

    /// The shape rotated by `rotation` about `pivot`.
    pub fn rotate_about(self, pivot: Vec3, rotation: Rot3) -> Self {
        let inverse = rotation.inverse();
        let (mut min, mut max) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for corner in 0..8u32 {
            let pick = |bit: u32, lo: f32, hi: f32| if corner & bit == 0 { lo } else { hi };
            let c = Vec3::new(
                pick(1, self.min.x, self.max.x),
                pick(2, self.min.y, self.max.y),
                pick(4, self.min.z, self.max.z),
            );
            let r = pivot + rotation * (c - pivot);
            min = min.min(r);
            max = max.max(r);
        }
        Self::new(min, max, move |p| self.eval(pivot + inverse * (p - pivot)))
    }

    /// The shape with `displacement(p)` added to its distance; `max_abs` bounds
    /// `|displacement|` and grows the box. The result is no longer an exact distance.
    pub fn displace(
        self,
        max_abs: f32,
        displacement: impl Fn(Vec3) -> f32 + Send + Sync + 'static,
    ) -> Self {
        let m = max_abs.abs();
        let (min, max) = (self.min - m, self.max + m);
        Self::new(min, max, move |p| self.eval(p) + displacement(p))
    }

    /// The shape seen through the domain warp `source_from_target` (a point of the result maps
    /// to the point of this shape it copies); `min` and `max` bound the warped surface.
    pub fn warp(
        self,
        min: Vec3,
        max: Vec3,
        source_from_target: impl Fn(Vec3) -> Vec3 + Send + Sync + 'static,
    ) -> Self {
        Self::new(min, max, move |p| self.eval(source_from_target(p)))
    }
}

/// The distance from `p` to the segment `a`-`b`.
pub(crate) fn segment_distance(p: Vec3, a: Vec3, b: Vec3) -> f32 {
    let ab = b - a;
    let len2 = ab.length_squared();
    let t = if len2 > 0.0 {
        ((p - a).dot(ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + ab * t)).length()
}

/// Polynomial smooth minimum with blend size `k` (> 0).
pub(crate) fn smooth_min(a: f32, b: f32, k: f32) -> f32 {
    let h = (k - (a - b).abs()).max(0.0) / k;
    a.min(b) - h * h * k * 0.25
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f32, b: f32) -> bool {
        (a - b).abs() < 1e-5
    }

    #[test]
    fn primitives_are_exact_on_simple_points() {
        let s = Sdf::sphere(Vec3::ZERO, 0.02);
        assert!(close(s.eval(Vec3::new(0.05, 0.0, 0.0)), 0.03));
        assert!(close(s.eval(Vec3::ZERO), -0.02));
        let b = Sdf::rounded_box(Vec3::ZERO, Vec3::new(0.02, 0.03, 0.04), 0.005);
        assert!(close(b.eval(Vec3::new(0.03, 0.0, 0.0)), 0.01));
        assert!(close(b.eval(Vec3::new(0.0, 0.0, -0.05)), 0.01));
        let c = Sdf::cylinder(Vec3::ZERO, Vec3::new(0.0, 0.0, 0.1), 0.02);
        assert!(close(c.eval(Vec3::new(0.05, 0.0, 0.05)), 0.03));
        assert!(close(c.eval(Vec3::new(0.0, 0.0, 0.12)), 0.02));
        assert!(close(c.eval(Vec3::new(0.0, 0.0, 0.05)), -0.02));
        let t = Sdf::torus(Vec3::ZERO, Vec3::Y, 0.03, 0.005);
        assert!(close(t.eval(Vec3::new(0.03, 0.0, 0.0)), -0.005));
        assert!(close(t.eval(Vec3::new(0.0, 0.0, 0.03)), -0.005));
        assert!(close(
            t.eval(Vec3::new(0.0, 0.03, 0.0)),
            0.03 * 2f32.sqrt() - 0.005
        ));
        let tube = Sdf::tube(&[Vec3::ZERO, Vec3::X * 0.1, Vec3::new(0.1, 0.1, 0.0)], 0.01);
        assert!(close(tube.eval(Vec3::new(0.05, 0.0, 0.02)), 0.01));
        assert!(close(tube.eval(Vec3::new(0.12, 0.05, 0.0)), 0.01));
    }

    #[test]
    fn operations_combine_distances() {
        let a = Sdf::sphere(Vec3::ZERO, 0.02);
        let b = Sdf::sphere(Vec3::X * 0.03, 0.02);
        let p = Vec3::new(0.015, 0.0, 0.0);
        assert!(a.clone().union(b.clone()).eval(p) < 0.0);
        assert!(a.clone().intersect(b.clone()).eval(p) < 0.0);
        assert!(a.clone().subtract(b.clone()).eval(p) > 0.0);
        assert!(a.clone().smooth_union(b.clone(), 0.01).eval(p) <= a.clone().union(b).eval(p));
        let moved = a.clone().translate(Vec3::Z * 0.1);
        assert!(close(moved.eval(Vec3::Z * 0.1), -0.02));
        assert!(close(moved.bounds().0.z, 0.08));
        let shell = a.clone().shell(0.004);
        assert!(close(shell.eval(Vec3::ZERO), 0.018));
        let turned = Sdf::rounded_box(Vec3::X * 0.05, Vec3::splat(0.01), 0.0).rotate_about(
            Vec3::ZERO,
            Rot3::from_rotation_z(std::f32::consts::FRAC_PI_2),
        );
        assert!(turned.eval(Vec3::Y * 0.05) < 0.0);
        assert!(turned.eval(Vec3::X * 0.05) > 0.0);
        assert!(turned.bounds().0.y > 0.039 && turned.bounds().1.y < 0.061);
    }
}
