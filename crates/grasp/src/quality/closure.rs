//! Force closure of a two-contact grasp under Coulomb friction (Nguyen's antipodal test).

use crate::error::{GraspError, Result};
use crate::quality::contacts::ContactPair;

/// Checks a friction coefficient: finite and > 0.
///
/// # Errors
/// [`GraspError::InvalidParameter`] naming `op` otherwise.
pub fn validate_friction_coef(op: &'static str, friction_coef: f32) -> Result<()> {
    if friction_coef.is_finite() && friction_coef > 0.0 {
        Ok(())
    } else {
        Err(GraspError::InvalidParameter {
            op,
            name: "friction_coef",
            value: friction_coef.to_string(),
            expected: "a finite number > 0",
        })
    }
}

/// Whether two point contacts with Coulomb friction `friction_coef` hold the object in force
/// closure: the line between the contacts lies inside both friction cones (half-angle
/// `atan(friction_coef)` about the inward normal), each jaw pushing into the surface.
///
/// The contacts of [`crate::quality::find_contacts`] lie on the closing line, so the line
/// between them is the closing axis. This is exactly the condition under which Dex-Net's
/// friction cone reports that a contact "would slip" (its `Contact3D.friction_cone`) and
/// `ferrari_canny_L1` scores 0.
///
/// # Errors
/// [`GraspError::InvalidParameter`] when `friction_coef` is not finite or not > 0.
pub fn force_closure(contacts: &ContactPair, friction_coef: f32) -> Result<bool> {
    validate_friction_coef("force closure", friction_coef)?;
    Ok(closure_holds(contacts, friction_coef))
}

/// [`force_closure`] for a coefficient already checked.
pub(crate) fn closure_holds(contacts: &ContactPair, friction_coef: f32) -> bool {
    contacts
        .contacts
        .iter()
        .zip(contacts.push_directions())
        .all(|(contact, push)| inside_cone(push.dot(contact.inward_normal()), friction_coef))
}

/// Whether a unit push whose cosine with the unit inward normal is `cos` lies in the friction
/// cone: tan(angle) <= mu, i.e. sin <= mu cos with cos > 0.
fn inside_cone(cos: f32, friction_coef: f32) -> bool {
    let cos = f64::from(cos).min(1.0);
    if cos <= 0.0 {
        return false;
    }
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    sin <= f64::from(friction_coef) * cos
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quality::contacts::Contact;
    use mvgrasp_geometry::Vec3;

    fn pair(n0: Vec3, n1: Vec3) -> ContactPair {
        ContactPair {
            contacts: [
                Contact {
                    point: Vec3::new(-0.02, 0.0, 0.0),
                    outward_normal: n0.normalize(),
                },
                Contact {
                    point: Vec3::new(0.02, 0.0, 0.0),
                    outward_normal: n1.normalize(),
                },
            ],
            closing_axis: Vec3::X,
            width_m: 0.04,
        }
    }

    #[test]
    fn antipodal_contacts_close_and_tilted_ones_need_friction() {
        let straight = pair(-Vec3::X, Vec3::X);
        assert!(force_closure(&straight, 0.01).unwrap());
        // 30 degrees off the axis at one contact: needs mu >= tan(30 deg) = 0.577.
        let tilted = pair(Vec3::new(-0.866, 0.5, 0.0), Vec3::X);
        assert!(!force_closure(&tilted, 0.5).unwrap());
        assert!(force_closure(&tilted, 0.6).unwrap());
        // A normal facing the wrong way (the jaw would pull) never closes.
        let wrong = pair(Vec3::X, Vec3::X);
        assert!(!force_closure(&wrong, 10.0).unwrap());
    }

    #[test]
    fn bad_friction_is_an_error_not_a_panic() {
        let straight = pair(-Vec3::X, Vec3::X);
        for mu in [0.0, -0.5, f32::NAN, f32::INFINITY] {
            let err = force_closure(&straight, mu).unwrap_err().to_string();
            assert!(err.contains("friction_coef"), "{err}");
        }
    }
}
