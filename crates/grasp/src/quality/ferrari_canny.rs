//! Ferrari and Canny's epsilon (the L1 "largest ball" metric, Dex-Net's `ferrari_canny_L1`):
//! the distance from the origin of wrench space to the boundary of the convex hull of the
//! contact wrenches, 0 when the origin is not inside.

use crate::error::Result;
use crate::object::GraspObject;
use crate::quality::closure::{closure_holds, validate_friction_coef};
use crate::quality::contacts::ContactPair;
use crate::quality::polar::{null_direction, two_contact_epsilon};
use crate::quality::wrench::{WRENCH_DIM, WrenchParams};

/// Epsilons below this fraction of the largest wrench's norm are roundoff of a flat set, and
/// read 0 ([`wrench_set_epsilon`]).
const RELATIVE_TOLERANCE: f64 = 1e-7;

/// Largest set [`wrench_set_epsilon`] takes: its cost grows as the number of 6-subsets.
pub const MAX_BRUTE_FORCE_WRENCHES: usize = 40;

/// Ferrari-Canny epsilon of a two-contact grasp on `object` (L1: the convex hull of the
/// wrenches of [`crate::quality::contact_wrenches`]).
///
/// Computed exactly from the polar polytope's vertices, which the two-contact structure lets
/// us enumerate directly (module `polar`); tested against qhull's results and against the
/// brute-force hull of [`wrench_set_epsilon`] to about 1e-9.
///
/// Returns 0 without building anything when the contacts are not in force closure
/// ([`crate::quality::force_closure`]): with a jaw's push outside its friction cone Dex-Net
/// scores 0 too (its contact "would slip"), and skipping the enumeration is most of the speed
/// of robust sampling.
///
/// # Errors
/// [`crate::GraspError::InvalidParameter`] for a bad `friction_coef` or `params`.
pub fn ferrari_canny_l1(
    object: &GraspObject,
    contacts: &ContactPair,
    friction_coef: f32,
    params: &WrenchParams,
) -> Result<f64> {
    validate_friction_coef("ferrari-canny", friction_coef)?;
    params.validate()?;
    Ok(epsilon_checked(object, contacts, friction_coef, params))
}

/// [`ferrari_canny_l1`] for checked parameters.
pub(crate) fn epsilon_checked(
    object: &GraspObject,
    contacts: &ContactPair,
    friction_coef: f32,
    params: &WrenchParams,
) -> f64 {
    if !closure_holds(contacts, friction_coef) {
        return 0.0;
    }
    two_contact_epsilon(
        object.center_of_mass(),
        object.torque_scale_m(),
        contacts,
        friction_coef,
        params,
    )
}

/// Epsilon of any small set of 6-D wrenches, by brute force: every 6-subset of affinely
/// independent wrenches spans a hyperplane, which is a facet's when every wrench lies on one
/// side of it and some wrench strictly off it; epsilon is the origin's distance inside the
/// nearest facet, or 0 when the origin is on or outside one.
///
/// The reference the grasp metric is tested against, for sets of a few contacts: it costs
/// `C(n, 6) n` small products (38,760 hyperplanes for the 20 wrenches of a Dex-Net grasp).
/// Sets of fewer than seven or more than [`MAX_BRUTE_FORCE_WRENCHES`] wrenches, flat sets,
/// non-finite wrenches and distances under 1e-7 of the largest wrench's norm (roundoff on a
/// flat set) give 0.
pub fn wrench_set_epsilon(wrenches: &[[f64; WRENCH_DIM]]) -> f64 {
    let n = wrenches.len();
    if !(WRENCH_DIM + 1..=MAX_BRUTE_FORCE_WRENCHES).contains(&n)
        || !wrenches.iter().flatten().all(|x| x.is_finite())
    {
        return 0.0;
    }
    let largest = wrenches
        .iter()
        .map(|w| w.iter().map(|x| x * x).sum::<f64>())
        .fold(0.0, f64::max)
        .sqrt();
    if largest <= 0.0 {
        return 0.0;
    }
    let on_plane = 1e-9 * largest;
    let mut nearest = f64::INFINITY;
    let mut subset: [usize; WRENCH_DIM] = std::array::from_fn(|i| i);
    loop {
        if let Some((normal, offset)) = hyperplane(wrenches, &subset) {
            let (mut above, mut below) = (false, false);
            for w in wrenches {
                let side = dot(&normal, w) - offset;
                above |= side > on_plane;
                below |= side < -on_plane;
            }
            if above != below {
                // A facet: every wrench on one side, some strictly. The origin's signed
                // distance inside it is the offset, outward normal pointing to the empty side.
                let inside = if above { -offset } else { offset };
                if inside <= 0.0 {
                    return 0.0;
                }
                nearest = nearest.min(inside);
            }
        }
        if !next_subset(&mut subset, n) {
            break;
        }
    }
    if nearest.is_finite() && nearest > RELATIVE_TOLERANCE * largest {
        nearest
    } else {
        0.0
    }
}

fn dot(a: &[f64; WRENCH_DIM], b: &[f64; WRENCH_DIM]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// The unit normal and offset (`normal . x = offset`) of the hyperplane through the six
/// wrenches of `subset`, or `None` when they are not affinely independent.
fn hyperplane(
    wrenches: &[[f64; WRENCH_DIM]],
    subset: &[usize; WRENCH_DIM],
) -> Option<([f64; WRENCH_DIM], f64)> {
    let origin = wrenches[subset[0]];
    // Rows: differences to the first wrench; the normal spans their null space.
    let mut rows = [[0.0f64; WRENCH_DIM + 1]; WRENCH_DIM - 1];
    for (row, &i) in rows.iter_mut().zip(&subset[1..]) {
        for (x, (a, b)) in row.iter_mut().zip(wrenches[i].iter().zip(&origin)) {
            *x = a - b;
        }
    }
    let normal = null_direction(&mut rows)?;
    Some((normal, dot(&normal, &origin)))
}

/// Advances `subset` to the next increasing 6-subset of `0..n` (lexicographic order); false
/// after the last.
fn next_subset(subset: &mut [usize; WRENCH_DIM], n: usize) -> bool {
    for i in (0..WRENCH_DIM).rev() {
        if subset[i] < n - WRENCH_DIM + i {
            subset[i] += 1;
            for j in i + 1..WRENCH_DIM {
                subset[j] = subset[j - 1] + 1;
            }
            return true;
        }
    }
    false
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The cross-polytope of radius r: +-r e_i. Its facets are at distance r / sqrt(6).
    fn cross_polytope(r: f64) -> Vec<[f64; 6]> {
        (0..6)
            .flat_map(|i| {
                [1.0, -1.0].map(|s| {
                    let mut w = [0.0; 6];
                    w[i] = s * r;
                    w
                })
            })
            .collect()
    }

    #[test]
    fn a_cross_polytope_has_its_inradius() {
        let epsilon = wrench_set_epsilon(&cross_polytope(2.0));
        assert!((epsilon - 2.0 / 6f64.sqrt()).abs() < 1e-9, "{epsilon}");
    }

    #[test]
    fn a_shifted_cross_polytope_has_the_distance_to_its_nearest_facet() {
        // Facets sigma . (x - s e0) = r at distance (r + sigma_0 s) / sqrt(6) from the origin:
        // the nearest has sigma_0 = -1.
        let shifted: Vec<_> = cross_polytope(1.0)
            .into_iter()
            .map(|mut w| {
                w[0] += 0.5;
                w
            })
            .collect();
        let epsilon = wrench_set_epsilon(&shifted);
        assert!((epsilon - 0.5 / 6f64.sqrt()).abs() < 1e-9, "{epsilon}");
    }

    #[test]
    fn origin_outside_or_flat_sets_score_zero() {
        let shifted: Vec<_> = cross_polytope(1.0)
            .into_iter()
            .map(|mut w| {
                w[0] += 1.5;
                w
            })
            .collect();
        assert_eq!(wrench_set_epsilon(&shifted), 0.0);
        let flat: Vec<_> = cross_polytope(1.0)
            .into_iter()
            .filter(|w| w[5] == 0.0)
            .collect();
        assert_eq!(wrench_set_epsilon(&flat), 0.0);
        assert_eq!(wrench_set_epsilon(&[]), 0.0);
        assert_eq!(wrench_set_epsilon(&[[f64::NAN; 6]; 8]), 0.0);
    }
}
