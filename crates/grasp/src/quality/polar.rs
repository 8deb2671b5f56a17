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
//! balancing a line outside a cone) boundedness is decided exactly from the same structure:
//! `P` is unbounded iff its recession cone `C = {d : W d <= 0}` is not `{0}`, i.e. iff the
//! rows do not have rank 6 (`C` holds a line) or `C` has an extreme ray. An extreme ray has
//! active rows of rank 5, and the rows active at a direction of `C` follow the same per-part
//! patterns as at a vertex of `P` (each contact's `{g : f_j . g <= 0}` is a cone with its apex
//! at 0 and the same faces); so solving every pattern with at least five equations for its
//! one-dimensional null space, and checking both senses against every row, finds a ray when
//! there is one. Unbounded means epsilon 0.
//!
//! This replaced qhull (a general hull, as the fallback and the reference) and is tested
//! against 400 of its results on real contact pairs (`tests/fixtures/qhull_epsilons.json`,
//! written by `examples/qhull_fixture.rs` at commit be65717, while the crate still linked
//! qhull), and against the brute-force hull of [`crate::quality::wrench_set_epsilon`].

use glam::DVec3;
use mvgrasp_geometry::Vec3;

use crate::quality::contacts::ContactPair;
use crate::quality::wrench::{WRENCH_DIM, WrenchParams};

/// A constraint row `a . y <= b` (or an equation), `[a, b]`.
pub(crate) type Row = [f64; WRENCH_DIM + 1];

/// Pivots below this are taken as a rank deficiency.
const PIVOT_TOLERANCE: f64 = 1e-12;

/// Slack of the feasibility check `w . y <= 1`.
const FEASIBILITY_TOLERANCE: f64 = 1e-9;

/// Slack of the ray check `w . d <= 0` for a unit direction `d`, relative to the largest
/// wrench's norm. A direction `d` with every `w . d <= delta` bounds epsilon by `delta`
/// (epsilon is the minimum over unit directions of the largest `w . d`), so this declares 0
/// only epsilons under 1e-7 of the largest wrench: the threshold under which the brute-force
/// reference (and qhull before it) reads 0 too.
const RAY_TOLERANCE: f64 = 1e-7;

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

/// Ferrari-Canny epsilon of the two contacts' wrench set: 0 without soft fingers or normal
/// force, when the origin is not strictly inside the hull, or for non-finite input.
pub(crate) fn two_contact_epsilon(
    center_of_mass: Vec3,
    torque_scale_m: f32,
    contacts: &ContactPair,
    friction_coef: f32,
    params: &WrenchParams,
) -> f64 {
    let k = params.num_cone_faces;
    let mu = f64::from(friction_coef);
    let inv_scale = 1.0 / f64::from(torque_scale_m).max(f64::MIN_POSITIVE);
    let tau = params.torsion_per_newton(friction_coef) * inv_scale;
    if k < 3 || !mu.is_finite() {
        return 0.0;
    }
    if !params.soft_fingers || tau.is_nan() || tau <= 0.0 {
        // Two point contacts cannot resist a torque about the line through them.
        return 0.0;
    }
    let com = center_of_mass.as_dvec3();
    let mut parts = Vec::with_capacity(2);
    let mut inside_both_cones = true;
    for (contact, push) in contacts.contacts.iter().zip(contacts.push_directions()) {
        let inward = contact.inward_normal();
        let share = f64::from(push.dot(inward));
        if share.is_nan() || share <= 0.0 {
            return 0.0;
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
        // Outside, the origin may still be inside the hull (torsion about non-parallel
        // normals can balance a line outside a cone), but the polar may be unbounded.
        inside_both_cones &= inside;
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
    if parts
        .iter()
        .flat_map(|part| part.rows())
        .any(|row| !row.iter().all(|x| x.is_finite()))
    {
        return 0.0;
    }
    let patterns: Vec<ConePattern> = std::iter::once(ConePattern::None)
        .chain((0..k).map(ConePattern::Single))
        .chain((0..k).map(ConePattern::Adjacent))
        .chain(std::iter::once(ConePattern::Apex))
        .collect();
    if !inside_both_cones && polar_is_unbounded(&parts, &patterns, k) {
        return 0.0;
    }
    largest_vertex_epsilon(&parts, &patterns, k)
}

impl ContactRows {
    /// Every inequality row: the cone edges and both torsions.
    fn rows(&self) -> impl Iterator<Item = &Row> {
        self.cone.iter().chain(&self.torsion)
    }
}

/// `1 / max |y|` over the vertices of the polar of the two contacts' rows (which must be
/// bounded), or 0 when no vertex was found.
fn largest_vertex_epsilon(parts: &[ContactRows], patterns: &[ConePattern], k: usize) -> f64 {
    let [a, b] = [&parts[0], &parts[1]];
    let mut best = 0.0f64;
    let mut system: Vec<Row> = Vec::with_capacity(8);
    for &pa in patterns {
        for &pb in patterns {
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
                    if norm2 > best && feasible(&y, parts) {
                        best = norm2;
                    }
                }
            }
        }
    }
    if best > 0.0 && best.is_finite() {
        1.0 / best.sqrt()
    } else {
        0.0
    }
}

/// Whether the polar `{y : W y <= 1}` is unbounded (the origin not strictly inside the hull):
/// the rows have rank under 6, or some pattern of at least five active rows has a
/// one-dimensional null space whose direction, in one sense, keeps every row `<= 0`.
fn polar_is_unbounded(parts: &[ContactRows], patterns: &[ConePattern], k: usize) -> bool {
    let mut all: Vec<Row> = parts.iter().flat_map(|p| p.rows()).copied().collect();
    if echelon(&mut all).1 < WRENCH_DIM {
        return true;
    }
    let scale = parts
        .iter()
        .flat_map(|p| p.rows())
        .map(|row| row[..WRENCH_DIM].iter().map(|x| x * x).sum::<f64>())
        .fold(0.0, f64::max)
        .sqrt();
    let slack = RAY_TOLERANCE * scale;
    let [a, b] = [&parts[0], &parts[1]];
    let mut system: Vec<Row> = Vec::with_capacity(8);
    for &pa in patterns {
        for &pb in patterns {
            let cone_equations = pa.equations() + pb.equations();
            // At most one torsion row of a contact is active (both only where it is 0 = 0,
            // which adds nothing to the rank).
            for ta in 0..2 {
                for tb in 0..2 {
                    if cone_equations + ta + tb < WRENCH_DIM - 1 {
                        continue;
                    }
                    system.clear();
                    push_pattern(&mut system, a, pa, ta, k);
                    push_pattern(&mut system, b, pb, tb, k);
                    let Some(d) = null_direction(&mut system) else {
                        continue;
                    };
                    for sign in [1.0, -1.0] {
                        let ray = d.map(|x| sign * x);
                        let is_ray = parts
                            .iter()
                            .flat_map(|p| p.rows())
                            .all(|row| lhs_dot(row, &ray) <= slack);
                        if is_ray {
                            return true;
                        }
                    }
                }
            }
        }
    }
    false
}

/// `a . y` over the left-hand side of the row `a`.
fn lhs_dot(row: &Row, y: &[f64; WRENCH_DIM]) -> f64 {
    row[..WRENCH_DIM].iter().zip(y).map(|(a, b)| a * b).sum()
}

/// Row-reduces `rows` in place (partial pivoting, columns in order; the right-hand sides are
/// carried along) and returns the pivot column of each of the first `rank` rows, and `rank`.
/// Pivots at or below [`PIVOT_TOLERANCE`] count as zero.
fn echelon(rows: &mut [Row]) -> ([usize; WRENCH_DIM], usize) {
    let mut pivots = [0; WRENCH_DIM];
    let mut r = 0;
    for col in 0..WRENCH_DIM {
        if r == rows.len() {
            break;
        }
        let Some(pivot) =
            (r..rows.len()).max_by(|&i, &j| rows[i][col].abs().total_cmp(&rows[j][col].abs()))
        else {
            break;
        };
        if rows[pivot][col].abs() <= PIVOT_TOLERANCE {
            continue;
        }
        rows.swap(r, pivot);
        let head = rows[r];
        for row in rows.iter_mut().skip(r + 1) {
            let factor = row[col] / head[col];
            if factor != 0.0 {
                for (x, h) in row.iter_mut().zip(head.iter()).skip(col) {
                    *x -= factor * h;
                }
            }
        }
        pivots[r] = col;
        r += 1;
    }
    (pivots, r)
}

/// The unit direction spanning the null space of the left-hand sides of `rows` when it is
/// one-dimensional (rank exactly 5), else `None`.
pub(crate) fn null_direction(rows: &mut [Row]) -> Option<[f64; WRENCH_DIM]> {
    let (pivots, rank) = echelon(rows);
    if rank != WRENCH_DIM - 1 {
        return None;
    }
    let pivots = &pivots[..rank];
    let free = (0..WRENCH_DIM).find(|c| !pivots.contains(c))?;
    let mut d = [0.0; WRENCH_DIM];
    d[free] = 1.0;
    for (r, &col) in pivots.iter().enumerate().rev() {
        let row = &rows[r];
        let known: f64 = (col + 1..WRENCH_DIM).map(|i| row[i] * d[i]).sum();
        d[col] = -known / row[col];
    }
    let norm = d.iter().map(|x| x * x).sum::<f64>().sqrt();
    (norm.is_finite() && norm > 0.0).then(|| d.map(|x| x / norm))
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
    parts
        .iter()
        .flat_map(|part| part.rows())
        .all(|row| lhs_dot(row, y) <= row[WRENCH_DIM] + FEASIBILITY_TOLERANCE)
}

/// The unique solution of the equations in `rows` (6 unknowns, 6 to 8 rows), or `None` when
/// they do not have rank 6 or contradict each other. Row-reduced in place ([`echelon`]), then
/// solved back to front.
fn solve(rows: &mut [Row]) -> Option<[f64; WRENCH_DIM]> {
    if echelon(rows).1 < WRENCH_DIM {
        return None;
    }
    // Rank 6: the pivots are the columns in order. Extra equations must be consistent
    // (reduced to 0 = 0).
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
    use crate::quality::ferrari_canny::wrench_set_epsilon;
    use crate::quality::wrench::{TorsionModel, contact_wrenches_at};
    use serde::Deserialize;

    /// One case of `tests/fixtures/qhull_epsilons.json` (written by `examples/qhull_fixture.rs`
    /// at commit be65717).
    #[derive(Deserialize)]
    struct Case {
        center_of_mass: Vec3,
        torque_scale_m: f32,
        contacts: ContactPair,
        friction_coef: f32,
        params: WrenchParams,
        near_cone_edge: bool,
        qhull_epsilon: f64,
    }

    fn cases() -> Vec<Case> {
        let text = include_str!("../../tests/fixtures/qhull_epsilons.json");
        serde_json::from_str(text).unwrap()
    }

    fn epsilon(case: &Case) -> f64 {
        two_contact_epsilon(
            case.center_of_mass,
            case.torque_scale_m,
            &case.contacts,
            case.friction_coef,
            &case.params,
        )
    }

    fn agree(ours: f64, reference: f64) -> bool {
        (ours - reference).abs() <= 1e-7 * reference.max(1e-3)
    }

    /// The exact enumeration against qhull on 400 real contact pairs, half of them drawn near
    /// the friction cone's edge (where the polar may be unbounded and the enumeration used to
    /// hand over to qhull).
    #[test]
    fn polar_vertices_match_the_qhull_fixture() {
        let cases = cases();
        assert_eq!(cases.len(), 400);
        let (mut near_positive, mut near_zero) = (0, 0);
        for case in &cases {
            let ours = epsilon(case);
            assert!(
                agree(ours, case.qhull_epsilon),
                "{ours} vs qhull {} ({:?}, mu {}, {:?})",
                case.qhull_epsilon,
                case.contacts,
                case.friction_coef,
                case.params
            );
            if case.near_cone_edge {
                near_positive += usize::from(case.qhull_epsilon > 0.0);
                near_zero += usize::from(case.qhull_epsilon == 0.0);
            }
        }
        // Both answers occur where the structure alone cannot tell boundedness.
        assert!(
            near_positive > 50 && near_zero > 20,
            "{near_positive} {near_zero}"
        );
    }

    /// Synthetic contact pairs whose closing line lies near or beyond the friction cone's
    /// edge, a quarter with exactly opposite normals (parallel faces: the torsion rows are
    /// dependent), every cone size: the enumeration against the brute-force hull.
    #[test]
    fn polar_vertices_match_the_brute_force_hull_near_the_cone_edge() {
        use crate::quality::contacts::Contact;
        use mvgrasp_geometry::Rot3;
        use rand::{RngExt, SeedableRng};

        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let unit = |rng: &mut rand_chacha::ChaCha8Rng| loop {
            let v = Vec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            );
            if (0.1..1.0).contains(&v.length()) {
                break v.normalize();
            }
        };
        let (mut positive, mut zero) = (0, 0);
        for i in 0..160 {
            let axis = unit(&mut rng);
            let p0 = unit(&mut rng) * rng.random_range(0.0..0.03);
            let width = rng.random_range(0.01..0.08);
            let friction_coef: f32 = rng.random_range(0.1..1.2);
            let tilt = |rng: &mut rand_chacha::ChaCha8Rng, push: Vec3, u: Vec3| {
                let angle = (friction_coef * rng.random_range(0.6..1.05)).atan();
                Rot3::from_axis_angle(push.cross(u).normalize(), angle) * push
            };
            let u0 = unit(&mut rng);
            let n0 = tilt(&mut rng, axis, u0);
            let n1 = if i % 4 == 0 {
                -n0
            } else {
                let u1 = unit(&mut rng);
                tilt(&mut rng, -axis, u1)
            };
            let contacts = ContactPair {
                contacts: [
                    Contact {
                        point: p0,
                        outward_normal: -n0,
                    },
                    Contact {
                        point: p0 + width * axis,
                        outward_normal: -n1,
                    },
                ],
                closing_axis: axis,
                width_m: width,
            };
            let params = WrenchParams {
                num_cone_faces: 3 + i % 6,
                torsion_model: [TorsionModel::UniformPatch, TorsionModel::DexNet][i % 2],
                finger_radius_m: rng.random_range(0.002..0.01),
                ..WrenchParams::default()
            };
            let com = unit(&mut rng) * rng.random_range(0.0..0.02);
            let scale = rng.random_range(0.03..0.07);
            let ours = two_contact_epsilon(com, scale, &contacts, friction_coef, &params);
            let wrenches = contact_wrenches_at(com, scale, &contacts, friction_coef, &params);
            let brute = wrench_set_epsilon(&wrenches);
            assert!(
                agree(ours, brute),
                "case {i}: {ours} vs brute force {brute}"
            );
            positive += usize::from(brute > 0.0);
            zero += usize::from(brute == 0.0);
        }
        assert!(positive > 30 && zero > 30, "{positive} > 0, {zero} = 0");
    }

    /// The brute-force hull agrees with qhull and with the enumeration on a sample.
    #[test]
    fn the_brute_force_hull_matches_the_qhull_fixture() {
        for case in cases().iter().step_by(10) {
            let wrenches = contact_wrenches_at(
                case.center_of_mass,
                case.torque_scale_m,
                &case.contacts,
                case.friction_coef,
                &case.params,
            );
            let brute = wrench_set_epsilon(&wrenches);
            assert!(
                agree(brute, case.qhull_epsilon),
                "{brute} vs qhull {}",
                case.qhull_epsilon
            );
        }
    }
}
