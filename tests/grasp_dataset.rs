//! Grasp datasets: crop geometry checked by re-projecting contacts, labels recomputed from the
//! shard's own records, determinism across thread counts, and kill -9 then resume.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // tests may fail loudly

use crate::common;

use common::renderer;
use std::path::Path;
use std::process::Command;

use mvgrasp::dataset::ObjectSource;
use mvgrasp::geometry::objects::{Category, ObjectSpec, generate as generate_object};
use mvgrasp::geometry::pose_as_matrix::from_rows;
use mvgrasp::geometry::{Camera, Vec3};
use mvgrasp::grasp::quality::{find_contacts, robust_quality};
use mvgrasp::grasp::{GraspObject, canonical_frame, check_collision};
use mvgrasp::grasp_dataset::{CameraDistribution, GraspDatasetConfig, MultiViewCameras, generate};
use mvgrasp_planner::crop::image_to_crop;
use safetensors::SafeTensors;

/// A small, quick config (debug builds run these).
fn small_config() -> GraspDatasetConfig {
    GraspDatasetConfig {
        stable_poses_per_object: 1,
        grasps_per_pose: 24,
        views_per_pose: 3,
        objects_per_shard: 1,
        physics_fraction: 0.1,
        ..GraspDatasetConfig::default()
    }
}

fn sources(categories: &[Category]) -> Vec<ObjectSource> {
    categories
        .iter()
        .map(|&category| {
            ObjectSource::Builtin(ObjectSpec {
                category,
                index: 0,
                seed: 0,
            })
        })
        .collect()
}

fn f32s(tensors: &SafeTensors, name: &str) -> Vec<f32> {
    let t = tensors.tensor(name).unwrap();
    t.data()
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect()
}

fn u32s(tensors: &SafeTensors, name: &str) -> Vec<u32> {
    let t = tensors.tensor(name).unwrap();
    t.data()
        .chunks_exact(4)
        .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect()
}

fn u64s(tensors: &SafeTensors, name: &str) -> Vec<u64> {
    let t = tensors.tensor(name).unwrap();
    t.data()
        .chunks_exact(8)
        .map(|b| u64::from_le_bytes(b.try_into().unwrap()))
        .collect()
}

fn matrix(values: &[f32], i: usize) -> [[f32; 4]; 4] {
    let m = &values[16 * i..16 * i + 16];
    [0, 1, 2, 3].map(|r| [m[4 * r], m[4 * r + 1], m[4 * r + 2], m[4 * r + 3]])
}

/// With physics on every collision-free datapoint, each gets a physics label from K perturbed
/// trials: a rate in steps of 1/K or so (settle failures left out), the label its majority;
/// datapoints that collide get none.
#[test]
fn every_collision_free_datapoint_gets_a_physics_label_from_k_trials() {
    let Some(renderer) = renderer() else { return };
    let dir = tempfile::tempdir().unwrap();
    let config = GraspDatasetConfig {
        grasps_per_pose: 12,
        views_per_pose: 2,
        physics_fraction: 1.0,
        physics_trials: 4,
        ..small_config()
    };
    let summary = generate(
        &renderer,
        &sources(&[Category::Box]),
        &config,
        dir.path(),
        false,
    )
    .unwrap();
    let bytes = std::fs::read(dir.path().join("shard_00000.safetensors")).unwrap();
    let shard = SafeTensors::deserialize(&bytes).unwrap();
    let rate = f32s(&shard, "physics_rate");
    let label = shard.tensor("physics").unwrap().data().to_vec();
    let free = shard.tensor("collision_free").unwrap().data().to_vec();
    let mut labelled = 0;
    for ((&r, &l), &f) in rate.iter().zip(&label).zip(&free) {
        let l = l as i8;
        if f == 0 {
            assert_eq!((r, l), (-1.0, -1), "a colliding datapoint gets no trial");
            continue;
        }
        if l < 0 {
            assert_eq!(r, -1.0, "every trial lost the resting pose");
            continue;
        }
        labelled += 1;
        assert!((0.0..=1.0).contains(&r), "{r}");
        // successes over the settled trials, 1 to 4 of them
        assert!(
            (1..=4).any(|n| ((r * n as f32).round() - r * n as f32).abs() < 1e-5),
            "{r}"
        );
        assert_eq!(l, i8::from(r >= 0.5));
    }
    assert!(labelled > 0, "{summary:?}");
    assert_eq!(summary.totals.physics_trials, labelled);

    // The physics labels change nothing else: without them every other column is the same
    // bytes (so the shipped datasets' configs could gain them without changing the networks'
    // training data).
    let plain = tempfile::tempdir().unwrap();
    let config = GraspDatasetConfig {
        physics_fraction: 0.0,
        physics_trials: 1,
        ..config
    };
    generate(
        &renderer,
        &sources(&[Category::Box]),
        &config,
        plain.path(),
        false,
    )
    .unwrap();
    let bytes = std::fs::read(plain.path().join("shard_00000.safetensors")).unwrap();
    let without = SafeTensors::deserialize(&bytes).unwrap();
    let physics_columns = ["physics", "physics_rate", "physics_stage"];
    let mut compared = 0;
    for (name, column) in shard.tensors() {
        if physics_columns.contains(&name.as_str()) {
            continue;
        }
        assert_eq!(
            column.data(),
            without.tensor(&name).unwrap().data(),
            "column {name}"
        );
        compared += 1;
    }
    assert!(compared >= 15, "{compared} columns");
}

#[test]
fn crops_are_centred_on_the_grasp_with_its_axis_along_the_rows_and_labels_recompute() {
    let Some(renderer) = renderer() else { return };
    let dir = tempfile::tempdir().unwrap();
    let config = GraspDatasetConfig {
        cameras: CameraDistribution::MultiView(MultiViewCameras::default()),
        grasps_per_pose: 48,
        views_per_pose: 8,
        ..small_config()
    };
    let objects = sources(&[Category::Mug]);
    let summary = generate(&renderer, &objects, &config, dir.path(), false).unwrap();
    let t = summary.totals;
    assert!(
        t.datapoints > 20 && t.collision_free >= 3 && t.positives > 0,
        "{summary:?}"
    );
    let bytes = std::fs::read(dir.path().join("shard_00000.safetensors")).unwrap();
    let shard = SafeTensors::deserialize(&bytes).unwrap();
    let n = summary.totals.datapoints;
    let crops = f32s(&shard, "depth_crops");
    assert_eq!(crops.len(), n * 32 * 32);
    let center_px = f32s(&shard, "center_px");
    let angle = f32s(&shard, "angle_rad");
    let depth = f32s(&shard, "grasp_depth_m");
    let epsilon = f32s(&shard, "robust_epsilon");
    let width = f32s(&shard, "width_m");
    let seeds = u64s(&shard, "quality_seed");
    let labels = shard.tensor("robust_label").unwrap().data().to_vec();
    let free = shard.tensor("collision_free").unwrap().data().to_vec();
    let object_from_gripper = f32s(&shard, "object_from_gripper");
    let table_from_object = f32s(&shard, "table_from_object");
    let world_from_camera = f32s(&shard, "world_from_camera");
    assert_eq!(u32s(&shard, "object_id"), vec![0; n]);

    let mesh = generate_object(Category::Mug, 0, 0).unwrap().mesh;
    let object = GraspObject::new(mesh).unwrap();
    let gripper = config.gripper().unwrap();
    let intrinsics = config.intrinsics().unwrap();
    let mut checked_contacts = 0;
    for i in (0..n).step_by((n / 12).max(1)) {
        let grasp = from_rows(matrix(&object_from_gripper, i)).unwrap();
        let table = from_rows(matrix(&table_from_object, i)).unwrap();
        let camera = Camera {
            intrinsics,
            world_from_camera: from_rows(matrix(&world_from_camera, i)).unwrap(),
        };
        let center = [center_px[2 * i], center_px[2 * i + 1]];
        let params = config.crop;
        // The grasp centre projects to the recorded pixel, at the recorded depth.
        let world_center = (table * grasp).translation;
        let projected = camera.project(world_center).unwrap();
        assert!((projected[0] - center[0]).abs() < 1e-2 && (projected[1] - center[1]).abs() < 1e-2);
        let in_camera = camera.camera_from_world().transform_point(world_center);
        assert!((in_camera.z - depth[i]).abs() < 1e-5);
        // The jaws, closed again on the mesh, touch where the crop's centre row says.
        if let Some(contacts) = find_contacts(&object, &grasp, &gripper) {
            let crop_xy = contacts.contacts.map(|c| {
                let uv = camera.project(table.transform_point(c.point)).unwrap();
                image_to_crop(center, angle[i], &params, uv)
            });
            let half = params.size_px as f32 / 2.0;
            // Within the tilt cone the contacts leave the row by at most tan(5 deg) of half the
            // width, well under a crop pixel.
            for xy in crop_xy {
                assert!(
                    (xy[1] - half).abs() < 0.5,
                    "contact off the centre row: {xy:?}"
                );
            }
            assert!(crop_xy[0][0] < half && crop_xy[1][0] > half, "{crop_xy:?}");
            assert!(((crop_xy[0][0] + crop_xy[1][0]) / 2.0 - half).abs() < 0.5);
            checked_contacts += 1;
        }
        // The crop sees the object or the table at its centre, within the views' range.
        let c = crops[i * 1024 + 16 * 32 + 16];
        assert!((0.3..1.0).contains(&c), "crop centre {c}");
        // Labels: robust quality from the recorded seed on the canonical frame of the axis,
        // collision along this view's approach.
        let axis = grasp.transform_vector(Vec3::X);
        let canonical = canonical_frame(grasp.translation, axis, 0.0);
        let q = robust_quality(&object, &canonical, &gripper, &config.quality, seeds[i]).unwrap();
        // The frame comes back from f32 matrices, a few ulps off the one scored: the contacts
        // move by as much, and epsilon by about as little.
        let recomputed = q.robust_epsilon as f32;
        assert!(
            (recomputed - epsilon[i]).abs() <= 1e-6 + 1e-3 * epsilon[i].abs(),
            "datapoint {i}: {recomputed} recomputed, {} stored",
            epsilon[i]
        );
        let collision = check_collision(
            &object,
            &gripper,
            &grasp,
            width[i],
            Some(&table),
            &config.sampling.collision,
        );
        assert_eq!(collision.is_free(), free[i] == 1, "datapoint {i}");
        assert_eq!(
            config
                .quality
                .dexnet_label(q.robust_epsilon, collision.is_free()),
            labels[i] == 1
        );
    }
    assert!(checked_contacts >= 5, "{checked_contacts}");
}

fn run_generator(out: &Path, config: &Path, threads: &str) -> std::process::Child {
    Command::new(env!("CARGO_BIN_EXE_grasp_dataset"))
        .args([
            "--quiet",
            "--per-category",
            "1",
            "--categories",
            "mug,box,can,bowl",
        ])
        .arg("--out")
        .arg(out)
        .arg("--config")
        .arg(config)
        .env("RAYON_NUM_THREADS", threads)
        .stdout(std::process::Stdio::null())
        .spawn()
        .unwrap()
}

fn shard_bytes(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut files: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_none_or(|e| e != "tmp"))
        .collect();
    files.sort();
    files
        .into_iter()
        .map(|p| {
            (
                p.file_name().unwrap().to_string_lossy().into_owned(),
                std::fs::read(&p).unwrap(),
            )
        })
        .collect()
}

#[test]
fn kill_and_resume_and_any_thread_count_give_the_same_bytes() {
    if renderer().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let config = dir.path().join("config.toml");
    std::fs::write(
        &config,
        "stable_poses_per_object = 1\ngrasps_per_pose = 16\nviews_per_pose = 2\n\
         objects_per_shard = 1\nphysics_fraction = 0.05\n",
    )
    .unwrap();
    let whole = dir.path().join("whole");
    assert!(
        run_generator(&whole, &config, "2")
            .wait()
            .unwrap()
            .success()
    );
    let single = dir.path().join("single");
    assert!(
        run_generator(&single, &config, "1")
            .wait()
            .unwrap()
            .success()
    );
    let reference = shard_bytes(&whole);
    assert_eq!(
        reference.len(),
        1 + 2 * 4,
        "{:?}",
        reference.iter().map(|f| &f.0).collect::<Vec<_>>()
    );
    assert_eq!(shard_bytes(&single), reference, "one thread and two differ");

    // Kill -9 once the first shard is finished, then resume.
    let killed = dir.path().join("killed");
    let mut child = run_generator(&killed, &config, "2");
    let first = killed.join("shard_00000.safetensors");
    let started = std::time::Instant::now();
    while !first.exists() && started.elapsed().as_secs() < 600 {
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let done_before = std::fs::read_dir(&killed)
        .unwrap()
        .filter(|e| {
            e.as_ref()
                .unwrap()
                .path()
                .extension()
                .is_some_and(|x| x == "safetensors")
        })
        .count();
    assert!(
        done_before < 4,
        "the run finished before it was killed; nothing was tested"
    );
    assert!(
        run_generator(&killed, &config, "2")
            .wait()
            .unwrap()
            .success()
    );
    assert_eq!(shard_bytes(&killed), reference, "resumed run differs");
}

/// Clutter changes what the crops show and which grasps are free, nothing else: the same
/// grasps, qualities and cameras as the object alone, every grasp that clutter leaves free is
/// free alone, and some crop shows a neighbour; physics labels are run among the neighbours.
#[test]
fn clutter_adds_neighbours_to_the_crops_and_to_the_hand_check_only() {
    let Some(renderer) = renderer() else { return };
    let objects = sources(&[Category::Box, Category::Can, Category::Mug]);
    let alone = GraspDatasetConfig {
        physics_fraction: 0.0,
        ..small_config()
    };
    let cluttered = GraspDatasetConfig {
        clutter: Some(mvgrasp::grasp_dataset::ClutterParams {
            neighbours: [2, 2],
            spread_m: 0.08,
            ..Default::default()
        }),
        ..alone.clone()
    };
    let read = |config: &GraspDatasetConfig| {
        let dir = tempfile::tempdir().unwrap();
        generate(&renderer, &objects, config, dir.path(), false).unwrap();
        (0..objects.len())
            .map(|i| std::fs::read(dir.path().join(format!("shard_{i:05}.safetensors"))).unwrap())
            .collect::<Vec<_>>()
    };
    let (alone_bytes, clutter_bytes) = (read(&alone), read(&cluttered));
    assert_eq!(
        clutter_bytes,
        read(&cluttered),
        "the same seed, the same bytes"
    );
    let (mut differing_crops, mut lost_freedom) = (0, 0);
    for (a, c) in alone_bytes.iter().zip(&clutter_bytes) {
        let (a, c) = (
            SafeTensors::deserialize(a).unwrap(),
            SafeTensors::deserialize(c).unwrap(),
        );
        for column in [
            "robust_epsilon",
            "object_from_gripper",
            "world_from_camera",
            "grasp",
        ] {
            assert_eq!(
                a.tensor(column).unwrap().data(),
                c.tensor(column).unwrap().data(),
                "{column}"
            );
        }
        let free = |t: &SafeTensors| t.tensor("collision_free").unwrap().data().to_vec();
        for (fa, fc) in free(&a).iter().zip(free(&c)) {
            assert!(fc <= *fa, "free in clutter but not alone");
            lost_freedom += usize::from(fc < *fa);
        }
        let (crops_a, crops_c) = (f32s(&a, "depth_crops"), f32s(&c, "depth_crops"));
        let side = 32 * 32;
        differing_crops += crops_a
            .chunks(side)
            .zip(crops_c.chunks(side))
            .filter(|(x, y)| x != y)
            .count();
    }
    assert!(differing_crops > 0, "no crop shows a neighbour");
    assert!(lost_freedom > 0, "no neighbour is in any hand's way");

    // Physics labels among the neighbours (the trial in the cluttered scene, where the
    // object must come out alone: `success_probability_among`, tested in the grasp crate):
    // every collision-free datapoint gets one, and the same seed gives the same bytes.
    let physics = GraspDatasetConfig {
        physics_fraction: 1.0,
        physics_trials: 2,
        ..cluttered
    };
    let labelled = read(&physics);
    assert_eq!(labelled, read(&physics), "the same seed, the same bytes");
    for bytes in &labelled {
        let shard = SafeTensors::deserialize(bytes).unwrap();
        let free = shard.tensor("collision_free").unwrap().data().to_vec();
        for (rate, free) in f32s(&shard, "physics_rate").iter().zip(free) {
            assert_eq!(
                *rate >= 0.0,
                free == 1,
                "a physics label on each free datapoint"
            );
        }
    }
}
