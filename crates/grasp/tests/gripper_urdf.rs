#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // tests may fail loudly
//! Grippers measured from URDFs: a two-finger slide with known dimensions, and the Robotiq
//! 2F-85 of the shared data (skipped when absent).

use std::path::Path;

use mvgrasp_grasp::{Gripper, UrdfGripperSpec};

use crate::shared_data::shared_data;

const SLIDE: &str = r#"<robot name="slide">
  <link name="palm"><collision><geometry><box size="0.1 0.04 0.02"/></geometry></collision></link>
  <link name="left_pad"><collision><geometry><box size="0.01 0.02 0.05"/></geometry></collision></link>
  <link name="right_pad"><collision><geometry><box size="0.01 0.02 0.05"/></geometry></collision></link>
  <joint name="left_slide" type="prismatic"><parent link="palm"/><child link="left_pad"/>
    <origin xyz="-0.005 0 0.035"/><axis xyz="-1 0 0"/>
    <limit lower="0" upper="0.03" effort="30" velocity="1"/></joint>
  <joint name="right_slide" type="prismatic"><parent link="palm"/><child link="right_pad"/>
    <origin xyz="0.005 0 0.035"/><axis xyz="1 0 0"/>
    <limit lower="0" upper="0.03" effort="30" velocity="1"/>
    <mimic joint="left_slide"/></joint>
</robot>"#;

fn write(dir: &Path, name: &str, text: &str) -> std::path::PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn a_sliding_two_finger_urdf_measures_as_built() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "slide.urdf", SLIDE);
    let measured = Gripper::from_urdf(&path, &UrdfGripperSpec::default()).unwrap();
    let g = &measured.gripper;
    let near = |a: f32, b: f32| (a - b).abs() < 1e-5;
    // Pads 1 cm thick centred at x = +-0.005 when shut touch (gap 0); the slide adds 2 x 3 cm.
    assert!(near(g.min_opening_m, 0.0), "{g:?}");
    assert!(near(g.max_opening_m, 0.06), "{g:?}");
    assert!(
        near(g.finger_thickness_m, 0.01) && near(g.finger_width_m, 0.02),
        "{g:?}"
    );
    // Pads span z 0.01..0.06 above the palm's centre, the palm's top is at 0.01.
    assert!(near(g.finger_length_m, 0.05), "{g:?}");
    assert!(
        near(g.palm_size_m[0], 0.1) && near(g.palm_size_m[2], 0.02),
        "{g:?}"
    );
    assert_eq!(g.name, "slide");
    assert_eq!(measured.joint, "left_slide");
    assert!(near(measured.open_position, 0.03));
    let origin = measured.urdf_root_from_gripper.translation;
    assert!((origin - mvgrasp_geometry::Vec3::new(0.0, 0.0, 0.06)).length() < 1e-5);
    // from_file takes the same path.
    assert_eq!(Gripper::from_file(&path).unwrap(), measured.gripper);
}

#[test]
fn urdf_problems_name_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let one_pad = write(
        dir.path(),
        "one_pad.urdf",
        &SLIDE.replace("right_pad", "right_finger"),
    );
    let err = Gripper::from_file(&one_pad).unwrap_err().to_string();
    assert!(
        err.contains("one_pad.urdf") && err.contains("finger-pad"),
        "{err}"
    );
    let spec = UrdfGripperSpec {
        finger_links: Some(["left_pad".into(), "nope".into()]),
        ..Default::default()
    };
    let path = write(dir.path(), "slide.urdf", SLIDE);
    let err = Gripper::from_urdf(&path, &spec).unwrap_err().to_string();
    assert!(err.contains("slide.urdf") && err.contains("nope"), "{err}");
    let stuck = write(
        dir.path(),
        "stuck.urdf",
        &SLIDE.replace(r#"upper="0.03""#, r#"upper="0""#),
    );
    let err = Gripper::from_file(&stuck).unwrap_err().to_string();
    assert!(
        err.contains("stuck.urdf") && err.contains("max_opening_m"),
        "{err}"
    );
    let missing = dir.path().join("missing.urdf");
    assert!(
        Gripper::from_file(&missing)
            .unwrap_err()
            .to_string()
            .contains("missing.urdf")
    );
}

#[test]
fn the_robotiq_2f_85_urdf_measures_close_to_its_datasheet() {
    let Some(path) =
        shared_data("grippers/pybullet_grasper/grippers/robotiq_2f_85/robotiq_2f_85.urdf")
    else {
        return;
    };
    let measured = Gripper::from_urdf(&path, &UrdfGripperSpec::default()).unwrap();
    let g = &measured.gripper;
    eprintln!(
        "{g:#?}\njoint {} open at {}",
        measured.joint, measured.open_position
    );
    assert_eq!(measured.joint, "finger_joint");
    // Datasheet: 85 mm stroke, closes fully.
    assert!((g.max_opening_m - 0.085).abs() < 0.005, "{g:?}");
    assert!(g.min_opening_m < 0.005, "{g:?}");
    assert!((0.02..0.08).contains(&g.finger_length_m), "{g:?}");
}
