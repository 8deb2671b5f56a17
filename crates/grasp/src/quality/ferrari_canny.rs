//! Ferrari and Canny's epsilon (the L1 "largest ball" metric, Dex-Net's `ferrari_canny_L1`):
//! the distance from the origin of wrench space to the boundary of the convex hull of the
//! contact wrenches, 0 when the origin is not inside.

use qhull::Qh;

use crate::error::Result;
use crate::object::GraspObject;
use crate::quality::closure::{closure_holds, validate_friction_coef};
use crate::quality::contacts::ContactPair;
use crate::quality::polar::two_contact_epsilon;
use crate::quality::wrench::{WRENCH_DIM, WrenchParams, push_wrenches};

/// Epsilons below this fraction of the largest wrench's norm are roundoff (or joggle) of a
/// flat set, and read 0.
const RELATIVE_TOLERANCE: f64 = 1e-7;

/// qhull's code for singular (flat) input: the wrenches span less than six dimensions, so the
/// origin cannot be interior and epsilon is 0 with no retry.
const QH_ERR_SINGULAR: i32 = 2;

/// Ferrari-Canny epsilon of a two-contact grasp on `object` (L1: the convex hull of the
/// wrenches of [`crate::quality::contact_wrenches`]).
///
/// Computed from the polar polytope's vertices, which the two-contact structure lets us
/// enumerate directly (module `polar`), with qhull ([`wrench_set_epsilon`]) as the fallback
/// and the reference it is tested against; both give the same value to about 1e-9.
///
/// Returns 0 without building the hull when the contacts are not in force closure
/// ([`crate::quality::force_closure`]): with a jaw's push outside its friction cone Dex-Net
/// scores 0 too (its contact "would slip"), and skipping the hull is most of the speed of
/// robust sampling.
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
    let mut buffer = Vec::new();
    Ok(epsilon_checked(
        object,
        contacts,
        friction_coef,
        params,
        &mut buffer,
    ))
}

/// [`ferrari_canny_l1`] for checked parameters, building the wrenches in `buffer`.
pub(crate) fn epsilon_checked(
    object: &GraspObject,
    contacts: &ContactPair,
    friction_coef: f32,
    params: &WrenchParams,
    buffer: &mut Vec<f64>,
) -> f64 {
    if !closure_holds(contacts, friction_coef) {
        return 0.0;
    }
    let center_of_mass = object.center_of_mass();
    let torque_scale_m = object.torque_scale_m();
    if let Some(epsilon) = two_contact_epsilon(
        center_of_mass,
        torque_scale_m,
        contacts,
        friction_coef,
        params,
    ) {
        return epsilon;
    }
    buffer.clear();
    push_wrenches(
        center_of_mass,
        torque_scale_m,
        contacts,
        friction_coef,
        params,
        buffer,
    );
    hull_epsilon(buffer)
}

/// Epsilon of any set of 6-D wrenches: the distance from the origin to the nearest facet
/// hyperplane of their convex hull when the origin is strictly inside, else 0. Flat sets,
/// sets of fewer than seven wrenches, hulls qhull cannot build (even joggled) and distances
/// under 1e-7 of the largest wrench's norm (roundoff on a flat set) give 0.
pub fn wrench_set_epsilon(wrenches: &[[f64; WRENCH_DIM]]) -> f64 {
    let mut flat: Vec<f64> = wrenches.iter().flatten().copied().collect();
    hull_epsilon(&mut flat)
}

/// [`wrench_set_epsilon`] on flat coordinates (six a wrench); qhull may reorder nothing but
/// needs them mutable.
fn hull_epsilon(points: &mut [f64]) -> f64 {
    if points.len() < (WRENCH_DIM + 1) * WRENCH_DIM
        || !points.len().is_multiple_of(WRENCH_DIM)
        || !points.iter().all(|x| x.is_finite())
    {
        return 0.0;
    }
    let largest = points
        .chunks_exact(WRENCH_DIM)
        .map(|w| w.iter().map(|x| x * x).sum::<f64>())
        .fold(0.0, f64::max)
        .sqrt();
    if !(largest.is_finite() && largest > 0.0) {
        return 0.0;
    }
    let epsilon = match hull_distance(points, false) {
        Ok(epsilon) => epsilon,
        Err(code) if code == QH_ERR_SINGULAR => 0.0,
        // Precision or topology trouble on nearly degenerate input: joggle once ('QJ').
        Err(_) => hull_distance(points, true).unwrap_or(0.0),
    };
    if epsilon > RELATIVE_TOLERANCE * largest {
        epsilon
    } else {
        0.0
    }
}

/// Builds the hull and returns min over facets of `-offset` (qhull's facet hyperplanes are
/// `normal . x + offset = 0` with unit outward normals, so `-offset` is the origin's distance
/// inside each), or 0 when some facet has the origin on or outside it; `Err` carries qhull's
/// error code.
fn hull_distance(points: &mut [f64], joggle: bool) -> std::result::Result<f64, i32> {
    let mut builder = Qh::builder().compute(false);
    if joggle {
        builder = builder.qhull_args(["QJ"]).map_err(|_| -1)?;
    }
    // Computing outside the builder keeps qhull's error (and its facet references) local:
    // the builder's own path would print discarded references to stderr.
    let mut qh = builder
        .build(WRENCH_DIM, points)
        .map_err(|e| e.kind.error_code())?;
    qh.compute().map_err(|e| e.kind.error_code())?;
    let mut nearest = f64::INFINITY;
    let mut facets = 0usize;
    for facet in qh.facets() {
        let distance = -facet.offset();
        if distance.is_nan() || distance <= 0.0 {
            return Ok(0.0);
        }
        nearest = nearest.min(distance);
        facets += 1;
    }
    Ok(if facets > WRENCH_DIM && nearest.is_finite() {
        nearest
    } else {
        0.0
    })
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
