//! World lighting and materials: lights fixed in the world, solid textures, highlights, the
//! background's colour, and the headlight unchanged by materials.

use mvgrasp_render::{Intrinsics, Light, Lighting, Material, Pattern, View, project};

use crate::common::{centred, cuboid, look_at, mesh, quad, renderers, view_at_origin};

/// One white light straight behind the camera (world = camera frame, looking along +z).
fn behind_the_camera(ambient: f32) -> Lighting {
    Lighting::World {
        ambient_rgb: [ambient; 3],
        lights: vec![Light {
            towards_world: [0.0, 0.0, -1.0],
            rgb: [0.8; 3],
        }],
        background_rgb: [0.2, 0.4, 0.6],
    }
}

#[test]
fn world_lights_shade_the_surface_and_the_background_takes_its_colour() {
    let Some(renderers) = renderers() else { return };
    let k = centred(64, 48);
    // A small quad facing the camera, 0.5 m ahead: the image's edges are background.
    let (p, i) = quad([0.0, 0.0, 0.5], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], 0.01);
    for r in renderers {
        let scene = r.upload(&[mesh(&p, &i, [200, 100, 50], 3)]).unwrap();
        let view = view_at_origin(k);
        let f = &r
            .render_lit(&scene, &[view], &behind_the_camera(0.25))
            .unwrap()[0];
        let centre = f.rgb_at(32, 24).unwrap();
        // Facing the light: (ambient 0.25 + diffuse 0.8) x colour, clamped at 255.
        for (got, colour) in centre.iter().zip([200.0f32, 100.0, 50.0]) {
            let expected = (colour * 1.05).min(255.0);
            assert!((f32::from(*got) - expected).abs() <= 2.0, "{centre:?}");
        }
        assert_eq!(f.mask_at(32, 24), Some(3));
        // Background: its colour, mask and depth empty.
        assert_eq!(f.rgb_at(0, 0), Some([51, 102, 153]));
        assert_eq!(f.mask_at(0, 0), Some(0));
        // The headlight of the same scene leaves the background black.
        let headlight = r.render_one(&scene, &view).unwrap();
        assert_eq!(headlight.rgb_at(0, 0), Some([0, 0, 0]));
        assert_eq!(
            headlight.depth_m, f.depth_m,
            "lighting must not move the depth"
        );
    }
}

#[test]
fn a_pattern_varies_the_colour_across_the_surface_and_only_under_world_lights() {
    let Some(renderers) = renderers() else { return };
    let k = centred(64, 48);
    let (p, i) = quad([0.0, 0.0, 0.5], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], 0.5);
    for r in renderers {
        for pattern in &Pattern::ALL[1..] {
            let mut m = mesh(&p, &i, [200, 200, 200], 1);
            m.material = Material {
                pattern: *pattern,
                cycles_per_m: 64.0,
                second_rgb: [0, 0, 0],
                contrast: 1.0,
                ..Material::MATTE
            };
            let scene = r.upload(&[m]).unwrap();
            let view = view_at_origin(k);
            let lit = &r
                .render_lit(&scene, &[view], &behind_the_camera(0.2))
                .unwrap()[0];
            let reds: Vec<u8> = lit.rgb.chunks_exact(3).map(|c| c[0]).collect();
            let (lo, hi) = (reds.iter().min().unwrap(), reds.iter().max().unwrap());
            assert!(hi - lo > 60, "{pattern:?}: reds {lo}..{hi}");
            // The headlight ignores materials: one flat colour.
            let flat = r.render_one(&scene, &view).unwrap();
            let plain = r
                .render_one(
                    &r.upload(&[mesh(&p, &i, [200, 200, 200], 1)]).unwrap(),
                    &view,
                )
                .unwrap();
            assert_eq!(flat.rgb, plain.rgb, "{pattern:?}");
        }
    }
}

#[test]
fn a_shiny_surface_glints_where_it_mirrors_the_light_into_the_camera() {
    let Some(renderers) = renderers() else { return };
    // A wide lens: the image's corner looks 61 degrees off the axis.
    let k = Intrinsics {
        fx: 20.0,
        fy: 20.0,
        ..centred(64, 48)
    };
    let (p, i) = quad([0.0, 0.0, 0.5], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], 2.0);
    for r in renderers {
        let dark = [40, 40, 40];
        let mut shiny = mesh(&p, &i, dark, 1);
        shiny.material = Material {
            specular: 1.0,
            shininess: 64.0,
            ..Material::MATTE
        };
        let view = view_at_origin(k);
        let lighting = behind_the_camera(0.0);
        let glint = &r
            .render_lit(&r.upload(&[shiny]).unwrap(), &[view], &lighting)
            .unwrap()[0];
        let matte = &r
            .render_lit(
                &r.upload(&[mesh(&p, &i, dark, 1)]).unwrap(),
                &[view],
                &lighting,
            )
            .unwrap()[0];
        // At the centre the half-way vector is the normal: the full highlight.
        let (g, m) = (
            glint.rgb_at(32, 24).unwrap()[0],
            matte.rgb_at(32, 24).unwrap()[0],
        );
        assert!(g >= m + 150, "glint {g}, matte {m}");
        // At the corner the half-way vector is 30 degrees off the normal: the glint is gone.
        let (gc, mc) = (
            glint.rgb_at(0, 0).unwrap()[0],
            matte.rgb_at(0, 0).unwrap()[0],
        );
        assert!(
            gc < g / 2 && gc >= mc,
            "corner glint {gc}, matte {mc}, centre {g}"
        );
    }
}

#[test]
fn bad_lighting_is_refused_naming_the_field() {
    let Some(renderers) = renderers() else { return };
    let (p, i) = quad([0.0, 0.0, 0.5], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], 0.5);
    let r = &renderers[0];
    let scene = r.upload(&[mesh(&p, &i, [1, 2, 3], 1)]).unwrap();
    let bad = Lighting::World {
        ambient_rgb: [0.1; 3],
        lights: Vec::new(),
        background_rgb: [2.0, 0.0, 0.0],
    };
    let err = r
        .render_lit(&scene, &[view_at_origin(centred(8, 8))], &bad)
        .unwrap_err()
        .to_string();
    assert!(err.contains("background_rgb"), "{err}");
}

#[test]
fn a_box_casts_its_shadow_away_from_the_light() {
    let Some(renderers) = renderers() else { return };
    let k = centred(64, 48);
    // A 4 cm cube on a plane, a light 45 degrees up from +x, a camera 1.5 m above (the image
    // spans 17 x 13 cm of the plane).
    let (plane_p, plane_i) = quad([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], 0.3);
    let (cube_p, cube_i) = cuboid([0.0, 0.0, 0.02], [0.02, 0.02, 0.02]);
    let camera_from_world = look_at([0.0, -0.01, 1.5], [0.0, 0.0, 0.0]);
    let view = View {
        intrinsics: k,
        camera_from_world,
    };
    let lighting = Lighting::World {
        ambient_rgb: [0.2; 3],
        lights: vec![Light {
            towards_world: [1.0, 0.0, 1.0],
            rgb: [0.8; 3],
        }],
        background_rgb: [0.0; 3],
    };
    let pixel_of = |p: [f32; 3]| {
        let m = camera_from_world;
        let c: [f32; 3] =
            std::array::from_fn(|r| m[r][0] * p[0] + m[r][1] * p[1] + m[r][2] * p[2] + m[r][3]);
        let [u, v] = project(&k, c);
        assert!(
            u >= 0.0 && v >= 0.0 && u < 64.0 && v < 48.0,
            "{p:?} is out of the image"
        );
        (u.round() as u32, v.round() as u32)
    };
    for r in renderers {
        let scene = r
            .upload(&[
                mesh(&plane_p, &plane_i, [200, 200, 200], 1),
                mesh(&cube_p, &cube_i, [200, 200, 200], 2),
            ])
            .unwrap();
        let f = &r.render_lit(&scene, &[view], &lighting).unwrap()[0];
        let level = |p: [f32; 3]| {
            let (u, v) = pixel_of(p);
            assert_eq!(f.mask_at(u, v), Some(1), "{p:?} is on the plane");
            f.rgb_at(u, v).unwrap()[0]
        };
        // Lit plane: (0.2 + 0.8 cos 45) x 200 = 153; in the shadow: 0.2 x 200 = 40.
        let lit = level([0.04, 0.0, 0.0]);
        let shadowed = level([-0.04, 0.0, 0.0]);
        let far = level([-0.08, 0.0, 0.0]);
        assert!((f32::from(lit) - 153.0).abs() <= 3.0, "lit {lit}");
        assert!(
            (f32::from(shadowed) - 40.0).abs() <= 3.0,
            "shadowed {shadowed}"
        );
        assert!(
            (f32::from(far) - 153.0).abs() <= 3.0,
            "past the shadow {far}"
        );
    }
}
