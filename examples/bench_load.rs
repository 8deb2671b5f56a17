//! The planner as a long-lived object under load, in Rust (`scripts/bench_load.py` measures the
//! same from Python): one policy made once, one depth image planned on again and again, as the
//! Python `Planner.plan` does (`mvgrasp._native.plan_depth`: the table fitted in the image, the
//! top-down GQ-CNN, the hand check).
//!
//! 1. `--plans N` plans one after the other, the process's resident memory (VmRSS) sampled every
//!    N/20 plans: printed at the start, after the warm-up (the first 5%) and at the end, with
//!    the growth after the warm-up; and whether every plan gave the first one's grasps.
//! 2. `--thread-plans M` plans shared by 1, 2 and 4 threads (`std::thread::scope`, one policy
//!    borrowed by all): a table of plans/s, p50 and p99 latency, and whether every grasp equals
//!    the single-thread one (the same seed and image give the same `grasps.json` bytes).
//!
//! It fails (exit code 2) when any plan did not give the first plan's grasps.
//!
//! ```text
//! cargo run --release --example bench_load -- [--plans 10000] [--threads 1 2 4]
//!     [--thread-plans 400] [--data ../shared/data]
//! ```
//!
//! The image is gqcnn's real Primesense `depth_0.npy` under `DATA/real_depth` when it is there,
//! else a synthetic 4 x 6 cm box on a table 0.7 m below a Primesense (the Python tests' box).

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::{Duration, Instant};

use clap::Parser;
use mvgrasp::cli::CliResult;
use mvgrasp::geometry::{Camera, Intrinsics, IntrinsicsPreset, Pose3};
use mvgrasp::grasp::Gripper;
use mvgrasp::grasps_file::GraspsFile;
use mvgrasp::planner::{
    DepthImage, PlanOptions, Planner, SensorFiles, SensorPlanParams, View, models, plan_on_view,
    read_view,
};

#[derive(Parser, Debug)]
#[command(about)]
struct Args {
    /// Plans one after the other for the memory measurement.
    #[arg(long, default_value_t = 10_000)]
    plans: usize,
    /// The thread counts of the throughput table.
    #[arg(long, num_args = 1.., default_values_t = [1usize, 2, 4])]
    threads: Vec<usize>,
    /// Plans per row of the throughput table, shared by its threads.
    #[arg(long, default_value_t = 400)]
    thread_plans: usize,
    /// The shared data folder (the real depth image, when present).
    #[arg(long, default_value = "../shared/data")]
    data: PathBuf,
}

fn main() -> ExitCode {
    mvgrasp::cli::exit(run(&Args::parse()))
}

/// The long-lived planner: the planner, gripper and settings made once, and the image.
struct LongLived {
    planner: Planner,
    gripper: Gripper,
    params: SensorPlanParams,
    intrinsics: Intrinsics,
    depth_m: Vec<f32>,
}

impl LongLived {
    /// One plan as `plan_depth` runs it (the image copied in, as from NumPy); the
    /// `grasps.json` text.
    fn plan(&self) -> CliResult<String> {
        let camera = Camera {
            intrinsics: self.intrinsics,
            world_from_camera: Pose3::IDENTITY,
        };
        let depth = DepthImage::new(self.intrinsics, self.depth_m.clone())?;
        let view = View::new(0, camera, depth)?;
        let report = plan_on_view(&self.planner, &self.gripper, view, false, &self.params)?;
        Ok(GraspsFile::of_sensor(&report).to_json()?)
    }
}

/// The process's resident memory, MiB (VmRSS of /proc/self/status; 0 where there is none).
fn rss_mib() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find_map(|l| l.strip_prefix("VmRSS:"))
                .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<f64>().ok())
        })
        .map_or(0.0, |kib| kib / 1024.0)
}

/// The real Primesense image and its intrinsics, or the synthetic box on a table.
fn depth_image(data: &Path) -> CliResult<(String, Intrinsics, Vec<f32>)> {
    let root = data.join("real_depth/gqcnn/data");
    let files = SensorFiles {
        depth: root.join("examples/single_object/primesense/depth_0.npy"),
        intrinsics: root.join("calib/primesense/primesense.intr"),
        camera_pose: None,
        mask: None,
    };
    if files.depth.is_file() && files.intrinsics.is_file() {
        let view = read_view(&files)?;
        return Ok((
            format!("{} (real Primesense)", files.depth.display()),
            view.camera.intrinsics,
            view.depth.as_slice().to_vec(),
        ));
    }
    // A 4 x 6 cm box, 5 cm tall, on a table 0.7 m below a Primesense looking straight down.
    let k = Intrinsics::preset(IntrinsicsPreset::Primesense);
    let (w, h) = (k.width as usize, k.height as usize);
    let depth = (0..w * h)
        .map(|i| {
            let (u, v) = ((i % w) as f32, (i / w) as f32);
            let (x, y) = ((u - k.cx) * 0.65 / k.fx, (v - k.cy) * 0.65 / k.fy);
            if x.abs() < 0.02 && y.abs() < 0.03 {
                0.65
            } else {
                0.7
            }
        })
        .collect();
    Ok(("a synthetic box on a table (640 x 480)".into(), k, depth))
}

/// The `q`-quantile (0 to 1) of sorted `values`, nearest rank.
fn quantile(sorted: &[Duration], q: f64) -> f64 {
    let rank = ((q * sorted.len() as f64).ceil() as usize).clamp(1, sorted.len());
    sorted[rank - 1].as_secs_f64() * 1000.0
}

fn run(args: &Args) -> CliResult<()> {
    if args.plans == 0 || args.thread_plans == 0 || args.threads.contains(&0) {
        return Err("--plans, --thread-plans and --threads: at least 1".into());
    }
    let (source, intrinsics, depth_m) = depth_image(&args.data)?;
    let options = PlanOptions::default();
    let net = models::GQCNN_TOPDOWN.load()?;
    let (planner, gripper, params) = options.on_depth(net)?;
    let planner = LongLived {
        planner,
        gripper,
        params,
        intrinsics,
        depth_m,
    };
    println!(
        "image: {source}; {} cores, rayon {} threads",
        std::thread::available_parallelism().map_or(1, |n| n.get()),
        rayon::current_num_threads()
    );

    // 1. Memory over many plans one after the other.
    let n = args.plans;
    let every = (n / 20).max(1);
    let warm_up = (n / 20).max(1);
    let rss_start = rss_mib();
    let reference = planner.plan()?;
    let mut rss_warm = rss_start;
    let mut samples = Vec::new();
    let mut differing = 0usize;
    // Plans that did not give the first plan's grasps, over both parts: the example fails on
    // any (the same seed and image give the same bytes, on any thread).
    let mut total_differing = 0usize;
    let started = Instant::now();
    for i in 1..=n {
        if planner.plan()? != reference {
            differing += 1;
        }
        if i == warm_up {
            rss_warm = rss_mib();
        }
        if i % every == 0 || i == n {
            samples.push((i, rss_mib()));
        }
    }
    let elapsed = started.elapsed().as_secs_f64();
    let rss_end = rss_mib();
    let peak = samples.iter().map(|s| s.1).fold(rss_warm, f64::max);
    println!(
        "\n{n} plans one after the other in {elapsed:.1} s ({:.1} ms a plan)",
        1000.0 * elapsed / n as f64
    );
    let trace: Vec<String> = samples.iter().map(|(_, r)| format!("{r:.0}")).collect();
    println!("RSS every {every} plans, MiB: {}", trace.join(" "));
    println!(
        "RSS: start {rss_start:.1} MiB, after warm-up ({warm_up} plans) {rss_warm:.1} MiB, end \
         {rss_end:.1} MiB (peak after warm-up {peak:.1}); growth after warm-up {:+.1} MiB",
        rss_end - rss_warm
    );
    println!(
        "every plan gave the first one's grasps: {}",
        if differing == 0 {
            "yes".to_string()
        } else {
            format!("no ({differing} of {n} differ)")
        }
    );

    total_differing += differing;

    // 2. Throughput and latency with 1, 2, 4 threads sharing the planner.
    println!(
        "\n{} plans per row, shared by the threads (Rust, std::thread::scope)\n",
        args.thread_plans
    );
    println!("| threads | plans/s | p50 ms | p99 ms | same grasps as one thread |");
    println!("|---|---|---|---|---|");
    for &threads in &args.threads {
        let started = Instant::now();
        let per_thread: Vec<CliResult<(Vec<Duration>, usize)>> = std::thread::scope(|s| {
            let handles: Vec<_> = (0..threads)
                .map(|t| {
                    let (planner, reference) = (&planner, &reference);
                    // Thread t plans t, t + threads, ...: thread_plans in all.
                    let count = (t..args.thread_plans).step_by(threads).count();
                    s.spawn(move || -> CliResult<(Vec<Duration>, usize)> {
                        let mut latencies = Vec::with_capacity(count);
                        let mut differing = 0;
                        for _ in 0..count {
                            let t0 = Instant::now();
                            let json = planner.plan()?;
                            latencies.push(t0.elapsed());
                            differing += usize::from(json != *reference);
                        }
                        Ok((latencies, differing))
                    })
                })
                .collect();
            handles
                .into_iter()
                .map(|h| h.join().unwrap_or_else(|_| Err("a thread panicked".into())))
                .collect()
        });
        let wall = started.elapsed().as_secs_f64();
        let mut latencies = Vec::new();
        let mut differing = 0;
        for result in per_thread {
            let (l, d) = result?;
            latencies.extend(l);
            differing += d;
        }
        latencies.sort();
        total_differing += differing;
        println!(
            "| {threads} | {:.1} | {:.1} | {:.1} | {} |",
            latencies.len() as f64 / wall,
            quantile(&latencies, 0.5),
            quantile(&latencies, 0.99),
            if differing == 0 {
                "yes".to_string()
            } else {
                format!("no ({differing} differ)")
            }
        );
    }
    if total_differing > 0 {
        return Err(format!(
            "{total_differing} plans did not give the first plan's grasps: the planner is not \
             deterministic"
        )
        .into());
    }
    Ok(())
}
