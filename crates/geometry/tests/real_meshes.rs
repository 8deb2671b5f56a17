//! Real meshes from `../shared/data/meshes`: sensible volumes, extents and stable poses.
//! Each test skips with a message when the data is absent.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // tests may fail loudly

use crate::common;

use mvgrasp_geometry::{StablePoseParams, Vec3, load_mesh, stable_poses};

fn all_poses() -> StablePoseParams {
    StablePoseParams {
        max_poses: 100,
        min_probability: 0.0,
        ..Default::default()
    }
}

/// (file, extents in metres sorted ascending, volume in cm^3), from the YCB and Dex-Net
/// object sheets and the meshes' own bounding boxes, to a few millimetres.
const KNOWN: &[(&str, [f32; 3], f32)] = &[
    (
        "ycb/meshes/003_cracker_box_textured.obj",
        [0.072, 0.164, 0.213],
        2173.0,
    ),
    (
        "ycb/meshes/004_sugar_box_textured.obj",
        [0.049, 0.094, 0.176],
        638.0,
    ),
    (
        "ycb/meshes/005_tomato_soup_can_textured.obj",
        [0.068, 0.068, 0.102],
        357.0,
    ),
    (
        "ycb/meshes/006_mustard_bottle_textured.obj",
        [0.067, 0.097, 0.191],
        699.0,
    ),
    (
        "ycb/meshes/009_gelatin_box_textured.obj",
        [0.030, 0.089, 0.101],
        179.0,
    ),
    (
        "ycb/meshes/010_potted_meat_can_textured.obj",
        [0.060, 0.084, 0.102],
        354.0,
    ),
    ("ycb/dishes/evo_bowl_col.obj", [0.061, 0.147, 0.147], 101.0),
    (
        "robosuite/objects/meshes/bottle.obj",
        [0.055, 0.059, 0.160],
        282.0,
    ),
    (
        "robosuite/objects/meshes/can.stl",
        [0.050, 0.050, 0.080],
        155.0,
    ),
    (
        "robosuite/objects/meshes/lemon.obj",
        [0.040, 0.040, 0.045],
        35.4,
    ),
    ("dexnet/meshes/example/box.obj", [0.042, 0.045, 0.074], 83.0),
    (
        "dexnet/test/models/bar_clamp.obj",
        [0.103, 0.112, 0.166],
        430.0,
    ),
];

#[test]
fn real_meshes_have_known_extents_volumes_and_poses_summing_to_one() {
    let Some(root) = common::shared_meshes() else {
        return;
    };
    for &(file, extents, volume_cm3) in KNOWN {
        let mesh = load_mesh(root.join(file)).unwrap();
        let mut got = mesh.aabb().extents().to_array();
        got.sort_by(f32::total_cmp);
        for (g, e) in got.iter().zip(extents) {
            assert!(
                (g - e).abs() < 0.002,
                "{file}: extents {got:?}, expected {extents:?}"
            );
        }
        let facts = mesh.mass_facts(1000.0).unwrap();
        let got_cm3 = facts.volume_m3 * 1e6;
        assert!(
            (got_cm3 - volume_cm3).abs() < 0.01 * volume_cm3,
            "{file}: {got_cm3} cm^3"
        );
        assert!(
            mesh.aabb().contains_local_point(facts.center_of_mass),
            "{file}: centre of mass"
        );
        let poses = stable_poses(&mesh, &all_poses()).unwrap();
        let sum: f32 = poses.iter().map(|p| p.probability).sum();
        assert!(
            (sum - 1.0).abs() < 1e-3,
            "{file}: probabilities sum to {sum}"
        );
        for pose in &poses {
            // Resting: the lowest point touches z = 0, nothing below the table.
            let lowest = mesh
                .vertices()
                .iter()
                .map(|v| pose.table_from_object.transform_point(*v).z)
                .fold(f32::INFINITY, f32::min);
            assert!(lowest.abs() < 1e-4, "{file}: lowest point at {lowest}");
        }
    }
}

#[test]
fn boxes_rest_on_their_six_sides_most_likely_on_the_largest() {
    let Some(root) = common::shared_meshes() else {
        return;
    };
    for file in [
        "ycb/meshes/003_cracker_box_textured.obj",
        "ycb/meshes/004_sugar_box_textured.obj",
    ] {
        let mesh = load_mesh(root.join(file)).unwrap();
        let poses = stable_poses(
            &mesh,
            &StablePoseParams {
                min_probability: 0.02,
                ..Default::default()
            },
        )
        .unwrap();
        let sides: Vec<_> = poses.iter().filter(|p| !p.marginal).collect();
        assert!(sides.len() >= 4, "{file}: {poses:#?}");
        // The two most probable poses lie on the two largest faces: the shortest axis is vertical.
        let [thin, ..] = smallest_axis(mesh.aabb().extents());
        for pose in &poses[..2] {
            assert!(
                pose.face_normal.dot(thin).abs() > 0.95,
                "{file}: {:?}",
                pose.face_normal
            );
            assert!(!pose.marginal && pose.probability > 0.3);
        }
    }
}

#[test]
fn cans_stand_on_their_ends_or_lie_on_their_rolling_side() {
    let Some(root) = common::shared_meshes() else {
        return;
    };
    for file in [
        "ycb/meshes/005_tomato_soup_can_textured.obj",
        "robosuite/objects/meshes/can.stl",
    ] {
        let mesh = load_mesh(root.join(file)).unwrap();
        let poses = stable_poses(&mesh, &StablePoseParams::default()).unwrap();
        let axis = Vec3::Z; // both cans stand along z in their files
        let ends: Vec<_> = poses
            .iter()
            .filter(|p| p.face_normal.dot(axis).abs() > 0.95)
            .collect();
        let sides: Vec<_> = poses
            .iter()
            .filter(|p| p.face_normal.dot(axis).abs() < 0.2)
            .collect();
        assert_eq!(ends.len(), 2, "{file}: {poses:#?}");
        assert!(
            ends.iter()
                .all(|p| !p.marginal && p.tipping_angle_rad > 20f32.to_radians())
        );
        assert_eq!(
            sides.len(),
            1,
            "{file}: the side is one rolling family: {poses:#?}"
        );
        assert!(sides[0].marginal && sides[0].probability > 0.5);
    }
}

#[test]
fn a_lemon_has_no_pose_that_stays_put() {
    let Some(root) = common::shared_meshes() else {
        return;
    };
    let mesh = load_mesh(root.join("robosuite/objects/meshes/lemon.obj")).unwrap();
    let poses = stable_poses(&mesh, &all_poses()).unwrap();
    assert!(poses.iter().all(|p| p.marginal), "{poses:#?}");
}

#[test]
fn pybullet_random_urdfs_load_at_urdf_scale_except_the_nan_one() {
    let Some(root) = common::shared_meshes() else {
        return;
    };
    let dir = root.join("pybullet/random_urdfs");
    let mut loaded = 0;
    for i in (0..1000).step_by(37).chain([168]) {
        let urdf = dir.join(format!("{i:03}/{i:03}.urdf"));
        match load_mesh(&urdf) {
            Ok(mesh) => {
                let largest = mesh.aabb().extents().max_element();
                assert!(
                    (0.01..0.25).contains(&largest),
                    "{}: {largest} m",
                    urdf.display()
                );
                stable_poses(&mesh, &StablePoseParams::default()).unwrap();
                loaded += 1;
            }
            Err(e) => {
                assert_eq!(i, 168, "{e}");
                assert!(e.to_string().contains("NaN"), "{e}");
            }
        }
    }
    assert_eq!(loaded, 28);
}

fn smallest_axis(extents: Vec3) -> [Vec3; 1] {
    let axes = [Vec3::X, Vec3::Y, Vec3::Z];
    let i = (0..3)
        .min_by(|&a, &b| extents[a].total_cmp(&extents[b]))
        .unwrap_or(0);
    [axes[i]]
}

#[test]
fn a_real_mug_decomposes_into_bounded_convex_parts() {
    let Some(root) = common::shared_meshes() else {
        return;
    };
    let Ok(mug) = load_mesh(root.join("pybullet/objects/mug.urdf")) else {
        eprintln!("skipped: pybullet mug not loadable here");
        return;
    };
    let params = mvgrasp_geometry::DecompositionParams::default();
    let parts = mug.convex_decomposition(&params).unwrap();
    assert!(
        (2..=params.max_parts as usize).contains(&parts.len()),
        "{} parts",
        parts.len()
    );
    let volume: f32 = parts.iter().map(|p| p.signed_volume_m3()).sum();
    let hull = mug.convex_hull().unwrap().signed_volume_m3();
    // A mug's parts leave its inside empty: well under its hull's volume.
    assert!(volume < 0.8 * hull, "parts {volume} vs hull {hull}");
}
