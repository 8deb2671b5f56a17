//! What the renderer draws, checked against geometry worked out by hand: depth of a cube and of
//! planes, the pixel-centre convention, occlusion, colours and shading.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // tests may fail loudly

use crate::common;

use common::{centred, cuboid, mesh, quad, renderers, view_at_origin};
use mvgrasp_render::{Colors, Intrinsics, View, project};

#[test]
fn a_cube_half_a_metre_away_has_depth_mask_and_colour() {
    let Some(renderers) = renderers() else { return };
    let k = Intrinsics::PHOXI_S;
    let (positions, indices) = cuboid([0.0, 0.0, 0.5], [0.05; 3]);
    for r in renderers {
        let scene = r
            .upload(&[mesh(&positions, &indices, [200, 120, 40], 3)])
            .unwrap();
        let frame = r.render_one(&scene, &view_at_origin(k)).unwrap();
        let who = r.adapter_info();
        assert_eq!((frame.width, frame.height), (516, 386));
        assert_eq!(frame.rgb.len(), 516 * 386 * 3);
        let (u, v) = (256, 192);
        let z = frame.depth_at(u, v).unwrap();
        assert!((z - 0.45).abs() < 1e-4, "{who}: centre depth {z}");
        assert_eq!(frame.mask_at(u, v), Some(3), "{who}");
        let rgb = frame.rgb_at(u, v).unwrap();
        assert!(rgb.iter().any(|&c| c > 0), "{who}: black cube {rgb:?}");
        // Shading scales the colour: red > green > blue as in [200, 120, 40].
        assert!(rgb[0] > rgb[1] && rgb[1] > rgb[2], "{who}: {rgb:?}");
        for (u, v) in [(0, 0), (515, 385), (10, 192), (256, 10)] {
            assert_eq!(
                frame.depth_at(u, v),
                Some(0.0),
                "{who}: background at {u},{v}"
            );
            assert_eq!(frame.mask_at(u, v), Some(0), "{who}");
            assert_eq!(frame.rgb_at(u, v), Some([0, 0, 0]), "{who}");
        }
        // The silhouette is the front face: a square of side fx * 0.1 / 0.45 pixels.
        let side = k.fx * 0.1 / 0.45;
        let covered = frame.mask.iter().filter(|&&m| m == 3).count() as f32;
        assert!(
            (covered - side * side).abs() < 4.0 * side,
            "{who}: {covered} pixels, expected about {}",
            side * side
        );
        // Every covered pixel sees the front face.
        for (i, &m) in frame.mask.iter().enumerate() {
            assert_eq!(m == 3, frame.depth_m[i] > 0.0, "{who}: pixel {i}");
            if m == 3 {
                assert!((frame.depth_m[i] - 0.45).abs() < 1e-4, "{who}: pixel {i}");
            }
        }
    }
}

#[test]
fn a_point_projecting_to_a_pixel_lands_on_that_pixel() {
    let Some(renderers) = renderers() else { return };
    let k = Intrinsics::PHOXI_S; // cy = 191.75: not centred on purpose
    let z = 0.5;
    for r in renderers {
        for (u0, v0) in [(100.0f32, 50.0f32), (300.25, 200.25), (7.0, 380.0)] {
            // A square 0.6 px wide centred on (u0, v0): it covers exactly one pixel centre.
            let x = (u0 - k.cx) * z / k.fx;
            let y = (v0 - k.cy) * z / k.fy;
            let [pu, pv] = project(&k, [x, y, z]);
            assert!((pu - u0).abs() < 1e-3 && (pv - v0).abs() < 1e-3);
            let half = 0.3 * z / k.fx;
            let (positions, indices) = quad([x, y, z], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], half);
            let scene = r
                .upload(&[mesh(&positions, &indices, [255; 3], 9)])
                .unwrap();
            let frame = r.render_one(&scene, &view_at_origin(k)).unwrap();
            let hits: Vec<(u32, u32)> = (0..frame.height)
                .flat_map(|v| (0..frame.width).map(move |u| (u, v)))
                .filter(|&(u, v)| frame.mask_at(u, v) == Some(9))
                .collect();
            let want = (u0.round() as u32, v0.round() as u32);
            assert_eq!(
                hits,
                vec![want],
                "{}: square at {u0},{v0}",
                r.adapter_info()
            );
        }
    }
}

#[test]
fn a_plane_facing_the_camera_has_constant_depth() {
    let Some(renderers) = renderers() else { return };
    let (positions, indices) = quad([0.0, 0.0, 0.7], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], 2.0);
    for r in renderers {
        let scene = r
            .upload(&[mesh(&positions, &indices, [90, 90, 90], 1)])
            .unwrap();
        for k in [Intrinsics::PHOXI_S, centred(64, 48)] {
            let frame = r.render_one(&scene, &view_at_origin(k)).unwrap();
            let worst = frame
                .depth_m
                .iter()
                .map(|z| (z - 0.7).abs())
                .fold(0.0f32, f32::max);
            assert!(
                worst < 1e-5,
                "{}: worst depth error {worst}",
                r.adapter_info()
            );
            assert!(frame.mask.iter().all(|&m| m == 1));
        }
    }
}

#[test]
fn a_tilted_plane_matches_the_ray_plane_intersection() {
    let Some(renderers) = renderers() else { return };
    let k = Intrinsics::PHOXI_S;
    let p0 = [0.02f32, -0.01, 0.8];
    // In-plane axes of a plane with normal ~ (0.3, -0.2, -1): tilted about both image axes.
    let e1 = normalise([1.0, 0.0, 0.3]);
    let e2 = normalise([0.0, 1.0, -0.2]);
    let n = normalise(cross(e1, e2));
    let (positions, indices) = quad(p0, e1, e2, 1.2);
    for r in renderers {
        let scene = r
            .upload(&[mesh(&positions, &indices, [90, 160, 220], 5)])
            .unwrap();
        let frame = r.render_one(&scene, &view_at_origin(k)).unwrap();
        let mut worst = 0.0f32;
        for v in 1..k.height - 1 {
            for u in 1..k.width - 1 {
                let d = [(u as f32 - k.cx) / k.fx, (v as f32 - k.cy) / k.fy, 1.0];
                let z = dot(n, p0) / dot(n, d);
                let got = frame.depth_at(u, v).unwrap();
                assert_eq!(frame.mask_at(u, v), Some(5));
                worst = worst.max((got - z).abs());
            }
        }
        assert!(
            worst < 1e-4,
            "{}: worst depth error {worst}",
            r.adapter_info()
        );
    }
}

#[test]
fn the_nearer_mesh_hides_the_farther_whatever_the_upload_order() {
    let Some(renderers) = renderers() else { return };
    let k = Intrinsics::PHOXI_S;
    let (cube_p, cube_i) = cuboid([0.0, 0.0, 0.5], [0.05; 3]);
    let (wall_p, wall_i) = quad([0.0, 0.0, 0.8], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], 2.0);
    let cube = mesh(&cube_p, &cube_i, [250, 10, 10], 1);
    let wall = mesh(&wall_p, &wall_i, [10, 250, 10], 2);
    for r in renderers {
        for meshes in [[cube, wall], [wall, cube]] {
            let scene = r.upload(&meshes).unwrap();
            assert_eq!(scene.mesh_count(), 2);
            assert_eq!(scene.triangle_count(), 14);
            let f = r.render_one(&scene, &view_at_origin(k)).unwrap();
            let who = r.adapter_info();
            assert_eq!(f.mask_at(256, 192), Some(1), "{who}");
            assert!((f.depth_at(256, 192).unwrap() - 0.45).abs() < 1e-4, "{who}");
            let rgb = f.rgb_at(256, 192).unwrap();
            assert!(rgb[0] > rgb[1], "{who}: {rgb:?}");
            assert_eq!(f.mask_at(20, 20), Some(2), "{who}");
            assert!((f.depth_at(20, 20).unwrap() - 0.8).abs() < 1e-4, "{who}");
            let rgb = f.rgb_at(20, 20).unwrap();
            assert!(rgb[1] > rgb[0], "{who}: {rgb:?}");
        }
    }
}

#[test]
fn per_face_colours_colour_their_faces_and_light_comes_from_above_left() {
    let Some(renderers) = renderers() else { return };
    let k = centred(64, 48);
    // Two triangles of a quad split along the diagonal from (-,-) to (+,+).
    let (positions, indices) = quad([0.0, 0.0, 0.5], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], 1.0);
    let faces = [[255, 0, 0], [0, 0, 255]];
    for r in renderers {
        let m = mvgrasp_render::MeshInput {
            colors: Colors::PerFace(&faces),
            ..mesh(&positions, &indices, [0; 3], 4)
        };
        let scene = r.upload(&[m]).unwrap();
        let f = r.render_one(&scene, &view_at_origin(k)).unwrap();
        // Triangle 0 = corners (-,-), (+,-), (+,+): the upper-right half of the image (y down).
        let upper_right = f.rgb_at(60, 3).unwrap();
        let lower_left = f.rgb_at(3, 44).unwrap();
        assert!(
            upper_right[0] > 100 && upper_right[2] == 0,
            "{upper_right:?}"
        );
        assert!(lower_left[2] > 100 && lower_left[0] == 0, "{lower_left:?}");
        // Facing the camera: shade = ambient + (1 - ambient) * 0.811 ~ 0.877.
        assert!(
            (upper_right[0] as f32 - 255.0 * 0.877).abs() < 3.0,
            "{upper_right:?}"
        );

        // A plane turned towards the upper left (towards the light) is brighter than one
        // turned towards the lower right.
        let shade_of = |normal_towards: [f32; 3]| {
            let e1 = normalise(cross(normal_towards, [0.0, 1.0, 0.0]));
            let e2 = normalise(cross(normal_towards, e1));
            let (p, i) = quad([0.0, 0.0, 0.5], e1, e2, 1.0);
            let scene = r.upload(&[mesh(&p, &i, [200, 200, 200], 1)]).unwrap();
            let view = View {
                intrinsics: k,
                camera_from_world: mvgrasp_render::IDENTITY,
            };
            r.render_one(&scene, &view).unwrap().rgb_at(32, 24).unwrap()[0]
        };
        let lit = shade_of([-0.5, -0.5, -1.0]);
        let dark = shade_of([0.5, 0.5, -1.0]);
        assert!(
            lit > dark + 30,
            "{}: lit {lit}, dark {dark}",
            r.adapter_info()
        );
    }
}

fn normalise(a: [f32; 3]) -> [f32; 3] {
    let l = dot(a, a).sqrt();
    [a[0] / l, a[1] / l, a[2] / l]
}

fn cross(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
