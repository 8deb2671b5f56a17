//! Depth-prediction time of the Rust runtime's multi-view stereo network on this machine:
//! `Mvs::predict` on the views of an inputs file, one JSON line. `benches/mvs/run.sh` runs it
//! beside torch (`benches/mvs/bench.py`: the same exported weights, the same inputs, the same
//! thread count) and the classical baseline, and prints the comparison.
//!
//! cargo run --release -p mvgrasp-infer --example bench_mvs -- MODEL.json INPUTS.safetensors \
//!     [--threads 1] [--seconds 2]
//!
//! INPUTS holds `images` `[V, 3, H, W]` at the network's size, `k` `[V, 3, 3]` at that size and
//! `camera_from_world` `[V, 4, 4]`. A warm-up of 2 calls, then calls until `--seconds` have
//! passed and at least 5 were made; reports the median call and the predicted depth's mean (a
//! check that both runtimes predicted alike).

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use clap::Parser;
use mvgrasp_infer::model::Weights;
use mvgrasp_infer::ops::CameraMatrices;
use mvgrasp_infer::{Mvs, Parallelism};

/// Any error, for the one `error: ...` line.
type CliResult<T> = Result<T, Box<dyn std::error::Error + Send + Sync>>;

/// Multi-view stereo prediction time of the Rust runtime, one JSON line on stdout.
#[derive(Parser)]
struct Args {
    /// The network's `NAME.json` (weights beside it).
    model: PathBuf,
    /// The inputs (see the module docs).
    inputs: PathBuf,
    /// Threads: a rayon pool of this size, and `Parallelism::Rayon` over it (1: sequential).
    #[arg(long, default_value_t = 1)]
    threads: usize,
    /// Timed seconds (at least 5 calls whatever this says).
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
    let net = Mvs::load(&args.model)?.with_parallelism(par);
    let mut inputs = Weights::load(&args.inputs)?;
    let mut take = |name: &str| inputs.take_any(name);
    let (images, k, pose) = (take("images")?, take("k")?, take("camera_from_world")?);
    let views = images.shape()[0];
    if k.shape() != [views, 3, 3] || pose.shape() != [views, 4, 4] {
        return Err(format!(
            "{}: k {:?} and camera_from_world {:?} for {views} views",
            args.inputs.display(),
            k.shape(),
            pose.shape()
        )
        .into());
    }
    let cameras: Vec<CameraMatrices> = (0..views)
        .map(|v| CameraMatrices {
            k: std::array::from_fn(|r| std::array::from_fn(|c| k.data()[v * 9 + r * 3 + c])),
            camera_from_world: std::array::from_fn(|r| {
                std::array::from_fn(|c| pose.data()[v * 16 + r * 4 + c])
            }),
        })
        .collect();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads)
        .build()?;
    let predict = || net.predict(&images, &cameras).map(|out| out.depth);
    let (times, depth) = pool.install(|| -> CliResult<_> {
        // Two warm-up calls.
        predict()?;
        let mut depth = predict()?;
        let mut times = Vec::new();
        let started = Instant::now();
        while times.len() < 5 || started.elapsed().as_secs_f64() < args.seconds {
            let t = Instant::now();
            depth = predict()?;
            times.push(t.elapsed().as_secs_f64());
        }
        Ok((times, depth))
    })?;
    let mut sorted = times.clone();
    sorted.sort_by(f64::total_cmp);
    let mean = depth.data().iter().map(|&v| f64::from(v)).sum::<f64>() / depth.len() as f64;
    let line = serde_json::json!({
        "runtime": "rust",
        "views": views,
        "threads": args.threads,
        "calls": times.len(),
        "median_s": sorted[sorted.len() / 2],
        "mean_depth_m": mean,
    });
    println!("{line}");
    Ok(())
}
