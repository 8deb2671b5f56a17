//! Robust Ferrari-Canny quality (Dex-Net 2.0's label): the mean epsilon of a grasp over
//! random perturbations of the gripper pose, the object pose and the friction coefficient.

use mvgrasp_geometry::{Pose3, Rot3, Vec3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::Result;
use crate::gripper::Gripper;
use crate::object::GraspObject;
use crate::quality::closure::{closure_holds, validate_friction_coef};
use crate::quality::contacts::{ContactPair, find_contacts};
use crate::quality::ferrari_canny::epsilon_checked;
use crate::quality::params::RobustQualityParams;
use crate::quality::wrench::WrenchParams;

/// One deterministic evaluation of a grasp ([`grasp_quality`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct GraspQuality {
    /// Where the jaws touch, if they close on the object within the gripper's range.
    pub contacts: Option<ContactPair>,
    /// Whether the contacts are in force closure.
    pub force_closure: bool,
    /// Ferrari-Canny epsilon (0 without contacts or force closure).
    pub epsilon: f64,
}

/// The result of [`robust_quality`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RobustQuality {
    /// Mean epsilon over the perturbed samples (a sample whose jaws find no contacts counts
    /// 0): Dex-Net's robust Ferrari-Canny.
    pub robust_epsilon: f64,
    /// Epsilon of the unperturbed grasp at the mean friction coefficient.
    pub nominal_epsilon: f64,
    /// Whether the unperturbed grasp is in force closure at the mean friction coefficient.
    pub nominal_force_closure: bool,
    /// The unperturbed grasp's contacts.
    pub nominal_contacts: Option<ContactPair>,
    /// Fraction of the samples in force closure.
    pub force_closure_fraction: f64,
    /// Fraction of the samples whose jaws found contacts.
    pub contact_fraction: f64,
    /// Samples drawn.
    pub num_samples: usize,
}

/// Closes `gripper` at `object_from_gripper` on `object` and scores the contacts: force
/// closure and Ferrari-Canny epsilon at `friction_coef`.
///
/// # Errors
/// [`crate::GraspError::InvalidParameter`] for a bad `friction_coef`, `wrench` or `gripper`.
pub fn grasp_quality(
    object: &GraspObject,
    object_from_gripper: &Pose3,
    gripper: &Gripper,
    friction_coef: f32,
    wrench: &WrenchParams,
) -> Result<GraspQuality> {
    validate_friction_coef("grasp quality", friction_coef)?;
    wrench.validate()?;
    gripper.validate()?;
    Ok(evaluate(
        object,
        object_from_gripper,
        gripper,
        friction_coef,
        wrench,
    ))
}

/// Robust Ferrari-Canny quality of the grasp `object_from_gripper` (the gripper frame in the
/// object's, see [`crate::Grasp`]): the mean epsilon over `params.num_samples` perturbations,
/// with the nominal evaluation beside it.
///
/// Each sample draws, from ChaCha8 seeded with `seed` on stream `i` (sample `i`), in this
/// order: the friction coefficient (normal, raised to `friction_coef_min`), the gripper's
/// translation and rotation vector (in its own frame, about the grasp centre), and the
/// object's translation and rotation vector (about its centre of mass); then closes the jaws
/// on the moved object. The same seed gives the same result on any thread.
///
/// # Errors
/// [`crate::GraspError::InvalidParameter`] for invalid `params` or `gripper`.
pub fn robust_quality(
    object: &GraspObject,
    object_from_gripper: &Pose3,
    gripper: &Gripper,
    params: &RobustQualityParams,
    seed: u64,
) -> Result<RobustQuality> {
    params.validate()?;
    gripper.validate()?;
    Ok(robust_checked(
        object,
        object_from_gripper,
        gripper,
        params,
        seed,
    ))
}

/// [`robust_quality`] of many grasps on one object, in parallel on rayon's pool. Grasp `i` is
/// seeded with [`grasp_seed`]`(seed, i)`, so its result equals `robust_quality(..,
/// grasp_seed(seed, i))` whatever the thread count.
///
/// # Errors
/// [`crate::GraspError::InvalidParameter`] for invalid `params` or `gripper`.
pub fn robust_qualities(
    object: &GraspObject,
    object_from_grippers: &[Pose3],
    gripper: &Gripper,
    params: &RobustQualityParams,
    seed: u64,
) -> Result<Vec<RobustQuality>> {
    params.validate()?;
    gripper.validate()?;
    Ok(object_from_grippers
        .par_iter()
        .enumerate()
        .map(|(i, pose)| robust_checked(object, pose, gripper, params, grasp_seed(seed, i)))
        .collect())
}

/// The seed of grasp `index` in a batch seeded with `seed` (SplitMix64 of both): distinct,
/// well-mixed seeds for neighbouring indices.
pub fn grasp_seed(seed: u64, index: usize) -> u64 {
    let mut z = seed ^ (index as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// [`robust_quality`] for checked inputs.
fn robust_checked(
    object: &GraspObject,
    object_from_gripper: &Pose3,
    gripper: &Gripper,
    params: &RobustQualityParams,
    seed: u64,
) -> RobustQuality {
    let nominal = evaluate(
        object,
        object_from_gripper,
        gripper,
        params.friction_coef_mean,
        &params.wrench,
    );
    let com = object.center_of_mass();
    let (mut epsilon_sum, mut closures, mut contacts) = (0.0, 0usize, 0usize);
    for i in 0..params.num_samples {
        let (pose, friction_coef) = perturb(params, object_from_gripper, com, seed, i as u64);
        let sample = evaluate(object, &pose, gripper, friction_coef, &params.wrench);
        epsilon_sum += sample.epsilon;
        closures += usize::from(sample.force_closure);
        contacts += usize::from(sample.contacts.is_some());
    }
    let n = params.num_samples as f64;
    RobustQuality {
        robust_epsilon: epsilon_sum / n,
        nominal_epsilon: nominal.epsilon,
        nominal_force_closure: nominal.force_closure,
        nominal_contacts: nominal.contacts,
        force_closure_fraction: closures as f64 / n,
        contact_fraction: contacts as f64 / n,
        num_samples: params.num_samples,
    }
}

/// One evaluation with checked parameters.
fn evaluate(
    object: &GraspObject,
    object_from_gripper: &Pose3,
    gripper: &Gripper,
    friction_coef: f32,
    wrench: &WrenchParams,
) -> GraspQuality {
    let Some(contacts) = find_contacts(object, object_from_gripper, gripper) else {
        return GraspQuality {
            contacts: None,
            force_closure: false,
            epsilon: 0.0,
        };
    };
    let force_closure = closure_holds(&contacts, friction_coef);
    let epsilon = if force_closure {
        epsilon_checked(object, &contacts, friction_coef, wrench)
    } else {
        0.0
    };
    GraspQuality {
        contacts: Some(contacts),
        force_closure,
        epsilon,
    }
}

/// Sample `index`'s grasp, in the moved object's frame, and friction coefficient.
fn perturb(
    params: &RobustQualityParams,
    object_from_gripper: &Pose3,
    center_of_mass: Vec3,
    seed: u64,
    index: u64,
) -> (Pose3, f32) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(index);
    let friction_coef = (params.friction_coef_mean
        + params.friction_coef_sigma * standard_normal(&mut rng))
    .max(params.friction_coef_min);
    let gripper_shift = standard_normal_vector(&mut rng) * params.gripper_translation_sigma_m;
    let gripper_turn = standard_normal_vector(&mut rng) * params.gripper_rotation_sigma_rad;
    let object_shift = standard_normal_vector(&mut rng) * params.object_translation_sigma_m;
    let object_turn = standard_normal_vector(&mut rng) * params.object_rotation_sigma_rad;

    let gripper_motion = Pose3::from_parts(gripper_shift, Rot3::from_scaled_axis(gripper_turn));
    // The object turns about its centre of mass, then shifts (in the nominal object frame).
    let moved_object = Pose3::from_translation(center_of_mass + object_shift)
        * Pose3::from_rotation(Rot3::from_scaled_axis(object_turn))
        * Pose3::from_translation(-center_of_mass);
    let pose = moved_object.inverse() * (*object_from_gripper * gripper_motion);
    (pose, friction_coef)
}

fn standard_normal(rng: &mut ChaCha8Rng) -> f32 {
    StandardNormal.sample(rng)
}

fn standard_normal_vector(rng: &mut ChaCha8Rng) -> Vec3 {
    let x = standard_normal(rng);
    let y = standard_normal(rng);
    Vec3::new(x, y, standard_normal(rng))
}

#[cfg(test)]
mod tests {
    use super::*;
    use mvgrasp_geometry::TriangleMesh;
    use parry3d::shape::Cuboid;

    fn cube() -> GraspObject {
        let (v, t) = Cuboid::new(Vec3::splat(0.02)).to_trimesh();
        GraspObject::new(TriangleMesh::new(v, t).unwrap()).unwrap()
    }

    #[test]
    fn without_noise_every_sample_is_the_nominal_grasp() {
        let object = cube();
        let params = RobustQualityParams::default().deterministic();
        let pose = Pose3::from_translation(Vec3::new(0.0, 0.003, 0.001));
        let q = robust_quality(&object, &pose, &Gripper::default(), &params, 7).unwrap();
        assert!(q.nominal_force_closure && q.nominal_epsilon > 0.0);
        assert!((q.robust_epsilon - q.nominal_epsilon).abs() < 1e-12);
        assert_eq!(q.force_closure_fraction, 1.0);
        assert_eq!(q.contact_fraction, 1.0);
    }

    #[test]
    fn batch_results_match_single_calls_with_the_derived_seeds() {
        let object = cube();
        let params = RobustQualityParams {
            num_samples: 5,
            ..Default::default()
        };
        let poses = [
            Pose3::identity(),
            Pose3::from_parts(Vec3::new(0.0, 0.01, 0.0), Rot3::from_rotation_z(0.3)),
        ];
        let gripper = Gripper::default();
        let batch = robust_qualities(&object, &poses, &gripper, &params, 3).unwrap();
        for (i, pose) in poses.iter().enumerate() {
            let single = robust_quality(&object, pose, &gripper, &params, grasp_seed(3, i));
            assert_eq!(batch[i], single.unwrap());
        }
        assert_ne!(grasp_seed(3, 0), grasp_seed(3, 1));
    }
}
