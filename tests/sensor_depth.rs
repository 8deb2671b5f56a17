//! Planning on real sensor depth: gqcnn's ten single-object Primesense images, with and
//! without their masks, the camera's pose withheld; and the errors of bad sensor files.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // tests may fail loudly

use std::path::Path;
use std::process::Command;

use mvgrasp::geometry::objects::{Category, generate as generate_object};
use mvgrasp::geometry::{Camera, Intrinsics, IntrinsicsPreset, RestingPoses, Vec3};
use mvgrasp::planner::{
    DepthImage, GqcnnPolicy, PlanParams, Planner, SensorFiles, SensorPlanParams, View, models,
    plan_on_sensor_depth, plan_on_view, read_view, read_views_dir,
};
use mvgrasp::scene::render_depths;

use crate::shared_data::shared_data;

/// How far the grasp's centre lies from the object, in the table plane: the distance from it
/// to the nearest of the mask's points, both projected onto the table, metres.
fn distance_to_object(files: &SensorFiles, camera: &Camera, centre: Vec3) -> f32 {
    let view = read_view(files).unwrap();
    let mask = view.mask.as_ref().unwrap();
    nearest_in_plane(&view.depth, camera, centre, |u, v, _| mask.at(u, v))
}

/// The distance in the world's xy plane from `centre` to the nearest point that `depth`
/// (seen through `camera`) shows at a pixel `on_object` accepts (it gets the pixel and the
/// world point), metres.
fn nearest_in_plane(
    depth: &DepthImage,
    camera: &Camera,
    centre: Vec3,
    on_object: impl Fn(i64, i64, Vec3) -> bool,
) -> f32 {
    let k = depth.intrinsics();
    let mut nearest = f32::INFINITY;
    for v in 0..i64::from(k.height) {
        for u in 0..i64::from(k.width) {
            let d = depth.at(u, v);
            let p = camera.unproject(u as f32, v as f32, d);
            if d > 0.0 && on_object(u, v, p) {
                nearest = nearest.min((p.x - centre.x).hypot(p.y - centre.y));
            }
        }
    }
    nearest
}

/// A plain JSON intrinsics file of `k` at `dir/name`.
fn write_intrinsics(dir: &Path, name: &str, k: &Intrinsics) -> std::path::PathBuf {
    let path = dir.join(name);
    std::fs::write(
        &path,
        format!(
            r#"{{"K": [[{}, 0, {}], [0, {}, {}], [0, 0, 1]], "width": {}, "height": {}}}"#,
            k.fx, k.cx, k.fy, k.cy, k.width, k.height
        ),
    )
    .unwrap();
    path
}

/// A 16-bit millimetre depth PNG of `values` (metres).
fn write_depth_png(path: &Path, width: u32, height: u32, values: &[f32]) {
    let file = std::fs::File::create(path).unwrap();
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), width, height);
    encoder.set_color(png::ColorType::Grayscale);
    encoder.set_depth(png::BitDepth::Sixteen);
    let data: Vec<u8> = values
        .iter()
        .flat_map(|&d| ((d * 1000.0).round() as u16).to_be_bytes())
        .collect();
    encoder
        .write_header()
        .unwrap()
        .write_image_data(&data)
        .unwrap();
}

/// A box `half_m` (x, y half extents) and 5 cm tall on a table 0.7 m below a Primesense
/// looking straight down, as its depth image.
fn box_depth(half_m: [f32; 2]) -> Vec<f32> {
    let k = Intrinsics::preset(IntrinsicsPreset::Primesense);
    (0..k.width * k.height)
        .map(|i| {
            let (u, v) = ((i % k.width) as f32, (i / k.width) as f32);
            let (x, y) = ((u - k.cx) * 0.65 / k.fx, (v - k.cy) * 0.65 / k.fy);
            if x.abs() < half_m[0] && y.abs() < half_m[1] {
                0.65
            } else {
                0.7
            }
        })
        .collect()
}

#[test]
fn a_grasp_on_each_real_single_object_image_with_and_without_its_mask() {
    let Some(root) = shared_data("real_depth/gqcnn/data") else {
        return;
    };
    let images = root.join("examples/single_object/primesense");
    let intrinsics = root.join("calib/primesense/primesense.intr");
    let (gripper, policy) = topdown_planner();
    let params = SensorPlanParams::default();
    for i in 0..10 {
        let mask = images.join(format!("segmask_{i}.png"));
        for with_mask in [true, false] {
            let files = SensorFiles {
                depth: images.join(format!("depth_{i}.npy")),
                intrinsics: intrinsics.clone(),
                camera_pose: None,
                mask: with_mask.then(|| mask.clone()),
            };
            let report = plan_on_sensor_depth(&policy, &gripper, &files, &params).unwrap();
            // The table under a camera 77 degrees above it (primesense.tf's optical axis).
            assert!(report.pose_estimated);
            assert!(
                (report.camera_elevation_deg - 77.3).abs() < 2.0,
                "image {i}: {report:?}"
            );
            let best = report
                .best
                .unwrap_or_else(|| panic!("image {i}, mask {with_mask}: no grasp: {report:?}"));
            let judged = SensorFiles {
                mask: Some(mask.clone()),
                ..files
            };
            let off = distance_to_object(&judged, &report.view.camera, best.grasp.center());
            assert!(
                off < 0.015,
                "image {i}, mask {with_mask}: the grasp's centre is {:.1} cm from the object",
                off * 100.0
            );
        }
    }
}

/// The default gripper and the shipped top-down GQ-CNN.
fn topdown_planner() -> (mvgrasp::grasp::Gripper, Planner) {
    let gripper = PlanParams::default().labels.gripper;
    let policy = Planner::from(
        GqcnnPolicy::new(models::GQCNN_TOPDOWN.load().unwrap(), gripper.max_opening_m).unwrap(),
    );
    (gripper, policy)
}

/// gqcnn's clutter images: (folder, images, intrinsics, camera pose).
const CLUTTER_SETS: [(&str, usize, &str, &str); 3] = [
    (
        "examples/clutter/phoxi/dex-net_4.0",
        5,
        "calib/phoxi/phoxi.intr",
        "calib/phoxi/phoxi_to_world.tf",
    ),
    (
        "examples/clutter/phoxi/fcgqcnn",
        5,
        "calib/phoxi/phoxi.intr",
        "calib/phoxi/phoxi_to_world.tf",
    ),
    (
        "examples/clutter/primesense",
        5,
        "calib/primesense/primesense.intr",
        "calib/primesense/primesense.tf",
    ),
];

/// The issue's target on real clutter: without a mask (the objects found on the fitted table
/// or bin floor), with the camera's pose, a grasp the network rates 0.5 or more, on an object
/// (judged by the image's own mask), in every one of the 15 images.
#[test]
fn a_grasp_rated_half_or_more_on_an_object_in_each_real_clutter_image_without_a_mask() {
    let Some(root) = shared_data("real_depth/gqcnn/data") else {
        return;
    };
    let (gripper, policy) = topdown_planner();
    let params = SensorPlanParams::default();
    let mut failures = Vec::new();
    for (folder, count, intrinsics, pose) in CLUTTER_SETS {
        for i in 0..count {
            let files = SensorFiles {
                depth: root.join(folder).join(format!("depth_{i}.npy")),
                intrinsics: root.join(intrinsics),
                camera_pose: Some(root.join(pose)),
                mask: None,
            };
            let report = plan_on_sensor_depth(&policy, &gripper, &files, &params).unwrap();
            let Some(best) = report.best else {
                failures.push(format!("{folder} {i}: no grasp"));
                continue;
            };
            let judged = SensorFiles {
                mask: Some(root.join(folder).join(format!("segmask_{i}.png"))),
                ..files
            };
            let off = distance_to_object(&judged, &report.view.camera, best.grasp.center());
            if best.quality < 0.5 || off > 0.015 {
                failures.push(format!(
                    "{folder} {i}: quality {:.3}, {:.1} cm from the objects",
                    best.quality,
                    off * 100.0
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

#[test]
fn a_grasp_on_some_object_in_each_real_clutter_image_with_and_without_the_camera_pose() {
    let Some(root) = shared_data("real_depth/gqcnn/data") else {
        return;
    };
    let (gripper, policy) = topdown_planner();
    let params = SensorPlanParams::default();
    for (folder, count, intrinsics, pose) in CLUTTER_SETS {
        for i in 0..count {
            let mask = root.join(folder).join(format!("segmask_{i}.png"));
            for with_pose in [true, false] {
                let files = SensorFiles {
                    depth: root.join(folder).join(format!("depth_{i}.npy")),
                    intrinsics: root.join(intrinsics),
                    camera_pose: with_pose.then(|| root.join(pose)),
                    mask: Some(mask.clone()),
                };
                let report = plan_on_sensor_depth(&policy, &gripper, &files, &params).unwrap();
                let best = report.best.unwrap_or_else(|| {
                    panic!("{folder} {i}, pose {with_pose}: no grasp: {report:?}")
                });
                let off = distance_to_object(&files, &report.view.camera, best.grasp.center());
                assert!(
                    off < 0.015,
                    "{folder} {i}, pose {with_pose}: the grasp's centre is {:.1} cm from the \
                     objects",
                    off * 100.0
                );
            }
        }
    }
}

#[test]
fn oblique_rendered_views_find_the_table_and_a_grasp_with_the_pose_withheld() {
    let Some(renderer) = crate::common::renderer() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let k = Intrinsics::preset(IntrinsicsPreset::Primesense);
    let intrinsics = write_intrinsics(dir.path(), "camera.json", &k);
    let object = generate_object(Category::Box, 0, 0).unwrap();
    let rest = RestingPoses::of(&object.mesh).unwrap();
    let (_, pose) = rest.get(0).unwrap();
    let gripper = PlanParams::default().labels.gripper;
    // The multi-view GQ-CNN: trained on views 10 to 90 degrees above the table.
    let policy = Planner::from(
        GqcnnPolicy::new(models::MVGQCNN.load().unwrap(), gripper.max_opening_m).unwrap(),
    );
    for elevation_deg in [20.0f32, 35.0, 50.0, 65.0, 80.0] {
        let e = elevation_deg.to_radians();
        let eye = Vec3::new(0.65 * e.cos() * 0.8, 0.65 * e.cos() * 0.6, 0.65 * e.sin());
        let camera = Camera::look_at(k, eye, Vec3::ZERO, Vec3::Z).unwrap();
        let depth = render_depths(&renderer, &object.mesh, &pose.table_from_object, &[camera])
            .unwrap()
            .remove(0);
        let path = dir.path().join("depth.png");
        write_depth_png(&path, k.width, k.height, depth.as_slice());
        let files = SensorFiles {
            depth: path,
            intrinsics: intrinsics.clone(),
            camera_pose: None,
            mask: None,
        };
        let report =
            plan_on_sensor_depth(&policy, &gripper, &files, &SensorPlanParams::default()).unwrap();
        // The table: its normal in the camera frame against the truth.
        let truth = camera.world_from_camera.rotation.inverse() * Vec3::Z;
        let error_deg = report.table.up().angle_between(truth).to_degrees();
        assert!(
            error_deg < 2.0,
            "{elevation_deg} deg: the table is {error_deg} deg off"
        );
        assert!(
            (report.camera_elevation_deg - elevation_deg).abs() < 2.0,
            "{report:?}"
        );
        // A grasp on the box: its centre, taken back to the true world, within 1.5 cm of the
        // box's points seen (those above the table) in the table plane.
        let best = report
            .best
            .unwrap_or_else(|| panic!("{elevation_deg} deg: no grasp: {report:?}"));
        let in_camera = report
            .view
            .camera
            .camera_from_world()
            .transform_point(best.grasp.center());
        let centre = camera.world_from_camera.transform_point(in_camera);
        let nearest = nearest_in_plane(&depth, &camera, centre, |_, _, p| p.z > 0.005);
        assert!(
            nearest < 0.015,
            "{elevation_deg} deg: the grasp's centre is {:.1} cm from the box",
            nearest * 100.0
        );
    }
}

/// The CLI on a synthetic sensor image (a 4 x 4 x 5 cm box on a table 0.7 m below a camera
/// looking straight down): `--out` writes `grasps.json` and the overlay, `--json` prints the
/// same file, and a scene with no feasible grasp exits with code 3, its outputs written.
#[test]
fn plan_on_depth_writes_grasps_json_and_an_overlay() {
    let dir = tempfile::tempdir().unwrap();
    let k = Intrinsics::preset(IntrinsicsPreset::Primesense);
    let intrinsics = write_intrinsics(
        dir.path(),
        "camera.json",
        &Intrinsics::preset(IntrinsicsPreset::Primesense),
    );
    let depth = dir.path().join("depth.png");
    write_depth_png(&depth, k.width, k.height, &box_depth([0.02, 0.02]));
    let out = dir.path().join("out");
    let run = |extra: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_plan"))
            .args(["--depth", depth.to_str().unwrap()])
            .args(["--intrinsics", intrinsics.to_str().unwrap()])
            .args(["--out", out.to_str().unwrap()])
            .args(extra)
            .output()
            .unwrap()
    };
    let result = run(&[]);
    assert!(
        result.status.success(),
        "{}",
        String::from_utf8_lossy(&result.stderr)
    );
    let text = String::from_utf8(result.stdout).unwrap();
    assert!(text.contains("camera pose: estimated"), "{text}");
    assert!(text.contains("best grasp: quality"), "{text}");
    let written = std::fs::read_to_string(out.join("grasps.json")).unwrap();
    let file: serde_json::Value = serde_json::from_str(&written).unwrap();
    assert_eq!(file["format"], "mvgrasp-grasps/1");
    assert_eq!(file["frame"], "estimated");
    let best = &file["grasps"][0];
    assert_eq!(best["rank"], 0);
    // Across the box: 4 cm wide, its centre on the box's axis, 0.7 m below the camera at
    // most, and the world frame on the table (the centre below the box's top, 5 cm up).
    let width = best["width_m"].as_f64().unwrap();
    assert!((0.035..0.05).contains(&width), "{best}");
    let camera_from_gripper = &best["camera_from_gripper"];
    let (x, y) = (
        camera_from_gripper[0][3].as_f64().unwrap(),
        camera_from_gripper[1][3].as_f64().unwrap(),
    );
    assert!(x.hypot(y) < 0.01, "{best}");
    let z_world = best["world_from_gripper"][2][3].as_f64().unwrap();
    assert!((0.0..0.05).contains(&z_world), "{best}");
    assert_eq!(best["p"][2], best["world_from_gripper"][2][3]);
    assert!(out.join("overlay_0.png").is_file());
    // The MCAP log: one message on each Foxglove channel, the grasps' poses those of the file.
    let log = std::fs::read(out.join("plan.mcap")).unwrap();
    let mut topics = std::collections::BTreeMap::new();
    for message in mcap::MessageStream::new(&log).unwrap() {
        let message = message.unwrap();
        let schema = message.channel.schema.as_ref().unwrap();
        assert_eq!(schema.encoding, "jsonschema");
        let body: serde_json::Value = serde_json::from_slice(&message.data).unwrap();
        topics.insert(message.channel.topic.clone(), (schema.name.clone(), body));
    }
    let names: Vec<(&str, &str)> = topics
        .iter()
        .map(|(topic, (schema, _))| (topic.as_str(), schema.as_str()))
        .collect();
    assert_eq!(
        names,
        [
            ("/camera_0/calibration", "foxglove.CameraCalibration"),
            ("/camera_0/depth", "foxglove.RawImage"),
            ("/grasps", "foxglove.PosesInFrame"),
            ("/table", "foxglove.PoseInFrame"),
            ("/tf", "foxglove.FrameTransforms"),
        ]
    );
    let poses = &topics["/grasps"].1["poses"];
    assert_eq!(
        poses.as_array().unwrap().len(),
        file["grasps"].as_array().unwrap().len()
    );
    for axis in 0..3 {
        let logged = poses[0]["position"][["x", "y", "z"][axis]]
            .as_f64()
            .unwrap();
        let listed = best["world_from_gripper"][axis][3].as_f64().unwrap();
        assert!((logged - listed).abs() < 1e-6, "{logged} {listed}");
    }
    // The camera on /tf is where grasps.json puts it: on the estimated table, 0.7 m above it.
    let logged_z = topics["/tf"].1["transforms"][0]["translation"]["z"]
        .as_f64()
        .unwrap();
    let listed_z = file["views"][0]["world_from_camera"][2][3]
        .as_f64()
        .unwrap();
    assert!(
        (logged_z - listed_z).abs() < 1e-6 && (logged_z - 0.7).abs() < 0.005,
        "{logged_z} {listed_z}"
    );
    let image = &topics["/camera_0/depth"].1;
    assert_eq!(
        (image["width"].as_u64(), image["encoding"].as_str()),
        (Some(640), Some("32FC1"))
    );
    // --json prints the same file.
    let printed = run(&["--json"]);
    assert!(printed.status.success());
    assert_eq!(
        String::from_utf8(printed.stdout).unwrap().trim(),
        written.trim()
    );
    // A box wider than the gripper opens: no grasp, exit code 3, the folder still written.
    std::fs::remove_dir_all(&out).unwrap();
    write_depth_png(&depth, k.width, k.height, &box_depth([0.06, 0.06]));
    let none = run(&[]);
    assert_eq!(
        none.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&none.stderr)
    );
    let text = String::from_utf8(none.stdout).unwrap();
    assert!(text.contains("no grasp:"), "{text}");
    let file: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("grasps.json")).unwrap()).unwrap();
    assert_eq!(file["grasps"].as_array().unwrap().len(), 0);
}

/// `plan --views-dir` on a folder `render` wrote (10 test views of a box, depth in 0.1 mm,
/// masks 0 / 1 object / 2 table): the multi-view GQ-CNN's grasp (each view on its own, and
/// the multi-view planner's) lies on the box; and folders
/// whose cameras and images disagree are refused.
#[test]
fn plan_over_a_rendered_views_folder() {
    let dir = tempfile::tempdir().unwrap();
    crate::common::render_dataset(dir.path(), "box");
    let views_dir = dir.path().join("box_000/test");
    let out = dir.path().join("out");
    let planned = Command::new(env!("CARGO_BIN_EXE_plan"))
        .args(["--views-dir", views_dir.to_str().unwrap(), "--no-fuse"])
        .args([
            "--model",
            "gqcnn_small_multiview",
            "--out",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(
        planned.status.success(),
        "{}",
        String::from_utf8_lossy(&planned.stderr)
    );
    let file: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("grasps.json")).unwrap()).unwrap();
    assert_eq!(file["frame"], "given");
    assert_eq!(file["views"].as_array().unwrap().len(), 10);
    assert!(out.join("overlay_9.png").is_file());
    let p = &file["grasps"][0]["p"];
    let centre = Vec3::new(
        p[0].as_f64().unwrap() as f32,
        p[1].as_f64().unwrap() as f32,
        p[2].as_f64().unwrap() as f32,
    );
    // The box's points seen in the top-down view (its mask: value 1).
    let views = read_views_dir(&views_dir).unwrap();
    let top = &views[0];
    let mask = top.mask.as_ref().unwrap();
    let k = top.depth.intrinsics();
    let nearest = nearest_in_plane(&top.depth, &top.camera, centre, |u, v, _| mask.at(u, v));
    assert!(
        nearest < 0.015,
        "the grasp is {:.1} cm from the box",
        nearest * 100.0
    );
    // The table's pixels (mask value 2) are not the object: the masks hold the box alone.
    assert!(
        mask.count() < (k.width * k.height / 4) as usize,
        "{}",
        mask.count()
    );

    // The multi-view planner over the same folder: the views fused in the given frame (its
    // z up from the fitted table), the best re-scored on virtual views; a grasp on the box.
    let fused = Command::new(env!("CARGO_BIN_EXE_plan"))
        .args([
            "--views-dir",
            views_dir.to_str().unwrap(),
            "--fuse",
            "--json",
        ])
        .output()
        .unwrap();
    assert!(
        fused.status.success(),
        "{}",
        String::from_utf8_lossy(&fused.stderr)
    );
    let file: serde_json::Value = serde_json::from_slice(&fused.stdout).unwrap();
    let best = &file["grasps"][0];
    assert!(best["view_quality"].as_f64().is_some(), "{best}");
    let p = &best["p"];
    let centre = Vec3::new(
        p[0].as_f64().unwrap() as f32,
        p[1].as_f64().unwrap() as f32,
        p[2].as_f64().unwrap() as f32,
    );
    let nearest = nearest_in_plane(&top.depth, &top.camera, centre, |u, v, _| mask.at(u, v));
    assert!(nearest < 0.015, "{:.1} cm from the box", nearest * 100.0);

    // One view of the folder through --depth: its PNG read in the dataset's 0.1 mm units
    // (not millimetres: the table would be 5 m away), its mask's object alone.
    // Its intrinsics are those of the folder's top-down camera, written as a plain JSON.
    let intrinsics = write_intrinsics(dir.path(), "camera.json", k);
    let single = Command::new(env!("CARGO_BIN_EXE_plan"))
        .args(["--depth", views_dir.join("000_depth.png").to_str().unwrap()])
        .args(["--intrinsics", intrinsics.to_str().unwrap()])
        .args([
            "--mask",
            views_dir.join("000_mask.png").to_str().unwrap(),
            "--json",
        ])
        .output()
        .unwrap();
    assert!(
        single.status.success(),
        "{}",
        String::from_utf8_lossy(&single.stderr)
    );
    let file: serde_json::Value = serde_json::from_slice(&single.stdout).unwrap();
    let height = file["table"]["camera_height_m"].as_f64().unwrap();
    assert!(
        (0.45..0.6).contains(&height),
        "the camera {height} m above the table"
    );

    // A camera without its depth image, and a depth image without its camera.
    let cameras_path = views_dir.join("cameras.json");
    let cameras: Vec<serde_json::Value> =
        serde_json::from_str(&std::fs::read_to_string(&cameras_path).unwrap()).unwrap();
    std::fs::remove_file(views_dir.join("004_depth.png")).unwrap();
    let err = read_views_dir(&views_dir)
        .map(|v| v.len())
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("004_depth.png") && err.contains("view 4"),
        "{err}"
    );
    std::fs::write(&cameras_path, serde_json::to_string(&cameras[..3]).unwrap()).unwrap();
    let err = read_views_dir(&views_dir)
        .map(|v| v.len())
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("003_depth.png") && err.contains("lists 3 cameras"),
        "{err}"
    );
    std::fs::write(&cameras_path, "[]").unwrap();
    let err = read_views_dir(&views_dir)
        .map(|v| v.len())
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("cameras.json") && err.contains("no camera"),
        "{err}"
    );
    // A dataset manifest that cannot be read: its depth units are not guessed.
    std::fs::write(dir.path().join("dataset.json"), "not json").unwrap();
    let files = SensorFiles {
        depth: views_dir.join("000_depth.png"),
        intrinsics,
        camera_pose: None,
        mask: None,
    };
    let err = read_view(&files).map(|_| ()).unwrap_err().to_string();
    assert!(
        err.contains("dataset.json") && err.contains("units"),
        "{err}"
    );
}

/// An in-memory view (a robot's depth stream) plans the same grasps as the same image read
/// from files.
#[test]
fn a_view_in_memory_plans_as_its_files_do() {
    let dir = tempfile::tempdir().unwrap();
    let k = Intrinsics::preset(IntrinsicsPreset::Primesense);
    let depth = box_depth([0.02, 0.03]);
    let path = dir.path().join("depth.png");
    write_depth_png(&path, k.width, k.height, &depth);
    let intrinsics = write_intrinsics(dir.path(), "camera.json", &k);
    let (gripper, policy) = topdown_planner();
    let params = SensorPlanParams::default();
    let files = SensorFiles {
        depth: path,
        intrinsics,
        camera_pose: None,
        mask: None,
    };
    let from_files = plan_on_sensor_depth(&policy, &gripper, &files, &params).unwrap();
    let camera = Camera {
        intrinsics: k,
        world_from_camera: mvgrasp::geometry::Pose3::IDENTITY,
    };
    let view = View::new(0, camera, DepthImage::new(k, depth).unwrap()).unwrap();
    let in_memory = plan_on_view(&policy, &gripper, view, false, &params).unwrap();
    assert!(
        in_memory.best.is_some() && in_memory.candidates > 50,
        "{in_memory:?}"
    );
    assert_eq!(in_memory.top, from_files.top);
    assert_eq!(in_memory.view.camera, from_files.view.camera);
}

#[test]
fn bad_sensor_files_are_one_clear_line_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let depth = dir.path().join("depth.png");
    let intr = write_intrinsics(
        dir.path(),
        "camera.json",
        &Intrinsics::preset(IntrinsicsPreset::Primesense),
    );
    let flat = vec![0.7f32; 640 * 480];
    let plan = |extra: &[&str]| {
        let out = Command::new(env!("CARGO_BIN_EXE_plan"))
            .args(["--depth", depth.to_str().unwrap()])
            .args(["--intrinsics", intr.to_str().unwrap()])
            .args(extra)
            .output()
            .unwrap();
        assert!(!out.status.success());
        let err = String::from_utf8(out.stderr).unwrap();
        assert!(!err.contains("panicked"), "{err}");
        err
    };
    // Intrinsics for another size.
    write_depth_png(&depth, 320, 240, &[0.7; 320 * 240]);
    let err = plan(&[]);
    assert!(
        err.contains("camera.json") && err.contains("640 x 480") && err.contains("320 x 240"),
        "{err}"
    );
    // A flat table with nothing on it; all missing; a mask of the wrong size.
    write_depth_png(&depth, 640, 480, &flat);
    assert!(
        plan(&[]).contains("nothing stands on the table"),
        "{}",
        plan(&[])
    );
    let mask = dir.path().join("mask.png");
    write_depth_png(&mask, 64, 48, &[0.001; 64 * 48]);
    let err = plan(&["--mask", mask.to_str().unwrap()]);
    assert!(err.contains("mask.png") && err.contains("64 x 48"), "{err}");
    write_depth_png(&depth, 640, 480, &[0.0; 640 * 480]);
    let err = plan(&[]);
    assert!(
        err.contains("depth.png") && err.contains("no valid depth"),
        "{err}"
    );
    // A pose that is not rigid.
    write_depth_png(&depth, 640, 480, &flat);
    let pose = dir.path().join("pose.json");
    std::fs::write(
        &pose,
        r#"{"world_from_camera": [[2, 0, 0, 0], [0, -1, 0, 0], [0, 0, -1, 0.7], [0, 0, 0, 1]]}"#,
    )
    .unwrap();
    let err = plan(&["--camera-pose", pose.to_str().unwrap()]);
    assert!(
        err.contains("pose.json") && err.contains("not a rigid transform"),
        "{err}"
    );
}
