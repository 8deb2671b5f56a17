//! The rapier world of one trial: the table, the object, and the gripper (a kinematic palm with
//! two force-limited prismatic fingers); plus the exact distance and sweep queries the trial
//! judges by.

use mvgrasp_geometry::{Pose3, Vec3};
use parry3d::query;
use parry3d::shape::SharedShape;
use parry3d::shape::{Cuboid, Shape, TriMesh};
use rapier3d::prelude::{
    CoefficientCombineRule, ColliderBuilder, ColliderHandle, FrictionModel, GenericJointBuilder,
    Group, ImpulseJointHandle, InteractionGroups, InteractionTestMode, JointAxesMask, JointAxis,
    PhysicsWorld, PrismaticJointBuilder, RigidBodyBuilder, RigidBodyHandle, RigidBodyType,
    SpringCoefficients,
};
use std::sync::Arc;

use crate::gripper::Gripper;
use crate::physics::object::PhysicsObject;
use crate::physics::params::PhysicsParams;
use crate::separation::{cuboid_hull_gap, cuboid_mesh_gap};

/// Half the side of the square table, metres: room for an object a metre across, and small
/// enough that the table's box in a tilted object's frame stays thin (see [`Scene::new`]).
const TABLE_HALF_SIDE_M: f32 = 0.6;
/// Half the thickness of the table slab (its top is z = 0), metres.
const TABLE_HALF_THICKNESS_M: f32 = 0.05;

const TABLE_GROUP: Group = Group::GROUP_1;
const OBJECT_GROUP: Group = Group::GROUP_2;
const GRIPPER_GROUP: Group = Group::GROUP_3;
/// The object's own surface, when the hand grips it ([`PhysicsParams::grip_true_surface`]).
const SURFACE_GROUP: Group = Group::GROUP_4;

/// The object group the hand touches: its true surface or its collision shape.
fn hand_touches(params: &PhysicsParams) -> Group {
    if params.grip_true_surface {
        SURFACE_GROUP
    } else {
        OBJECT_GROUP
    }
}

/// The table, the object and, once added, the gripper.
pub(crate) struct Scene {
    pub world: PhysicsWorld,
    pub table: ColliderHandle,
    pub object_body: RigidBodyHandle,
    /// The object's shape (one hull, or a compound of convex parts), in its body frame: for
    /// exact distances.
    object_shape: SharedShape,
    /// The object's true surface, in its body frame: for the approach.
    object_surface: Arc<TriMesh>,
    /// The other objects on the table ([`Scene::add_neighbour`]), each body with its true
    /// surface in its body frame.
    neighbours: Vec<(RigidBodyHandle, Arc<TriMesh>)>,
    /// The pads' twist friction, once the hand is in.
    pads: Vec<PadTwist>,
}

/// A pad's torsional friction beyond what its contacts give (see [`Scene::step`]).
struct PadTwist {
    pad: ColliderHandle,
    /// A joint from the finger to the object that locks nothing and only brakes their relative
    /// turn about the closing axis, up to the force the step allows.
    joint: ImpulseJointHandle,
    /// (2/3) mu r: the pad's torsional friction per newton pressing it, metres.
    twist_per_newton_m: f32,
    friction: f32,
}

/// The gripper's bodies, colliders and joints, and its shape in its own frame.
pub(crate) struct Hand {
    pub palm: RigidBodyHandle,
    /// The +x finger, then the -x finger.
    pub fingers: [RigidBodyHandle; 2],
    /// Each finger's colliders: its (recessed) box and its pad.
    pub finger_colliders: [[ColliderHandle; 2]; 2],
    pub shape: HandShape,
}

/// Radius of the balls whose contacts make up a simulated pad, metres (see
/// [`pad_ring_radius`]).
pub const PAD_BALL_RADIUS_M: f32 = 2.0e-3;

/// The simulated pad of `gripper` touches through [`PAD_BALLS`] balls of
/// [`PAD_BALL_RADIUS_M`] on a ring of this radius about the pad's centre, their tops flush with
/// the finger's inner face: (2/3) `pad_radius_m`, the mean lever arm of a round pad pressed
/// evenly, metres.
pub fn pad_ring_radius(gripper: &Gripper) -> f32 {
    PAD_LEVER * gripper.pad_radius_m
}
/// The mean lever arm of a round pad pressed evenly, over its radius: its torsional friction is
/// (2/3) mu F r.
const PAD_LEVER: f32 = 2.0 / 3.0;

/// Balls per simulated pad.
pub const PAD_BALLS: usize = 4;
/// In the simulated hand a finger's box stands this far back from the pad's face, so that the
/// pad, not the box, touches an object pressed flat against the finger, metres.
const PAD_PROUD_M: f32 = 3.0e-3;

/// The gripper's boxes in the gripper frame (origin midway between the finger tips, +z approach,
/// +x closing axis), fingers open for the grasp, and its pads.
#[derive(Clone, Copy, Debug)]
pub(crate) struct HandShape {
    pub finger: Cuboid,
    pub palm: Cuboid,
    /// Gripper-frame centre of the palm box.
    pub palm_center: Vec3,
    /// Gripper-frame |x| of a finger's centre when open for the grasp.
    pub finger_open_x: f32,
    /// Gripper-frame |x| of a finger's centre when shut to the narrowest.
    pub finger_shut_x: f32,
    /// Gripper-frame z of the finger centres.
    pub finger_z: f32,
    /// Finger thickness along x.
    pub thickness: f32,
    /// Gripper-frame z of the pads' centres.
    pub pad_z: f32,
    /// Pad radius.
    pub pad_radius: f32,
}

impl HandShape {
    /// The hand open `opening_m` (see [`Gripper::opening_for`]).
    pub fn new(gripper: &Gripper, opening_m: f32) -> Self {
        let open = gripper.finger_center(opening_m, 1.0);
        Self {
            finger: Cuboid::new(gripper.finger_half_extents()),
            palm: Cuboid::new(gripper.palm_half_extents()),
            palm_center: gripper.palm_center(),
            finger_open_x: open.x,
            finger_shut_x: gripper.finger_center(gripper.min_opening_m, 1.0).x,
            finger_z: open.z,
            thickness: gripper.finger_thickness_m,
            pad_z: gripper.pad_center(opening_m, 1.0).z,
            pad_radius: gripper.pad_radius_m,
        }
    }

    /// The +x finger's simulated box, in its body frame (the finger box's centre): the box
    /// with its inner face set back by [`PAD_PROUD_M`], behind the pad.
    fn recessed_finger(&self) -> (Cuboid, Vec3) {
        let half = self.finger.half_extents;
        let recess = PAD_PROUD_M.min(half.x);
        (
            Cuboid::new(Vec3::new(half.x - recess / 2.0, half.y, half.z)),
            Vec3::new(recess / 2.0, 0.0, 0.0),
        )
    }

    /// The +x finger's pad, in its body frame: [`PAD_BALLS`] small balls on a ring of radius
    /// (2/3) `pad_radius` about the pad's centre, their tops flush with the finger's inner face.
    ///
    /// A round pad of radius r pressed evenly with F resists a twist about its normal with up
    /// to (2/3) mu F r: its contact points' mean lever arm is (2/3) r. On the ring every
    /// contact has that arm, so the pad's torsional friction is exact however the solver
    /// shares F among them (a disk of contacts was tried: rapier loads its outer contacts more,
    /// so it resisted up to 20 % more than the pad). On a curved surface the ring still
    /// touches at two or three contacts apart, as a pad's patch does, not at a point.
    fn pad(&self) -> SharedShape {
        let balls = self
            .pad_ball_centers()
            .map(|center| {
                (
                    Pose3::from_translation(center),
                    SharedShape::ball(PAD_BALL_RADIUS_M),
                )
            })
            .collect();
        SharedShape::compound(balls)
    }

    /// The centres of the +x finger's pad balls in its body frame, in the pad's order.
    fn pad_ball_centers(&self) -> impl Iterator<Item = Vec3> {
        let face_x = -self.finger.half_extents.x + PAD_BALL_RADIUS_M;
        let pad_z = self.pad_z - self.finger_z;
        let ring = PAD_LEVER * self.pad_radius;
        (0..PAD_BALLS).map(move |i| {
            let angle = std::f32::consts::TAU * i as f32 / PAD_BALLS as f32;
            let (sin, cos) = angle.sin_cos();
            Vec3::new(face_x, ring * cos, pad_z + ring * sin)
        })
    }

    /// Gripper-frame poses of the +x and -x fingers open for the grasp.
    pub fn open_finger_poses(&self) -> [Pose3; 2] {
        [1.0, -1.0]
            .map(|s| Pose3::from_translation(Vec3::new(s * self.finger_open_x, 0.0, self.finger_z)))
    }
}

impl Scene {
    /// The table and `object` placed at `table_from_object` (world = table frame).
    pub fn new(object: &PhysicsObject, table_from_object: &Pose3, params: &PhysicsParams) -> Self {
        let (mut world, table) = table_world(params);
        let object_body = insert_object(&mut world, object, table_from_object, params);
        Self {
            world,
            table,
            object_body,
            object_shape: object.shape().clone(),
            object_surface: object.surface().clone(),
            neighbours: Vec::new(),
            pads: Vec::new(),
        }
    }

    /// Adds another object resting at `table_from_object`: it collides with the table, the
    /// object, the other neighbours and the hand, and the approach must clear it.
    pub fn add_neighbour(
        &mut self,
        object: &PhysicsObject,
        table_from_object: &Pose3,
        params: &PhysicsParams,
    ) {
        let body = insert_object(&mut self.world, object, table_from_object, params);
        self.neighbours.push((body, object.surface().clone()));
    }

    /// Adds a fixed obstacle at `table_from_object` (a bin's wall): objects and the hand
    /// collide with it and the approach must clear it, but nothing moves it. It grips like the
    /// table ([`PhysicsParams::table_friction`]).
    pub fn add_fixed(
        &mut self,
        object: &PhysicsObject,
        table_from_object: &Pose3,
        params: &PhysicsParams,
    ) {
        let body = insert_object(&mut self.world, object, table_from_object, params);
        if let Some(b) = self.world.bodies.get_mut(body) {
            b.set_body_type(RigidBodyType::Fixed, true);
            for &collider in b.colliders() {
                if let Some(c) = self.world.colliders.get_mut(collider) {
                    c.set_friction(params.table_friction);
                    c.set_friction_combine_rule(CoefficientCombineRule::Average);
                }
            }
        }
        self.neighbours.push((body, object.surface().clone()));
    }

    /// The neighbours' centres of mass in the world, in the order they were added.
    pub fn neighbour_coms(&self) -> Vec<Vec3> {
        self.neighbours
            .iter()
            .map(|(body, _)| {
                self.world
                    .bodies
                    .get(*body)
                    .map_or(Vec3::ZERO, |b| b.center_of_mass())
            })
            .collect()
    }

    /// One rapier step, after setting each pad's twist brake for it.
    ///
    /// A round pad of radius r pressed with F resists a twist about its normal with up to
    /// (2/3) mu F r, wherever on it the load lies; rapier's contacts resist with mu times the
    /// sum of each contact's load and its distance from their load centre, which is the pad's
    /// (2/3) mu F r when the load is on the ring of a flat face ([`HandShape::pad`]) and
    /// nothing when one ball touches a curved surface. The brake, a joint motor about the
    /// closing axis, makes up the difference, from the loads of the step before.
    pub fn step(&mut self, dt: f32) {
        for pad in &self.pads {
            let limit = self.twist_shortfall(pad, dt);
            if let Some(joint) = self.world.impulse_joints.get_mut(pad.joint, false) {
                joint.data.set_motor_max_force(JointAxis::AngX, limit);
            }
        }
        self.world.step();
    }

    /// (2/3) mu F r less what the pad's contacts resist, newton-metres (0 when untouched).
    fn twist_shortfall(&self, pad: &PadTwist, dt: f32) -> f32 {
        let colliders = &self.world.colliders;
        let on_object = |handle| {
            colliders
                .get(handle)
                .is_some_and(|c| c.parent() == Some(self.object_body))
        };
        // The pad's contacts with the object as the solver saw them (rapier clusters the
        // manifolds of parallel normals, as a pad's on a flat face, into a few points), each
        // with its point on the pad in the world and the impulse it bore.
        let Some(pad_pose) = colliders.get(pad.pad).map(|c| *c.position()) else {
            return 0.0;
        };
        let loads: Vec<(Vec3, f32)> = self
            .world
            .narrow_phase
            .contact_pairs_with(pad.pad)
            .filter(|pair| on_object(pair.collider1) || on_object(pair.collider2))
            .flat_map(|pair| {
                let pad_is_first = pair.collider1 == pad.pad;
                pair.solver_manifolds().iter().flat_map(move |m| {
                    let sub = if pad_is_first {
                        m.subshape_pos1()
                    } else {
                        m.subshape_pos2()
                    };
                    let frame = pad_pose * sub.copied().unwrap_or(Pose3::IDENTITY);
                    m.points.iter().map(move |p| {
                        let local = if pad_is_first { p.local_p1 } else { p.local_p2 };
                        (frame.transform_point(local), p.data.impulse.abs())
                    })
                })
            })
            .collect();
        let total: f32 = loads.iter().map(|(_, impulse)| impulse).sum();
        if total <= 0.0 {
            return 0.0;
        }
        let centre = loads.iter().map(|(p, i)| *p * *i).sum::<Vec3>() / total;
        let spread: f32 = loads.iter().map(|(p, i)| p.distance(centre) * i).sum();
        let force_n = total / dt;
        (pad.twist_per_newton_m * force_n - pad.friction * spread / dt).max(0.0)
    }

    /// Adds the gripper at `world_from_gripper`, fingers open `shape`'s opening and closing at
    /// `params.closing_speed_m_s` with at most `force_n` each; every part of the hand grips
    /// with the gripper's `pad_friction`.
    pub fn add_hand(
        &mut self,
        world_from_gripper: &Pose3,
        shape: HandShape,
        gripper: &Gripper,
        params: &PhysicsParams,
        force_n: f32,
    ) -> Hand {
        let gripper_groups = groups(GRIPPER_GROUP, TABLE_GROUP | hand_touches(params));
        let friction = gripper.pad_friction;
        let world = &mut self.world;
        let (palm, _) = world.insert(
            RigidBodyBuilder::kinematic_position_based().pose(*world_from_gripper),
            ColliderBuilder::new(SharedShape::new(shape.palm))
                .translation(shape.palm_center)
                .friction(friction)
                .collision_groups(gripper_groups),
        );
        let (finger_box, box_offset) = shape.recessed_finger();
        let finger_volume = 8.0 * finger_box.half_extents.element_product();
        let pad = shape.pad();
        let mut fingers = [palm; 2];
        let mut finger_colliders = [[ColliderHandle::invalid(); 2]; 2];
        for (i, (side, local)) in [1.0f32, -1.0]
            .into_iter()
            .zip(shape.open_finger_poses())
            .enumerate()
        {
            // The -x finger is the +x one turned half a turn about the approach axis.
            let mirror = if side > 0.0 {
                Pose3::IDENTITY
            } else {
                Pose3::from_rotation(mvgrasp_geometry::Rot3::from_rotation_z(
                    std::f32::consts::PI,
                ))
            };
            let (finger, collider) = world.insert(
                RigidBodyBuilder::dynamic()
                    .pose(*world_from_gripper * local)
                    .gravity_scale(0.0)
                    .can_sleep(false),
                ColliderBuilder::new(SharedShape::new(finger_box))
                    .position(mirror * Pose3::from_translation(box_offset))
                    .density(params.finger_mass_kg / finger_volume)
                    .friction(friction)
                    .collision_groups(gripper_groups),
            );
            let pad_collider = world.colliders.insert_with_parent(
                ColliderBuilder::new(pad.clone())
                    .position(mirror)
                    .density(0.0)
                    .friction(friction)
                    .collision_groups(groups(GRIPPER_GROUP, hand_touches(params))),
                finger,
                &mut world.bodies,
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
            finger_colliders[i] = [collider, pad_collider];
            // The twist brake: frames whose x is the closing axis on both bodies, as they
            // stand now.
            let world_from_finger = *world_from_gripper * local;
            let object_from_finger = world
                .bodies
                .get(self.object_body)
                .map_or(Pose3::IDENTITY, |b| {
                    b.position().inverse() * world_from_finger
                });
            let brake = GenericJointBuilder::new(JointAxesMask::empty())
                .local_frame1(Pose3::IDENTITY)
                .local_frame2(object_from_finger)
                .motor_velocity(JointAxis::AngX, 0.0, MOTOR_DAMPING)
                .motor_max_force(JointAxis::AngX, 0.0);
            let joint = world.insert_impulse_joint(finger, self.object_body, brake);
            self.pads.push(PadTwist {
                pad: pad_collider,
                joint,
                twist_per_newton_m: PAD_LEVER * friction * shape.pad_radius,
                friction,
            });
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

    /// Exact distance between a finger (its box or its pad, whichever is nearer) and the
    /// object, metres.
    pub fn finger_distance(&self, finger: [ColliderHandle; 2]) -> f32 {
        finger
            .into_iter()
            .map(|part| self.distance_to_object(part))
            .fold(f32::INFINITY, f32::min)
    }

    /// Exact distance between a collider and the object, metres (0 when they overlap;
    /// infinite when the collider is missing or the shapes are not supported).
    pub fn distance_to_object(&self, collider: ColliderHandle) -> f32 {
        match self.world.colliders.get(collider) {
            Some(c) => exact_distance(
                c.position(),
                c.shape(),
                &self.world_from_object(),
                &*self.object_shape,
            )
            .unwrap_or(f32::INFINITY),
            None => f32::INFINITY,
        }
    }

    /// Whether the open gripper, moving in a straight line from `world_from_pregrasp` by
    /// `motion` (world frame), comes within [`SWEEP_TOUCH_M`] of the table, the object or a
    /// neighbour anywhere on the way, the start and the end included.
    ///
    /// Conservative advancement on exact distances: a shape that is `d` away from an obstacle
    /// can move `d` along a straight line before it can touch it, so the path is walked in
    /// steps of the current distance. (parry 0.31's `cast_shapes` between a cuboid and a convex
    /// polyhedron reports hits for fingers passing 8 mm beside a box, so it is not used.)
    pub fn sweep_hits(&self, shape: &HandShape, world_from_pregrasp: &Pose3, motion: Vec3) -> bool {
        let mut moving: Vec<(Pose3, &Cuboid)> = shape
            .open_finger_poses()
            .into_iter()
            .map(|local| (*world_from_pregrasp * local, &shape.finger))
            .collect();
        moving.push((
            *world_from_pregrasp * Pose3::from_translation(shape.palm_center),
            &shape.palm,
        ));
        let world_from_object = self.world_from_object();
        let table = self
            .world
            .colliders
            .get(self.table)
            .map(|c| (*c.position(), c.shape()));
        moving.iter().any(|(start, cuboid)| {
            let to_object = |pose: &Pose3| {
                Some(cuboid_mesh_gap(
                    cuboid,
                    pose,
                    &self.object_surface,
                    &world_from_object,
                    SWEEP_REACH_M,
                ))
            };
            let to_table = |pose: &Pose3| {
                table.and_then(|(table_pose, table_shape)| {
                    exact_distance(pose, *cuboid, &table_pose, table_shape)
                })
            };
            path_touches(start, motion, to_object)
                || path_touches(start, motion, to_table)
                || self.neighbours.iter().any(|(body, surface)| {
                    let Some(world_from_neighbour) =
                        self.world.bodies.get(*body).map(|b| *b.position())
                    else {
                        return false;
                    };
                    path_touches(start, motion, |pose: &Pose3| {
                        Some(cuboid_mesh_gap(
                            cuboid,
                            pose,
                            surface,
                            &world_from_neighbour,
                            SWEEP_REACH_M,
                        ))
                    })
                })
        })
    }
}

/// A world of the trial's settings holding only the table (its top the plane z = 0), and the
/// table's collider.
pub(crate) fn table_world(params: &PhysicsParams) -> (PhysicsWorld, ColliderHandle) {
    let mut world = PhysicsWorld::new();
    world.gravity = Vec3::new(0.0, 0.0, -9.81);
    let ip = &mut world.integration_parameters;
    ip.dt = params.timestep_s;
    ip.num_solver_iterations = params.solver_iterations;
    ip.length_unit = params.solver_length_unit_m;
    let soft = SpringCoefficients::new(params.contact_frequency_hz, params.contact_damping_ratio);
    ip.contact_softness = soft;
    ip.static_contact_softness = soft;
    // One Coulomb cone per contact point: the torque a finger pad resists about the closing
    // axis comes from its contact points' spread, which decides off-centre grasps.
    ip.friction_model = FrictionModel::Coulomb;
    // Contacts are recomputed only when a pair has moved by more than 0.3 mm since (rapier's
    // default, 15 mm at this length unit, let the fingers squeeze through a can on stale
    // contacts); a resting or held object's pairs are reused, most of a trial's steps.
    ip.contact_recycling = true;
    ip.normalized_contact_recycle_distance = 1.0e-3;
    // No continuous collision detection: nothing moves faster than a few millimetres a step
    // (the contacts' prediction distance), and its sweeps recomputed every slab's mass
    // properties each step, a third of a trial's time on a shell of slabs.
    ip.max_ccd_substeps = 0;

    let table_body = world.insert_body(RigidBodyBuilder::fixed());
    let table = world.insert_collider(
        ColliderBuilder::cuboid(TABLE_HALF_SIDE_M, TABLE_HALF_SIDE_M, TABLE_HALF_THICKNESS_M)
            .translation(Vec3::new(0.0, 0.0, -TABLE_HALF_THICKNESS_M))
            .friction(params.table_friction)
            .collision_groups(groups(TABLE_GROUP, Group::ALL)),
        Some(table_body),
    );
    (world, table)
}

/// Inserts `object` as a dynamic body resting at `table_from_object`, with its collision
/// shape (and its true surface, when the hand grips that); its body.
pub(crate) fn insert_object(
    world: &mut PhysicsWorld,
    object: &PhysicsObject,
    table_from_object: &Pose3,
    params: &PhysicsParams,
) -> RigidBodyHandle {
    let object_body = world.insert_body(
        RigidBodyBuilder::dynamic()
            .pose(*table_from_object)
            .can_sleep(false),
    );
    // One collider: the parts turned to stand as they rest on the table, so that the
    // compound's frame is the table's. rapier finds the parts near another shape by that
    // shape's box in the compound's frame: in the mesh's own frame the box of a table
    // tilted under a lying object spans every part, and hundreds of parts then cost
    // seconds a trial; axis-aligned it holds the parts near the table only.
    let turn = Pose3::from_rotation(table_from_object.rotation);
    let parts: Vec<(Pose3, SharedShape)> = object
        .parts()
        .into_iter()
        .map(|(pose, part)| (turn * pose, part))
        .collect();
    let shape = match parts.as_slice() {
        [(pose, only)] if *pose == Pose3::IDENTITY => only.clone(),
        _ => SharedShape::compound(parts),
    };
    let collider_in_body = turn.inverse();
    world.colliders.insert_with_parent(
        // Friction 1 combined by product: a pair's coefficient is the other collider's, so
        // the table's against the table and the pads' against the hand.
        ColliderBuilder::new(shape)
            .position(collider_in_body)
            // A collider's mass properties are in its own frame.
            .mass_properties(
                object
                    .mass_properties(params.object_density_kg_m3)
                    .transform_by(&turn),
            )
            .friction(1.0)
            .friction_combine_rule(CoefficientCombineRule::Multiply)
            .collision_groups(groups(OBJECT_GROUP, Group::ALL)),
        object_body,
        &mut world.bodies,
    );
    if params.grip_true_surface {
        world.colliders.insert_with_parent(
            ColliderBuilder::new(SharedShape(object.surface().clone()))
                .density(0.0)
                .friction(1.0)
                .friction_combine_rule(CoefficientCombineRule::Multiply)
                .collision_groups(groups(SURFACE_GROUP, GRIPPER_GROUP)),
            object_body,
            &mut world.bodies,
        );
    }
    object_body
}

/// How close the sweep may come to an obstacle before it counts as touching it, metres.
pub(crate) const SWEEP_TOUCH_M: f32 = 1.0e-4;

/// How far the sweep looks for the object's triangles around the hand at each step, metres
/// (a step is at most this long).
const SWEEP_REACH_M: f32 = 0.02;

/// The most distance queries one shape's sweep may take; beyond, it counts as touching (a path
/// grazing an obstacle at just over [`SWEEP_TOUCH_M`] for its whole length).
const MAX_SWEEP_QUERIES: usize = 4096;

/// Whether a shape translated from `start` by `motion` comes within [`SWEEP_TOUCH_M`] of an
/// obstacle, `distance` giving a lower bound on its distance at a pose (`None`: it cannot be
/// measured, which counts as touching: a grasp is never passed unchecked).
fn path_touches(start: &Pose3, motion: Vec3, distance: impl Fn(&Pose3) -> Option<f32>) -> bool {
    let length = motion.length();
    let mut t = 0.0f32;
    for _ in 0..MAX_SWEEP_QUERIES {
        let pose = Pose3::from_parts(start.translation + motion * t, start.rotation);
        let Some(d) = distance(&pose) else {
            return true;
        };
        if d <= SWEEP_TOUCH_M {
            return true;
        }
        if t >= 1.0 || length == 0.0 {
            return false;
        }
        t = (t + d / length).min(1.0);
    }
    true
}

/// The distance between `a` and `b` (one convex shape or a compound of them), metres; `None` when
/// parry cannot measure the pair.
///
/// A compound is measured part by part, and no part is nearer than the gap between its box and
/// `a`'s. Where GJK reads a box as touching a convex part, the separating axes decide (see
/// [`crate::separation`]: parry 0.31's GJK reads thin slabs millimetres away as touching).
fn exact_distance(pose_a: &Pose3, a: &dyn Shape, pose_b: &Pose3, b: &dyn Shape) -> Option<f32> {
    let Some(compound) = b.as_compound() else {
        return query::distance(pose_a, a, pose_b, b)
            .ok()
            .map(|d| d.distance);
    };
    let box_a = a.compute_aabb(pose_a);
    let mut best = f32::INFINITY;
    for (part_pose, part) in compound.shapes() {
        let world = *pose_b * *part_pose;
        let gap = aabb_gap(&box_a, &part.compute_aabb(&world));
        if gap >= best {
            continue;
        }
        let mut d = query::distance(pose_a, a, &world, &**part).ok()?.distance;
        if d <= SWEEP_TOUCH_M
            && let (Some(cuboid), Some(hull)) = (a.as_cuboid(), part.as_convex_polyhedron())
            && hull.points().len() <= MAX_CHECKED_HULL_POINTS
        {
            d = d.max(cuboid_hull_gap(cuboid, pose_a, hull, &world));
        }
        best = best.min(d.max(gap));
    }
    Some(best)
}

/// The most corners a convex part may have for the separating axes to re-check a GJK
/// "touching" on it: a shell's slabs (where GJK fails) have a few dozen; the check costs
/// corners times edges, and on an object's hull of thousands of corners it took a third of a
/// trial, only to confirm real touches.
const MAX_CHECKED_HULL_POINTS: usize = 64;

/// The distance between two boxes (0 when they overlap).
fn aabb_gap(a: &parry3d::bounding_volume::Aabb, b: &parry3d::bounding_volume::Aabb) -> f32 {
    let below = (b.mins - a.maxs).max(Vec3::ZERO);
    let above = (a.mins - b.maxs).max(Vec3::ZERO);
    (below + above).length()
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
        let shape = HandShape::new(&Gripper::default(), 0.08);
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
        let short = HandShape::new(&short, 0.08);
        let pre = Pose3::from_parts(Vec3::new(0.0, 0.0, 0.09), down);
        assert!(scene.sweep_hits(&short, &pre, Vec3::new(0.0, 0.0, -0.08)));
    }

    /// The sweep's distance to a compound of slabs backs GJK with the separating axes: a 1 mm
    /// slab about 5 mm beside a finger-sized box (GJK: 0) is about 5 mm away.
    #[test]
    fn a_slab_beside_a_box_is_apart_for_the_sweep() {
        let (points, finger, pose) = crate::separation::slab_beside_a_box();
        let slab = SharedShape::convex_hull(&points).unwrap();
        let compound = SharedShape::compound(vec![(Pose3::IDENTITY, slab)]);
        let d = exact_distance(&pose, &finger, &Pose3::IDENTITY, &*compound).unwrap();
        assert!((0.0045..=0.0055).contains(&d), "{d}");
    }
}
