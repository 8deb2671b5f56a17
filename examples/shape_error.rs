//! How far the physics trial's object shapes stray from the true surface: for every mesh under
//! `../shared/data/meshes` (and the first `--random-urdfs` of pybullet's random objects), the
//! one-sided distance from the collision shape's surface to the mesh ([`ShapeError`]): median,
//! 95th percentile and largest, in millimetres, with the shape's parts and build time.
//!
//! ```sh
//! cargo run --release --example shape_error -- [--data ../shared/data/meshes] [--random-urdfs 20]
//! ```

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use clap::Parser;
use mvgrasp_geometry::{DecompositionParams, load_mesh};
use mvgrasp_grasp::physics::PhysicsObject;

#[derive(Parser)]
struct Args {
    /// The shared mesh folder.
    #[arg(long, default_value = "../shared/data/meshes")]
    data: PathBuf,
    /// How many of pybullet's random_urdfs to include (they are 1,000).
    #[arg(long, default_value_t = 20)]
    random_urdfs: usize,
    /// Points measured per object.
    #[arg(long, default_value_t = 20_000)]
    samples: usize,
}

fn main() -> ExitCode {
    let args = Args::parse();
    if !args.data.is_dir() {
        eprintln!("shape_error: no mesh folder at {}", args.data.display());
        return ExitCode::FAILURE;
    }
    let mut files = Vec::new();
    collect(&args.data, &mut files);
    files.sort();
    let mut random: Vec<PathBuf> = files.iter().filter(|f| is_random(f)).cloned().collect();
    random.truncate(args.random_urdfs);
    files.retain(|f| !is_random(f));
    files.extend(random);

    println!(
        "{:<58} {:>7} {:>5} {:>7} {:>7} {:>7} {:>8}",
        "mesh", "faces", "parts", "p50 mm", "p95 mm", "max mm", "build ms"
    );
    let (mut measured, mut within) = (0, 0);
    let mut p95s = Vec::new();
    for file in &files {
        let name = file
            .strip_prefix(&args.data)
            .unwrap_or(file)
            .display()
            .to_string();
        let mesh = match load_mesh(file) {
            Ok(mesh) => mesh,
            Err(e) => {
                println!("{name:<58} skipped: {e}");
                continue;
            }
        };
        let start = Instant::now();
        let object = match PhysicsObject::new(&mesh, &DecompositionParams::default()) {
            Ok(object) => object,
            Err(e) => {
                println!("{name:<58} skipped: {e}");
                continue;
            }
        };
        let build_ms = start.elapsed().as_secs_f64() * 1e3;
        let error = match object.shape_error(&mesh, args.samples, 1) {
            Ok(error) => error,
            Err(e) => {
                println!("{name:<58} skipped: {e}");
                continue;
            }
        };
        measured += 1;
        within += usize::from(error.p95_m <= 1e-3);
        p95s.push(error.p95_m);
        println!(
            "{name:<58} {:>7} {:>5} {:>7.2} {:>7.2} {:>7.2} {:>8.0}",
            mesh.triangles().len(),
            object.num_parts(),
            error.median_m * 1e3,
            error.p95_m * 1e3,
            error.max_m * 1e3,
            build_ms
        );
    }
    p95s.sort_by(f32::total_cmp);
    let median = p95s.get(p95s.len() / 2).copied().unwrap_or(0.0);
    println!(
        "\n{measured} objects: {within} within 1 mm at the 95th percentile; median p95 {:.2} mm",
        median * 1e3
    );
    ExitCode::SUCCESS
}

fn is_random(path: &Path) -> bool {
    path.components().any(|c| c.as_os_str() == "random_urdfs")
}

/// Every OBJ, STL and URDF under `dir`; a mesh file that a URDF beside it names is left to the
/// URDF (its scale and pose are the URDF's).
fn collect(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let mut here: Vec<PathBuf> = entries.filter_map(|e| e.ok().map(|e| e.path())).collect();
    here.sort();
    let urdf_text: String = here
        .iter()
        .filter(|p| p.extension().is_some_and(|e| e == "urdf"))
        .filter_map(|p| std::fs::read_to_string(p).ok())
        .collect();
    for path in here {
        if path.is_dir() {
            collect(&path, out);
            continue;
        }
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .unwrap_or_default()
            .to_ascii_lowercase();
        let named_by_urdf = path
            .file_name()
            .and_then(|n| n.to_str())
            .is_some_and(|n| urdf_text.contains(n));
        if ext == "urdf" || (matches!(ext.as_str(), "obj" | "stl") && !named_by_urdf) {
            out.push(path);
        }
    }
}
