#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
//! Grasp quality with known answers: boxes across parallel faces, spheres off their centre,
//! cylinders across their axis; friction, determinism, errors, and a timing report.

use std::time::Instant;

use mvgrasp_geometry::{Mat3, Pose3, Rot3, TriangleMesh, Vec3};
use mvgrasp_grasp::quality::{
    RobustQualityParams, WrenchParams, contact_wrenches, ferrari_canny_l1, find_contacts,
    force_closure, grasp_quality, grasp_seed, robust_qualities, robust_quality, wrench_set_epsilon,
};
use mvgrasp_grasp::{GraspError, GraspObject, Gripper};
use parry3d::shape::{Ball, Cuboid, Cylinder};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal, Uniform};

fn object(vertices: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> GraspObject {
    GraspObject::new(TriangleMesh::new(vertices, triangles).unwrap()).unwrap()
}

fn cube(half_m: f32) -> GraspObject {
    let (v, t) = Cuboid::new(Vec3::splat(half_m)).to_trimesh();
    object(v, t)
}

fn sphere(radius_m: f32) -> GraspObject {
    let (v, t) = Ball::new(radius_m).to_trimesh(32, 32);
    object(v, t)
}

/// A cylinder along y (parry's axis).
fn cylinder(half_height_m: f32, radius_m: f32) -> GraspObject {
    let (v, t) = Cylinder::new(half_height_m, radius_m).to_trimesh(64);
    object(v, t)
}

/// The gripper frame with its closing axis along `axis` (unit) and its centre at `center`.
fn closing_along(axis: Vec3, center: Vec3) -> Pose3 {
    let (y, z) = axis.any_orthonormal_pair();
    let rotation = Rot3::from_mat3(&Mat3::from_cols(axis, y, z));
    Pose3::from_parts(center, rotation)
}

fn nominal_epsilon(object: &GraspObject, pose: &Pose3, mu: f32) -> f64 {
    grasp_quality(
        object,
        pose,
        &Gripper::default(),
        mu,
        &WrenchParams::default(),
    )
    .unwrap()
    .epsilon
}

#[test]
fn a_box_grasped_across_parallel_faces_is_in_force_closure_with_positive_epsilon() {
    let object = cube(0.025);
    let pose = Pose3::from_translation(Vec3::new(0.0, 0.005, -0.004));
    let gripper = Gripper::default();
    let contacts = find_contacts(&object, &pose, &gripper).unwrap();
    assert!((contacts.width_m - 0.05).abs() < 1e-5, "{contacts:?}");
    let [c0, c1] = contacts.contacts;
    assert!((c0.point.x + 0.025).abs() < 1e-5 && (c1.point.x - 0.025).abs() < 1e-5);
    assert!((c0.outward_normal - -Vec3::X).length() < 1e-5);
    assert!((c1.outward_normal - Vec3::X).length() < 1e-5);
    assert!(force_closure(&contacts, 0.5).unwrap());
    let epsilon = ferrari_canny_l1(&object, &contacts, 0.5, &WrenchParams::default()).unwrap();
    println!("box across parallel faces: epsilon {epsilon:.5}");
    assert!(epsilon > 0.0);
    // A good grasp clears Dex-Net's label threshold with the default contact model.
    assert!(epsilon > RobustQualityParams::default().positive_threshold);
}

#[test]
fn a_sphere_grasped_through_non_antipodal_points_has_no_force_closure() {
    let object = sphere(0.03);
    // The closing line passes 2.5 cm from the centre: the normals lean asin(0.83) = 56 degrees
    // off it, far outside a cone of atan(0.5) = 27 degrees.
    let pose = Pose3::from_translation(Vec3::new(0.0, 0.025, 0.0));
    let contacts = find_contacts(&object, &pose, &Gripper::default()).unwrap();
    assert!(!force_closure(&contacts, 0.5).unwrap());
    assert_eq!(
        ferrari_canny_l1(&object, &contacts, 0.5, &WrenchParams::default()).unwrap(),
        0.0
    );
    // Through the centre it holds.
    let through = find_contacts(&object, &Pose3::identity(), &Gripper::default()).unwrap();
    assert!(force_closure(&through, 0.5).unwrap());
    assert!(nominal_epsilon(&object, &Pose3::identity(), 0.5) > 0.0);
}

#[test]
fn a_cylinders_best_grasps_straddle_its_axis() {
    let radius = 0.02;
    let object = cylinder(0.04, radius);
    // Closing lines along x, across the axis (y), offset along z from -r to r.
    let offsets: Vec<f32> = (-9..=9).map(|i| i as f32 * radius / 10.0).collect();
    let scores: Vec<f64> = offsets
        .iter()
        .map(|z| {
            nominal_epsilon(
                &object,
                &Pose3::from_translation(Vec3::new(0.0, 0.01, *z)),
                0.5,
            )
        })
        .collect();
    println!("cylinder offsets {offsets:?}\n  epsilons {scores:?}");
    let best = scores.iter().copied().fold(0.0, f64::max);
    assert!(best > 0.0);
    for (z, score) in offsets.iter().zip(&scores) {
        if *score >= 0.9 * best {
            assert!(
                z.abs() <= 0.25 * radius,
                "offset {z} scores {score} (best {best})"
            );
        }
        // Beyond the friction cone's reach (sin 27 deg = 0.45 r) nothing holds.
        if z.abs() > 0.5 * radius {
            assert_eq!(*score, 0.0, "offset {z}");
        }
    }
    // Along the axis, across the flat ends, it holds too.
    let along = closing_along(Vec3::Y, Vec3::new(0.003, 0.0, 0.0));
    assert!(nominal_epsilon(&object, &along, 0.5) > 0.0);
}

#[test]
fn epsilon_grows_with_friction() {
    let object = cube(0.025);
    // Tilted 9.7 degrees about z: the contacts sit on the same faces, 10 degrees off normal.
    let pose = Pose3::from_parts(Vec3::new(0.0, 0.004, 0.0), Rot3::from_rotation_z(0.17));
    let mus = [0.15, 0.2, 0.3, 0.5, 0.8, 1.2];
    let epsilons: Vec<f64> = mus
        .iter()
        .map(|mu| nominal_epsilon(&object, &pose, *mu))
        .collect();
    println!("mu {mus:?} -> epsilon {epsilons:?}");
    assert_eq!(
        epsilons[0], 0.0,
        "tan(9.7 deg) = 0.17 > 0.15: outside the cones"
    );
    for pair in epsilons[1..].windows(2) {
        assert!(pair[1] > pair[0], "{epsilons:?}");
    }
}

#[test]
fn robust_quality_is_deterministic_for_a_seed_whatever_the_threads() {
    let object = sphere(0.03);
    let params = RobustQualityParams::default();
    let gripper = Gripper::default();
    let pose = Pose3::from_translation(Vec3::new(0.0, 0.006, 0.002));
    let a = robust_quality(&object, &pose, &gripper, &params, 42).unwrap();
    let b = robust_quality(&object, &pose, &gripper, &params, 42).unwrap();
    assert_eq!(a, b);
    assert_eq!(a.robust_epsilon.to_bits(), b.robust_epsilon.to_bits());
    let c = robust_quality(&object, &pose, &gripper, &params, 43).unwrap();
    assert_ne!(a.robust_epsilon, c.robust_epsilon);
    println!("sphere near centre: {a:?}");
    assert!(a.nominal_force_closure && a.robust_epsilon > 0.0);
    // A 1 cm object shift often moves the line 27 degrees off the normals of a 3 cm sphere.
    assert!(a.force_closure_fraction > 0.2 && a.force_closure_fraction < 1.0);

    let poses: Vec<Pose3> = (0..6)
        .map(|i| Pose3::from_translation(Vec3::new(0.0, 0.003 * i as f32, 0.0)))
        .collect();
    let on = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| robust_qualities(&object, &poses, &gripper, &params, 9).unwrap())
    };
    let one = on(1);
    assert_eq!(one, on(3));
    let single = robust_quality(&object, &poses[4], &gripper, &params, grasp_seed(9, 4));
    assert_eq!(one[4], single.unwrap());
}

#[test]
fn robust_quality_falls_off_the_edge_of_a_box() {
    let object = cube(0.025);
    let params = RobustQualityParams::default();
    let gripper = Gripper::default();
    let centre = robust_quality(&object, &Pose3::identity(), &gripper, &params, 1).unwrap();
    // 2 mm inside the edge: many perturbed jaws miss or meet the edge.
    let edge = Pose3::from_translation(Vec3::new(0.0, 0.023, 0.0));
    let edge = robust_quality(&object, &edge, &gripper, &params, 1).unwrap();
    println!("box centre {centre:?}\nbox edge {edge:?}");
    assert!(centre.robust_epsilon > edge.robust_epsilon);
    assert!(params.dexnet_label(centre.robust_epsilon, true));
    assert!(!params.dexnet_label(centre.robust_epsilon, false));
}

#[test]
fn bad_friction_is_an_invalid_parameter_error() {
    let object = cube(0.025);
    let gripper = Gripper::default();
    let contacts = find_contacts(&object, &Pose3::identity(), &gripper).unwrap();
    let wrench = WrenchParams::default();
    for mu in [0.0, -0.3, f32::NAN, f32::INFINITY] {
        let errors = [
            force_closure(&contacts, mu).unwrap_err(),
            ferrari_canny_l1(&object, &contacts, mu, &wrench).unwrap_err(),
            contact_wrenches(&object, &contacts, mu, &wrench).unwrap_err(),
            grasp_quality(&object, &Pose3::identity(), &gripper, mu, &wrench).unwrap_err(),
            robust_quality(
                &object,
                &Pose3::identity(),
                &gripper,
                &RobustQualityParams {
                    friction_coef_mean: mu,
                    ..Default::default()
                },
                0,
            )
            .unwrap_err(),
        ];
        for error in errors {
            assert!(
                matches!(
                    error,
                    GraspError::InvalidParameter {
                        name: "friction_coef",
                        ..
                    }
                ),
                "{error}"
            );
        }
    }
}

#[test]
fn jaws_that_start_inside_miss_or_close_too_far_find_no_contacts() {
    let gripper = Gripper::default(); // 8 cm opening
    // 10 cm wide: both jaws start inside.
    assert!(find_contacts(&cube(0.05), &Pose3::identity(), &gripper).is_none());
    let object = cube(0.025);
    // The closing line passes beside the box.
    let beside = Pose3::from_translation(Vec3::new(0.0, 0.03, 0.0));
    assert!(find_contacts(&object, &beside, &gripper).is_none());
    // One jaw starts inside: the gripper centre is off along the closing axis.
    let off = Pose3::from_translation(Vec3::new(0.05, 0.0, 0.0));
    assert!(find_contacts(&object, &off, &gripper).is_none());
    // Narrower than the gripper closes.
    let stiff = Gripper {
        min_opening_m: 0.06,
        ..Gripper::default()
    };
    assert!(find_contacts(&object, &Pose3::identity(), &stiff).is_none());
    // No contacts: zero quality, no error.
    let q = grasp_quality(&object, &beside, &gripper, 0.5, &WrenchParams::default()).unwrap();
    assert!(q.contacts.is_none() && !q.force_closure && q.epsilon == 0.0);
}

#[test]
fn flat_and_one_sided_wrench_sets_score_zero_without_panicking() {
    assert_eq!(wrench_set_epsilon(&[[0.0; 6]; 10]), 0.0);
    let ramp: Vec<[f64; 6]> = (0..20).map(|i| [i as f64; 6]).collect();
    assert_eq!(wrench_set_epsilon(&ramp), 0.0);
    // Point contacts without torsion cannot resist a torque about the closing line.
    let object = cube(0.025);
    let hard = WrenchParams {
        soft_fingers: false,
        ..WrenchParams::default()
    };
    let contacts = find_contacts(&object, &Pose3::identity(), &Gripper::default()).unwrap();
    assert_eq!(
        ferrari_canny_l1(&object, &contacts, 0.5, &hard).unwrap(),
        0.0
    );
}

/// Random closing lines through points near the object's centre of mass: within `spread_m` of
/// it, along `mean_axis` tilted by about `tilt` radians (or any direction for `None`).
fn random_grasps(
    object: &GraspObject,
    count: usize,
    spread_m: f32,
    mean_axis: Option<(Vec3, f32)>,
    seed: u64,
) -> Vec<Pose3> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let offset = Uniform::new(-spread_m, spread_m).unwrap();
    (0..count)
        .map(|_| {
            let mut normal = || -> f32 { StandardNormal.sample(&mut rng) };
            let noise = Vec3::new(normal(), normal(), normal());
            let axis = match mean_axis {
                Some((mean, tilt)) => (mean + noise * tilt).normalize(),
                None => noise.normalize(),
            };
            let center = object.center_of_mass()
                + Vec3::new(
                    offset.sample(&mut rng),
                    offset.sample(&mut rng),
                    offset.sample(&mut rng),
                );
            closing_along(axis, center)
        })
        .collect()
}

/// Prints the cost of robust quality (never asserts on time). For figures, run
/// `cargo test --release -p mvgrasp-grasp --test quality -- --nocapture timing`.
#[test]
fn timing_report() {
    let count = if cfg!(debug_assertions) { 8 } else { 200 };
    let params = RobustQualityParams::default();
    let gripper = Gripper::default();
    let mug = mvgrasp_geometry::default_object().unwrap();
    let cases = [
        (
            "box 5 cm, lines near the face normal (mostly in closure)",
            cube(0.025),
            Some((Vec3::X, 0.1)),
        ),
        (
            "mug (procedural), random lines near the centre",
            GraspObject::new(mug.mesh).unwrap(),
            None,
        ),
    ];
    for (name, object, axis) in cases {
        let poses = random_grasps(&object, count, 0.01, axis, 5);
        let start = Instant::now();
        let mut closure = 0.0;
        for (i, pose) in poses.iter().enumerate() {
            closure += robust_quality(&object, pose, &gripper, &params, i as u64)
                .unwrap()
                .force_closure_fraction;
        }
        let seconds = start.elapsed().as_secs_f64();
        let samples = count * (params.num_samples + 1);
        let start = Instant::now();
        let batch = robust_qualities(&object, &poses, &gripper, &params, 5).unwrap();
        let parallel = start.elapsed().as_secs_f64();
        println!(
            "{name} ({} triangles): {:.1} us/sample, {:.0} robust evals/s single-thread, \
             {:.0} robust evals/s on {} threads; {:.0}% of samples in force closure",
            object.mesh().triangles().len(),
            seconds / samples as f64 * 1e6,
            count as f64 / seconds,
            batch.len() as f64 / parallel,
            rayon::current_num_threads(),
            100.0 * closure / count as f64,
        );
    }
}
