//! The wrenches two contacts can apply to an object: linearised Coulomb friction cones and
//! soft-finger torsion, as in Dex-Net's `PointGraspMetrics3D.grasp_matrix`.
//!
//! A wrench is `(force, torque / L)` in 6-D, f64, where the torque is taken about the object's
//! centre of mass and `L` is [`GraspObject::torque_scale_m`], so that forces and torques weigh
//! alike (Dex-Net's `torque_scaling`).

use mvgrasp_geometry::Vec3;
use serde::{Deserialize, Serialize};

use crate::error::{GraspError, Result};
use crate::object::GraspObject;
use crate::quality::closure::validate_friction_coef;
use crate::quality::contacts::ContactPair;

/// Dimension of wrench space: force (3) and scaled torque (3).
pub const WRENCH_DIM: usize = 6;

/// Most friction-cone facets a contact may have (the hull's cost grows quickly with them).
pub const MAX_CONE_FACES: usize = 64;

/// How a soft finger resists torsion about the contact normal, per newton of normal force.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TorsionModel {
    /// `(2/3) mu r`, in metres: the torsional friction limit of a flat circular pad of radius
    /// `r` pressing with uniform pressure (integrating `mu p rho` over the disc). The default:
    /// with torques divided by the object's radius it gives Ferrari-Canny values on the scale
    /// Dex-Net's 0.002 threshold was set for.
    #[default]
    UniformPatch,
    /// `pi r^2 mu`, Dex-Net's `grasp_matrix` term verbatim (square metres, so it is not a
    /// moment; with torques divided by a few-centimetre object radius it stays under 1e-3 for
    /// r = 5 mm, which caps epsilon below Dex-Net's threshold). For comparison with Dex-Net.
    DexNet,
}

/// The contact model behind the wrench set.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct WrenchParams {
    /// Facets of the linearised friction cone at each contact (Dex-Net: `num_cone_faces: 8`).
    pub num_cone_faces: usize,
    /// Whether each contact also resists torsion about its normal (Dex-Net:
    /// `soft_fingers: 1`). Without it, two point contacts can never resist a torque about the
    /// line through them and epsilon is always 0.
    pub soft_fingers: bool,
    /// Radius of the finger's contact patch for torsion, metres (Dex-Net's `grasp_matrix`
    /// default `finger_radius=0.005`).
    pub finger_radius_m: f32,
    /// How the patch resists torsion.
    pub torsion_model: TorsionModel,
}

impl Default for WrenchParams {
    fn default() -> Self {
        Self {
            num_cone_faces: 8,
            soft_fingers: true,
            finger_radius_m: 0.005,
            torsion_model: TorsionModel::UniformPatch,
        }
    }
}

impl WrenchParams {
    /// Checks the cone facets (3 ..= [`MAX_CONE_FACES`]) and the finger radius (finite, >= 0).
    ///
    /// # Errors
    /// [`GraspError::InvalidParameter`] naming the first bad field.
    pub fn validate(&self) -> Result<()> {
        if !(3..=MAX_CONE_FACES).contains(&self.num_cone_faces) {
            return Err(GraspError::InvalidParameter {
                op: "wrench params",
                name: "num_cone_faces",
                value: self.num_cone_faces.to_string(),
                expected: "3 to 64",
            });
        }
        if !(self.finger_radius_m.is_finite() && self.finger_radius_m >= 0.0) {
            return Err(GraspError::InvalidParameter {
                op: "wrench params",
                name: "finger_radius_m",
                value: self.finger_radius_m.to_string(),
                expected: "a finite number >= 0",
            });
        }
        Ok(())
    }

    /// How many wrenches a two-contact grasp has: the cone facets of both contacts, plus two
    /// torsion wrenches (both senses) per contact for soft fingers.
    pub fn wrenches_per_grasp(&self) -> usize {
        2 * self.num_cone_faces + if self.soft_fingers { 4 } else { 0 }
    }

    /// The torsional friction moment per newton of normal force, metres (see [`TorsionModel`]).
    pub fn torsion_per_newton(&self, friction_coef: f32) -> f64 {
        let r = f64::from(self.finger_radius_m);
        let mu = f64::from(friction_coef);
        match self.torsion_model {
            TorsionModel::UniformPatch => 2.0 / 3.0 * mu * r,
            TorsionModel::DexNet => std::f64::consts::PI * r * r * mu,
        }
    }
}

/// The wrenches the two contacts can apply to `object` with friction `friction_coef`, one
/// `[fx, fy, fz, tx / L, ty / L, tz / L]` each (see the module docs).
///
/// Each contact contributes its friction cone's edges `n + mu (cos a t1 + sin a t2)` (inward
/// normal `n`, tangents `t1`, `t2`, `a` in steps of 2 pi / facets) and, for soft fingers, a
/// torsion of either sense about `n`; all are scaled by the normal share of the jaw's unit
/// push, `max(push . n, 0)` (Dex-Net's `normal_force_magnitude`). Contact 0's wrenches come
/// first, in that order.
///
/// # Errors
/// [`GraspError::InvalidParameter`] for a bad `friction_coef` or `params`.
pub fn contact_wrenches(
    object: &GraspObject,
    contacts: &ContactPair,
    friction_coef: f32,
    params: &WrenchParams,
) -> Result<Vec<[f64; WRENCH_DIM]>> {
    validate_friction_coef("contact wrenches", friction_coef)?;
    params.validate()?;
    Ok(contact_wrenches_at(
        object.center_of_mass(),
        object.torque_scale_m(),
        contacts,
        friction_coef,
        params,
    ))
}

/// The wrenches of [`contact_wrenches`] about `center_of_mass`, torques divided by
/// `torque_scale_m`, for checked parameters.
pub(crate) fn contact_wrenches_at(
    center_of_mass: Vec3,
    torque_scale_m: f32,
    contacts: &ContactPair,
    friction_coef: f32,
    params: &WrenchParams,
) -> Vec<[f64; WRENCH_DIM]> {
    let mut out = Vec::with_capacity(params.wrenches_per_grasp());
    let mu = f64::from(friction_coef);
    let inv_scale = 1.0 / f64::from(torque_scale_m).max(f64::MIN_POSITIVE);
    let com = center_of_mass.as_dvec3();
    let faces = params.num_cone_faces;
    let torsion = params.torsion_per_newton(friction_coef) * inv_scale;
    for (contact, push) in contacts.contacts.iter().zip(contacts.push_directions()) {
        let inward = contact.inward_normal();
        let normal_share = f64::from(push.dot(inward)).max(0.0);
        let (t1, t2) = inward.any_orthonormal_pair();
        let (n, t1, t2) = (inward.as_dvec3(), t1.as_dvec3(), t2.as_dvec3());
        let arm = contact.point.as_dvec3() - com;
        for j in 0..faces {
            let angle = std::f64::consts::TAU * j as f64 / faces as f64;
            let (sin, cos) = angle.sin_cos();
            let force = normal_share * (n + mu * (cos * t1 + sin * t2));
            let torque = arm.cross(force) * inv_scale;
            out.push([force.x, force.y, force.z, torque.x, torque.y, torque.z]);
        }
        if params.soft_fingers {
            for sign in [1.0, -1.0] {
                let torque = n * (sign * normal_share * torsion);
                out.push([0.0, 0.0, 0.0, torque.x, torque.y, torque.z]);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quality::contacts::Contact;

    fn box_pair() -> ContactPair {
        ContactPair {
            contacts: [
                Contact {
                    point: Vec3::new(-0.02, 0.0, 0.0),
                    outward_normal: -Vec3::X,
                },
                Contact {
                    point: Vec3::new(0.02, 0.0, 0.0),
                    outward_normal: Vec3::X,
                },
            ],
            closing_axis: Vec3::X,
            width_m: 0.04,
        }
    }

    #[test]
    fn cone_edges_sit_at_the_friction_angle_and_torques_are_arm_cross_force() {
        let params = WrenchParams::default();
        let out = contact_wrenches_at(Vec3::ZERO, 0.5, &box_pair(), 0.5, &params);
        assert_eq!(out.len(), params.wrenches_per_grasp());
        for w in out.iter().take(8) {
            // Normal part 1 along +x, tangential part of length mu.
            assert!((w[0] - 1.0).abs() < 1e-6);
            assert!(((w[1] * w[1] + w[2] * w[2]).sqrt() - 0.5).abs() < 1e-6);
            // arm (-0.02, 0, 0) x f = (0, 0.02 fz, -0.02 fy), divided by 0.5.
            assert!(w[3].abs() < 1e-9);
            assert!((w[4] - 0.04 * w[2]).abs() < 1e-6 && (w[5] + 0.04 * w[1]).abs() < 1e-6);
        }
        // Torsion about the inward normal, both senses: (2/3) mu r / L.
        let torsion = &out[8];
        assert!(torsion[..3].iter().all(|f| *f == 0.0));
        assert!((torsion[3] - 2.0 / 3.0 * 0.5 * 0.005 / 0.5).abs() < 1e-9);
    }

    #[test]
    fn params_are_checked() {
        let few = WrenchParams {
            num_cone_faces: 2,
            ..WrenchParams::default()
        };
        assert!(
            few.validate()
                .unwrap_err()
                .to_string()
                .contains("num_cone_faces")
        );
        let negative = WrenchParams {
            finger_radius_m: -1.0,
            ..WrenchParams::default()
        };
        assert!(negative.validate().is_err());
        let dexnet = WrenchParams {
            torsion_model: TorsionModel::DexNet,
            ..WrenchParams::default()
        };
        let expected = std::f64::consts::PI * 0.005f64.powi(2) * 0.5;
        assert!((dexnet.torsion_per_newton(0.5) / expected - 1.0).abs() < 1e-6);
    }
}
