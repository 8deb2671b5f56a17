//! The physics trial among other objects (`simulate_grasp_among`): the approach must clear the
//! neighbours, and the object must come out alone.

use mvgrasp_geometry::{Pose3, Rot3, TriangleMesh, Vec3};
use mvgrasp_grasp::physics::{
    FailureStage, PhysicsObject, PhysicsParams, ShapeParams, simulate_grasp, simulate_grasp_among,
};
use mvgrasp_grasp::{Grasp, Gripper};
use parry3d::shape::Cuboid;

fn cube(half: f32) -> PhysicsObject {
    let (v, t) = Cuboid::new(Vec3::splat(half)).to_trimesh();
    PhysicsObject::new(&TriangleMesh::new(v, t).unwrap(), &ShapeParams::default()).unwrap()
}

/// A cube of half side `half` resting on the table with its centre at (x, y).
fn resting(half: f32, x: f32, y: f32) -> Pose3 {
    Pose3::from_translation(Vec3::new(x, y, half))
}

/// Straight down onto (x, 0, z), closing along world x.
fn top_down(x: f32, z: f32, width_m: f32) -> Grasp {
    Grasp {
        world_from_gripper: Pose3::from_parts(
            Vec3::new(x, 0.0, z),
            Rot3::from_rotation_x(std::f32::consts::PI),
        ),
        width_m,
    }
}

#[test]
fn without_neighbours_the_trial_is_the_single_object_trial() {
    let object = cube(0.025);
    let grasp = top_down(0.0, 0.02, 0.05);
    let params = PhysicsParams::default();
    let gripper = Gripper::default();
    let pose = resting(0.025, 0.0, 0.0);
    let alone = simulate_grasp(&object, &pose, &grasp, &gripper, &params).unwrap();
    let among = simulate_grasp_among(&object, &pose, &[], &grasp, &gripper, &params).unwrap();
    assert!(alone.success, "{alone:?}");
    assert_eq!(format!("{alone:?}"), format!("{among:?}"));
}

#[test]
fn a_neighbour_under_a_finger_stops_the_approach_and_one_beside_it_does_not() {
    let object = cube(0.025);
    let grasp = top_down(0.0, 0.02, 0.05);
    let params = PhysicsParams::default();
    let gripper = Gripper::default();
    let pose = resting(0.025, 0.0, 0.0);
    // The Panda opens 7 cm for this grasp: its fingers come down 3.5 cm either side of the
    // closing line, about 1 cm thick. A 2 cm cube 4.5 cm along x is under a finger; one 15 cm
    // along y is out of the way.
    let small = cube(0.01);
    let under = [(&small, resting(0.01, 0.045, 0.0))];
    let outcome = simulate_grasp_among(&object, &pose, &under, &grasp, &gripper, &params).unwrap();
    assert_eq!(
        outcome.failed_at,
        Some(FailureStage::Approach),
        "{outcome:?}"
    );
    let aside = [(&small, resting(0.01, 0.0, 0.15))];
    let outcome = simulate_grasp_among(&object, &pose, &aside, &grasp, &gripper, &params).unwrap();
    assert!(outcome.success, "{outcome:?}");
}

/// A plank 4 x 12 x 2 cm lying on the table, and a grasp straight down across its middle.
fn plank_gripped_across() -> (PhysicsObject, Pose3, Grasp) {
    let (v, t) = Cuboid::new(Vec3::new(0.02, 0.06, 0.01)).to_trimesh();
    let plank =
        PhysicsObject::new(&TriangleMesh::new(v, t).unwrap(), &ShapeParams::default()).unwrap();
    let pose = Pose3::from_translation(Vec3::new(0.0, 0.0, 0.01));
    (plank, pose, top_down(0.0, 0.012, 0.04))
}

#[test]
fn a_neighbour_lifted_with_the_object_is_not_a_grasp_of_the_object_alone() {
    // A plank 4 x 12 x 2 cm, gripped across its middle; a 2 cm cube resting on its far end,
    // clear of the hand, rides up with it: the plank is held, but not alone.
    let (plank, pose, grasp) = plank_gripped_across();
    let params = PhysicsParams::default();
    let gripper = Gripper::default();
    let alone = simulate_grasp(&plank, &pose, &grasp, &gripper, &params).unwrap();
    assert!(alone.success, "{alone:?}");
    let rider = cube(0.01);
    let on_top = [(&rider, Pose3::from_translation(Vec3::new(0.0, 0.045, 0.03)))];
    let outcome = simulate_grasp_among(&plank, &pose, &on_top, &grasp, &gripper, &params).unwrap();
    assert_eq!(outcome.failed_at, Some(FailureStage::Lift), "{outcome:?}");
    assert!(
        outcome.object_lift_m > 0.1,
        "the plank itself was lifted: {outcome:?}"
    );
}

#[test]
fn the_success_probability_among_neighbours_counts_a_neighbour_that_comes_along() {
    // The plank and the cube resting on its far end (as above): held alone in most perturbed
    // trials, far fewer with the cube on it.
    let (plank, pose, grasp) = plank_gripped_across();
    let params = PhysicsParams::default();
    // Small perturbations: the grasp is 8 mm above the table.
    let noise = mvgrasp_grasp::physics::PhysicsNoise {
        gripper_translation_sigma_m: 0.001,
        gripper_rotation_sigma_rad: 0.01,
        object_translation_sigma_m: 0.001,
        object_yaw_sigma_rad: 0.01,
        ..Default::default()
    };
    let gripper = Gripper::default();
    let small = cube(0.01);
    let on_it = [(&small, Pose3::from_translation(Vec3::new(0.0, 0.045, 0.03)))];
    let estimate = |neighbours: &[(&PhysicsObject, Pose3)]| {
        mvgrasp_grasp::physics::success_probability_among(
            &plank, &pose, neighbours, &grasp, &gripper, &params, &noise, 4, 7,
        )
        .unwrap()
        .probability
    };
    let alone = mvgrasp_grasp::physics::success_probability(
        &plank, &pose, &grasp, &gripper, &params, &noise, 4, 7,
    )
    .unwrap()
    .probability;
    assert_eq!(
        estimate(&[]),
        alone,
        "without neighbours, success_probability"
    );
    assert!(alone > 0.7, "{alone}");
    // The cube is not perturbed with the plank: it comes along in some trials, not all.
    let among = estimate(&on_it);
    assert!(among <= alone - 0.25, "{among} among, {alone} alone");
}
