//! `render`: the multi-view RGB-D dataset of the seed paper. Per object: 20 training views on
//! the hemisphere and 10 novel test views with novel colouring (the first exactly top-down):
//! RGB, depth and mask PNGs and the cameras as JSON. Resumes where an earlier run stopped.
//!
//! ```text
//! cargo run --release --bin render -- --out DIR [--per-category N] [--seed S] [--library-seed S]
//!     [--mesh FILE_OR_FOLDER ...]
//! ```

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use clap::Parser;
use mvgrasp::cli::{CliResult, LibraryArgs};
use mvgrasp::dataset::{DatasetConfig, write_dataset};
use mvgrasp::geometry::{Intrinsics, IntrinsicsPreset};
use mvgrasp::render::{Backend, Renderer};

/// Render the multi-view RGB-D dataset (training and novel test views per object).
#[derive(Parser, Debug)]
#[command(version, about)]
struct Args {
    /// Output folder (created if missing; finished objects are skipped).
    #[arg(long)]
    out: PathBuf,
    #[command(flatten)]
    objects: LibraryArgs,
    /// Seed of the camera layouts and colours.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Camera intrinsics preset: phoxi_s, primesense, realsense_d435.
    #[arg(long, default_value = "phoxi_s")]
    camera: String,
    /// Graphics backend: auto, vulkan, gl, metal, dx12 (or MVGRASP_RENDER_BACKEND).
    #[arg(long, default_value = "auto")]
    backend: String,
    /// Leave out the table plane.
    #[arg(long)]
    no_table: bool,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
}

fn main() -> ExitCode {
    mvgrasp::cli::exit(run(&Args::parse()))
}

fn run(args: &Args) -> CliResult<()> {
    let preset: IntrinsicsPreset = args.camera.parse().map_err(|e| format!("--camera: {e}"))?;
    let backend = Backend::parse(&args.backend).ok_or_else(|| {
        format!(
            "--backend: unknown backend {:?} (expected auto, vulkan, gl, metal, dx12)",
            args.backend
        )
    })?;
    let sources = args.objects.sources()?;
    let config = DatasetConfig {
        seed: args.seed,
        intrinsics: Intrinsics::preset(preset),
        table: !args.no_table,
        ..Default::default()
    };
    let renderer = Renderer::new(backend)?;
    if !args.quiet {
        eprintln!(
            "rendering {} objects with {}",
            sources.len(),
            renderer.adapter_info()
        );
    }
    let started = Instant::now();
    let summary = write_dataset(&renderer, &sources, &config, &args.out, !args.quiet)?;
    let seconds = started.elapsed().as_secs_f64();
    println!(
        "{} objects written ({} views, {:.1} views/s), {} already done, in {:.1} s: {}",
        summary.written,
        summary.views,
        summary.views as f64 / seconds.max(1e-9),
        summary.skipped,
        seconds,
        args.out.display()
    );
    Ok(())
}
