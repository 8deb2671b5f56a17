//! Stable poses of built-in objects whose physics everyone knows.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // tests may fail loudly

use mvgrasp_geometry::objects::{Category, default_object, generate};
use mvgrasp_geometry::{StablePoseParams, Vec3, stable_poses};

#[test]
fn a_mug_stands_and_rests_on_its_handle_but_its_bare_side_rolls() {
    let mug = default_object().unwrap().mesh;
    let poses = stable_poses(&mug, &StablePoseParams::default()).unwrap();
    let upright = poses
        .iter()
        .find(|p| p.face_normal.dot(-Vec3::Z) > 0.99)
        .unwrap();
    assert!(!upright.marginal);
    let sides: Vec<_> = poses
        .iter()
        .filter(|p| p.face_normal.z.abs() < 0.1)
        .collect();
    assert!(
        sides.iter().any(|p| p.marginal),
        "the bare side rolls: {poses:#?}"
    );
    assert!(
        sides.iter().any(|p| !p.marginal),
        "resting on the handle holds: {poses:#?}"
    );
}

#[test]
fn a_can_lying_down_rolls() {
    let can = generate(Category::Can, 0, 0).unwrap().mesh;
    let poses = stable_poses(&can, &StablePoseParams::default()).unwrap();
    let side = poses
        .iter()
        .filter(|p| p.face_normal.z.abs() < 0.1)
        .collect::<Vec<_>>();
    assert_eq!(side.len(), 1, "{poses:#?}");
    assert!(side[0].marginal);
}
