//! The real Berkeley calibration files in `../shared/data/real_depth/gqcnn/data/calib`, and a
//! real depth image back-projected with them.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // tests may fail loudly

use crate::common;

use mvgrasp_geometry::{Intrinsics, IntrinsicsPreset, Vec3, read_camera_pose, read_tf};

#[test]
fn berkeley_intr_files_match_the_presets() {
    let Some(meshes) = common::shared_meshes() else {
        return;
    };
    let calib = meshes.join("../real_depth/gqcnn/data/calib");
    let phoxi = Intrinsics::from_intr_file(calib.join("phoxi/phoxi.intr")).unwrap();
    assert_eq!(phoxi, Intrinsics::preset(IntrinsicsPreset::PhoxiS));
    let primesense = Intrinsics::from_intr_file(calib.join("primesense/primesense.intr")).unwrap();
    assert_eq!(primesense, Intrinsics::preset(IntrinsicsPreset::Primesense));
}

#[test]
fn the_primesense_pose_looks_down_at_the_table() {
    let Some(meshes) = common::shared_meshes() else {
        return;
    };
    let tf = meshes.join("../real_depth/gqcnn/data/calib/primesense/primesense.tf");
    let (from, to, world_from_camera) = read_tf(tf).unwrap();
    assert_eq!(
        (from.as_str(), to.as_str()),
        ("primesense_overhead", "world")
    );
    let optical_axis = world_from_camera.transform_vector(Vec3::Z);
    assert!(
        optical_axis.z < -0.9,
        "an overhead camera looks down: {optical_axis}"
    );
    assert!((0.5..1.5).contains(&world_from_camera.translation.z));
}

#[test]
fn bad_intr_files_name_the_file_and_the_field() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.intr");
    std::fs::write(
        &bad,
        r#"{"_fx": -1, "_fy": 525, "_cx": 319.5, "_cy": 239.5, "_width": 640, "_height": 480}"#,
    )
    .unwrap();
    let err = Intrinsics::from_intr_file(&bad).unwrap_err().to_string();
    assert!(err.contains("bad.intr") && err.contains("fx"), "{err}");
    std::fs::write(&bad, r#"{"_fx": 525}"#).unwrap();
    let err = Intrinsics::from_intr_file(&bad).unwrap_err().to_string();
    assert!(err.contains("bad.intr") && err.contains("_fy"), "{err}");
    assert!(Intrinsics::from_intr_file(dir.path().join("none.intr")).is_err());
}

#[test]
fn intrinsics_read_from_a_plain_json_camera_matrix_or_an_intr_file() {
    let dir = tempfile::tempdir().unwrap();
    let plain = dir.path().join("k.json");
    std::fs::write(
        &plain,
        r#"{"K": [[525, 0, 319.5], [0, 525, 239.5], [0, 0, 1]], "width": 640, "height": 480}"#,
    )
    .unwrap();
    let primesense = Intrinsics::preset(IntrinsicsPreset::Primesense);
    assert_eq!(Intrinsics::from_file(&plain).unwrap(), primesense);
    // A .json holding the .intr keys reads as one.
    let intr_json = dir.path().join("intr.json");
    std::fs::write(
        &intr_json,
        r#"{"_fx": 525, "_fy": 525, "_cx": 319.5, "_cy": 239.5, "_width": 640, "_height": 480}"#,
    )
    .unwrap();
    assert_eq!(Intrinsics::from_file(&intr_json).unwrap(), primesense);
    // Skew, a principal point outside the image, a missing size: errors naming the file.
    for (text, expected) in [
        (
            r#"{"K": [[525, 1, 319.5], [0, 525, 239.5], [0, 0, 1]], "width": 640, "height": 480}"#,
            "no skew",
        ),
        (
            r#"{"K": [[525, 0, 900], [0, 525, 239.5], [0, 0, 1]], "width": 640, "height": 480}"#,
            "cx",
        ),
        (
            r#"{"K": [[525, 0, 319.5], [0, 525, 239.5], [0, 0, 1]], "width": 640}"#,
            "height",
        ),
    ] {
        std::fs::write(&plain, text).unwrap();
        let err = Intrinsics::from_file(&plain).unwrap_err().to_string();
        assert!(err.contains("k.json") && err.contains(expected), "{err}");
    }
}

#[test]
fn camera_poses_read_from_tf_files_and_json_and_must_be_rigid() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("pose.json");
    // Looking straight down from 0.7 m: the camera's z is the world's -z.
    std::fs::write(
        &path,
        r#"{"world_from_camera": [[1, 0, 0, 0.1], [0, -1, 0, 0], [0, 0, -1, 0.7], [0, 0, 0, 1]]}"#,
    )
    .unwrap();
    let pose = read_camera_pose(&path).unwrap();
    assert!((pose.translation - Vec3::new(0.1, 0.0, 0.7)).length() < 1e-6);
    assert!((pose.transform_vector(Vec3::Z) - Vec3::new(0.0, 0.0, -1.0)).length() < 1e-6);
    for (text, expected) in [
        (
            r#"{"world_from_camera": [[2, 0, 0, 0], [0, -1, 0, 0], [0, 0, -1, 0.7], [0, 0, 0, 1]]}"#,
            "not a rigid transform",
        ),
        (
            r#"{"world_from_camera": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, -1, 0.7], [0, 0, 0, 1]]}"#,
            "not a rigid transform",
        ),
        (
            r#"{"world_from_camera": [[1, 0, 0, 0], [0, -1, 0, 0], [0, 0, -1, 0.7], [0, 0, 1, 1]]}"#,
            "not a rigid transform",
        ),
        (r#"{"pose": []}"#, "world_from_camera"),
    ] {
        std::fs::write(&path, text).unwrap();
        let err = read_camera_pose(&path).unwrap_err().to_string();
        assert!(err.contains("pose.json") && err.contains(expected), "{err}");
    }
    if let Some(meshes) = common::shared_meshes() {
        let tf = meshes.join("../real_depth/gqcnn/data/calib/primesense/primesense.tf");
        assert_eq!(read_camera_pose(&tf).unwrap(), read_tf(&tf).unwrap().2);
    }
}
