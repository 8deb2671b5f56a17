//! `grasp_dataset`: labelled grasp images for the GQ-CNN (top-down cameras) and the multi-view
//! GQ-CNN (cameras anywhere on the hemisphere), as safetensors shards with a JSON manifest.
//! Resumes where an earlier run stopped; `--shard K` makes one shard (for many machines).
//!
//! ```text
//! cargo run --release --bin grasp_dataset -- --out DIR [--config FILE.toml] [--seed S]
//!     [--mesh PATH ...] [--per-category N] [--shard K] [--preview PNG] [--backend B] [--quiet]
//! ```

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use clap::Parser;
use mvgrasp::cli::{CliResult, LibraryArgs};
use mvgrasp::grasp_dataset::preview::write_preview;
use mvgrasp::grasp_dataset::{DatasetPlan, GraspDatasetConfig, generate, generate_shard};
use mvgrasp::render::{Backend, Renderer};

/// Generate a grasp dataset (see docs/datasets-and-training.md).
#[derive(Parser, Debug)]
#[command(version, about)]
struct Args {
    /// Output folder (created if missing; finished shards are skipped).
    #[arg(long)]
    out: PathBuf,
    /// The dataset config (TOML; missing keys keep their defaults).
    #[arg(long)]
    config: Option<PathBuf>,
    /// Overrides the config's seed.
    #[arg(long)]
    seed: Option<u64>,
    #[command(flatten)]
    objects: LibraryArgs,
    /// Make only this shard (and update the manifest).
    #[arg(long)]
    shard: Option<usize>,
    /// Graphics backend: auto, vulkan, gl, metal, dx12 (or MVGRASP_RENDER_BACKEND).
    #[arg(long, default_value = "auto")]
    backend: String,
    /// Also draw a preview of the dataset's crops here (PNG: positives on top, negatives
    /// below).
    #[arg(long)]
    preview: Option<PathBuf>,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
}

fn main() -> ExitCode {
    mvgrasp::cli::exit(run(&Args::parse()))
}

fn run(args: &Args) -> CliResult<()> {
    let mut config = match &args.config {
        Some(path) => GraspDatasetConfig::from_file(path)?,
        None => GraspDatasetConfig::default(),
    };
    if let Some(seed) = args.seed {
        config.seed = seed;
    }
    let backend = Backend::parse(&args.backend).ok_or_else(|| {
        format!(
            "--backend: unknown backend {:?} (expected auto, vulkan, gl, metal, dx12)",
            args.backend
        )
    })?;
    let sources = args.objects.sources()?;
    let renderer = Renderer::new(backend)?;
    let started = Instant::now();
    let totals = match args.shard {
        Some(index) => {
            let plan = DatasetPlan::new(&sources, &config)?;
            std::fs::create_dir_all(&args.out)
                .map_err(|e| format!("{}: {e}", args.out.display()))?;
            generate_shard(&renderer, &plan, &args.out, index)?;
            plan.write_manifest(&args.out)?.totals
        }
        None => {
            if !args.quiet {
                eprintln!(
                    "{} objects, rendering with {}",
                    sources.len(),
                    renderer.adapter_info()
                );
            }
            let summary = generate(&renderer, &sources, &config, &args.out, !args.quiet)?;
            if !args.quiet {
                eprintln!(
                    "{} shards written, {} already done",
                    summary.written, summary.skipped
                );
            }
            summary.totals
        }
    };
    let seconds = started.elapsed().as_secs_f64();
    if let Some(png) = &args.preview {
        write_preview(&args.out, png, 24, 12)?;
    }
    let rate = |n: usize, of: usize| {
        if of == 0 {
            0.0
        } else {
            100.0 * n as f64 / of as f64
        }
    };
    println!(
        "{} datapoints ({:.1}% positive, {:.1}% collision-free), {} physics labels of {} trials \
         each ({:.1}% held, {:.1}% of the {} that reached the grasp agree with the robust label), \
         {:.1} s: {}",
        totals.datapoints,
        rate(totals.positives, totals.datapoints),
        rate(totals.collision_free, totals.datapoints),
        totals.physics_trials,
        config.physics_trials,
        rate(totals.physics_held, totals.physics_trials),
        rate(totals.physics_agree, totals.physics_tested),
        totals.physics_tested,
        seconds,
        args.out.display()
    );
    Ok(())
}
