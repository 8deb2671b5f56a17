//! Grasp analysis on real meshes: per object, the antipodal grasps found, the fraction that
//! Dex-Net 2.0's robust label calls positive, and how that label agrees with physics (a rapier
//! close-lift-shake trial per grasp): the confusion table of issue 4.
//!
//! cargo run --release --example grasp_eval -- [--n 100] [--seed 0] [--data ../shared/data/meshes]
//!     [--json OUT.json]
//!
//! Meshes missing from the data folder are skipped with a note.

mod common;

use common::{EvalArgs, REAL_MESHES, Rested, analyse_at_rest};
use std::process::ExitCode;
use std::time::Instant;

use clap::Parser;
use mvgrasp::cli::CliResult;
use mvgrasp::geometry::load_mesh;
use mvgrasp::grasp::physics::{PhysicsParams, StageCounts};
use mvgrasp::grasp::{AnalysisConfig, Gripper};
use serde::Serialize;

/// Evaluate robust labels against physics on real meshes.
#[derive(Parser, Debug)]
struct Args {
    /// Grasps sampled per object.
    #[arg(long, default_value_t = 100)]
    n: usize,
    #[command(flatten)]
    eval: EvalArgs,
}

/// One object's figures.
#[derive(Serialize, Default)]
struct Row {
    object: String,
    stable_pose: usize,
    tries: usize,
    grasps: usize,
    positives: usize,
    /// [label +, held], [label +, failed], [label -, held], [label -, failed].
    confusion: [usize; 4],
    /// Failed trials by stage.
    failures: StageCounts,
    seconds: f64,
}

fn main() -> ExitCode {
    mvgrasp::cli::exit(run(&Args::parse()))
}

fn run(args: &Args) -> CliResult<()> {
    let config = AnalysisConfig {
        sampling: mvgrasp::grasp::SamplingParams {
            target_grasps: args.n,
            max_tries: 40 * args.n,
            ..Default::default()
        },
        physics: Some(PhysicsParams::default()),
        ..AnalysisConfig::default()
    };
    let gripper = Gripper::default();
    let mut rows = Vec::new();
    println!(
        "| object | pose | tries | grasps | robust + | +held | +failed | -held | -failed | agreement | failures (settle/approach/close/lift/shake) | s |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|");
    for relative in &REAL_MESHES[..12] {
        let path = args.eval.data.join(relative);
        if !path.exists() {
            eprintln!("skipping {} (not found)", path.display());
            continue;
        }
        let started = Instant::now();
        let mesh = load_mesh(&path)?;
        let Some(Rested {
            pose_index,
            analysis,
            ..
        }) = analyse_at_rest(relative, mesh, &gripper, &config, args.eval.seed)?
        else {
            continue;
        };
        let mut row = Row {
            object: relative.rsplit('/').next().unwrap_or(relative).to_string(),
            stable_pose: pose_index,
            tries: analysis.sampling.tries,
            grasps: analysis.grasps.len(),
            ..Row::default()
        };
        for g in &analysis.grasps {
            row.positives += usize::from(g.robust_label);
            let Some(outcome) = g.physics else { continue };
            let cell = match (g.robust_label, outcome.success) {
                (true, true) => 0,
                (true, false) => 1,
                (false, true) => 2,
                (false, false) => 3,
            };
            row.confusion[cell] += 1;
            if let Some(stage) = outcome.failed_at {
                row.failures.count(stage);
            }
        }
        row.seconds = started.elapsed().as_secs_f64();
        print_row(&row);
        rows.push(row);
    }
    let mut total = Row {
        object: "all".into(),
        ..Row::default()
    };
    for row in &rows {
        total.tries += row.tries;
        total.grasps += row.grasps;
        total.positives += row.positives;
        for i in 0..4 {
            total.confusion[i] += row.confusion[i];
        }
        total.failures += row.failures;
        total.seconds += row.seconds;
    }
    print_row(&total);
    if let Some(path) = &args.eval.json {
        let json = serde_json::to_string_pretty(&rows)?;
        std::fs::write(path, json).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    Ok(())
}

fn print_row(row: &Row) {
    let [ph, pf, nh, nf] = row.confusion;
    let judged = ph + pf + nh + nf;
    let percent = |a: usize, b: usize| {
        if b == 0 {
            "-".to_string()
        } else {
            format!("{:.0}%", 100.0 * a as f64 / b as f64)
        }
    };
    let f = &row.failures;
    println!(
        "| {} | {} | {} | {} | {} | {ph} | {pf} | {nh} | {nf} | {} | {}/{}/{}/{}/{} | {:.1} |",
        row.object,
        row.stable_pose,
        row.tries,
        row.grasps,
        percent(row.positives, row.grasps),
        percent(ph + nf, judged),
        f.settle,
        f.approach,
        f.close,
        f.lift,
        f.shake,
        row.seconds
    );
}
