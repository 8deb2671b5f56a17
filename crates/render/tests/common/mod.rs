//! Shared helpers of the GPU tests: the renderers under test, meshes and cameras.
//!
//! Every test runs on each backend that opens here (Vulkan and GL; on a machine without a GPU,
//! Mesa's lavapipe and llvmpipe). No backend at all fails the test with the install hint;
//! `MVGRASP_SKIP_GPU_TESTS=1` skips instead.

#![allow(dead_code)] // each test binary uses its own part

use std::sync::OnceLock;

use mvgrasp_render::{
    Backend, Colors, IDENTITY, INSTALL_HINT, Intrinsics, MeshInput, RenderError, Renderer, Sides,
    View,
};

/// The renderers to test on, or `None` (after printing why) when GPU tests are skipped.
pub fn renderers() -> Option<&'static [Renderer]> {
    if std::env::var("MVGRASP_SKIP_GPU_TESTS").is_ok_and(|v| v == "1") {
        eprintln!("MVGRASP_SKIP_GPU_TESTS=1: skipping a GPU test");
        return None;
    }
    static RENDERERS: OnceLock<Vec<Renderer>> = OnceLock::new();
    let all = RENDERERS.get_or_init(|| {
        let mut out = Vec::new();
        let mut errors = Vec::new();
        for backend in [Backend::Vulkan, Backend::Gl] {
            match Renderer::new(backend) {
                Ok(r) => {
                    eprintln!("testing on {}", r.adapter_info());
                    out.push(r);
                }
                Err(e) => errors.push(e),
            }
        }
        if out.is_empty() {
            // Also try whatever Auto finds (Metal, DX12 on other systems).
            match Renderer::new(Backend::Auto) {
                Ok(r) => out.push(r),
                Err(e) => errors.push(e),
            }
        }
        // Errors other than "no adapter" say more than the hint (e.g. a missing format).
        let other: Vec<String> = errors
            .iter()
            .filter(|e| !matches!(e, RenderError::NoAdapter { .. }))
            .map(|e| format!(" ({e})"))
            .collect();
        assert!(
            !out.is_empty(),
            "no usable graphics adapter for the GPU tests on Vulkan, GL or any other \
             backend{}; {INSTALL_HINT}; or set MVGRASP_SKIP_GPU_TESTS=1 to skip them",
            other.concat()
        );
        out
    });
    Some(all)
}

/// A camera looking straight down the world's +z (world = camera frame).
pub fn view_at_origin(intrinsics: Intrinsics) -> View {
    View {
        intrinsics,
        camera_from_world: IDENTITY,
    }
}

/// PhoXi S intrinsics at another size, principal point centred.
pub fn centred(width: u32, height: u32) -> Intrinsics {
    Intrinsics {
        cx: (width as f32 - 1.0) / 2.0,
        cy: (height as f32 - 1.0) / 2.0,
        width,
        height,
        ..Intrinsics::PHOXI_S
    }
}

/// An axis-aligned box: 8 corners and 12 triangles (outward winding).
pub fn cuboid(centre: [f32; 3], half: [f32; 3]) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let mut positions = Vec::new();
    for i in 0..8u32 {
        let s = |bit: u32| if i & bit != 0 { 1.0 } else { -1.0 };
        positions.push([
            centre[0] + s(1) * half[0],
            centre[1] + s(2) * half[1],
            centre[2] + s(4) * half[2],
        ]);
    }
    let indices = vec![
        [0, 2, 1],
        [1, 2, 3],
        [4, 5, 6],
        [5, 7, 6],
        [0, 1, 4],
        [1, 5, 4],
        [2, 6, 3],
        [3, 6, 7],
        [0, 4, 2],
        [2, 4, 6],
        [1, 3, 5],
        [3, 7, 5],
    ];
    (positions, indices)
}

/// A quad `origin + a e1 + b e2`, `a, b` in `[-half, half]`.
pub fn quad(
    origin: [f32; 3],
    e1: [f32; 3],
    e2: [f32; 3],
    half: f32,
) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let corner = |a: f32, b: f32| {
        [
            origin[0] + a * e1[0] + b * e2[0],
            origin[1] + a * e1[1] + b * e2[1],
            origin[2] + a * e1[2] + b * e2[2],
        ]
    };
    (
        vec![
            corner(-half, -half),
            corner(half, -half),
            corner(half, half),
            corner(-half, half),
        ],
        vec![[0, 1, 2], [0, 2, 3]],
    )
}

/// A mesh input with a uniform colour and the identity placement.
pub fn mesh<'a>(
    positions: &'a [[f32; 3]],
    indices: &'a [[u32; 3]],
    color: [u8; 3],
    instance_id: u8,
) -> MeshInput<'a> {
    MeshInput {
        positions,
        indices,
        sides: Sides::Both,
        colors: Colors::Uniform(color),
        world_from_mesh: IDENTITY,
        instance_id,
        material: mvgrasp_render::Material::MATTE,
    }
}

/// `camera_from_world` of a camera at `eye` looking at `target`, world +z up (OpenCV frame).
pub fn look_at(eye: [f32; 3], target: [f32; 3]) -> [[f32; 4]; 4] {
    let sub = |a: [f32; 3], b: [f32; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let cross = |a: [f32; 3], b: [f32; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let norm = |a: [f32; 3]| {
        let l = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
        [a[0] / l, a[1] / l, a[2] / l]
    };
    let dot = |a: [f32; 3], b: [f32; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let forward = norm(sub(target, eye));
    let right = norm(cross(forward, [0.0, 0.0, 1.0]));
    let down = cross(forward, right);
    let mut m = IDENTITY;
    for (row, axis) in [right, down, forward].into_iter().enumerate() {
        m[row] = [axis[0], axis[1], axis[2], -dot(axis, eye)];
    }
    m
}

/// A UV sphere with about `2 * rings * segments` triangles.
pub fn sphere(radius: f32, rings: u32, segments: u32) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let mut positions = Vec::new();
    for r in 0..=rings {
        let theta = std::f32::consts::PI * r as f32 / rings as f32;
        for s in 0..segments {
            let phi = 2.0 * std::f32::consts::PI * s as f32 / segments as f32;
            positions.push([
                radius * theta.sin() * phi.cos(),
                radius * theta.sin() * phi.sin(),
                radius * theta.cos(),
            ]);
        }
    }
    let mut indices = Vec::new();
    for r in 0..rings {
        for s in 0..segments {
            let a = r * segments + s;
            let b = r * segments + (s + 1) % segments;
            let c = a + segments;
            let d = b + segments;
            indices.push([a, c, b]);
            indices.push([b, c, d]);
        }
    }
    (positions, indices)
}
