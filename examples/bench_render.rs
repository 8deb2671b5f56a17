//! Rendering speed on a real mesh: the paper's 20 training views (PhoXi S, 516 x 386) of one
//! mesh, RGB + depth + mask read back, all views in one call. The benchmark of
//! `benches/render/run.sh`, which runs PyRender on the same views in the same run.
//!
//! ```text
//! cargo run --release --example bench_render -- --mesh PATH [--views 20] [--repeats 5]
//!     [--backend gl|vulkan|auto] [--seed 0] [--cameras-out cams.json] [--depth-out d0.npy] [--json]
//! ```
//!
//! The mesh is uploaded once with seeded random per-face colours; one warm-up call, then
//! `--repeats` timed calls of all views. Prints views per second from the median call.
//! `--cameras-out` writes the cameras (intrinsics and row-major `world_from_camera`, OpenCV
//! frame) as JSON, `--depth-out` the first view's depth (z, metres, 0 = background) as a
//! little-endian float32 `.npy` of shape (height, width).

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use clap::Parser;
use mvgrasp::cli::CliResult;
use mvgrasp_geometry::{Camera, HemisphereLayout, Intrinsics, TriangleMesh, Vec3};
use mvgrasp_render::{Backend, Colors, IDENTITY, Material, MeshInput, Renderer, View};

mod common;

/// Time mvgrasp's renderer on a mesh seen from the paper's hemisphere of cameras.
#[derive(Parser, Debug)]
#[command(about)]
struct Args {
    /// Mesh file (OBJ, STL, URDF; metres).
    #[arg(long)]
    mesh: PathBuf,
    /// Views per call (cameras on the paper's training hemisphere, 0.5 m away).
    #[arg(long, default_value_t = 20)]
    views: usize,
    /// Timed calls after the warm-up call.
    #[arg(long, default_value_t = 5)]
    repeats: usize,
    /// Graphics backend: gl, vulkan or auto (auto honours MVGRASP_RENDER_BACKEND).
    #[arg(long, default_value = "auto")]
    backend: String,
    /// Seed of the camera layout and the face colours.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Write the cameras here as JSON (for the PyRender side of the benchmark).
    #[arg(long)]
    cameras_out: Option<PathBuf>,
    /// Write the first view's depth here as a float32 .npy (height x width, metres).
    #[arg(long)]
    depth_out: Option<PathBuf>,
    /// Print one JSON object instead of a line of text.
    #[arg(long)]
    json: bool,
}

fn main() -> ExitCode {
    mvgrasp::cli::exit(run(&Args::parse()))
}

fn run(args: &Args) -> CliResult<()> {
    if args.repeats == 0 {
        return Err("--repeats must be at least 1".into());
    }
    let backend = Backend::parse(&args.backend)
        .ok_or_else(|| format!("--backend {}: expected gl, vulkan or auto", args.backend))?;
    let mesh = mvgrasp_geometry::load_mesh(&args.mesh)?;
    let target = mesh.aabb().center();
    let layout = HemisphereLayout {
        count: args.views,
        ..HemisphereLayout::paper_training()
    };
    let cameras = layout.cameras(Intrinsics::phoxi_s(), target, args.seed)?;
    let views = cameras
        .iter()
        .map(|camera| checked_view(camera, &mesh, target))
        .collect::<Result<Vec<_>, _>>()?;
    if let Some(path) = &args.cameras_out {
        write_cameras(path, &args.mesh, target, &cameras)?;
    }

    let positions: Vec<[f32; 3]> = mesh.vertices().iter().map(|v| v.to_array()).collect();
    let colors = mvgrasp_render::random_colors(args.seed, mesh.triangles().len());
    let renderer = Renderer::new(backend)?;
    let started = Instant::now();
    let scene = renderer.upload(&[MeshInput {
        positions: &positions,
        indices: mesh.triangles(),
        sides: mvgrasp::convert::sides_of(&mesh),
        colors: Colors::PerFace(&colors),
        world_from_mesh: IDENTITY,
        instance_id: 1,
        material: Material::MATTE,
    }])?;
    let upload_ms = ms_since(started);

    let started = Instant::now();
    let frames = renderer.render(&scene, &views)?;
    let warm_up_ms = ms_since(started);
    let seen: Vec<usize> = frames
        .iter()
        .map(|f| f.mask.iter().filter(|&&m| m == 1).count())
        .collect();
    if let Some((i, _)) = seen.iter().enumerate().find(|&(_, &n)| n == 0) {
        return Err(format!("view {i} does not see the mesh: a camera or backend fault").into());
    }
    if let (Some(path), Some(frame)) = (&args.depth_out, frames.first()) {
        common::write_npy_f32(
            path,
            &[frame.height as usize, frame.width as usize],
            &frame.depth_m,
        )?;
    }

    let mut call_ms = Vec::with_capacity(args.repeats);
    for _ in 0..args.repeats {
        let started = Instant::now();
        let frames = renderer.render(&scene, &views)?;
        call_ms.push(ms_since(started));
        if frames.len() != views.len() {
            return Err(format!("{} frames for {} views", frames.len(), views.len()).into());
        }
    }
    let median_ms = mvgrasp::infer::bench::median(call_ms.clone());
    let views_per_s = views.len() as f64 / (median_ms / 1e3);
    let ms_per_view = median_ms / views.len() as f64;
    let k = Intrinsics::phoxi_s();
    if args.json {
        let report = serde_json::json!({
            "renderer": "mvgrasp",
            "backend": format!("{:?}", renderer.backend()).to_lowercase(),
            "adapter": renderer.adapter_info(),
            "software": renderer.is_software(),
            "mesh": args.mesh.display().to_string(),
            "triangles": mesh.triangles().len(),
            "width": k.width,
            "height": k.height,
            "views": views.len(),
            "repeats": args.repeats,
            "upload_ms": upload_ms,
            "warm_up_ms": warm_up_ms,
            "call_ms": call_ms,
            "median_call_ms": median_ms,
            "ms_per_view": ms_per_view,
            "views_per_s": views_per_s,
            "mask_pixels": seen,
        });
        println!("{report}");
    } else {
        println!(
            "mvgrasp {:?} [{}]: {} triangles, {} views of {}x{} per call (RGB + depth + mask), \
             upload {upload_ms:.1} ms, warm-up {warm_up_ms:.1} ms, median of {} calls \
             {median_ms:.1} ms: {ms_per_view:.2} ms/view, {views_per_s:.1} views/s",
            renderer.backend(),
            renderer.adapter_info(),
            mesh.triangles().len(),
            views.len(),
            k.width,
            k.height,
            args.repeats,
        );
    }
    Ok(())
}

/// The render view of a camera, checked: the target and the mesh's first vertices project to
/// the same pixels through the view's row-major `camera_from_world` as through
/// [`Camera::project`].
fn checked_view(camera: &Camera, mesh: &TriangleMesh, target: Vec3) -> CliResult<View> {
    let view: View = mvgrasp::convert::render_view(camera);
    let m = view.camera_from_world;
    for &p in std::iter::once(&target).chain(mesh.vertices().iter().take(16)) {
        let in_camera = [0, 1, 2].map(|r| m[r][0] * p.x + m[r][1] * p.y + m[r][2] * p.z + m[r][3]);
        let got = mvgrasp_render::project(&view.intrinsics, in_camera);
        let expected = camera
            .project(p)
            .ok_or_else(|| format!("point {p} is behind a camera"))?;
        if (got[0] - expected[0]).abs() > 1e-2 || (got[1] - expected[1]).abs() > 1e-2 {
            return Err(format!(
                "camera conversion is wrong: {p} projects to {got:?}, the camera says {expected:?}"
            )
            .into());
        }
    }
    Ok(view)
}

fn write_cameras(path: &Path, mesh: &Path, target: Vec3, cameras: &[Camera]) -> CliResult<()> {
    let json = serde_json::json!({
        "mesh": mesh.display().to_string(),
        "target": target.to_array(),
        "frame": "OpenCV camera frame (x right, y down, z forward); world_from_camera row-major",
        "pixel_centres": "integer image coordinates (u = fx x / z + cx)",
        "cameras": cameras,
    });
    let text = serde_json::to_string_pretty(&json)?;
    Ok(std::fs::write(path, text).map_err(|e| format!("cannot write {}: {e}", path.display()))?)
}

fn ms_since(start: Instant) -> f64 {
    start.elapsed().as_secs_f64() * 1e3
}
