//! Ferrari-Canny epsilon of a two-contact soft-finger wrench set without a general hull: the
//! vertices of the polar polytope, enumerated from the set's structure.
//!
//! Epsilon is the distance from the origin to the nearest facet of `conv(W)`. When the origin
//! is inside, the polar `P = {y : w . y <= 1 for all w in W}` is bounded and its vertices are
//! the facets `y . w = 1` of the hull, at distance `1 / |y|`; so epsilon is `1 / max |y|` over
//! the vertices of `P`.
//!
//! For one contact, every cone wrench is `w = (f, r x f / L)`, so `w . y = f . g(y)` with
//! `g(y) = y_f + y_t x r / L` in 3-D; the cone edges `s (n + mu e_j)` make `{g : f_j . g <= 1}`
//! a cone with apex `n / s` whose faces are: one constraint, two *adjacent* constraints, or
//! all of them (the apex, three independent equations). A torsion pair `+-s tau (0, n)` has at
//! most one side active. A vertex of `P` is the unique solution of all its active constraints,
//! so solving every combination of these per-part patterns with at least six equations finds
//! every vertex (about 460 small systems for 8 facets).
//!
//! The enumeration needs `P` bounded, i.e. the origin inside `conv(W)`. That holds when the
//! closing line lies strictly inside both linearised cones (for `g0` in the first polar cone
//! `g0 . a < 0`, for `g1` in the second `g1 . a > 0`, and `g1 - g0` is normal to the axis
//! `a`, so no direction has every `w . d <= 0`), which is tested first. Otherwise (a line in
//! the circular cone but outside the inscribed polygon, or torsion about non-parallel normals
//! balancing a line outside a cone) the caller falls back to qhull
//! ([`crate::quality::wrench_set_epsilon`]), the reference this is tested against; qhull is
//! 10-20 times slower on these degenerate sets.

use glam::DVec3;
use mvgrasp_geometry::Vec3;

use crate::quality::contacts::ContactPair;
use crate::quality::wrench::{WRENCH_DIM, WrenchParams};

/// A constraint row `a . y <= b` (or an equation), `[a, b]`.
type Row = [f64; WRENCH_DIM + 1];

/// Pivots below this are taken as a rank deficiency.
const PIVOT_TOLERANCE: f64 = 1e-12;

/// Slack of the feasibility check `w . y <= 1`.
const FEASIBILITY_TOLERANCE: f64 = 1e-9;

/// One contact's constraint rows.
struct ContactRows {
    /// Cone edges, `w_j . y <= 1`.
    cone: Vec<Row>,
    /// The apex of the cone in `g`: `g . n = 1 / s`, `g . t1 = 0`, `g . t2 = 0`.
    apex: [Row; 3],
    /// Torsion of either sense, `+-s tau n . y_t <= 1`.
    torsion: [Row; 2],
}

/// Which of a contact's cone constraints a system takes.
#[derive(Clone, Copy)]
enum ConePattern {
    None,
    Single(usize),
    Adjacent(usize),
    Apex,
}

impl ConePattern {
    fn equations(self) -> usize {
        match self {
            Self::None => 0,
            Self::Single(_) => 1,
            Self::Adjacent(_) => 2,
            Self::Apex => 3,
        }
    }
}

/// Epsilon of the two contacts (0 without soft fingers or normal force), or `None` when the
/// closing line is not strictly inside both linearised cones or no vertex was found
/// (numerical trouble): the caller then falls back to qhull.
pub(crate) fn two_contact_epsilon(
    center_of_mass: Vec3,
    torque_scale_m: f32,
    contacts: &ContactPair,
    friction_coef: f32,
    params: &WrenchParams,
) -> Option<f64> {
    let k = params.num_cone_faces;
    let mu = f64::from(friction_coef);
    let inv_scale = 1.0 / f64::from(torque_scale_m).max(f64::MIN_POSITIVE);
    let tau = params.torsion_per_newton(friction_coef) * inv_scale;
    if k < 3 {
        return None;
    }
    if !params.soft_fingers || tau.is_nan() || tau <= 0.0 {
        // Two point contacts cannot resist a torque about the line through them.
        return Some(0.0);
    }
    let com = center_of_mass.as_dvec3();
    let mut parts = Vec::with_capacity(2);
    for (contact, push) in contacts.contacts.iter().zip(contacts.push_directions()) {
        let inward = contact.inward_normal();
        let share = f64::from(push.dot(inward));
        if share.is_nan() || share <= 0.0 {
            return Some(0.0);
        }
        let (t1, t2) = inward.any_orthonormal_pair();
        let (n, t1, t2) = (inward.as_dvec3(), t1.as_dvec3(), t2.as_dvec3());
        // Strictly inside the linearised cone: the push's tangential part, per unit normal
        // part, inside the regular k-gon of circumradius mu.
        let d = push.as_dvec3();
        let (p1, p2) = (d.dot(t1) / share, d.dot(t2) / share);
        let inradius = mu * (std::f64::consts::PI / k as f64).cos();
        let inside = (0..k).all(|m| {
            let angle = std::f64::consts::PI * (2 * m + 1) as f64 / k as f64;
            p1 * angle.cos() + p2 * angle.sin() < inradius
        });
        if !inside {
            // The origin may still be inside (torsion about non-parallel normals can balance
            // a line outside a cone), but the polar may be unbounded: leave it to qhull.
            return None;
        }
        let arm = contact.point.as_dvec3() - com;
        let wrench_row = |v: DVec3, scale: f64, rhs: f64| -> Row {
            let f = scale * v;
            let t = arm.cross(f) * inv_scale;
            [f.x, f.y, f.z, t.x, t.y, t.z, rhs]
        };
        let cone = (0..k)
            .map(|j| {
                let (sin, cos) = (std::f64::consts::TAU * j as f64 / k as f64).sin_cos();
                wrench_row(n + mu * (cos * t1 + sin * t2), share, 1.0)
            })
            .collect();
        let apex = [
            wrench_row(n, 1.0, 1.0 / share),
            wrench_row(t1, 1.0, 0.0),
            wrench_row(t2, 1.0, 0.0),
        ];
        let torsion = [1.0, -1.0].map(|sign| {
            let m = n * (sign * share * tau);
            [0.0, 0.0, 0.0, m.x, m.y, m.z, 1.0]
        });
        parts.push(ContactRows {
            cone,
            apex,
            torsion,
        });
    }
    let [a, b] = [&parts[0], &parts[1]];
    let patterns: Vec<ConePattern> = std::iter::once(ConePattern::None)
        .chain((0..k).map(ConePattern::Single))
        .chain((0..k).map(ConePattern::Adjacent))
        .chain(std::iter::once(ConePattern::Apex))
        .collect();
    let mut best = 0.0f64;
    let mut system: Vec<Row> = Vec::with_capacity(8);
    for &pa in &patterns {
        for &pb in &patterns {
            let cone_equations = pa.equations() + pb.equations();
            if cone_equations + 2 < WRENCH_DIM {
                continue;
            }
            for ta in 0..3 {
                for tb in 0..3 {
                    let equations = cone_equations + usize::from(ta > 0) + usize::from(tb > 0);
                    if equations < WRENCH_DIM {
                        continue;
                    }
                    system.clear();
                    push_pattern(&mut system, a, pa, ta, k);
                    push_pattern(&mut system, b, pb, tb, k);
                    let Some(y) = solve(&mut system) else {
                        continue;
                    };
                    let norm2: f64 = y.iter().map(|v| v * v).sum();
                    if norm2 > best && feasible(&y, &parts) {
                        best = norm2;
                    }
                }
            }
        }
    }
    (best > 0.0 && best.is_finite()).then(|| 1.0 / best.sqrt())
}

fn push_pattern(
    system: &mut Vec<Row>,
    part: &ContactRows,
    cone: ConePattern,
    torsion: usize,
    k: usize,
) {
    match cone {
        ConePattern::None => {}
        ConePattern::Single(j) => system.push(part.cone[j]),
        ConePattern::Adjacent(j) => {
            system.push(part.cone[j]);
            system.push(part.cone[(j + 1) % k]);
        }
        ConePattern::Apex => system.extend_from_slice(&part.apex),
    }
    if torsion > 0 {
        system.push(part.torsion[torsion - 1]);
    }
}

/// Whether `y` satisfies every constraint of both contacts.
fn feasible(y: &[f64; WRENCH_DIM], parts: &[ContactRows]) -> bool {
    let ok = |row: &Row| {
        let value: f64 = row[..WRENCH_DIM].iter().zip(y).map(|(a, b)| a * b).sum();
        value <= row[WRENCH_DIM] + FEASIBILITY_TOLERANCE
    };
    parts
        .iter()
        .all(|part| part.cone.iter().all(ok) && part.torsion.iter().all(ok))
}

/// The unique solution of the equations in `rows` (6 unknowns, 6 to 8 rows), or `None` when
/// they do not have rank 6 or contradict each other. Gaussian elimination with partial
/// pivoting, in place.
fn solve(rows: &mut [Row]) -> Option<[f64; WRENCH_DIM]> {
    let m = rows.len();
    for col in 0..WRENCH_DIM {
        let pivot = (col..m).max_by(|&i, &j| rows[i][col].abs().total_cmp(&rows[j][col].abs()))?;
        if rows[pivot][col].abs() <= PIVOT_TOLERANCE {
            return None;
        }
        rows.swap(col, pivot);
        let head = rows[col];
        for row in rows.iter_mut().skip(col + 1) {
            let factor = row[col] / head[col];
            if factor != 0.0 {
                for (x, h) in row.iter_mut().zip(head.iter()).skip(col) {
                    *x -= factor * h;
                }
            }
        }
    }
    // Extra equations must be consistent (reduced to 0 = 0).
    if rows[WRENCH_DIM..]
        .iter()
        .any(|row| row[WRENCH_DIM].abs() > 1e-9)
    {
        return None;
    }
    let mut y = [0.0; WRENCH_DIM];
    for col in (0..WRENCH_DIM).rev() {
        let row = &rows[col];
        let known: f64 = (col + 1..WRENCH_DIM).map(|i| row[i] * y[i]).sum();
        y[col] = (row[WRENCH_DIM] - known) / row[col];
    }
    y.iter().all(|v| v.is_finite()).then_some(y)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gripper::Gripper;
    use crate::object::GraspObject;
    use crate::quality::contacts::find_contacts;
    use crate::quality::ferrari_canny::wrench_set_epsilon;
    use crate::quality::wrench::{TorsionModel, contact_wrenches};
    use mvgrasp_geometry::{Mat3, Pose3, Rot3, TriangleMesh};
    use parry3d::shape::{Ball, Cuboid};

    /// Random closing lines near the centre; the polar enumeration must match qhull.
    #[test]
    fn polar_vertices_match_the_qhull_reference() {
        let objects = [
            {
                let (v, t) = Cuboid::new(Vec3::new(0.02, 0.03, 0.025)).to_trimesh();
                GraspObject::new(TriangleMesh::new(v, t).unwrap()).unwrap()
            },
            {
                let (v, t) = Ball::new(0.03).to_trimesh(12, 12);
                GraspObject::new(TriangleMesh::new(v, t).unwrap()).unwrap()
            },
        ];
        let gripper = Gripper::default();
        let mut state = 12345u64;
        let mut uniform = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 11) as f64 / (1u64 << 53) as f64) as f32 * 2.0 - 1.0
        };
        let (mut compared, mut positive) = (0, 0);
        for object in &objects {
            for i in 0..300 {
                let axis = Vec3::new(uniform(), 0.3 * uniform(), 0.3 * uniform()).normalize();
                let (y, z) = axis.any_orthonormal_pair();
                let pose = Pose3::from_parts(
                    Vec3::new(uniform(), uniform(), uniform()) * 0.012,
                    Rot3::from_mat3(&Mat3::from_cols(axis, y, z)),
                );
                let Some(contacts) = find_contacts(object, &pose, &gripper) else {
                    continue;
                };
                let params = WrenchParams {
                    num_cone_faces: [4, 6, 8][i % 3],
                    torsion_model: [TorsionModel::UniformPatch, TorsionModel::DexNet][i % 2],
                    ..WrenchParams::default()
                };
                let mu = 0.3 + 0.5 * (uniform() + 1.0);
                let Some(fast) = two_contact_epsilon(
                    object.center_of_mass(),
                    object.torque_scale_m(),
                    &contacts,
                    mu,
                    &params,
                ) else {
                    continue;
                };
                let wrenches = contact_wrenches(object, &contacts, mu, &params).unwrap();
                let reference = wrench_set_epsilon(&wrenches);
                assert!(
                    (fast - reference).abs() <= 1e-7 * reference.max(1e-3),
                    "{fast} vs qhull {reference} ({contacts:?}, mu {mu}, {params:?})"
                );
                compared += 1;
                positive += usize::from(reference > 0.0);
            }
        }
        assert!(
            compared > 200 && positive > 100,
            "{compared} compared, {positive} > 0"
        );
    }
}
