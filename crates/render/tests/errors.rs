//! Bad input is an error that says what is wrong, never a panic.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // tests may fail loudly

use crate::common;

use common::{cuboid, mesh, renderers, view_at_origin};
use mvgrasp_render::{Backend, Colors, IDENTITY, Intrinsics, RenderError, Renderer, View};

#[test]
fn bad_meshes_are_refused_by_upload() {
    let Some(renderers) = renderers() else { return };
    let (p, i) = cuboid([0.0, 0.0, 0.5], [0.05; 3]);
    let good = mesh(&p, &i, [255, 255, 255], 1);
    let out_of_range = [[0, 1, 8]];
    let nan = [[f32::NAN, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    let few_colours = [[0u8; 3]; 3];
    let cases: Vec<(&str, Vec<mvgrasp_render::MeshInput<'_>>, &str)> = vec![
        ("no meshes", vec![], "at least one mesh"),
        (
            "index out of range",
            vec![good, mesh(&p, &out_of_range, [0; 3], 2)],
            "mesh 1: triangle 0 has index 8",
        ),
        (
            "NaN position",
            vec![mesh(&nan, &[[0, 1, 2]], [0; 3], 1)],
            "not finite",
        ),
        ("no triangles", vec![mesh(&p, &[], [0; 3], 1)], "empty"),
        (
            "instance id 0",
            vec![mesh(&p, &i, [0; 3], 0)],
            "instance_id is 0",
        ),
        (
            "colour count",
            vec![mvgrasp_render::MeshInput {
                colors: Colors::PerVertex(&few_colours),
                ..good
            }],
            "3 per-vertex colours, expected 8",
        ),
        (
            "projective placement",
            vec![mvgrasp_render::MeshInput {
                world_from_mesh: [[1.0, 0.0, 0.0, 0.0]; 4],
                ..good
            }],
            "world_from_mesh",
        ),
    ];
    for r in renderers {
        for (what, meshes, message) in &cases {
            let err = r.upload(meshes).expect_err(what).to_string();
            assert!(err.contains(message), "{what}: {err}");
        }
        assert!(r.upload(&[good]).is_ok());
    }
}

#[test]
fn bad_views_are_refused_by_render() {
    let Some(renderers) = renderers() else { return };
    let (p, i) = cuboid([0.0, 0.0, 0.5], [0.05; 3]);
    let good = view_at_origin(Intrinsics::PHOXI_S);
    let with = |f: &dyn Fn(&mut View)| {
        let mut v = good;
        f(&mut v);
        v
    };
    let mut scaled = IDENTITY;
    scaled[1][1] = 1.5;
    let cases = [
        ("zero focal length", with(&|v| v.intrinsics.fx = 0.0), "fx"),
        (
            "NaN principal point",
            with(&|v| v.intrinsics.cy = f32::NAN),
            "cy",
        ),
        ("empty image", with(&|v| v.intrinsics.height = 0), "height"),
        (
            "huge image",
            with(&|v| v.intrinsics.width = 1 << 20),
            "width",
        ),
        (
            "near behind far",
            with(&|v| v.intrinsics.z_near_m = 3.0),
            "z_near_m",
        ),
        (
            "zero near",
            with(&|v| v.intrinsics.z_near_m = 0.0),
            "z_near_m",
        ),
        (
            "scaled pose",
            with(&|v| v.camera_from_world = scaled),
            "camera_from_world",
        ),
    ];
    for r in renderers {
        let scene = r.upload(&[mesh(&p, &i, [255, 255, 255], 1)]).unwrap();
        for (what, view, field) in &cases {
            let err = r.render(&scene, &[good, *view]).expect_err(what);
            assert!(
                matches!(&err, RenderError::InvalidView { view_index: 1, name, .. } if name.contains(field)),
                "{what}: {err}"
            );
        }
        // The renderer still works after refusing.
        assert_eq!(r.render(&scene, &[good]).unwrap().len(), 1);
    }
}

#[test]
fn a_scene_from_another_renderer_is_refused() {
    let Some(renderers) = renderers() else { return };
    let (p, i) = cuboid([0.0, 0.0, 0.5], [0.05; 3]);
    let first = &renderers[0];
    let other = Renderer::new(first.backend()).unwrap();
    let scene = other.upload(&[mesh(&p, &i, [255, 255, 255], 1)]).unwrap();
    let err = first.render(&scene, &[view_at_origin(Intrinsics::PHOXI_S)]);
    assert!(
        matches!(err, Err(RenderError::ForeignScene { .. })),
        "{err:?}"
    );
}

#[test]
fn a_bad_backend_variable_is_an_error_and_backend_names_parse() {
    assert_eq!(Backend::parse("gl"), Some(Backend::Gl));
    assert_eq!(Backend::parse("VULKAN"), Some(Backend::Vulkan));
    assert_eq!(Backend::parse("software"), None);
    // The variable is read only for Backend::Auto; checked in a child process so that the
    // other tests' environment stays untouched.
    if std::env::var("MVGRASP_RENDER_BACKEND_CHILD").is_ok() {
        let err = Renderer::new(Backend::Auto).unwrap_err().to_string();
        assert!(err.contains("MVGRASP_RENDER_BACKEND"), "{err}");
        return;
    }
    let exe = std::env::current_exe().unwrap();
    let status = std::process::Command::new(exe)
        .args([
            "a_bad_backend_variable_is_an_error_and_backend_names_parse",
            "--exact",
            "--nocapture",
        ])
        .env("MVGRASP_RENDER_BACKEND", "software")
        .env("MVGRASP_RENDER_BACKEND_CHILD", "1")
        .status()
        .unwrap();
    assert!(status.success());
}
