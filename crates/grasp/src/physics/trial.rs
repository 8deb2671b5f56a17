//! One physics trial of a grasp: settle, approach, close, lift, shake ([`simulate_grasp`]).

use mvgrasp_geometry::{Pose3, Rot3, Vec3};
use serde::{Deserialize, Serialize};

use crate::error::{GraspError, Result};
use crate::grasp::Grasp;
use crate::gripper::Gripper;
use crate::physics::object::PhysicsObject;
use crate::physics::params::PhysicsParams;
use crate::physics::scene::{Hand, HandShape, Scene};

/// Fingers closer than this to their narrowest opening have shut on nothing, metres.
const SHUT_TOLERANCE_M: f32 = 1.0e-3;

/// Where a trial failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FailureStage {
    /// The object did not stay in its pose on the table before the gripper came (it rolled or
    /// toppled): the pose is not stable, so the grasp was not tried.
    Settle,
    /// The open gripper touched the table or the object on its way from the pre-grasp pose to
    /// the grasp pose.
    Approach,
    /// Nothing between the fingers after closing: a finger does not touch the object, or they
    /// shut to their narrowest.
    Close,
    /// The object slipped out or was left on the table during the lift.
    Lift,
    /// The object was dropped (or slid too far) during the shake.
    Shake,
}

impl FailureStage {
    /// Every stage, in the order a trial runs them (`stage as usize` indexes this).
    pub const ALL: [FailureStage; 5] = [
        Self::Settle,
        Self::Approach,
        Self::Close,
        Self::Lift,
        Self::Shake,
    ];

    /// The stage's name, as in JSON.
    pub fn name(self) -> &'static str {
        match self {
            Self::Settle => "settle",
            Self::Approach => "approach",
            Self::Close => "close",
            Self::Lift => "lift",
            Self::Shake => "shake",
        }
    }
}

/// What happened in one trial.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PhysicsOutcome {
    /// The object was held at the end (see [`crate::physics`] for the criterion).
    pub success: bool,
    /// The stage that failed, `None` on success.
    pub failed_at: Option<FailureStage>,
    /// How far the object's centre of mass rose above where it rested on the table, metres
    /// (at the end of the trial, which is the end of the failed stage on a failure).
    pub object_lift_m: f32,
    /// How far the object's centre of mass moved relative to the gripper since the fingers
    /// closed, metres (0 when they never closed).
    pub slip_m: f32,
    /// How much the object turned relative to the gripper since the fingers closed, radians.
    pub slip_rad: f32,
    /// Opening between the finger pads at the end, metres (0 when the gripper never came).
    pub opening_m: f32,
    /// The object's final pose in the world (the table frame).
    #[serde(with = "mvgrasp_geometry::pose_as_matrix")]
    pub world_from_object: Pose3,
    /// Simulated time, seconds.
    pub sim_time_s: f32,
    /// rapier steps taken.
    pub steps: u32,
}

/// Simulates `grasp` (world frame) with `gripper` on `object` resting at `table_from_object`.
///
/// The object is placed (a stable pose puts its face on the table plane z = 0) and settles; the
/// open gripper sweeps from the pre-grasp pose to the grasp pose; the fingers close with the
/// force limit; the palm lifts and shakes. See [`crate::physics`] for the phases and the success
/// criterion. Deterministic: the same inputs give the same outcome, bit for bit.
///
/// # Errors
/// [`GraspError::InvalidParameter`] for invalid `params` or `gripper`, or a non-finite pose.
pub fn simulate_grasp(
    object: &PhysicsObject,
    table_from_object: &Pose3,
    grasp: &Grasp,
    gripper: &Gripper,
    params: &PhysicsParams,
) -> Result<PhysicsOutcome> {
    simulate_grasp_among(object, table_from_object, &[], grasp, gripper, params)
}

/// [`simulate_grasp`] with other objects on the table (`neighbours`, each resting at its pose):
/// they settle with the object, the approach must clear them as it clears the object, the hand
/// and the object push them as they meet, and the object is held only if it comes out alone:
/// a neighbour whose centre of mass has risen as far as the object must
/// ([`PhysicsParams::min_lift_fraction`] of the lift) has come along, and the phase fails.
/// Without neighbours it is [`simulate_grasp`], step for step.
///
/// # Errors
/// See [`simulate_grasp`]; a non-finite neighbour pose.
pub fn simulate_grasp_among(
    object: &PhysicsObject,
    table_from_object: &Pose3,
    neighbours: &[(&PhysicsObject, Pose3)],
    grasp: &Grasp,
    gripper: &Gripper,
    params: &PhysicsParams,
) -> Result<PhysicsOutcome> {
    simulate_grasp_in_scene(
        object,
        table_from_object,
        neighbours,
        &[],
        grasp,
        gripper,
        params,
    )
}

/// [`simulate_grasp_among`] with fixed obstacles beside the neighbours (`fixed`, each at its
/// pose: a bin's walls): objects and the hand collide with them and the approach must clear
/// them, but nothing moves them.
///
/// # Errors
/// See [`simulate_grasp_among`]; a non-finite obstacle pose.
pub fn simulate_grasp_in_scene(
    object: &PhysicsObject,
    table_from_object: &Pose3,
    neighbours: &[(&PhysicsObject, Pose3)],
    fixed: &[(&PhysicsObject, Pose3)],
    grasp: &Grasp,
    gripper: &Gripper,
    params: &PhysicsParams,
) -> Result<PhysicsOutcome> {
    if let Some((_, pose)) = neighbours
        .iter()
        .chain(fixed)
        .find(|(_, pose)| !pose.is_finite())
    {
        return Err(GraspError::InvalidParameter {
            op: "physics trial",
            name: "neighbour pose",
            value: format!("{pose:?}"),
            expected: "a finite pose",
        });
    }
    params.validate()?;
    gripper.validate()?;
    for (name, pose) in [
        ("table_from_object", table_from_object),
        ("grasp.world_from_gripper", &grasp.world_from_gripper),
    ] {
        if !pose.is_finite() {
            return Err(GraspError::InvalidParameter {
                op: "physics trial",
                name,
                value: format!("{pose:?}"),
                expected: "a finite pose",
            });
        }
    }
    let mut scene = Scene::new(object, table_from_object, params);
    for (neighbour, pose) in neighbours {
        scene.add_neighbour(neighbour, pose, params);
    }
    for (obstacle, pose) in fixed {
        scene.add_fixed(obstacle, pose, params);
    }
    let mut trial = Trial {
        scene,
        params,
        steps: 0,
    };
    Ok(trial.run(grasp, gripper))
}

struct Trial<'a> {
    scene: Scene,
    params: &'a PhysicsParams,
    steps: u32,
}

/// What the trial knows once the fingers have closed.
struct Grip {
    hand: Hand,
    /// The gripper's narrowest opening: fingers within [`SHUT_TOLERANCE_M`] of it hold nothing.
    min_opening_m: f32,
    rest_com_z: f32,
    /// The neighbours' centres of mass' heights once settled.
    neighbour_rest_z: Vec<f32>,
    /// The object in the gripper frame when the fingers had closed.
    gripper_from_object: Pose3,
    /// Its centre of mass in the gripper frame then.
    com_in_gripper: Vec3,
}

/// How the object sits in the hand at a checkpoint.
struct Hold {
    held: bool,
    lift_m: f32,
    slip_m: f32,
    slip_rad: f32,
    opening_m: f32,
}

impl Trial<'_> {
    fn run(&mut self, grasp: &Grasp, gripper: &Gripper) -> PhysicsOutcome {
        let Some(rest_com) = self.settle() else {
            return self.failure(FailureStage::Settle, 0.0);
        };
        let shape = HandShape::new(gripper, gripper.opening_for(grasp.width_m));
        if self.approach_hits(&shape, grasp, gripper.approach_distance_m) {
            return self.failure(FailureStage::Approach, 0.0);
        }
        let grip = match self.close(grasp, shape, gripper, rest_com) {
            Ok(grip) => grip,
            Err(opening_m) => return self.failure(FailureStage::Close, opening_m),
        };
        let lifted = self.lift(&grip, &grasp.world_from_gripper);
        let hold = self.hold(&grip);
        if !hold.held {
            return self.outcome(Some(FailureStage::Lift), &hold);
        }
        self.shake(&grip, &lifted);
        let hold = self.hold(&grip);
        self.outcome((!hold.held).then_some(FailureStage::Shake), &hold)
    }

    /// Lets the object rest; its centre of mass once settled, or `None` if it moved or turned
    /// beyond the settle tolerances.
    fn settle(&mut self) -> Option<Vec3> {
        let p = self.params;
        let placed = self.scene.world_from_object();
        let placed_com = self.scene.object_com();
        self.step_for(p.settle_time_s);
        let rested = self.scene.world_from_object();
        let rest_com = self.scene.object_com();
        let turned = (placed.rotation.inverse() * rested.rotation)
            .to_axis_angle()
            .1;
        let stable = rest_com.distance(placed_com) <= p.settle_tolerance_m
            && turned <= p.settle_tolerance_rad;
        stable.then_some(rest_com)
    }

    /// Whether the open gripper touches anything on its way from the pre-grasp pose.
    fn approach_hits(&self, shape: &HandShape, grasp: &Grasp, approach_distance_m: f32) -> bool {
        let travel = grasp.approach() * approach_distance_m;
        let world_from_grasp = grasp.world_from_gripper;
        let pregrasp = Pose3::from_parts(
            world_from_grasp.translation - travel,
            world_from_grasp.rotation,
        );
        self.scene.sweep_hits(shape, &pregrasp, travel)
    }

    /// Adds the hand at the grasp pose and closes it; the grip, or the opening when the
    /// fingers hold nothing.
    fn close(
        &mut self,
        grasp: &Grasp,
        shape: HandShape,
        gripper: &Gripper,
        rest_com: Vec3,
    ) -> std::result::Result<Grip, f32> {
        let p = self.params;
        let neighbour_rest_z: Vec<f32> = self.scene.neighbour_coms().iter().map(|c| c.z).collect();
        let force_n = p.closing_force_n.unwrap_or(gripper.force_limit_n);
        let hand = self
            .scene
            .add_hand(&grasp.world_from_gripper, shape, gripper, p, force_n);
        let travel_m = hand.shape.finger_open_x - hand.shape.finger_shut_x;
        let max_steps = self.steps_for(travel_m / p.closing_speed_m_s + 0.1);
        let slow = 0.1 * p.closing_speed_m_s;
        let mut still = 0;
        for _ in 0..max_steps {
            self.step();
            let stopped = hand
                .fingers
                .iter()
                .all(|&f| self.finger_speed(&hand, f) < slow);
            still = if stopped { still + 1 } else { 0 };
            if still >= 3 {
                break;
            }
        }
        self.step_for(p.close_hold_s);
        let opening_m = self.opening(&hand);
        let touching = hand
            .finger_colliders
            .iter()
            .all(|&f| self.scene.finger_distance(f) <= p.contact_tolerance_m);
        if !touching || shut(opening_m, gripper.min_opening_m) {
            return Err(opening_m);
        }
        let world_from_gripper = self.palm_pose(&hand);
        Ok(Grip {
            min_opening_m: gripper.min_opening_m,
            rest_com_z: rest_com.z,
            neighbour_rest_z,
            gripper_from_object: world_from_gripper.inverse() * self.scene.world_from_object(),
            com_in_gripper: world_from_gripper.inverse_transform_point(self.scene.object_com()),
            hand,
        })
    }

    /// Lifts the palm straight up on a minimum-jerk profile and holds still; the lifted pose.
    fn lift(&mut self, grip: &Grip, world_from_grasp: &Pose3) -> Pose3 {
        let p = self.params;
        let steps = self.steps_for(p.lift_duration_s).max(1);
        let raised = |s: f32| {
            Pose3::from_parts(
                world_from_grasp.translation + Vec3::Z * (p.lift_height_m * s),
                world_from_grasp.rotation,
            )
        };
        for k in 1..=steps {
            self.move_palm(&grip.hand, &raised(min_jerk(k as f32 / steps as f32)));
            self.step();
        }
        let lifted = raised(1.0);
        self.move_palm(&grip.hand, &lifted);
        self.step_for(p.lift_hold_s);
        lifted
    }

    /// Shakes the palm about `lifted`: up and down, and turning about the closing axis, faded
    /// in and out by a half sine; then holds still.
    fn shake(&mut self, grip: &Grip, lifted: &Pose3) {
        let p = self.params;
        let axis = lifted.transform_vector(Vec3::X);
        let steps = self.steps_for(p.shake_duration_s);
        let omega = std::f32::consts::TAU * p.shake_frequency_hz;
        for k in 1..=steps {
            let t = k as f32 * p.timestep_s;
            let fade = (std::f32::consts::PI * k as f32 / steps as f32).sin();
            let u = (omega * t).sin() * fade;
            let target = Pose3::from_parts(
                lifted.translation + Vec3::Z * (p.shake_amplitude_m * u),
                Rot3::from_axis_angle(axis, p.shake_angle_rad * u) * lifted.rotation,
            );
            self.move_palm(&grip.hand, &target);
            self.step();
        }
        self.move_palm(&grip.hand, lifted);
        self.step_for(p.final_hold_s);
    }

    fn steps_for(&self, seconds: f32) -> u32 {
        (seconds / self.params.timestep_s).round() as u32
    }

    fn step(&mut self) {
        self.scene.step(self.params.timestep_s);
        self.steps += 1;
    }

    fn step_for(&mut self, seconds: f32) {
        for _ in 0..self.steps_for(seconds) {
            self.step();
        }
    }

    fn palm_pose(&self, hand: &Hand) -> Pose3 {
        self.scene
            .world
            .bodies
            .get(hand.palm)
            .map_or(Pose3::IDENTITY, |b| *b.position())
    }

    fn move_palm(&mut self, hand: &Hand, target: &Pose3) {
        if let Some(palm) = self.scene.world.bodies.get_mut(hand.palm) {
            palm.set_next_kinematic_position(*target);
        }
    }

    /// A finger's speed along the closing axis relative to the palm.
    fn finger_speed(&self, hand: &Hand, finger: rapier3d::prelude::RigidBodyHandle) -> f32 {
        let bodies = &self.scene.world.bodies;
        match (bodies.get(hand.palm), bodies.get(finger)) {
            (Some(palm), Some(finger)) => {
                let axis = palm.position().transform_vector(Vec3::X);
                (finger.linvel() - palm.linvel()).dot(axis).abs()
            }
            _ => 0.0,
        }
    }

    /// The opening between the finger pads, metres.
    fn opening(&self, hand: &Hand) -> f32 {
        let palm = self.palm_pose(hand);
        let bodies = &self.scene.world.bodies;
        let x = hand.fingers.map(|f| {
            bodies
                .get(f)
                .map_or(0.0, |b| palm.inverse_transform_point(b.translation()).x)
        });
        (x[0] - x[1] - hand.shape.thickness).max(0.0)
    }

    /// The held test: both fingers touch the object, the table does not, the fingers have not
    /// shut (an object between them keeps them apart; shut fingers touching it have passed into
    /// its collision shape or carry it hanging on one finger), the centre of mass has risen
    /// enough and has not slid too far in the hand.
    fn hold(&self, grip: &Grip) -> Hold {
        let p = self.params;
        let scene = &self.scene;
        let world_from_gripper = self.palm_pose(&grip.hand);
        let com = scene.object_com();
        let lift_m = com.z - grip.rest_com_z;
        let slip_m = world_from_gripper
            .inverse_transform_point(com)
            .distance(grip.com_in_gripper);
        let gripper_from_object = world_from_gripper.inverse() * scene.world_from_object();
        let slip_rad = (grip.gripper_from_object.rotation.inverse() * gripper_from_object.rotation)
            .to_axis_angle()
            .1;
        let fingers_touch = grip
            .hand
            .finger_colliders
            .iter()
            .all(|&f| scene.finger_distance(f) <= p.contact_tolerance_m);
        let off_table = scene.distance_to_object(scene.table) > p.contact_tolerance_m;
        let min_lift_m = p.min_lift_fraction * p.lift_height_m;
        let alone = scene
            .neighbour_coms()
            .iter()
            .zip(&grip.neighbour_rest_z)
            .all(|(com, rest_z)| com.z - rest_z < min_lift_m);
        let opening_m = self.opening(&grip.hand);
        Hold {
            held: fingers_touch
                && off_table
                && alone
                && !shut(opening_m, grip.min_opening_m)
                && lift_m >= min_lift_m
                && p.max_slip_m.is_none_or(|max| slip_m <= max),
            lift_m,
            slip_m,
            slip_rad,
            opening_m,
        }
    }

    fn failure(&self, stage: FailureStage, opening_m: f32) -> PhysicsOutcome {
        self.outcome(
            Some(stage),
            &Hold {
                held: false,
                lift_m: 0.0,
                slip_m: 0.0,
                slip_rad: 0.0,
                opening_m,
            },
        )
    }

    fn outcome(&self, failed_at: Option<FailureStage>, hold: &Hold) -> PhysicsOutcome {
        PhysicsOutcome {
            success: failed_at.is_none(),
            failed_at,
            object_lift_m: hold.lift_m,
            slip_m: hold.slip_m,
            slip_rad: hold.slip_rad,
            opening_m: hold.opening_m,
            world_from_object: self.scene.world_from_object(),
            sim_time_s: self.steps as f32 * self.params.timestep_s,
            steps: self.steps,
        }
    }
}

/// The minimum-jerk profile from 0 to 1 over s in [0, 1]: zero velocity and acceleration at
/// both ends.
fn min_jerk(s: f32) -> f32 {
    let s = s.clamp(0.0, 1.0);
    s * s * s * (10.0 + s * (-15.0 + 6.0 * s))
}

/// Whether fingers at `opening_m` have shut: within [`SHUT_TOLERANCE_M`] of the gripper's
/// narrowest opening, where nothing is between them.
fn shut(opening_m: f32, min_opening_m: f32) -> bool {
    opening_m <= min_opening_m + SHUT_TOLERANCE_M
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fingers_within_a_millimetre_of_their_narrowest_have_shut() {
        assert!(shut(0.0, 0.0));
        assert!(shut(0.4e-3, 0.0));
        assert!(!shut(2.0e-3, 0.0));
        assert!(shut(10.5e-3, 10.0e-3));
        assert!(!shut(12.0e-3, 10.0e-3));
    }

    #[test]
    fn min_jerk_runs_from_zero_to_one_smoothly() {
        assert_eq!(min_jerk(0.0), 0.0);
        assert!((min_jerk(1.0) - 1.0).abs() < 1e-6);
        assert!((min_jerk(0.5) - 0.5).abs() < 1e-6);
        assert!(min_jerk(0.01) < 1e-4);
    }
}
