#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
//! Physics validation with known answers: a box lifted by a centred grasp, dropped or missed by
//! bad ones, an approach through the table, determinism, and (ignored, run in release) the cost
//! of a trial.

use mvgrasp_geometry::{Pose3, Rot3, StablePoseParams, TriangleMesh, Vec3, stable_poses};
use mvgrasp_grasp::physics::{
    FailureStage, PhysicsNoise, PhysicsObject, PhysicsOutcome, PhysicsParams, ShapeParams,
    simulate_grasp, success_probability,
};
use mvgrasp_grasp::{Grasp, Gripper, GripperPreset};
use parry3d::shape::Cuboid;

fn box_mesh(half: Vec3) -> TriangleMesh {
    let (v, t) = Cuboid::new(half).to_trimesh();
    TriangleMesh::new(v, t).unwrap()
}

/// The object and its most probable stable pose.
fn on_table(mesh: &TriangleMesh) -> (PhysicsObject, Pose3) {
    let object = PhysicsObject::new(mesh, &ShapeParams::default()).unwrap();
    let pose = stable_poses(mesh, &StablePoseParams::default()).unwrap()[0].table_from_object;
    (object, pose)
}

/// A top-down grasp (approach straight down) with its closing line at `center`, closing along
/// world x turned by `yaw_rad` about the vertical.
fn top_down(center: Vec3, yaw_rad: f32, width_m: f32) -> Grasp {
    let rotation = Rot3::from_rotation_z(yaw_rad) * Rot3::from_rotation_x(std::f32::consts::PI);
    Grasp {
        world_from_gripper: Pose3::from_parts(center, rotation),
        width_m,
    }
}

fn panda() -> Gripper {
    Gripper::preset(GripperPreset::Panda)
}

fn run(object: &PhysicsObject, pose: &Pose3, grasp: &Grasp) -> PhysicsOutcome {
    simulate_grasp(object, pose, grasp, &panda(), &PhysicsParams::default()).unwrap()
}

#[test]
fn a_centred_top_down_grasp_lifts_a_5cm_box_through_the_shake() {
    let (object, pose) = on_table(&box_mesh(Vec3::splat(0.025)));
    // Closing line 2 cm above the table: the 5 cm fingers overlap the box's sides by 3 cm.
    let outcome = run(
        &object,
        &pose,
        &top_down(Vec3::new(0.0, 0.0, 0.02), 0.0, 0.05),
    );
    assert!(outcome.success, "{outcome:?}");
    assert_eq!(outcome.failed_at, None);
    assert!(
        (outcome.object_lift_m - 0.15).abs() < 0.02,
        "lifted with the palm: {outcome:?}"
    );
    assert!(
        (outcome.opening_m - 0.05).abs() < 0.003,
        "the fingers rest on the box's faces: {outcome:?}"
    );
    assert!(outcome.slip_m < 0.01, "{outcome:?}");
}

#[test]
fn fingers_closing_above_the_box_top_hold_nothing() {
    // The closing line 5 mm above the 5 cm box's top: the fingers meet over it, touching
    // nothing, and shut to their narrowest.
    let (object, pose) = on_table(&box_mesh(Vec3::splat(0.025)));
    let outcome = run(
        &object,
        &pose,
        &top_down(Vec3::new(0.0, 0.0, 0.055), 0.0, 0.05),
    );
    assert!(!outcome.success);
    assert_eq!(outcome.failed_at, Some(FailureStage::Close), "{outcome:?}");
    assert!(outcome.opening_m < 0.002, "{outcome:?}");
}

#[test]
fn a_grip_too_weak_to_carry_the_weight_slips_during_the_lift() {
    // 0.125 kg weighs 1.23 N; two fingers squeezing 0.5 N each with the pads' friction 0.5
    // hold at most 0.5 N: the box stays on the table.
    let (object, pose) = on_table(&box_mesh(Vec3::splat(0.025)));
    let params = PhysicsParams {
        closing_force_n: Some(0.5),
        ..PhysicsParams::default()
    };
    let grasp = top_down(Vec3::new(0.0, 0.0, 0.02), 0.0, 0.05);
    let outcome = simulate_grasp(&object, &pose, &grasp, &panda(), &params).unwrap();
    assert_eq!(outcome.failed_at, Some(FailureStage::Lift), "{outcome:?}");
    assert!(outcome.object_lift_m < 0.05, "{outcome:?}");
}

#[test]
fn a_weak_grip_far_off_centre_lets_a_stick_pivot_out() {
    // A 20 x 3 x 3 cm stick (0.18 kg) gripped with 5 N a finger. At its centre friction carries
    // the weight (2 x 0.5 x 5 N = 5 N > 1.8 N). 8 cm off centre gravity pulls with 0.14 N m
    // about the closing axis, more than the two 1 cm pads can resist (2 x (2/3) x 0.5 x 5 N x
    // 1 cm = 0.033 N m): the stick swings down about the closing axis, its far end back on the
    // table.
    let (object, pose) = on_table(&box_mesh(Vec3::new(0.1, 0.015, 0.015)));
    let params = PhysicsParams {
        closing_force_n: Some(5.0),
        ..PhysicsParams::default()
    };
    let across = |x: f32| top_down(Vec3::new(x, 0.0, 0.01), std::f32::consts::FRAC_PI_2, 0.03);
    let centred = simulate_grasp(&object, &pose, &across(0.0), &panda(), &params).unwrap();
    assert!(centred.success, "{centred:?}");
    let off = simulate_grasp(&object, &pose, &across(0.08), &panda(), &params).unwrap();
    assert_eq!(off.failed_at, Some(FailureStage::Lift), "{off:?}");
    assert!(off.slip_rad > 0.5, "it turned in the hand: {off:?}");
    // Panda's full 70 N holds it there.
    let strong = run(&object, &pose, &across(0.08));
    assert!(strong.success, "{strong:?}");
}

#[test]
fn a_decomposed_l_shape_is_lifted_by_one_arm() {
    // Two 2 cm thick bars, 10 cm each, in an L lying flat; its centre of mass is outside both.
    let a = box_mesh(Vec3::new(0.05, 0.01, 0.01));
    let b = box_mesh(Vec3::new(0.01, 0.05, 0.01))
        .transformed(&Pose3::from_translation(Vec3::new(0.04, 0.06, 0.0)));
    let l = TriangleMesh::concatenate(&[a, b], std::path::Path::new("l")).unwrap();
    let object = PhysicsObject::new(&l, &ShapeParams::default()).unwrap();
    assert!(object.num_parts() >= 2, "{object:?}");
    let pose = Pose3::from_translation(Vec3::new(0.0, 0.0, 0.01));
    // Across the first bar, 4 cm from the corner.
    let grasp = top_down(
        Vec3::new(-0.01, 0.0, 0.01),
        std::f32::consts::FRAC_PI_2,
        0.02,
    );
    let outcome = run(&object, &pose, &grasp);
    assert!(outcome.success, "{outcome:?}");
    assert!((outcome.opening_m - 0.02).abs() < 0.003, "{outcome:?}");
}

#[test]
fn fingers_that_would_go_through_the_table_fail_on_the_approach() {
    // Closing line 5 mm below the table's top.
    let (object, pose) = on_table(&box_mesh(Vec3::splat(0.025)));
    let outcome = run(
        &object,
        &pose,
        &top_down(Vec3::new(0.0, 0.0, -0.005), 0.0, 0.05),
    );
    assert_eq!(
        outcome.failed_at,
        Some(FailureStage::Approach),
        "{outcome:?}"
    );
    // A grasp whose closing axis is too narrow for the box: a finger lands on its top.
    let (object, pose) = on_table(&box_mesh(Vec3::new(0.045, 0.02, 0.02)));
    let outcome = run(
        &object,
        &pose,
        &top_down(Vec3::new(0.0, 0.0, 0.02), 0.0, 0.09),
    );
    assert_eq!(
        outcome.failed_at,
        Some(FailureStage::Approach),
        "{outcome:?}"
    );
}

#[test]
fn a_box_tipped_on_its_edge_topples_before_the_gripper_comes() {
    // Resting on one edge, tilted 30 degrees: not a stable pose, it falls onto a face.
    let mesh = box_mesh(Vec3::splat(0.025));
    let object = PhysicsObject::new(&mesh, &ShapeParams::default()).unwrap();
    let tilt = Rot3::from_rotation_y(30f32.to_radians());
    let lowest = mesh
        .vertices()
        .iter()
        .map(|v| (tilt * *v).z)
        .fold(f32::INFINITY, f32::min);
    let pose = Pose3::from_parts(Vec3::new(0.0, 0.0, -lowest), tilt);
    let outcome = run(
        &object,
        &pose,
        &top_down(Vec3::new(0.0, 0.0, 0.02), 0.0, 0.05),
    );
    assert_eq!(outcome.failed_at, Some(FailureStage::Settle), "{outcome:?}");
}

#[test]
fn a_trial_is_deterministic_to_the_bit() {
    let (object, pose) = on_table(&box_mesh(Vec3::new(0.04, 0.02, 0.015)));
    let grasp = top_down(Vec3::new(0.01, 0.0, 0.015), 0.3, 0.04);
    let a = run(&object, &pose, &grasp);
    let b = run(&object, &pose, &grasp);
    assert_eq!(a, b);
    let bits = |o: &PhysicsOutcome| {
        let p = o.world_from_object;
        (
            p.translation.to_array().map(f32::to_bits),
            p.rotation.to_array().map(f32::to_bits),
        )
    };
    assert_eq!(bits(&a), bits(&b));
}

#[test]
fn success_probability_is_deterministic_for_a_seed() {
    let (object, pose) = on_table(&box_mesh(Vec3::splat(0.025)));
    let grasp = top_down(Vec3::new(0.0, 0.0, 0.02), 0.0, 0.05);
    let noise = PhysicsNoise::default();
    let params = PhysicsParams::default();
    let estimate =
        |seed| success_probability(&object, &pose, &grasp, &panda(), &params, &noise, 6, seed);
    let a = estimate(7).unwrap();
    let b = estimate(7).unwrap();
    assert_eq!(a, b);
    assert_eq!(a.trials, 6);
    assert_eq!(
        a.successes
            + a.failures.settle
            + a.failures.approach
            + a.failures.close
            + a.failures.lift
            + a.failures.shake,
        6
    );
    // Small noise around a good grasp: most trials hold.
    assert!(a.probability >= 0.5, "{a:?}");
    // The same trials on one thread.
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    assert_eq!(pool.install(|| estimate(7).unwrap()), a);
    assert!(success_probability(&object, &pose, &grasp, &panda(), &params, &noise, 0, 7).is_err());
}

#[test]
fn bad_inputs_are_errors_not_panics() {
    let (object, pose) = on_table(&box_mesh(Vec3::splat(0.025)));
    let grasp = top_down(Vec3::new(f32::NAN, 0.0, 0.02), 0.0, 0.05);
    assert!(simulate_grasp(&object, &pose, &grasp, &panda(), &PhysicsParams::default()).is_err());
    let params = PhysicsParams {
        timestep_s: -1.0,
        ..PhysicsParams::default()
    };
    let grasp = top_down(Vec3::new(0.0, 0.0, 0.02), 0.0, 0.05);
    let err = simulate_grasp(&object, &pose, &grasp, &panda(), &params)
        .unwrap_err()
        .to_string();
    assert!(err.contains("timestep_s"), "{err}");
}

/// Cost of a trial; run with
/// `cargo test --release -p mvgrasp-grasp --test physics -- --ignored --nocapture`.
#[test]
#[ignore = "a benchmark: run in release"]
fn trial_cost() {
    let mug = mvgrasp_geometry::default_object().unwrap().mesh;
    let cases = [
        ("5 cm box", box_mesh(Vec3::splat(0.025)), 0.02, 0.0),
        (
            "8x4x3 cm box",
            box_mesh(Vec3::new(0.04, 0.02, 0.015)),
            0.015,
            std::f32::consts::FRAC_PI_2,
        ),
        ("mug", mug, 0.04, 0.0),
    ];
    let noise = PhysicsNoise::default();
    let params = PhysicsParams::default();
    for (name, mesh, height, yaw) in cases {
        let start = std::time::Instant::now();
        let (object, pose) = on_table(&mesh);
        println!(
            "{name}: {} convex parts, prepared in {:.1} ms",
            object.num_parts(),
            start.elapsed().as_secs_f64() * 1e3
        );
        let com = pose.transform_point(object.center_of_mass());
        let grasp = top_down(Vec3::new(com.x, com.y, height), yaw, 0.04);
        let mut times = Vec::new();
        let mut steps = 0;
        let mut successes = 0;
        for i in 0..40 {
            let mut g = grasp;
            g.world_from_gripper.translation.y += 0.0002 * i as f32;
            let start = std::time::Instant::now();
            let outcome = simulate_grasp(&object, &pose, &g, &panda(), &params).unwrap();
            times.push(start.elapsed().as_secs_f64() * 1e3);
            steps += outcome.steps;
            successes += usize::from(outcome.success);
            if i == 0 {
                println!("{name}: {outcome:?}");
            }
        }
        times.sort_by(f64::total_cmp);
        let median = times[times.len() / 2];
        let mean_steps = f64::from(steps) / 40.0;
        println!(
            "{name}: {successes}/40 held, {mean_steps:.0} steps, median {median:.2} ms/trial, {:.1} us/step, {:.0} trials/s single-thread",
            median * 1e3 / mean_steps,
            1e3 / median
        );
        let start = std::time::Instant::now();
        let estimate =
            success_probability(&object, &pose, &grasp, &panda(), &params, &noise, 64, 1).unwrap();
        let seconds = start.elapsed().as_secs_f64();
        println!(
            "{name}: success_probability over 64 trials on {} threads: {:.2} in {:.3} s = {:.0} trials/s; {:?}",
            rayon::current_num_threads(),
            estimate.probability,
            seconds,
            64.0 / seconds,
            estimate.failures
        );
    }
}
