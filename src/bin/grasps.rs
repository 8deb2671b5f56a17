//! `grasps`: antipodal grasps on an object resting on a table, scored (force closure,
//! Ferrari-Canny epsilon, robust epsilon, Dex-Net 2.0's label) and checked in physics (close,
//! lift, shake with rapier); writes `grasps.json` and `grasps.png` (the best five).
//!
//! cargo run --release --bin grasps -- [--mesh PATH | --category C --index I] [--n 100]
//!     [--gripper panda|yumi|robotiq_2f_85|FILE] [--pose K] [--physics-trials N] [--out DIR]

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use clap::Parser;
use mvgrasp::cli::{CliResult, ObjectArgs};
use mvgrasp::geometry::RestingPoses;
use mvgrasp::grasp::physics::PhysicsParams;
use mvgrasp::grasp::{AnalysisConfig, GraspObject, Gripper, analyse};
use mvgrasp::grasp_image::write_grasp_picture;
use serde::Serialize;

/// Sample, score and physically check parallel-jaw grasps on one object.
#[derive(Parser, Debug)]
#[command(version, about)]
struct Args {
    #[command(flatten)]
    object: ObjectArgs,
    /// Grasps to sample (default: the config's `sampling.target_grasps`, 100).
    #[arg(long)]
    n: Option<usize>,
    /// Gripper: a preset (panda, yumi, robotiq_2f_85) or a .toml/.json file.
    #[arg(long, default_value = "panda")]
    gripper: String,
    /// The pose to rest the object in, among those offered (the same list as `plan
    /// --stable-pose`): 0, the default, is the most probable that is not marginal (a marginal
    /// one for an object with no other).
    #[arg(long)]
    pose: Option<usize>,
    /// Skip the physics trials.
    #[arg(long)]
    no_physics: bool,
    /// Perturbed physics trials per grasp (a success probability), beside the nominal one.
    #[arg(long, default_value_t = 0)]
    physics_trials: usize,
    /// A TOML file with the analysis parameters (sections sampling, quality, physics, ...).
    #[arg(long)]
    config: Option<PathBuf>,
    /// Folder for grasps.json and grasps.png.
    #[arg(long, default_value = "grasps_out")]
    out: PathBuf,
}

fn main() -> ExitCode {
    mvgrasp::cli::exit(run(&Args::parse()))
}

fn load_gripper(spec: &str) -> CliResult<Gripper> {
    Ok(Gripper::from_name_or_file(spec).map_err(|e| format!("--gripper: {e}"))?)
}

fn load_config(args: &Args) -> CliResult<AnalysisConfig> {
    let mut config = match &args.config {
        Some(path) => {
            let text = std::fs::read_to_string(path)
                .map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
            toml::from_str(&text).map_err(|e| {
                format!(
                    "{}: {}",
                    path.display(),
                    mvgrasp::geometry::one_line(&e.to_string())
                )
            })?
        }
        None => AnalysisConfig {
            physics: Some(PhysicsParams::default()),
            ..AnalysisConfig::default()
        },
    };
    if let Some(n) = args.n {
        config.sampling.target_grasps = n;
        config.sampling.max_tries = config.sampling.max_tries.max(40 * n);
    }
    if args.no_physics {
        config.physics = None;
    }
    config.physics_trials = args.physics_trials;
    Ok(config)
}

/// What `grasps.json` holds.
#[derive(Serialize)]
struct Output<'a> {
    object: &'a str,
    gripper: &'a Gripper,
    stable_pose: usize,
    stable_pose_probability: f32,
    config: &'a AnalysisConfig,
    seed: u64,
    analysis: &'a mvgrasp::grasp::Analysis,
}

fn run(args: &Args) -> CliResult<()> {
    let started = Instant::now();
    let gripper = load_gripper(&args.gripper)?;
    let config = load_config(args)?;
    let loaded = args.object.load()?;
    let name = &loaded.display_name;
    let rest = RestingPoses::of(&loaded.mesh)?;
    let k = args.pose.unwrap_or(0);
    let (pose_index, pose) = rest.get(k).map_err(|e| format!("--pose {k}: {e}"))?;
    if rest.only_marginal() {
        eprintln!("{name}: every stable pose is marginal (it rolls or topples): resting it in one");
    }
    let object = GraspObject::new(loaded.mesh)?;
    let analysis = analyse(
        &object,
        &pose.table_from_object,
        &gripper,
        &config,
        args.object.seed,
    )?;

    println!(
        "{name}: stable pose {pose_index} (p = {:.2}), gripper {}",
        pose.probability, gripper.name
    );
    println!("sampling: {}", analysis.sampling.summary());
    if analysis.grasps.is_empty() {
        println!("no feasible grasp for this gripper in this pose");
    }
    print_table(&analysis);

    std::fs::create_dir_all(&args.out)
        .map_err(|e| format!("{}: cannot create: {e}", args.out.display()))?;
    let output = Output {
        object: &loaded.name,
        gripper: &gripper,
        stable_pose: pose_index,
        stable_pose_probability: pose.probability,
        config: &config,
        seed: args.object.seed,
        analysis: &analysis,
    };
    let json_path = args.out.join("grasps.json");
    let json = serde_json::to_string_pretty(&output)?;
    std::fs::write(&json_path, json)
        .map_err(|e| format!("{}: cannot write: {e}", json_path.display()))?;
    let best: Vec<_> = analysis.grasps.iter().take(5).map(|g| g.grasp).collect();
    let png_path = args.out.join("grasps.png");
    match write_grasp_picture(
        &png_path,
        object.mesh(),
        &pose.table_from_object,
        &best,
        &gripper,
    ) {
        Ok(()) => println!("wrote {} and {}", json_path.display(), png_path.display()),
        Err(e) => println!("wrote {} (no picture: {e})", json_path.display()),
    }
    println!("{:.2} s", started.elapsed().as_secs_f64());
    Ok(())
}

fn print_table(analysis: &mvgrasp::grasp::Analysis) {
    let shown = analysis.grasps.len().min(10);
    if shown == 0 {
        return;
    }
    println!(
        "best {shown} of {} (by robust epsilon); world frame, table z = 0:",
        analysis.grasps.len()
    );
    println!(
        "  #  centre (cm)              width cm  closure  epsilon  robust eps  label  physics"
    );
    for (i, g) in analysis.grasps.iter().take(shown).enumerate() {
        let c = g.grasp.center() * 100.0;
        let physics = match (&g.physics, &g.physics_success) {
            (Some(o), Some(p)) => format!(
                "{} ({:.0}% of {})",
                if o.success { "held" } else { "failed" },
                100.0 * p.probability,
                p.trials
            ),
            (Some(o), None) => match o.failed_at {
                None => "held".into(),
                Some(stage) => format!("failed ({})", stage.name()),
            },
            _ => "-".into(),
        };
        println!(
            "{:>3}  ({:>6.2}, {:>6.2}, {:>5.2})  {:>8.2}  {:>7}  {:>7.4}  {:>10.4}  {:>5}  {physics}",
            i,
            c.x,
            c.y,
            c.z,
            g.grasp.width_m * 100.0,
            if g.quality.nominal_force_closure {
                "yes"
            } else {
                "no"
            },
            g.quality.nominal_epsilon,
            g.quality.robust_epsilon,
            if g.robust_label { "+" } else { "-" },
        );
    }
    let labelled: Vec<_> = analysis
        .grasps
        .iter()
        .filter(|g| g.physics.is_some())
        .collect();
    if !labelled.is_empty() {
        let count = |label: bool, held: bool| {
            labelled
                .iter()
                .filter(|g| g.robust_label == label && g.physics.is_some_and(|o| o.success) == held)
                .count()
        };
        println!(
            "robust label vs physics: +held {}  +failed {}  -held {}  -failed {}",
            count(true, true),
            count(true, false),
            count(false, true),
            count(false, false)
        );
    }
}
