//! Time of the Rust runtime's sweep refiner on this machine: `SweepRefiner::predict` on every
//! view of an inputs file in turn, one JSON line. `benches/sweep_refiner/run.sh` runs it beside
//! torch (`benches/sweep_refiner/bench.py`: the same exported weights, the same inputs, the
//! same thread count) and prints the comparison.
//!
//! cargo run --release -p mvgrasp-infer --example bench_sweep_refiner -- MODEL.json \
//!     INPUTS.safetensors [--threads 1] [--seconds 2]
//!
//! INPUTS holds `features.0`, `features.1`, ... each `[1, C, H, W]` (one view's box). A
//! warm-up of 2 passes, then passes until `--seconds` have passed and at least 5 were made;
//! reports the median pass (all views) and the corrections' mean (a check that both runtimes
//! predicted alike).

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use clap::Parser;
use mvgrasp_infer::model::Weights;
use mvgrasp_infer::{Parallelism, SweepRefiner};

/// Any error, for the one `error: ...` line.
type CliResult<T> = Result<T, Box<dyn std::error::Error + Send + Sync>>;

/// Sweep refiner time of the Rust runtime, one JSON line on stdout.
#[derive(Parser)]
struct Args {
    /// The network's `NAME.json` (weights beside it).
    model: PathBuf,
    /// The inputs (see the module docs).
    inputs: PathBuf,
    /// Threads: a rayon pool of this size, and `Parallelism::Rayon` over it (1: sequential).
    #[arg(long, default_value_t = 1)]
    threads: usize,
    /// Timed seconds (at least 5 passes whatever this says).
    #[arg(long, default_value_t = 2.0)]
    seconds: f64,
}

fn main() -> ExitCode {
    match run(Args::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("error: {message}");
            ExitCode::from(2)
        }
    }
}

fn run(args: Args) -> CliResult<()> {
    if args.threads == 0 {
        return Err("--threads must be at least 1".into());
    }
    let par = match args.threads {
        1 => Parallelism::Sequential,
        threads => Parallelism::Rayon { threads },
    };
    let net = SweepRefiner::load(&args.model)?.with_parallelism(par);
    let mut inputs = Weights::load(&args.inputs)?;
    let mut views = Vec::new();
    while let Ok(features) = inputs.take_any(&format!("features.{}", views.len())) {
        views.push(features);
    }
    if views.is_empty() {
        return Err(format!("{}: no features.0", args.inputs.display()).into());
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads)
        .build()?;
    let pass = || -> CliResult<f64> {
        let mut sum = 0.0f64;
        let mut count = 0usize;
        for features in &views {
            let out = net.predict(features)?;
            sum += out
                .correction_m
                .data()
                .iter()
                .map(|&v| f64::from(v))
                .sum::<f64>();
            count += out.correction_m.len();
        }
        Ok(sum / count.max(1) as f64)
    };
    let (times, mean) = pool.install(|| -> CliResult<_> {
        pass()?;
        let mut mean = pass()?;
        let mut times = Vec::new();
        let started = Instant::now();
        while times.len() < 5 || started.elapsed().as_secs_f64() < args.seconds {
            let t = Instant::now();
            mean = pass()?;
            times.push(t.elapsed().as_secs_f64());
        }
        Ok((times, mean))
    })?;
    let mut sorted = times.clone();
    sorted.sort_by(f64::total_cmp);
    let line = serde_json::json!({
        "runtime": "rust",
        "views": views.len(),
        "threads": args.threads,
        "calls": times.len(),
        "median_s": sorted[sorted.len() / 2],
        "mean_correction_m": mean,
    });
    println!("{line}");
    Ok(())
}
