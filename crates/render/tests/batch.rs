//! Many views per call: the same frames as one view per call, byte for byte, whatever the mix
//! of image sizes; the same frames on every call; resources reused between calls.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // tests may fail loudly

use crate::common;

use common::{centred, cuboid, look_at, renderers, sphere};
use mvgrasp_render::{
    Colors, Frame, IDENTITY, Intrinsics, MeshInput, Renderer, Sides, View, random_colors,
};

/// `n` cameras on a ring 0.6 m from the origin, 0.4 m up, looking at the origin.
fn ring(n: usize, intrinsics: Intrinsics) -> Vec<View> {
    (0..n)
        .map(|i| {
            let a = 2.0 * std::f32::consts::PI * i as f32 / n as f32;
            View {
                intrinsics,
                camera_from_world: look_at([0.6 * a.cos(), 0.6 * a.sin(), 0.4], [0.0; 3]),
            }
        })
        .collect()
}

/// A randomly coloured sphere on a box, both in view of the ring.
struct TestScene {
    sphere: (Vec<[f32; 3]>, Vec<[u32; 3]>),
    colours: Vec<[u8; 3]>,
    table: (Vec<[f32; 3]>, Vec<[u32; 3]>),
}

fn scene_meshes() -> TestScene {
    let sphere = sphere(0.08, 24, 48);
    let colours = random_colors(11, sphere.0.len());
    let table = cuboid([0.0, 0.0, -0.05], [0.2, 0.15, 0.05]);
    TestScene {
        sphere,
        colours,
        table,
    }
}

fn upload(r: &Renderer, s: &TestScene) -> mvgrasp_render::Scene {
    upload_with(r, s, Sides::Front, &s.sphere.1)
}

/// The test scene with the sphere's triangles `sphere_indices`, drawn with `sides` (the box
/// always both sides).
fn upload_with(
    r: &Renderer,
    s: &TestScene,
    sides: Sides,
    sphere_indices: &[[u32; 3]],
) -> mvgrasp_render::Scene {
    let mut lifted = IDENTITY;
    lifted[2][3] = 0.08;
    r.upload(&[
        MeshInput {
            positions: &s.sphere.0,
            indices: sphere_indices,
            sides,
            colors: Colors::PerVertex(&s.colours),
            world_from_mesh: lifted,
            instance_id: 1,
            material: mvgrasp_render::Material::MATTE,
        },
        MeshInput {
            positions: &s.table.0,
            indices: &s.table.1,
            sides: Sides::Both,
            colors: Colors::PerFace(&[[180, 180, 170]; 12]),
            world_from_mesh: IDENTITY,
            instance_id: 2,
            material: mvgrasp_render::Material::MATTE,
        },
    ])
    .unwrap()
}

fn assert_same(a: &Frame, b: &Frame, what: &str) {
    assert_eq!((a.width, a.height), (b.width, b.height), "{what}");
    assert!(a.rgb == b.rgb, "{what}: rgb differs");
    assert!(a.mask == b.mask, "{what}: mask differs");
    let bits = |f: &Frame| f.depth_m.iter().map(|z| z.to_bits()).collect::<Vec<_>>();
    assert!(bits(a) == bits(b), "{what}: depth differs");
}

#[test]
fn twenty_views_in_one_call_match_twenty_single_calls() {
    let Some(renderers) = renderers() else { return };
    let meshes = scene_meshes();
    let views = ring(20, Intrinsics::PHOXI_S);
    for r in renderers {
        let scene = upload(r, &meshes);
        let frames = r.render(&scene, &views).unwrap();
        assert_eq!(frames.len(), 20);
        for (i, (view, batched)) in views.iter().zip(&frames).enumerate() {
            let single = r.render_one(&scene, view).unwrap();
            assert_same(batched, &single, &format!("{} view {i}", r.adapter_info()));
            // Every view sees both objects.
            assert!(
                batched.mask.contains(&1) && batched.mask.contains(&2),
                "view {i}"
            );
        }
        // The views differ from each other (the uniforms really are per view).
        assert_ne!(frames[0].mask, frames[5].mask);
    }
}

#[test]
fn the_same_inputs_give_the_same_bytes() {
    let Some(renderers) = renderers() else { return };
    let meshes = scene_meshes();
    let views = ring(4, Intrinsics::PHOXI_S);
    for r in renderers {
        let scene = upload(r, &meshes);
        let first = r.render(&scene, &views).unwrap();
        let again = r.render(&scene, &views).unwrap();
        let other_scene = upload(r, &meshes);
        let reuploaded = r.render(&other_scene, &views).unwrap();
        for i in 0..views.len() {
            assert_same(
                &first[i],
                &again[i],
                &format!("{} call 2", r.adapter_info()),
            );
            assert_same(&first[i], &reuploaded[i], "re-uploaded scene");
        }
    }
}

#[test]
fn mixed_image_sizes_in_one_call() {
    let Some(renderers) = renderers() else { return };
    let meshes = scene_meshes();
    let small = centred(65, 47); // rows not a multiple of 256 bytes, odd sizes
    let mut views = ring(6, Intrinsics::PHOXI_S);
    for (i, v) in views.iter_mut().enumerate() {
        if i % 2 == 1 {
            v.intrinsics = small;
        }
    }
    for r in renderers {
        let scene = upload(r, &meshes);
        let frames = r.render(&scene, &views).unwrap();
        for (i, (view, f)) in views.iter().zip(&frames).enumerate() {
            assert_eq!(
                (f.width, f.height),
                (view.intrinsics.width, view.intrinsics.height)
            );
            assert_same(
                f,
                &r.render_one(&scene, view).unwrap(),
                &format!("view {i}"),
            );
        }
        assert!(r.cached_target_sizes() >= 2);
    }
}

#[test]
fn no_views_give_no_frames() {
    let Some(renderers) = renderers() else { return };
    let (p, i) = cuboid([0.0, 0.0, 0.5], [0.05; 3]);
    for r in renderers {
        let scene = r
            .upload(&[common::mesh(&p, &i, [255, 255, 255], 1)])
            .unwrap();
        assert!(r.render(&scene, &[]).unwrap().is_empty());
    }
}

#[test]
fn backends_agree_on_depth_and_mask() {
    let Some(renderers) = renderers() else { return };
    if renderers.len() < 2 {
        eprintln!("only one backend here: nothing to compare");
        return;
    }
    let meshes = scene_meshes();
    let views = ring(3, Intrinsics::PHOXI_S);
    let frames: Vec<Vec<Frame>> = renderers
        .iter()
        .map(|r| r.render(&upload(r, &meshes), &views).unwrap())
        .collect();
    for (a, b) in frames[0].iter().zip(&frames[1]) {
        let mut differing = 0;
        for i in 0..a.mask.len() {
            if a.mask[i] != b.mask[i] {
                differing += 1;
            } else if a.mask[i] != 0 {
                let (za, zb) = (a.depth_m[i], b.depth_m[i]);
                assert!((za - zb).abs() < 1e-4, "pixel {i}: {za} vs {zb}");
            }
        }
        // Rasterisers may differ only on a few silhouette pixels.
        assert!(differing < a.mask.len() / 1000, "{differing} pixels differ");
    }
}

#[test]
fn more_views_than_one_batch_holds_come_back_in_order() {
    let Some(renderers) = renderers() else { return };
    let meshes = scene_meshes();
    // 1030 tiny views: past the 1024 views of one submission.
    let views = ring(1030, centred(8, 6));
    for r in renderers {
        let scene = upload(r, &meshes);
        let frames = r.render(&scene, &views).unwrap();
        assert_eq!(frames.len(), views.len());
        for i in [0, 517, 1023, 1024, 1029] {
            let single = r.render_one(&scene, &views[i]).unwrap();
            assert_same(
                &frames[i],
                &single,
                &format!("{} view {i}", r.adapter_info()),
            );
        }
    }
}

#[test]
fn front_faces_only_gives_the_same_frames_for_a_closed_outward_mesh() {
    let Some(renderers) = renderers() else { return };
    let meshes = scene_meshes();
    let views = ring(6, Intrinsics::PHOXI_S);
    // The same sphere wound inside out: with front faces only its far half shows.
    let inside_out: Vec<[u32; 3]> = meshes.sphere.1.iter().map(|&[a, b, c]| [a, c, b]).collect();
    for r in renderers {
        let both = r
            .render(
                &upload_with(r, &meshes, Sides::Both, &meshes.sphere.1),
                &views,
            )
            .unwrap();
        let front = r
            .render(
                &upload_with(r, &meshes, Sides::Front, &meshes.sphere.1),
                &views,
            )
            .unwrap();
        let culled_wrong = r
            .render(&upload_with(r, &meshes, Sides::Front, &inside_out), &views)
            .unwrap();
        for (i, ((b, f), w)) in both.iter().zip(&front).zip(&culled_wrong).enumerate() {
            let what = format!("{} view {i}", r.adapter_info());
            assert_same(b, f, &what);
            // Where the sphere shows, the inside-out one is farther away (its back half).
            let farther = (0..b.depth_m.len())
                .filter(|&p| b.mask[p] == 1 && w.mask[p] == 1)
                .filter(|&p| w.depth_m[p] > b.depth_m[p] + 0.01)
                .count();
            let sphere_pixels = b.mask.iter().filter(|&&m| m == 1).count();
            assert!(
                sphere_pixels > 1000 && farther * 10 > sphere_pixels * 9,
                "{what}: {farther} of {sphere_pixels} sphere pixels show the far side"
            );
        }
    }
}
