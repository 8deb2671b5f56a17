//! Does the gripper hit the object or the table? Finger and palm boxes (parry cuboids) against
//! the object's triangle mesh and the table's half-space, at the grasp and along the approach.

use mvgrasp_geometry::{Pose3, Rot3, Vec3};
use parry3d::query;
use parry3d::shape::Cuboid;
use serde::{Deserialize, Serialize};

use crate::gripper::Gripper;
use crate::object::GraspObject;

/// How collisions are checked (the approach sweep is the gripper's `approach_distance_m`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CollisionParams {
    /// Shapes closer than this to the table count as touching it, metres.
    pub table_margin_m: f32,
}

impl Default for CollisionParams {
    fn default() -> Self {
        Self {
            table_margin_m: 0.002,
        }
    }
}

/// What a gripper pose collides with.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Collision {
    /// A finger or the palm meets the object's surface.
    pub object: bool,
    /// A finger or the palm dips below the table's plane.
    pub table: bool,
}

impl Collision {
    /// Free of both.
    pub fn is_free(&self) -> bool {
        !self.object && !self.table
    }
}

/// The gripper's boxes at one opening, each with its pose in the gripper frame, swept back
/// along the approach.
#[derive(Clone, Debug)]
pub struct HandShapes {
    boxes: [(Cuboid, Pose3); 3],
}

impl HandShapes {
    /// The fingers `opening_m` apart (clipped to the gripper's range) and the palm, each box
    /// extended back along -z by `sweep_m` so that one test covers the straight approach.
    pub fn new(gripper: &Gripper, opening_m: f32, sweep_m: f32) -> Self {
        let opening = opening_m.clamp(gripper.min_opening_m, gripper.max_opening_m);
        let back = Vec3::new(0.0, 0.0, sweep_m.max(0.0) / 2.0);
        let swept = |half: Vec3, center: Vec3| {
            (
                Cuboid::new(half + back),
                Pose3::from_parts(center - back, Rot3::IDENTITY),
            )
        };
        let finger = gripper.finger_half_extents();
        Self {
            boxes: [
                swept(finger, gripper.finger_center(opening, -1.0)),
                swept(finger, gripper.finger_center(opening, 1.0)),
                swept(gripper.palm_half_extents(), gripper.palm_center()),
            ],
        }
    }

    /// The boxes and their poses in the gripper frame: left finger, right finger, palm.
    pub fn boxes(&self) -> &[(Cuboid, Pose3); 3] {
        &self.boxes
    }

    /// Whether any box meets the object's surface, the gripper at `object_from_gripper`.
    pub fn hits_object(&self, object: &GraspObject, object_from_gripper: &Pose3) -> bool {
        let mesh = object.caster().trimesh();
        self.boxes.iter().any(|(shape, gripper_from_box)| {
            let pose = *object_from_gripper * *gripper_from_box;
            query::intersection_test(&pose, shape, &Pose3::IDENTITY, mesh)
                .map(|hit| hit.intersecting)
                // Cuboid against a triangle mesh is always supported; count a refusal as a hit.
                .unwrap_or(true)
        })
    }

    /// The lowest point of any box above the table (z in `world_from_gripper`'s frame), metres.
    pub fn lowest_z(&self, world_from_gripper: &Pose3) -> f32 {
        self.boxes
            .iter()
            .map(|(shape, gripper_from_box)| {
                shape
                    .aabb(&(*world_from_gripper * *gripper_from_box))
                    .mins
                    .z
            })
            .fold(f32::INFINITY, f32::min)
    }
}

/// Checks the gripper at `object_from_gripper`, open for a grasp `width_m` wide as it comes in
/// ([`Gripper::opening_for`], as physics does), swept along its approach, against the object;
/// and, when the object rests on a table (`table_from_object`, the table the plane z = 0),
/// against the table.
pub fn check_collision(
    object: &GraspObject,
    gripper: &Gripper,
    object_from_gripper: &Pose3,
    width_m: f32,
    table_from_object: Option<&Pose3>,
    params: &CollisionParams,
) -> Collision {
    let hand = HandShapes::new(
        gripper,
        gripper.opening_for(width_m),
        gripper.approach_distance_m,
    );
    let table = table_from_object.is_some_and(|table_from_object| {
        hand.lowest_z(&(*table_from_object * *object_from_gripper)) < params.table_margin_m
    });
    Collision {
        object: hand.hits_object(object, object_from_gripper),
        table,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mvgrasp_geometry::TriangleMesh;

    /// A 5 cm cube centred at the origin.
    fn cube() -> GraspObject {
        let (v, t) = Cuboid::new(Vec3::splat(0.025)).to_trimesh();
        GraspObject::new(TriangleMesh::new(v, t).unwrap()).unwrap()
    }

    fn top_down(center: Vec3) -> Pose3 {
        // Approach -z (down), closing along x.
        Pose3::from_parts(center, Rot3::from_rotation_x(std::f32::consts::PI))
    }

    #[test]
    fn a_top_down_grasp_across_the_cube_is_free() {
        let c = check_collision(
            &cube(),
            &Gripper::default(),
            &top_down(Vec3::new(0.0, 0.0, 0.0)),
            0.05,
            None,
            &CollisionParams::default(),
        );
        assert!(c.is_free(), "{c:?}");
    }

    #[test]
    fn fingers_too_close_for_the_cube_hit_it() {
        // A Panda opened 7 cm (the cube's 5 cm and the 2 cm margin), off centre by 2 cm: a finger
        // cuts the cube.
        let c = check_collision(
            &cube(),
            &Gripper::default(),
            &top_down(Vec3::new(0.02, 0.0, 0.0)),
            0.05,
            None,
            &CollisionParams::default(),
        );
        assert!(c.object, "{c:?}");
    }

    #[test]
    fn fingers_below_the_table_are_caught() {
        let object = cube();
        // The cube on the table: its bottom face at z = 0.
        let table_from_object = Pose3::from_parts(Vec3::new(0.0, 0.0, 0.025), Rot3::IDENTITY);
        let params = CollisionParams::default();
        let gripper = Gripper::default();
        // Grasp line 1 cm above the table: the finger tips stay above it.
        let high = top_down(Vec3::new(0.0, 0.0, -0.015));
        let c = check_collision(
            &object,
            &gripper,
            &high,
            0.05,
            Some(&table_from_object),
            &params,
        );
        assert!(c.is_free(), "{c:?}");
        // Grasp line 5 mm below the cube's bottom: the finger tips go through the table (and
        // the palm, 5 cm behind the tips, reaches the cube's top).
        let low = top_down(Vec3::new(0.0, 0.0, -0.03));
        let c = check_collision(
            &object,
            &gripper,
            &low,
            0.05,
            Some(&table_from_object),
            &params,
        );
        assert!(c.table, "{c:?}");
        let c = check_collision(&object, &gripper, &low, 0.05, None, &params);
        assert!(!c.table, "no table given: {c:?}");
    }
}
