//! Where a parallel-jaw gripper touches an object when it closes: two ray casts along the
//! closing line ([`find_contacts`]).

use mvgrasp_geometry::{Pose3, Vec3};
use parry3d::query::{Ray, RayCast};
use serde::{Deserialize, Serialize};

use crate::gripper::Gripper;
use crate::object::GraspObject;

/// Narrowest width between two contacts that counts as a grasp, metres (below it the jaws
/// graze a single point of the surface).
pub const MIN_CONTACT_WIDTH_M: f32 = 1e-5;

/// One finger's contact with the object, object frame.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Contact {
    /// The contact point, metres.
    pub point: Vec3,
    /// The unit surface normal at the contact, pointing *out of* the object, towards the jaw
    /// that touches it.
    pub outward_normal: Vec3,
}

impl Contact {
    /// The unit normal pointing into the object: the direction of a frictionless push.
    pub fn inward_normal(&self) -> Vec3 {
        -self.outward_normal
    }
}

/// The two contacts of a closed parallel-jaw grasp, object frame.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ContactPair {
    /// `[0]`: met by the jaw that starts at gripper x = -max_opening/2 and moves along +x;
    /// `[1]`: met by the jaw that starts at +max_opening/2 and moves along -x.
    pub contacts: [Contact; 2],
    /// The gripper's closing axis (gripper +x) in the object frame, unit: the direction from
    /// contact 0 to contact 1, and the push of jaw 0 (jaw 1 pushes along its negative).
    pub closing_axis: Vec3,
    /// Distance between the two contacts, metres.
    pub width_m: f32,
}

impl ContactPair {
    /// The unit direction each jaw pushes its contact: `closing_axis` for contact 0, its
    /// negative for contact 1.
    pub fn push_directions(&self) -> [Vec3; 2] {
        [self.closing_axis, -self.closing_axis]
    }
}

/// Closes the jaws of `gripper`, placed at `object_from_gripper`, on `object`.
///
/// The jaws start at x = -max_opening/2 and +max_opening/2 on the closing line (the gripper's
/// x axis through its origin, where the finger tips are) and move towards each other; each
/// stops at the first surface it meets (one ray cast per jaw, either side of a triangle).
///
/// Returns `None` when the jaws meet nothing, when the width between the contacts is outside
/// `[min_opening_m, max_opening_m]` (or under [`MIN_CONTACT_WIDTH_M`]), or when a jaw starts
/// inside the object. The last is only detected on watertight meshes, whose triangles face
/// outwards (a [`GraspObject`] refuses one turned inside out): a jaw is inside when the first
/// triangle it meets faces away from it. An open mesh has no inside, so there both hits are
/// taken as they are.
pub fn find_contacts(
    object: &GraspObject,
    object_from_gripper: &Pose3,
    gripper: &Gripper,
) -> Option<ContactPair> {
    let half_opening = 0.5 * gripper.max_opening_m;
    if !(half_opening.is_finite() && half_opening > 0.0) {
        return None;
    }
    let axis = object_from_gripper.transform_vector(Vec3::X).normalize();
    let center = object_from_gripper.translation;
    if !(axis.is_finite() && center.is_finite()) {
        return None;
    }
    let check_inside = object.is_watertight();
    let opening = 2.0 * half_opening;
    let first = jaw_contact(
        object,
        center - axis * half_opening,
        axis,
        opening,
        check_inside,
    )?;
    let second = jaw_contact(
        object,
        center + axis * half_opening,
        -axis,
        opening,
        check_inside,
    )?;
    let width_m = opening - first.0 - second.0;
    if !(width_m >= MIN_CONTACT_WIDTH_M && gripper.fits(width_m)) {
        return None;
    }
    Some(ContactPair {
        contacts: [first.1, second.1],
        closing_axis: axis,
        width_m,
    })
}

/// The distance a jaw starting at `start` travels along `direction` (unit) before it touches the
/// surface, and the contact; `None` if it meets nothing within `max_travel` (the other jaw's
/// start) or, with `check_inside`, starts inside.
fn jaw_contact(
    object: &GraspObject,
    start: Vec3,
    direction: Vec3,
    max_travel: f32,
    check_inside: bool,
) -> Option<(f32, Contact)> {
    let trimesh = object.caster().trimesh();
    let ray = Ray::new(start, direction);
    let hit = trimesh.cast_local_ray_and_get_normal(&ray, max_travel, false)?;
    if check_inside {
        let triangle = trimesh.triangle(hit.subshape);
        if triangle.scaled_normal().dot(direction) > 0.0 {
            return None;
        }
    }
    // parry turns the normal towards the ray's origin: out of the object, towards the jaw.
    let outward_normal = hit.normal.normalize();
    if !outward_normal.is_finite() {
        return None;
    }
    Some((
        hit.time_of_impact,
        Contact {
            point: ray.point_at(hit.time_of_impact),
            outward_normal,
        },
    ))
}
