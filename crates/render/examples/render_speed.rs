//! Rendering speed: a ~16k-triangle sphere seen by 20 PhoXi S cameras (516 x 386), RGB + depth
//! + mask read back, on every backend that opens here. Prints a table of views per second.
//!
//! `cargo run --release -p mvgrasp-render --example render_speed [-- REPEATS]`

use std::time::Instant;

use mvgrasp_render::{Backend, Colors, IDENTITY, Intrinsics, MeshInput, Renderer, Sides, View};

const VIEWS: usize = 20;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let repeats: usize = match std::env::args().nth(1) {
        Some(s) => s.parse()?,
        None => 5,
    };
    let (positions, indices) = sphere(0.06, 64, 128);
    let colors = mvgrasp_render::random_colors(1, indices.len());
    let views = ring(VIEWS);
    println!(
        "{} triangles, {VIEWS} views of {}x{} per call, {repeats} calls after one warm-up",
        indices.len(),
        Intrinsics::PHOXI_S.width,
        Intrinsics::PHOXI_S.height
    );
    println!("| backend | adapter | upload ms | ms per call | ms per view | views/s |");
    println!("|---|---|---|---|---|---|");
    let mut ran = 0;
    for backend in [Backend::Vulkan, Backend::Gl] {
        let renderer = match Renderer::new(backend) {
            Ok(r) => r,
            Err(e) => {
                println!("| {backend:?} | unavailable: {e} | | | | |");
                continue;
            }
        };
        let start = Instant::now();
        let scene = renderer.upload(&[MeshInput {
            positions: &positions,
            indices: &indices,
            sides: Sides::Front,
            colors: Colors::PerFace(&colors),
            world_from_mesh: IDENTITY,
            instance_id: 1,
            material: mvgrasp_render::Material::MATTE,
        }])?;
        let upload_ms = start.elapsed().as_secs_f64() * 1e3;
        let warm = renderer.render(&scene, &views)?;
        assert_eq!(warm.len(), VIEWS);
        for f in &warm {
            let seen = f.mask.iter().filter(|&&m| m == 1).count();
            assert!(seen > 1000, "a view sees only {seen} pixels of the sphere");
        }
        let start = Instant::now();
        for _ in 0..repeats {
            let frames = renderer.render(&scene, &views)?;
            assert_eq!(frames.len(), VIEWS);
        }
        let per_call = start.elapsed().as_secs_f64() / repeats.max(1) as f64;
        println!(
            "| {backend:?} | {} | {upload_ms:.1} | {:.1} | {:.2} | {:.1} |",
            renderer.adapter_info(),
            per_call * 1e3,
            per_call * 1e3 / VIEWS as f64,
            VIEWS as f64 / per_call
        );
        ran += 1;
    }
    assert!(
        ran > 0,
        "no backend opened; {}",
        mvgrasp_render::INSTALL_HINT
    );
    Ok(())
}

/// Cameras on a ring 0.5 m from the origin, 0.3 m up, looking at the origin.
fn ring(n: usize) -> Vec<View> {
    (0..n)
        .map(|i| {
            let a = 2.0 * std::f32::consts::PI * i as f32 / n as f32;
            let eye = [0.5 * a.cos(), 0.5 * a.sin(), 0.3];
            let f = normalise([-eye[0], -eye[1], -eye[2]]);
            let r = normalise(cross(f, [0.0, 0.0, 1.0]));
            let d = cross(f, r);
            let mut m = IDENTITY;
            for (row, axis) in [r, d, f].into_iter().enumerate() {
                let t = -(axis[0] * eye[0] + axis[1] * eye[1] + axis[2] * eye[2]);
                m[row] = [axis[0], axis[1], axis[2], t];
            }
            View {
                intrinsics: Intrinsics::PHOXI_S,
                camera_from_world: m,
            }
        })
        .collect()
}

/// A UV sphere with `2 * rings * segments` triangles.
fn sphere(radius: f32, rings: u32, segments: u32) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
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
            let (a, b) = (r * segments + s, r * segments + (s + 1) % segments);
            indices.push([a, a + segments, b]);
            indices.push([b, a + segments, b + segments]);
        }
    }
    (positions, indices)
}

fn cross(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn normalise(a: [f32; 3]) -> [f32; 3] {
    let l = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    [a[0] / l, a[1] / l, a[2] / l]
}
