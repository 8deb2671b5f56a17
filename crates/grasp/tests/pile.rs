//! Piles (`drop_pile`): objects dropped into a box rest on the table and on each other, inside
//! the workspace, the same bits each time; the trial's settle finds them at rest; in a bin
//! (the box kept) they stay inside and its walls are obstacles of the trial.

use mvgrasp_geometry::{Pose3, Rot3, TriangleMesh, Vec3};
use mvgrasp_grasp::physics::{
    Drop, FailureStage, PhysicsObject, PhysicsParams, PileParams, ShapeParams, box_walls,
    drop_pile, settle_objects, simulate_grasp_among, simulate_grasp_in_scene,
};
use mvgrasp_grasp::{Grasp, Gripper};
use parry3d::shape::Cuboid;

fn block(half: Vec3) -> PhysicsObject {
    let (v, t) = Cuboid::new(half).to_trimesh();
    PhysicsObject::new(&TriangleMesh::new(v, t).unwrap(), &ShapeParams::default()).unwrap()
}

/// Four blocks let go over nearly the same spot, each turned.
fn four_drops(blocks: &[PhysicsObject]) -> Vec<Drop<'_>> {
    blocks
        .iter()
        .enumerate()
        .map(|(i, object)| Drop {
            object,
            rotation: Rot3::from_euler(glam::EulerRot::XYZ, 0.3 * i as f32, 0.7, 1.1 * i as f32),
            xy: [0.01 * i as f32, -0.005 * i as f32],
        })
        .collect()
}

fn blocks() -> Vec<PhysicsObject> {
    vec![
        block(Vec3::new(0.04, 0.03, 0.02)),
        block(Vec3::new(0.03, 0.03, 0.03)),
        block(Vec3::new(0.05, 0.015, 0.015)),
        block(Vec3::new(0.02, 0.02, 0.04)),
    ]
}

#[test]
fn dropped_blocks_pile_up_at_rest_inside_the_workspace_the_same_bits_each_time() {
    let blocks = blocks();
    let drops = four_drops(&blocks);
    let pile = PileParams::default();
    let physics = PhysicsParams::default();
    let poses = drop_pile(&drops, &pile, &physics).unwrap();
    assert_eq!(poses.len(), 4);
    let again = drop_pile(&drops, &pile, &physics).unwrap();
    assert_eq!(format!("{poses:?}"), format!("{again:?}"));
    let mut top = 0.0f32;
    for (pose, drop) in poses.iter().zip(&drops) {
        let pose = pose.expect("a block let go over the middle stays in the workspace");
        let aabb = drop.object.shape().compute_aabb(&pose);
        // On the table, not through it (the contacts' softness allows a millimetre).
        assert!(
            aabb.mins.z > -1.0e-3,
            "a block sank into the table: {aabb:?}"
        );
        let com = pose.transform_point(drop.object.center_of_mass());
        assert!(
            com.x.abs() < pile.workspace_half_side_m && com.y.abs() < pile.workspace_half_side_m
        );
        top = top.max(aabb.maxs.z);
    }
    // Four blocks let go over one spot do not all lie flat on the table side by side: the
    // tallest alone stands 8 cm, so a pile higher than that has one on another.
    assert!(top > 0.06, "no block rests on another: top {top}");
}

#[test]
fn the_trial_finds_a_pile_at_rest() {
    let blocks = blocks();
    let drops = four_drops(&blocks);
    let physics = PhysicsParams::default();
    let poses: Vec<Pose3> = drop_pile(&drops, &PileParams::default(), &physics)
        .unwrap()
        .into_iter()
        .map(Option::unwrap)
        .collect();
    // A grasp far from the pile: whatever it meets, the pile must first pass the settle.
    let grasp = Grasp {
        world_from_gripper: Pose3::from_parts(
            Vec3::new(0.4, 0.4, 0.02),
            Rot3::from_rotation_x(std::f32::consts::PI),
        ),
        width_m: 0.05,
    };
    for target in 0..blocks.len() {
        let others: Vec<(&PhysicsObject, Pose3)> = (0..blocks.len())
            .filter(|&i| i != target)
            .map(|i| (&blocks[i], poses[i]))
            .collect();
        let outcome = simulate_grasp_among(
            &blocks[target],
            &poses[target],
            &others,
            &grasp,
            &Gripper::default(),
            &physics,
        )
        .unwrap();
        assert_ne!(
            outcome.failed_at,
            Some(FailureStage::Settle),
            "block {target}"
        );
    }
}

#[test]
fn a_bad_setting_or_drop_is_refused_by_name() {
    let blocks = blocks();
    let physics = PhysicsParams::default();
    let pile = PileParams {
        box_height_m: f32::NAN,
        ..PileParams::default()
    };
    let err = drop_pile(&four_drops(&blocks), &pile, &physics).unwrap_err();
    assert!(err.to_string().contains("box_height_m"), "{err}");
    let mut drops = four_drops(&blocks);
    drops[1].xy[0] = f32::INFINITY;
    let err = drop_pile(&drops, &PileParams::default(), &physics).unwrap_err();
    assert!(err.to_string().contains("drop"), "{err}");
}

#[test]
fn a_block_left_on_nothing_comes_down_to_the_table_and_one_off_the_edge_is_taken_away() {
    let physics = PhysicsParams::default();
    let pile = PileParams::default();
    let top = block(Vec3::new(0.03, 0.03, 0.02));
    // Where it rested on a 4 cm block that a grasp took away; and one beyond the workspace.
    let floating = Pose3::from_translation(Vec3::new(0.0, 0.0, 0.06));
    let outside = Pose3::from_translation(Vec3::new(0.2, 0.0, 0.02));
    let poses = settle_objects(&[(&top, floating), (&top, outside)], &pile, &physics).unwrap();
    let rested = poses[0].expect("in the workspace");
    assert!((rested.translation.z - 0.02).abs() < 1.0e-3, "{rested:?}");
    assert!(poses[1].is_none(), "{:?}", poses[1]);
}

#[test]
fn in_a_bin_the_pile_stays_inside_the_walls_and_a_wall_under_a_finger_stops_the_approach() {
    let blocks = blocks();
    let physics = PhysicsParams::default();
    let bin = PileParams {
        keep_box: true,
        ..PileParams::default()
    };
    // Let go near a wall: without it they would spill past it.
    let drops: Vec<Drop<'_>> = four_drops(&blocks)
        .into_iter()
        .map(|d| Drop {
            xy: [d.xy[0] + 0.07, d.xy[1]],
            ..d
        })
        .collect();
    let poses = drop_pile(&drops, &bin, &physics).unwrap();
    for (pose, drop) in poses.iter().zip(&drops) {
        let pose = pose.expect("nothing leaves a bin");
        let aabb = drop.object.shape().compute_aabb(&pose);
        let inside = bin.box_half_side_m + 1.0e-3;
        assert!(
            aabb.maxs.x <= inside && aabb.mins.x >= -inside && aabb.maxs.y <= inside,
            "a block outside the walls: {aabb:?}"
        );
    }
    // A cube against the +x wall's inside of a low bin (4 cm, under the palm), gripped across
    // x: the outer finger comes down on the wall. Across y it clears it.
    let low = PileParams {
        box_height_m: 0.04,
        ..bin
    };
    let cube = block(Vec3::splat(0.02));
    let walls: Vec<(PhysicsObject, Pose3)> = box_walls(&low)
        .into_iter()
        .map(|(half, centre)| (block(half), Pose3::from_translation(centre)))
        .collect();
    let fixed: Vec<(&PhysicsObject, Pose3)> = walls.iter().map(|(w, p)| (w, *p)).collect();
    let x = bin.box_half_side_m - 0.021;
    let pose = Pose3::from_translation(Vec3::new(x, 0.0, 0.02));
    let down = Rot3::from_rotation_x(std::f32::consts::PI);
    let across_x = Grasp {
        world_from_gripper: Pose3::from_parts(Vec3::new(x, 0.0, 0.02), down),
        width_m: 0.04,
    };
    let across_y = Grasp {
        world_from_gripper: Pose3::from_parts(
            Vec3::new(x, 0.0, 0.02),
            Rot3::from_rotation_z(std::f32::consts::FRAC_PI_2) * down,
        ),
        width_m: 0.04,
    };
    let gripper = Gripper::default();
    let blocked =
        simulate_grasp_in_scene(&cube, &pose, &[], &fixed, &across_x, &gripper, &physics).unwrap();
    assert_eq!(
        blocked.failed_at,
        Some(FailureStage::Approach),
        "{blocked:?}"
    );
    let held =
        simulate_grasp_in_scene(&cube, &pose, &[], &fixed, &across_y, &gripper, &physics).unwrap();
    assert!(held.success, "{held:?}");
}
