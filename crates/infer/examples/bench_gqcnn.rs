//! GQ-CNN scoring throughput of the Rust runtime on this machine: `Gqcnn::predict` (softmax
//! included) on seeded random batches, one JSON line per batch size. `benches/gqcnn/run.sh`
//! runs it beside torch (`benches/gqcnn/bench_torch.py`, same inputs, same timing) and prints
//! the comparison.
//!
//! cargo run --release -p mvgrasp-infer --example bench_gqcnn -- MODEL.json \
//!     [--threads 1] [--batches 1,64,256] [--seconds 2]
//!
//! Each batch size: one batch of crops (depth uniform in 0.6..0.75 m) and poses (grasp depth
//! 0.6..0.75 m, theta 0..1.57 rad when the network takes it) from SplitMix64 seeded with
//! `--seed` (the torch script draws the same numbers), a warm-up of `--warmup-seconds`, then
//! calls until `--seconds` have passed and at least 5 calls were made. Reports the median
//! call and crops per second at that median, and the mean probability as a check that both
//! runtimes scored the same inputs alike.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::Parser;
use mvgrasp_infer::bench::time_gqcnn;
use mvgrasp_infer::{Gqcnn, Parallelism};

/// Any error, for the one `error: ...` line.
type CliResult<T> = Result<T, Box<dyn std::error::Error + Send + Sync>>;

/// GQ-CNN throughput of the Rust runtime, JSON lines on stdout.
#[derive(Parser)]
struct Args {
    /// The network's `NAME.json` (weights beside it).
    model: PathBuf,
    /// Threads: a rayon pool of this size, and `Parallelism::Rayon` over it (1: sequential).
    #[arg(long, default_value_t = 1)]
    threads: usize,
    /// Batch sizes, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "1,64,256")]
    batches: Vec<usize>,
    /// Timed seconds per batch size (at least 5 calls whatever this says).
    #[arg(long, default_value_t = 2.0)]
    seconds: f64,
    /// Untimed warm-up seconds per batch size (at least 2 calls).
    #[arg(long, default_value_t = 0.3)]
    warmup_seconds: f64,
    /// Seed of the inputs.
    #[arg(long, default_value_t = 0)]
    seed: u64,
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
    if args.threads == 0 || args.batches.contains(&0) {
        return Err("--threads and every batch size must be at least 1".into());
    }
    let par = match args.threads {
        1 => Parallelism::Sequential,
        threads => Parallelism::Rayon { threads },
    };
    let net = Gqcnn::load(&args.model)?.with_parallelism(par);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads)
        .build()?;
    let arch = net.architecture();
    let pose_inputs = arch.pose_inputs;
    let model = args.model.display().to_string();
    for &batch in &args.batches {
        let timing = pool
            .install(|| time_gqcnn(&net, batch, args.seed, (args.warmup_seconds, args.seconds)))?;
        let median_s = timing.median_s;
        let line = serde_json::json!({
            "runtime": "rust",
            "model": model,
            "architecture": arch.name,
            "pose_inputs": pose_inputs,
            "threads": args.threads,
            "batch": batch,
            "calls": timing.calls,
            "median_s": median_s,
            "crops_per_s": batch as f64 / median_s,
            "mean_p": timing.mean_p,
        });
        println!("{line}");
    }
    Ok(())
}
