//! `plan`: the main job. With no arguments it takes the built-in default object (a procedural
//! mug) and reports what the planner knows about it: mesh facts, stable poses, camera views.
//! Grasp planning joins this command as its issues land.

use std::process::ExitCode;

use clap::Parser;
use mvgrasp::cli::ObjectArgs;
use mvgrasp::geometry::{Intrinsics, IntrinsicsPreset};
use mvgrasp::{ObjectReport, ReportParams};

/// Plan for an object: today, describe it (mesh facts, stable poses, hemisphere views).
#[derive(Parser, Debug)]
#[command(version, about)]
struct Args {
    #[command(flatten)]
    object: ObjectArgs,
    /// Camera intrinsics preset: phoxi_s, primesense, realsense_d435.
    #[arg(long, default_value = "phoxi_s")]
    camera: String,
    /// Print the full report as JSON on stdout instead of the summary.
    #[arg(long)]
    json: bool,
}

fn main() -> ExitCode {
    mvgrasp::cli::exit(run(&Args::parse()))
}

fn run(args: &Args) -> Result<(), String> {
    let preset: IntrinsicsPreset = args.camera.parse().map_err(|e| format!("--camera: {e}"))?;
    let object = args.object.load()?;
    let params = ReportParams {
        intrinsics: Intrinsics::preset(preset),
        views_seed: args.object.seed,
        ..Default::default()
    };
    let report = ObjectReport::describe(&object.display_name, &object.mesh, &params)
        .map_err(|e| e.to_string())?;
    if args.json {
        let json = serde_json::to_string_pretty(&report).map_err(|e| e.to_string())?;
        println!("{json}");
    } else {
        print!("{}", report.summary());
    }
    Ok(())
}
