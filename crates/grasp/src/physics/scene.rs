//! The rapier world of one trial: the table, the object, and the gripper (a kinematic palm with
//! two force-limited prismatic fingers); plus the exact distance and sweep queries the trial
//! judges by.

use mvgrasp_geometry::{Pose3, Vec3};
use parry3d::query;
use parry3d::shape::{Cuboid, Shape};
use rapier3d::prelude::{
    ColliderBuilder, ColliderHandle, FrictionModel, Group, InteractionGroups, InteractionTestMode,
    PhysicsWorld, PrismaticJointBuilder, RigidBodyBuilder, RigidBodyHandle, SpringCoefficients,
};

use crate::gripper::Gripper;
use crate::physics::object::PhysicsObject;
use crate::physics::params::PhysicsParams;

/// Half the side of the square table, metres.
const TABLE_HALF_SIDE_M: f32 = 1.0;
/// Half the thickness of the table slab (its top is z = 0), metres.
const TABLE_HALF_THICKNESS_M: f32 = 0.05;

const TABLE_GROUP: Group = Group::GROUP_1;
const OBJECT_GROUP: Group = Group::GROUP_2;
const GRIPPER_GROUP: Group = Group::GROUP_3;

/// The table, the object and, once added, the gripper.
pub(crate) struct Scene {
    pub world: PhysicsWorld,
    pub table: ColliderHandle,
    pub object_body: RigidBodyHandle,
    pub object: ColliderHandle,
}

/// The gripper's bodies, colliders and joints, and its shape in its own frame.
pub(crate) struct Hand {
    pub palm: RigidBodyHandle,
    /// The +x finger, then the -x finger.
    pub fingers: [RigidBodyHandle; 2],
    pub finger_colliders: [ColliderHandle; 2],
    pub shape: HandShape,
}

/// The gripper's boxes in the gripper frame (origin midway between the finger tips, +z approach,
/// +x closing axis), fingers open to the widest.
#[derive(Clone, Copy, Debug)]
pub(crate) struct HandShape {
    pub finger: Cuboid,
    pub palm: Cuboid,
    /// Gripper-frame centre of the palm box.
    pub palm_center: Vec3,
    /// Gripper-frame |x| of a finger's centre when open to the widest.
    pub finger_open_x: f32,
    /// Gripper-frame |x| of a finger's centre when shut to the narrowest.
    pub finger_shut_x: f32,
    /// Gripper-frame z of the finger centres.
    pub finger_z: f32,
    /// Finger thickness along x.
    pub thickness: f32,
}

impl HandShape {
    pub fn new(gripper: &Gripper) -> Self {
        let open = gripper.finger_center(gripper.max_opening_m, 1.0);
        Self {
            finger: Cuboid::new(gripper.finger_half_extents()),
            palm: Cuboid::new(gripper.palm_half_extents()),
            palm_center: gripper.palm_center(),
            finger_open_x: open.x,
            finger_shut_x: gripper.finger_center(gripper.min_opening_m, 1.0).x,
            finger_z: open.z,
            thickness: gripper.finger_thickness_m,
        }
    }

    /// Gripper-frame poses of the +x and -x fingers open to the widest.
    pub fn open_finger_poses(&self) -> [Pose3; 2] {
        [1.0, -1.0]
            .map(|s| Pose3::from_translation(Vec3::new(s * self.finger_open_x, 0.0, self.finger_z)))
    }
}

impl Scene {
    /// The table and `object` placed at `table_from_object` (world = table frame).
    pub fn new(object: &PhysicsObject, table_from_object: &Pose3, params: &PhysicsParams) -> Self {
        let mut world = PhysicsWorld::new();
        world.gravity = Vec3::new(0.0, 0.0, -9.81);
        let ip = &mut world.integration_parameters;
        ip.dt = params.timestep_s;
        ip.num_solver_iterations = params.solver_iterations;
        ip.length_unit = params.solver_length_unit_m;
        let soft =
            SpringCoefficients::new(params.contact_frequency_hz, params.contact_damping_ratio);
        ip.contact_softness = soft;
        ip.static_contact_softness = soft;
        // One Coulomb cone per contact point: the torque a finger pad resists about the closing
        // axis comes from its contact points' spread, which decides off-centre grasps.
        ip.friction_model = FrictionModel::Coulomb;
        // A held object moves with the fingers, so recycled contacts would never be recomputed
        // while the fingers sink into it: they would squeeze through a can in a fraction of a
        // second.
        ip.contact_recycling = false;

        let table_body = world.insert_body(RigidBodyBuilder::fixed());
        let table = world.insert_collider(
            ColliderBuilder::cuboid(TABLE_HALF_SIDE_M, TABLE_HALF_SIDE_M, TABLE_HALF_THICKNESS_M)
                .translation(Vec3::new(0.0, 0.0, -TABLE_HALF_THICKNESS_M))
                .friction(params.table_friction)
                .collision_groups(groups(TABLE_GROUP, Group::ALL)),
            Some(table_body),
        );
        let (object_body, object) = world.insert(
            RigidBodyBuilder::dynamic()
                .pose(*table_from_object)
                .can_sleep(false),
            ColliderBuilder::new(object.shape().clone())
                .mass_properties(object.mass_properties(params.object_density_kg_m3))
                .friction(params.object_friction)
                .collision_groups(groups(OBJECT_GROUP, Group::ALL)),
        );
        Self {
            world,
            table,
            object_body,
            object,
        }
    }

    /// Adds the gripper at `world_from_gripper`, fingers open to the widest and closing at
    /// `params.closing_speed_m_s` with at most `force_n` each.
    pub fn add_hand(
        &mut self,
        world_from_gripper: &Pose3,
        gripper: &Gripper,
        params: &PhysicsParams,
        force_n: f32,
    ) -> Hand {
        let shape = HandShape::new(gripper);
        let gripper_groups = groups(GRIPPER_GROUP, TABLE_GROUP | OBJECT_GROUP);
        let world = &mut self.world;
        let (palm, _) = world.insert(
            RigidBodyBuilder::kinematic_position_based().pose(*world_from_gripper),
            ColliderBuilder::new(parry3d::shape::SharedShape::new(shape.palm))
                .translation(shape.palm_center)
                .friction(params.finger_friction)
                .collision_groups(gripper_groups),
        );
        let finger_volume = 8.0 * shape.finger.half_extents.element_product();
        let mut fingers = [palm; 2];
        let mut finger_colliders = [ColliderHandle::invalid(); 2];
        for (i, (side, local)) in [1.0f32, -1.0]
            .into_iter()
            .zip(shape.open_finger_poses())
            .enumerate()
        {
            let (finger, collider) = world.insert(
                RigidBodyBuilder::dynamic()
                    .pose(*world_from_gripper * local)
                    .gravity_scale(0.0)
                    .can_sleep(false),
                ColliderBuilder::new(parry3d::shape::SharedShape::new(shape.finger))
                    .density(params.finger_mass_kg / finger_volume)
                    .friction(params.finger_friction)
                    .collision_groups(gripper_groups),
            );
            // The joint coordinate is the finger centre's gripper-frame x: the +x finger lives
            // in [shut, open] and closes towards -x, the -x finger mirrors it.
            let (lo, hi) = (shape.finger_shut_x, shape.finger_open_x);
            let limits = if side > 0.0 { [lo, hi] } else { [-hi, -lo] };
            let joint = PrismaticJointBuilder::new(Vec3::X)
                .local_anchor1(Vec3::new(0.0, 0.0, shape.finger_z))
                .local_anchor2(Vec3::ZERO)
                .limits(limits)
                .motor_velocity(-side * params.closing_speed_m_s, MOTOR_DAMPING)
                .motor_max_force(force_n)
                .contacts_enabled(false);
            world.insert_impulse_joint(palm, finger, joint);
            fingers[i] = finger;
            finger_colliders[i] = collider;
        }
        Hand {
            palm,
            fingers,
            finger_colliders,
            shape,
        }
    }

    /// The object's pose in the world.
    pub fn world_from_object(&self) -> Pose3 {
        self.world
            .bodies
            .get(self.object_body)
            .map_or(Pose3::IDENTITY, |b| *b.position())
    }

    /// The object's centre of mass in the world.
    pub fn object_com(&self) -> Vec3 {
        self.world
            .bodies
            .get(self.object_body)
            .map_or(Vec3::ZERO, |b| b.center_of_mass())
    }

    /// Exact distance between two colliders, metres (0 when they overlap; infinite when either
    /// is missing or the shapes are not supported).
    pub fn distance(&self, a: ColliderHandle, b: ColliderHandle) -> f32 {
        let colliders = &self.world.colliders;
        match (colliders.get(a), colliders.get(b)) {
            (Some(a), Some(b)) => query::distance(a.position(), a.shape(), b.position(), b.shape())
                .map_or(f32::INFINITY, |d| d.distance),
            _ => f32::INFINITY,
        }
    }

    /// Whether the open gripper, moving in a straight line from `world_from_pregrasp` by
    /// `motion` (world frame), comes within [`SWEEP_TOUCH_M`] of the table or the object
    /// anywhere on the way, the start and the end included.
    ///
    /// Conservative advancement on exact distances: a shape that is `d` away from an obstacle
    /// can move `d` along a straight line before it can touch it, so the path is walked in
    /// steps of the current distance. (parry 0.31's `cast_shapes` between a cuboid and a convex
    /// polyhedron reports hits for fingers passing 8 mm beside a box, so it is not used.)
    pub fn sweep_hits(&self, shape: &HandShape, world_from_pregrasp: &Pose3, motion: Vec3) -> bool {
        let mut moving: Vec<(Pose3, &dyn Shape)> = shape
            .open_finger_poses()
            .into_iter()
            .map(|local| (*world_from_pregrasp * local, &shape.finger as &dyn Shape))
            .collect();
        moving.push((
            *world_from_pregrasp * Pose3::from_translation(shape.palm_center),
            &shape.palm as &dyn Shape,
        ));
        let colliders = &self.world.colliders;
        [self.table, self.object]
            .into_iter()
            .filter_map(|handle| colliders.get(handle))
            .any(|fixed| {
                moving.iter().any(|(start, shape)| {
                    path_touches(start, motion, *shape, fixed.position(), fixed.shape())
                })
            })
    }
}

/// How close the sweep may come to an obstacle before it counts as touching it, metres.
pub(crate) const SWEEP_TOUCH_M: f32 = 1.0e-4;

/// The most distance queries one shape's sweep may take; beyond, it counts as touching (a path
/// grazing an obstacle at just over [`SWEEP_TOUCH_M`] for its whole length).
const MAX_SWEEP_QUERIES: usize = 4096;

/// Whether `moving`, translated from `start` by `motion`, comes within [`SWEEP_TOUCH_M`] of
/// `fixed` at `fixed_pose`. A pair parry cannot measure counts as touching: a grasp is never
/// passed unchecked.
fn path_touches(
    start: &Pose3,
    motion: Vec3,
    moving: &dyn Shape,
    fixed_pose: &Pose3,
    fixed: &dyn Shape,
) -> bool {
    let length = motion.length();
    let mut t = 0.0f32;
    for _ in 0..MAX_SWEEP_QUERIES {
        let pose = Pose3::from_parts(start.translation + motion * t, start.rotation);
        let Ok(d) = query::distance(&pose, moving, fixed_pose, fixed) else {
            return true;
        };
        if d.distance <= SWEEP_TOUCH_M {
            return true;
        }
        if t >= 1.0 || length == 0.0 {
            return false;
        }
        t = (t + d.distance / length).min(1.0);
    }
    true
}

/// The finger motors' velocity gain: large, so a finger moves at the closing speed until its
/// force limit stops it.
const MOTOR_DAMPING: f32 = 1.0e4;

fn groups(memberships: Group, filter: Group) -> InteractionGroups {
    InteractionGroups::new(memberships, filter, InteractionTestMode::And)
}

#[cfg(test)]
mod tests {
    use super::*;
    use mvgrasp_geometry::{Rot3, TriangleMesh};

    /// parry's `cast_shapes` saw a hit here (fingers 8 mm beside a 5 cm box).
    #[test]
    fn the_sweep_passes_fingers_beside_a_box_and_stops_fingers_on_it() {
        let (v, t) = Cuboid::new(Vec3::splat(0.025)).to_trimesh();
        let mesh = TriangleMesh::new(v, t).unwrap();
        let object = PhysicsObject::new(&mesh, &Default::default()).unwrap();
        let params = PhysicsParams::default();
        let on_table = Pose3::from_translation(Vec3::new(0.0, 0.0, 0.025));
        let scene = Scene::new(&object, &on_table, &params);
        let shape = HandShape::new(&Gripper::default());
        let down = Rot3::from_rotation_x(std::f32::consts::PI);
        // Open Panda fingers: inner faces 4 cm either side of the closing line.
        let hits = |x: f32, z_end: f32| {
            let pre = Pose3::from_parts(Vec3::new(x, 0.0, z_end + 0.08), down);
            scene.sweep_hits(&shape, &pre, Vec3::new(0.0, 0.0, -0.08))
        };
        for x in [0.0, 0.007, 0.0145] {
            assert!(!hits(x, 0.02), "fingers {} m beside the box", 0.015 - x);
        }
        assert!(hits(0.0151, 0.02), "a finger lands on the box's top edge");
        assert!(hits(0.0, -0.001), "the finger tips end in the table");
        assert!(
            !hits(0.0, 0.001),
            "the finger tips end 1 mm above the table"
        );
        // 3 cm fingers reaching 1 cm above the table: the palm lands on the 5 cm box.
        let short = Gripper {
            finger_length_m: 0.03,
            ..Gripper::default()
        };
        let short = HandShape::new(&short);
        let pre = Pose3::from_parts(Vec3::new(0.0, 0.0, 0.09), down);
        assert!(scene.sweep_hits(&short, &pre, Vec3::new(0.0, 0.0, -0.08)));
    }
}
