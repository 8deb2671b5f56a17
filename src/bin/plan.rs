//! `plan`: the main job. With no arguments it takes the built-in default object (a procedural
//! mug) and reports what the planner knows about it: mesh facts, stable poses, camera views.
//! Grasp planning joins this command as its issues land.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::Parser;
use mvgrasp::geometry::objects::{Category, generate};
use mvgrasp::geometry::{Intrinsics, IntrinsicsPreset, LoadOptions, load_mesh_with};
use mvgrasp::{ObjectReport, ReportParams};

/// Plan for an object: today, describe it (mesh facts, stable poses, hemisphere views).
#[derive(Parser, Debug)]
#[command(version, about)]
struct Args {
    /// A mesh file (OBJ, STL or URDF, metres). Default: the built-in object below.
    #[arg(long)]
    mesh: Option<PathBuf>,
    /// Multiply the mesh's coordinates by this (0.001 for millimetres).
    #[arg(long, default_value_t = 1.0)]
    scale: f32,
    /// Built-in object category when no --mesh is given.
    #[arg(long, default_value = "mug")]
    category: String,
    /// Built-in object index within its category.
    #[arg(long, default_value_t = 0)]
    index: u32,
    /// Seed for the built-in object and the camera layouts.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Camera intrinsics preset: phoxi_s, primesense, realsense_d435.
    #[arg(long, default_value = "phoxi_s")]
    camera: String,
    /// Print the full report as JSON on stdout instead of the summary.
    #[arg(long)]
    json: bool,
}

fn main() -> ExitCode {
    let args = Args::parse();
    match run(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("error: {message}");
            ExitCode::from(2)
        }
    }
}

fn run(args: &Args) -> Result<(), String> {
    let preset: IntrinsicsPreset = args.camera.parse().map_err(|e| format!("--camera: {e}"))?;
    let (name, mesh) = match &args.mesh {
        Some(path) => {
            let options = LoadOptions {
                scale: args.scale,
                ..Default::default()
            };
            let mesh = load_mesh_with(path, &options).map_err(|e| e.to_string())?;
            let name = path
                .file_stem()
                .map_or("mesh".into(), |s| s.to_string_lossy().into_owned());
            (name, mesh)
        }
        None => {
            let category: Category = args
                .category
                .parse()
                .map_err(|e| format!("--category: {e}"))?;
            let object = generate(category, args.index, args.seed).map_err(|e| e.to_string())?;
            (
                format!("{} (built-in, seed {})", object.name, args.seed),
                object.mesh,
            )
        }
    };
    let params = ReportParams {
        intrinsics: Intrinsics::preset(preset),
        views_seed: args.seed,
        ..Default::default()
    };
    let report = ObjectReport::describe(&name, &mesh, &params).map_err(|e| e.to_string())?;
    if args.json {
        let json = serde_json::to_string_pretty(&report).map_err(|e| e.to_string())?;
        println!("{json}");
    } else {
        print!("{}", report.summary());
    }
    Ok(())
}
