//! `objects`: writes the built-in procedural object library as OBJ files plus a manifest.
//!
//! ```text
//! cargo run --release --bin objects -- --out DIR --per-category N --seed S [--categories mug,bowl]
//! ```
//!
//! Every object is a closed mesh in metres resting on z = 0. The same seed always writes the
//! same bytes, so existing files of the same name are simply regenerated.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use clap::Parser;
use mvgrasp_geometry::objects::{
    Category, GeneratedObject, MarchingParams, ObjectParams, ObjectSpec, generate_with,
};
use mvgrasp_geometry::write_obj;
use serde::Serialize;

/// Write procedural household objects (OBJ, metres) and a manifest.json.
#[derive(Parser, Debug)]
#[command(name = "objects", version, about)]
struct Args {
    /// Output folder (created if missing).
    #[arg(long)]
    out: PathBuf,
    /// Objects per category.
    #[arg(long, default_value_t = 5)]
    per_category: u32,
    /// Library seed.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Comma-separated categories (default: all): bottle, mug, bowl, box, can, toy_car,
    /// stapler (or hole_punch), toy_chair, squash, blob.
    #[arg(long, value_delimiter = ',')]
    categories: Vec<Category>,
    /// Grid cell of the mesher, millimetres.
    #[arg(long, default_value_t = 2.0)]
    cell_mm: f32,
}

/// One manifest entry.
#[derive(Serialize)]
struct Entry<'a> {
    name: &'a str,
    category: Category,
    index: u32,
    seed: u64,
    file: String,
    triangles: usize,
    vertices: usize,
    extents_m: [f32; 3],
    params: &'a ObjectParams,
}

/// The manifest written next to the OBJ files.
#[derive(Serialize)]
struct Manifest<'a> {
    seed: u64,
    per_category: u32,
    cell_m: f32,
    units: &'static str,
    objects: Vec<Entry<'a>>,
}

/// A failure and the exit code it maps to (2: the user's input or environment, 1: a bug).
struct Failure {
    message: String,
    code: u8,
}

fn main() -> ExitCode {
    let args = Args::parse();
    match run(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(failure) => {
            eprintln!("error: {}", failure.message);
            ExitCode::from(failure.code)
        }
    }
}

fn user(message: String) -> Failure {
    Failure { message, code: 2 }
}

fn run(args: &Args) -> Result<(), Failure> {
    if !(args.cell_mm.is_finite() && (0.5..=20.0).contains(&args.cell_mm)) {
        return Err(user(format!(
            "--cell-mm {} is out of range (expected 0.5 to 20)",
            args.cell_mm
        )));
    }
    let categories: Vec<Category> = if args.categories.is_empty() {
        Category::ALL.to_vec()
    } else {
        let mut seen = Vec::new();
        for c in &args.categories {
            if !seen.contains(c) {
                seen.push(*c);
            }
        }
        seen
    };
    std::fs::create_dir_all(&args.out)
        .map_err(|e| user(format!("{}: cannot create folder: {e}", args.out.display())))?;
    let marching = MarchingParams::with_cell(args.cell_mm * 1e-3);
    let total = categories.len() * args.per_category as usize;
    let mut objects: Vec<(GeneratedObject, String)> = Vec::with_capacity(total);
    let started = Instant::now();
    for category in categories {
        for index in 0..args.per_category {
            let spec = ObjectSpec {
                category,
                index,
                seed: args.seed,
            };
            let t0 = Instant::now();
            let object = generate_with(&spec, &marching).map_err(|e| Failure {
                message: format!("generating {}: {e}", spec.name()),
                code: 1,
            })?;
            let file = format!("{}.obj", object.name);
            let path = args.out.join(&file);
            write_obj(&object.mesh, &path).map_err(|e| user(e.to_string()))?;
            let e = object.extents_m();
            eprintln!(
                "[{}/{total}] {}: {} triangles, {:.1} x {:.1} x {:.1} cm, {:.2} s",
                objects.len() + 1,
                path.display(),
                object.mesh.triangles().len(),
                e.x * 100.0,
                e.y * 100.0,
                e.z * 100.0,
                t0.elapsed().as_secs_f32()
            );
            objects.push((object, file));
        }
    }
    write_manifest(args, &marching, &objects)?;
    eprintln!(
        "wrote {} objects and manifest.json to {} in {:.1} s",
        objects.len(),
        args.out.display(),
        started.elapsed().as_secs_f32()
    );
    Ok(())
}

fn write_manifest(
    args: &Args,
    marching: &MarchingParams,
    objects: &[(GeneratedObject, String)],
) -> Result<(), Failure> {
    let manifest = Manifest {
        seed: args.seed,
        per_category: args.per_category,
        cell_m: marching.cell_m,
        units: "metres",
        objects: objects
            .iter()
            .map(|(o, file)| Entry {
                name: &o.name,
                category: o.spec.category,
                index: o.spec.index,
                seed: o.spec.seed,
                file: file.clone(),
                triangles: o.mesh.triangles().len(),
                vertices: o.mesh.vertices().len(),
                extents_m: o.extents_m().to_array(),
                params: &o.params,
            })
            .collect(),
    };
    let mut text = serde_json::to_string_pretty(&manifest).map_err(|e| Failure {
        message: format!("serialising the manifest: {e}"),
        code: 1,
    })?;
    text.push('\n');
    write_atomically(&args.out.join("manifest.json"), text.as_bytes())
}

/// Writes `bytes` to a temporary name next to `path`, then renames it into place.
fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), Failure> {
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".tmp");
    let tmp = PathBuf::from(tmp);
    std::fs::write(&tmp, bytes)
        .and_then(|()| std::fs::rename(&tmp, path))
        .map_err(|e| user(format!("{}: cannot write: {e}", path.display())))
}
