//! Rendered depth agrees with a parry ray cast through the same pixel, and the dataset is
//! byte-for-byte deterministic and resumable.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // tests may fail loudly

use crate::common;

use crate::shared_data::shared_data;
use common::renderer;
use std::path::{Path, PathBuf};

use mvgrasp::convert::render_view;
use mvgrasp::dataset::{DatasetConfig, ObjectSource, PlacedObject, write_dataset};
use mvgrasp::geometry::objects::{Category, ObjectSpec};
use mvgrasp::geometry::{HemisphereLayout, Intrinsics, RayCaster, TriangleMesh, Vec3, load_mesh};
use mvgrasp::render::Renderer;
use mvgrasp::scene::OBJECT_ID;

/// Fraction of object pixels (away from silhouette and occlusion edges) whose rendered depth is
/// within 1 mm of the ray cast, over the paper's 10 test views.
fn agreement(renderer: &Renderer, mesh: TriangleMesh) -> (f64, usize) {
    let placed = PlacedObject::new(mesh, 0).unwrap();
    let data = placed.scene_data();
    let colors = placed.colors(placed.test_color_seed);
    let scene = renderer
        .upload(&placed.inputs(&data, &colors, false))
        .unwrap();
    let world_mesh = placed.mesh.transformed(&placed.table_from_object);
    let caster = RayCaster::new(&world_mesh).unwrap();
    let target = world_mesh.aabb().center();
    let cameras = HemisphereLayout::paper_test()
        .cameras(Intrinsics::phoxi_s(), target, 5)
        .unwrap();
    let views: Vec<_> = cameras.iter().map(render_view).collect();
    let frames = renderer.render(&scene, &views).unwrap();
    let (mut good, mut total) = (0usize, 0usize);
    for (camera, frame) in cameras.iter().zip(&frames) {
        let (w, h) = (frame.width as usize, frame.height as usize);
        let k = camera.intrinsics;
        // Reference depth per pixel: the ray through the pixel centre, z in the camera frame.
        let reference: Vec<f32> = (0..w * h)
            .map(|i| {
                let (u, v) = ((i % w) as f32, (i / w) as f32);
                let dir_camera = Vec3::new((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0);
                let dir_world = camera.world_from_camera.transform_vector(dir_camera);
                // With dir_camera.z = 1, the ray parameter is the z depth.
                caster
                    .cast(camera.position(), dir_world, 10.0)
                    .map_or(0.0, |hit| hit.time_of_impact)
            })
            .collect();
        for v in 1..h - 1 {
            for u in 1..w - 1 {
                let i = v * w + u;
                let object_here = frame.mask[i] == OBJECT_ID || reference[i] > 0.0;
                if !object_here {
                    continue;
                }
                let neighbours = [
                    i - w - 1,
                    i - w,
                    i - w + 1,
                    i - 1,
                    i + 1,
                    i + w - 1,
                    i + w,
                    i + w + 1,
                ];
                let edge = neighbours.iter().any(|&j| {
                    frame.mask[j] != frame.mask[i] || (reference[j] - reference[i]).abs() > 0.005
                });
                if edge {
                    continue;
                }
                total += 1;
                let rendered = if frame.mask[i] == OBJECT_ID {
                    frame.depth_m[i]
                } else {
                    0.0
                };
                if reference[i] > 0.0 && (rendered - reference[i]).abs() <= 0.001 {
                    good += 1;
                }
            }
        }
    }
    (good as f64 / total.max(1) as f64, total)
}

#[test]
fn rendered_depth_matches_ray_casts_on_built_in_objects() {
    let Some(renderer) = renderer() else { return };
    for category in [Category::Mug, Category::ToyChair, Category::Bowl] {
        let mesh = mvgrasp::geometry::objects::generate(category, 0, 0)
            .unwrap()
            .mesh;
        let (fraction, pixels) = agreement(&renderer, mesh);
        eprintln!("{category}: {:.5} of {pixels} pixels within 1 mm", fraction);
        assert!(pixels > 10_000, "{category}: only {pixels} pixels");
        assert!(
            fraction >= 0.999,
            "{category}: {fraction} of {pixels} pixels within 1 mm"
        );
    }
}

#[test]
fn rendered_depth_matches_ray_casts_on_real_meshes() {
    let Some(root) = shared_data("meshes") else {
        return;
    };
    let Some(renderer) = renderer() else { return };
    for file in [
        "ycb/meshes/006_mustard_bottle_textured.obj",
        "dexnet/test/models/bar_clamp.obj",
    ] {
        let (fraction, pixels) = agreement(&renderer, load_mesh(root.join(file)).unwrap());
        eprintln!("{file}: {:.5} of {pixels} pixels within 1 mm", fraction);
        assert!(
            pixels > 10_000 && fraction >= 0.999,
            "{file}: {fraction} of {pixels}"
        );
    }
}

fn files(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else {
                out.push((
                    path.strip_prefix(dir).unwrap().to_path_buf(),
                    std::fs::read(&path).unwrap(),
                ));
            }
        }
    }
    out.sort();
    out
}

#[test]
fn the_dataset_is_deterministic_and_resumes_after_an_interruption() {
    let Some(renderer) = renderer() else { return };
    let sources: Vec<ObjectSource> = [Category::Can, Category::Squash]
        .into_iter()
        .map(|category| {
            ObjectSource::Builtin(ObjectSpec {
                category,
                index: 0,
                seed: 1,
            })
        })
        .collect();
    let config = DatasetConfig {
        seed: 1,
        ..Default::default()
    };
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    let first = write_dataset(&renderer, &sources, &config, &a, false).unwrap();
    assert_eq!((first.written, first.skipped, first.views), (2, 0, 60));
    // An interrupted second run: one object finished, the other left half-written.
    write_dataset(&renderer, &sources[..1], &config, &b, false).unwrap();
    std::fs::create_dir_all(b.join(".squash_000.partial/train")).unwrap();
    std::fs::write(b.join(".squash_000.partial/train/000_rgb.png"), b"half").unwrap();
    let resumed = write_dataset(&renderer, &sources, &config, &b, false).unwrap();
    assert_eq!((resumed.written, resumed.skipped), (1, 1));
    let (fa, fb) = (files(&a), files(&b));
    // Per object: object.json, mesh.obj, two cameras.json, 30 views x 3 images; plus
    // dataset.json and settings.json.
    let per_object = 2 + 2 + 30 * 3;
    assert_eq!(fa.len(), 2 * per_object + 2, "file count");
    assert_eq!(
        fa.iter().map(|f| &f.0).collect::<Vec<_>>(),
        fb.iter().map(|f| &f.0).collect::<Vec<_>>()
    );
    for ((name, x), (_, y)) in fa.iter().zip(&fb) {
        assert!(x == y, "{} differs between the runs", name.display());
    }
    // A run with other settings into the folder is refused (it would mix two datasets),
    // naming the file that records the folder's settings.
    let other = DatasetConfig {
        seed: 2,
        ..Default::default()
    };
    let refused = write_dataset(&renderer, &sources, &other, &b, false).unwrap_err();
    assert!(refused.to_string().contains("settings.json"), "{refused}");
    // So is a folder whose objects were made before settings were recorded.
    std::fs::remove_file(b.join("settings.json")).unwrap();
    assert!(write_dataset(&renderer, &sources, &config, &b, false).is_err());
    // The test split's first camera is exactly top-down; cameras read back.
    let cameras = mvgrasp::dataset::read_cameras(&a.join("can_000/test/cameras.json")).unwrap();
    assert_eq!(cameras.len(), 10);
    assert!((cameras[0].optical_axis() - -Vec3::Z).length() < 1e-6);
}
