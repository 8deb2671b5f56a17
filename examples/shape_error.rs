//! How far the physics trial's object shapes stray from the true surface: for every mesh under
//! `../shared/data/meshes` (and the first `--random-urdfs` of pybullet's random objects), the
//! bulge (how far the collision shape's surface stands outside the mesh: median, 95th percentile,
//! largest) and the gap (95th percentile of how far the mesh's surface lies outside the shape),
//! in millimetres, with the shell's parts and build time; beside them the parts and bulge of the
//! default shape (the shell off: the hull, or VHACD's parts).
//!
//! ```sh
//! cargo run --release --example shape_error -- [--data ../shared/data/meshes] [--random-urdfs 20]
//! ```

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use clap::Parser;
use mvgrasp_geometry::{TriangleMesh, load_mesh};
use mvgrasp_grasp::physics::{PhysicsObject, ShapeParams};

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
    /// Also the built-in objects of each category with these indices (e.g. 30,31).
    #[arg(long, value_delimiter = ',')]
    builtin: Vec<u32>,
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
        "{:<50} {:>6} {:>5} {:>6} {:>6} {:>6} {:>6} {:>6} | {:>5} {:>6}",
        "mesh", "faces", "parts", "bulge", "p95", "max", "gap95", "ms", "old", "p95"
    );
    let (mut measured, mut within, mut within_old) = (0, 0, 0);
    let mut p95s = Vec::new();
    let mut old_p95s = Vec::new();
    let mut items: Vec<(String, Result<TriangleMesh, String>)> = files
        .iter()
        .map(|file| {
            let name = file
                .strip_prefix(&args.data)
                .unwrap_or(file)
                .display()
                .to_string();
            (name, load_mesh(file).map_err(|e| e.to_string()))
        })
        .collect();
    for category in mvgrasp_geometry::Category::ALL {
        for &index in &args.builtin {
            match mvgrasp_geometry::objects::generate(category, index, 0) {
                Ok(o) => items.push((o.name, Ok(o.mesh))),
                Err(e) => items.push((format!("{category:?} {index}"), Err(e.to_string()))),
            }
        }
    }
    for (name, mesh) in items {
        let mesh = match mesh {
            Ok(mesh) => mesh,
            Err(e) => {
                println!("{name:<50} skipped: {e}");
                continue;
            }
        };
        let start = Instant::now();
        let params = ShapeParams {
            shell: true,
            ..ShapeParams::default()
        };
        let object = match PhysicsObject::new(&mesh, &params) {
            Ok(object) => object,
            Err(e) => {
                println!("{name:<50} skipped: {e}");
                continue;
            }
        };
        let build_ms = start.elapsed().as_secs_f64() * 1e3;
        let error = match object.shape_error(&mesh, args.samples, 1) {
            Ok(error) => error,
            Err(e) => {
                println!("{name:<50} skipped: {e}");
                continue;
            }
        };
        // The default shape (the shell off): the hull, or VHACD's parts.
        let (old_parts, old_p95) = match PhysicsObject::new(&mesh, &ShapeParams::default()) {
            Ok(old) => (
                old.num_parts(),
                old.shape_error(&mesh, args.samples, 1)
                    .map_or(f32::NAN, |e| e.bulge_p95_m),
            ),
            Err(_) => (0, f32::NAN),
        };
        measured += 1;
        within += usize::from(error.bulge_p95_m <= 1e-3);
        within_old += usize::from(old_p95 <= 1e-3);
        p95s.push(error.bulge_p95_m);
        old_p95s.push(old_p95);
        println!(
            "{name:<50} {:>6} {:>5} {:>6.2} {:>6.2} {:>6.2} {:>6.2} {:>6.0} | {:>5} {:>6.2}",
            mesh.triangles().len(),
            object.num_parts(),
            error.bulge_median_m * 1e3,
            error.bulge_p95_m * 1e3,
            error.bulge_max_m * 1e3,
            error.gap_p95_m * 1e3,
            build_ms,
            old_parts,
            old_p95 * 1e3
        );
    }
    let median = |v: &mut Vec<f32>| {
        v.sort_by(f32::total_cmp);
        v.get(v.len() / 2).copied().unwrap_or(0.0) * 1e3
    };
    println!(
        "\n{measured} objects. Bulge p95 within 1 mm: {within} now (median {:.2} mm), {within_old} \
         with the default shapes (median {:.2} mm)",
        median(&mut p95s),
        median(&mut old_p95s)
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
