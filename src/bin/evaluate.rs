//! `evaluate`: the project's evaluation from one command, into a report folder.
//!
//! ```text
//! cargo run --release --bin evaluate                       # the small default: minutes
//! cargo run --release --bin evaluate -- --full --out report-full
//! cargo run --release --bin evaluate -- --set real --policy rgb --policy depth-fused --seeds 0,1,2
//! ```
//!
//! Writes `OUT/report.md`, `OUT/report.html` (self-contained), `OUT/results.json` (every
//! record), `OUT/pictures/` and its records `OUT/records.jsonl`: run the same command again
//! after an interruption and it takes up where it stopped (the same settings and seeds give
//! the same bytes). See `mvgrasp::evaluate`.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::Parser;
use indicatif::{ProgressBar, ProgressStyle};
use mvgrasp::cli::CliResult;
use mvgrasp::evaluate::grasps::POLICIES;
use mvgrasp::evaluate::{EvalConfig, Lines, Progress, RunOptions, Shard, evaluate_with};

/// Evaluate the planners on held-out and real objects, checked in the project's trial, and
/// write a report folder.
#[derive(Parser, Debug)]
#[command(name = "evaluate", version, about)]
struct Args {
    /// The report folder (created; a folder of another run's settings is refused).
    #[arg(long, default_value = "report")]
    out: PathBuf,
    /// The full evaluation: 5 held-out built-in objects per category and every real mesh,
    /// every resting pose of at least 5%, seeds 0, 1 and 2, the exhaustive search for
    /// coverage, the policies rgb, depth, rgb-fused and depth-fused, 50 clutter rounds of
    /// each scene from 1 and 5 views, 20 grasps' labels per object judged by 50 trials, and
    /// 15 timed plans per policy (hours on 2 cores).
    /// Options given beside it override its choices.
    #[arg(long)]
    full: bool,
    /// An object set (repeat): held-out (built-in objects past every training index), dev
    /// (built-in, where settings are chosen), real (every real mesh of --data), dev-real (50
    /// of pybullet's random_urdfs in --data, real meshes where settings are chosen),
    /// builtin:N (built-in objects from index N), or folder:PATH. Default: held-out and real.
    #[arg(long = "set")]
    sets: Vec<String>,
    /// Built-in objects per category in the built-in sets (default 1; --full: 5).
    #[arg(long)]
    per_category: Option<u32>,
    /// The shared mesh folder (`real` takes every real mesh found there).
    #[arg(long, default_value = "../shared/data/meshes")]
    data: PathBuf,
    /// At most this many meshes of each file set (real, dev-real, folder:PATH; 0: all; default 6,
    /// --full: all).
    #[arg(long)]
    max_meshes: Option<usize>,
    /// A policy (repeat): rgb-fused (the default run: the multi-view planner on the plane
    /// sweep's depth from RGB views), depth-fused (the same on rendered depth), rgb and depth
    /// (the top-down GQ-CNN alone: `plan --no-fuse`), lsm, lsm-fused, mvs, mvs-fused,
    /// refined, refined-fused. Default: rgb-fused and depth-fused.
    #[arg(long = "policy")]
    policies: Vec<String>,
    /// The plans' seeds (default 0; --full: 0,1,2).
    #[arg(long, value_delimiter = ',')]
    seeds: Vec<u64>,
    /// Every offered resting pose of at least 5% probability, not only the most probable.
    #[arg(long)]
    all_poses: bool,
    /// The exhaustive search on the true mesh for a grasp that holds (coverage).
    #[arg(long)]
    coverage: bool,
    /// A suite (repeat): grasps (plans checked in the trial), depth (depth from RGB against
    /// the rendered depth), clutter (VGN and GIGA's clutter-removal rounds, packed, pile and
    /// bin, drawn from the object sets), labels (the robust and physics labels of sampled
    /// grasps against an outcome of more trials), speed (each stage's median on the default
    /// object, and the networks beside torch where it installs). Default: all five.
    #[arg(long = "suite")]
    suites: Vec<String>,
    /// The depth suite's numbers of input views (default: 1,3,5,9).
    #[arg(long, value_delimiter = ',')]
    depth_views: Vec<usize>,
    /// The depth suite's camera distance, metres (default: 0.5, the paper's test views).
    #[arg(long)]
    depth_distance_m: Option<f32>,
    /// The depth suite's views with the photographic look (textures, gloss, room lights, a
    /// background, sensor noise, blur, JPEG) instead of random colours.
    #[arg(long)]
    depth_photo: bool,
    /// A clutter scene (repeat): packed, pile, bin (default all three).
    #[arg(long = "clutter-scene")]
    clutter_scenes: Vec<String>,
    /// The clutter suite's numbers of depth views: 1 plans with the top-down GQ-CNN alone, more
    /// fuse the top-down view and cameras 50 degrees up around (default: 1; --full: 1,5).
    #[arg(long, value_delimiter = ',')]
    clutter_views: Vec<usize>,
    /// Clutter rounds per scene and number of views (default 5; --full: 50).
    #[arg(long)]
    clutter_rounds: Option<usize>,
    /// Objects per clutter round (default 5, as VGN and GIGA).
    #[arg(long)]
    clutter_objects: Option<usize>,
    /// The clutter suite's cameras: phoxi_s (default), primesense or realsense_d435.
    #[arg(long)]
    clutter_camera: Option<String>,
    /// Their distance from the table's centre, metres (default 0.7).
    #[arg(long)]
    clutter_distance_m: Option<f32>,
    /// The clutter suite's top-down GQ-CNN sees each grasp's crop as from within its training
    /// cameras' distances (0.65-0.75 m): the window scaled to the metres it spans there and
    /// its depths shifted (for cameras nearer or farther than the network was trained at).
    #[arg(long)]
    clutter_training_depths: bool,
    /// The clutter suite's depth from RGB views instead of rendered depth, by this method:
    /// baseline (the plane sweep, as the default run), refined, mvs or lsm. The objects are
    /// rendered in random colours and the method given the foreground as its masks; every
    /// --clutter-views at least 2.
    #[arg(long)]
    clutter_depth_from: Option<String>,
    /// The labels suite's grasps sampled per object (default 10; --full: 20).
    #[arg(long)]
    label_grasps: Option<usize>,
    /// Its perturbed trials of the physics label (default 10).
    #[arg(long)]
    label_trials: Option<usize>,
    /// Its perturbed trials of the outcome the labels are judged by (default 20; --full: 50).
    #[arg(long)]
    label_outcome_trials: Option<usize>,
    /// The speed suite's timed plans per policy (default 5; --full: 15).
    #[arg(long)]
    speed_runs: Option<usize>,
    /// Objects evaluated at once, each on its own thread (the records and the report are the
    /// same whatever the number; the planner's own stages use every core either way).
    #[arg(long, default_value_t = 1)]
    jobs: usize,
    /// Run only shard K of N (K/N, from 0) of the objects and clutter rounds, for a run spread
    /// over machines that share the report folder: each appends its records to
    /// OUT/shards/K-of-N.jsonl and writes no report; the same command without --shard then
    /// takes every shard's records and writes the report (scripts/evaluate_ray.py does this on
    /// a Ray cluster).
    #[arg(long)]
    shard: Option<Shard>,
    /// Plain progress lines even on a terminal.
    #[arg(long)]
    plain: bool,
}

struct Bar(ProgressBar);

impl Progress for Bar {
    fn step(&mut self, done: usize, total: usize, what: &str) {
        self.0.set_length(total as u64);
        self.0.set_position(done as u64);
        self.0.set_message(what.to_string());
    }
}

fn main() -> ExitCode {
    mvgrasp::cli::exit(run(&Args::parse()))
}

fn config_of(args: &Args) -> EvalConfig {
    let mut config = EvalConfig::small(args.data.clone());
    if args.full {
        config.per_category = 5;
        config.seeds = vec![0, 1, 2];
        config.all_poses = true;
        config.coverage = true;
        config.max_meshes = 0;
        config.policies = ["rgb", "depth", "rgb-fused", "depth-fused"]
            .map(String::from)
            .to_vec();
        config.clutter_views = vec![1, 5];
        config.clutter_rounds = 50;
        config.label_grasps = 20;
        config.label_outcome_trials = 50;
        config.speed_runs = 15;
    }
    if !args.sets.is_empty() {
        config.sets.clone_from(&args.sets);
    }
    if let Some(n) = args.per_category {
        config.per_category = n;
    }
    if let Some(n) = args.max_meshes {
        config.max_meshes = n;
    }
    if !args.policies.is_empty() {
        config.policies.clone_from(&args.policies);
    }
    if !args.seeds.is_empty() {
        config.seeds.clone_from(&args.seeds);
    }
    if !args.suites.is_empty() {
        config.suites.clone_from(&args.suites);
    }
    if !args.depth_views.is_empty() {
        config.depth_views.clone_from(&args.depth_views);
    }
    if let Some(d) = args.depth_distance_m {
        config.depth_distance_m = d;
    }
    if !args.clutter_scenes.is_empty() {
        config.clutter_scenes.clone_from(&args.clutter_scenes);
    }
    if !args.clutter_views.is_empty() {
        config.clutter_views.clone_from(&args.clutter_views);
    }
    if let Some(n) = args.clutter_rounds {
        config.clutter_rounds = n;
    }
    if let Some(n) = args.clutter_objects {
        config.clutter_objects = n;
    }
    if let Some(c) = &args.clutter_camera {
        config.clutter_camera.clone_from(c);
    }
    if let Some(d) = args.clutter_distance_m {
        config.clutter_distance_m = d;
    }
    if let Some(n) = args.label_grasps {
        config.label_grasps = n;
    }
    if let Some(n) = args.label_trials {
        config.label_trials = n;
    }
    if let Some(n) = args.label_outcome_trials {
        config.label_outcome_trials = n;
    }
    if let Some(n) = args.speed_runs {
        config.speed_runs = n;
    }
    if let Some(from) = &args.clutter_depth_from {
        config.clutter_depth_from = Some(from.clone());
    }
    config.all_poses |= args.all_poses;
    config.depth_photo |= args.depth_photo;
    config.clutter_training_depths |= args.clutter_training_depths;
    config.coverage |= args.coverage;
    config
}

fn run(args: &Args) -> CliResult<()> {
    let config = config_of(args);
    let known: Vec<&str> = POLICIES.iter().map(|(n, ..)| *n).collect();
    if let Some(p) = config
        .policies
        .iter()
        .find(|p| !known.contains(&p.as_str()))
    {
        return Err(format!("--policy {p}: expected one of {}", known.join(", ")).into());
    }
    if args.jobs == 0 {
        return Err("--jobs 0: expected at least 1".into());
    }
    let mut progress: Box<dyn Progress> = if std::io::stderr().is_terminal() && !args.plain {
        let bar = ProgressBar::new(0);
        bar.set_style(
            ProgressStyle::with_template("{bar:30} {pos}/{len} objects, {eta} left  {msg}")
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        Box::new(Bar(bar))
    } else {
        Box::new(Lines)
    };
    let run = RunOptions {
        jobs: args.jobs,
        shard: args.shard,
    };
    let results = evaluate_with(&config, &args.out, progress.as_mut(), run)?;
    if let Some(shard) = args.shard {
        println!(
            "shard {} of {}: {} plans, {} depth records, {} clutter rounds, {} labelled grasps \
             recorded in {}",
            shard.index,
            shard.count,
            results.grasps.len(),
            results.depth.len(),
            results.clutter.len(),
            results.labels.len(),
            args.out.join("shards").display()
        );
        return Ok(());
    }
    for (object, why) in &results.skipped {
        eprintln!("not evaluated: {object}: {why}");
    }
    println!(
        "{} plans on {} objects and poses, {} depth records, {} clutter rounds, {} labelled \
         grasps{}: {}",
        results.grasps.len(),
        results.objects.len(),
        results.depth.len(),
        results.clutter.len(),
        results.labels.len(),
        if results.speed.is_some() {
            ", timings"
        } else {
            ""
        },
        args.out.join("report.md").display()
    );
    Ok(())
}
