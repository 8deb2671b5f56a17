//! The real Berkeley calibration files in `../shared/data/real_depth/gqcnn/data/calib`, and a
//! real depth image back-projected with them.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // tests may fail loudly

use crate::common;

use mvgrasp_geometry::{Intrinsics, IntrinsicsPreset, Vec3, read_tf};

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
