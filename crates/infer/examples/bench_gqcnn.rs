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
use std::time::Instant;

use clap::Parser;
use mvgrasp_infer::{Gqcnn, GqcnnWorkspace, Parallelism, Tensor};

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
    let (size, pose_inputs) = (arch.image_size_px, arch.pose_inputs);
    let model = args.model.display().to_string();
    for &batch in &args.batches {
        let (depth, pose) = inputs(batch, size, pose_inputs, args.seed)?;
        let mut workspace = GqcnnWorkspace::default();
        let mut call = || net.predict(&depth, &pose, &mut workspace);
        let (times, mean_p) = pool.install(|| -> CliResult<(Vec<f64>, f64)> {
            let mut p = Vec::new();
            let warm = Instant::now();
            for i in 0.. {
                if i >= 2 && warm.elapsed().as_secs_f64() >= args.warmup_seconds {
                    break;
                }
                p = call()?;
            }
            let mut times = Vec::new();
            let started = Instant::now();
            while times.len() < 5 || started.elapsed().as_secs_f64() < args.seconds {
                let t = Instant::now();
                p = call()?;
                times.push(t.elapsed().as_secs_f64());
            }
            let mean_p = p.iter().map(|&v| f64::from(v)).sum::<f64>() / batch as f64;
            Ok((times, mean_p))
        })?;
        let median_s = median(times.clone());
        let line = serde_json::json!({
            "runtime": "rust",
            "model": model,
            "architecture": arch.name,
            "pose_inputs": pose_inputs,
            "threads": args.threads,
            "batch": batch,
            "calls": times.len(),
            "median_s": median_s,
            "crops_per_s": batch as f64 / median_s,
            "mean_p": mean_p,
        });
        println!("{line}");
    }
    Ok(())
}

/// SplitMix64, as `bench_torch.py` has it: the same numbers in both.
struct SplitMix64(u64);

impl SplitMix64 {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `[lo, hi)`, computed in f64 and rounded once to f32.
    fn uniform(&mut self, lo: f64, hi: f64) -> f32 {
        let unit = (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
        (lo + (hi - lo) * unit) as f32
    }
}

/// `batch` depth crops `[batch, 1, size, size]` (0.6..0.75 m) and poses `[batch, P]` (grasp
/// depth 0.6..0.75 m, then theta 0..1.57 rad): crops first, then poses, row by row.
fn inputs(batch: usize, size: usize, pose_inputs: usize, seed: u64) -> CliResult<(Tensor, Tensor)> {
    let mut rng = SplitMix64(seed);
    let depth = (0..batch * size * size)
        .map(|_| rng.uniform(0.6, 0.75))
        .collect();
    let pose = (0..batch * pose_inputs)
        .map(|i| match i % pose_inputs {
            0 => rng.uniform(0.6, 0.75),
            _ => rng.uniform(0.0, 1.57),
        })
        .collect();
    Ok((
        Tensor::new(&[batch, 1, size, size], depth)?,
        Tensor::new(&[batch, pose_inputs], pose)?,
    ))
}

fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    let n = values.len();
    match n {
        0 => f64::NAN,
        _ if n % 2 == 1 => values[n / 2],
        _ => 0.5 * (values[n / 2 - 1] + values[n / 2]),
    }
}
