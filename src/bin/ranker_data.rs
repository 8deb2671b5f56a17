//! `ranker_data`: the data the multi-view planner's ranker is fitted on
//! (`training/scripts/fit_ranker.py`): on each object of the sets, at rest in its most
//! probable pose, the default run's planner on rendered depth without the ranker, every
//! candidate it re-scored tried in the physics trial (`mvgrasp::ranker_data`).
//!
//! ```text
//! cargo run --release --bin ranker_data -- --out ../datasets/ranker/fit [--set builtin:60]
//!     [--per-category 10] [--ranked] [--data ../shared/data/meshes] [--max-meshes 0]
//! ```
//!
//! Writes `OUT/rescored.jsonl` (one candidate a line, objects in the sets' order) from the
//! records in `OUT/records.jsonl`, one per object as it finishes: run the same command again
//! after an interruption and it takes up where it stopped (the same settings give the same
//! bytes).

use std::path::PathBuf;
use std::process::ExitCode;

use clap::Parser;
use mvgrasp::cli::{CliResult, objects_of_sets};
use mvgrasp::evaluate::journal::Journal;
use mvgrasp::grasp_dataset::shard::write_atomically;
use mvgrasp::ranker_data::{RankerData, RankerSample};
use mvgrasp::render::{Backend, Renderer};

/// Make the multi-view planner's ranker data: its re-scored candidates tried in physics.
#[derive(Parser, Debug)]
#[command(name = "ranker_data", version, about)]
struct Args {
    /// The data folder (created; finished objects are kept).
    #[arg(long)]
    out: PathBuf,
    /// An object set (repeat), as `evaluate --set` names them. Default: builtin:60 (built-in
    /// objects from index 60, past every training, evaluation and development index).
    #[arg(long = "set")]
    sets: Vec<String>,
    /// Built-in objects per category in the built-in sets.
    #[arg(long, default_value_t = 10)]
    per_category: u32,
    /// The shared mesh folder the `real` and `dev-real` sets read.
    #[arg(long, default_value = "../shared/data/meshes")]
    data: PathBuf,
    /// At most this many meshes of each file set (0: all).
    #[arg(long, default_value_t = 0)]
    max_meshes: usize,
    /// Order the candidates by the shipped ranker (to measure it) instead of the re-score.
    #[arg(long)]
    ranked: bool,
}

fn main() -> ExitCode {
    mvgrasp::cli::exit(run(&Args::parse()))
}

fn run(args: &Args) -> CliResult<()> {
    let names = if args.sets.is_empty() {
        vec!["builtin:60".to_string()]
    } else {
        args.sets.clone()
    };
    let found = objects_of_sets(&names, args.per_category, &args.data, args.max_meshes)?;
    if found.is_empty() {
        return Err(format!(
            "no objects in {} (--data {})",
            names.join(", "),
            args.data.display()
        )
        .into());
    }
    std::fs::create_dir_all(&args.out).map_err(|e| format!("{}: {e}", args.out.display()))?;
    let journal = Journal::open(&args.out.join("records.jsonl"))?;
    let renderer = Renderer::new(Backend::Auto)?;
    // The planner, made only when some object is missing.
    let mut data: Option<RankerData> = None;
    let mut all: Vec<RankerSample> = Vec::new();
    let mut skipped = 0;
    for (done, object) in found.iter().enumerate() {
        // The key names the ordering, so that a ranked run does not take unranked records.
        let key = format!(
            "ranker|{}|{}|{}",
            if args.ranked { "ranked" } else { "rescored" },
            object.set,
            object.name
        );
        let samples: Vec<RankerSample> = match journal.get(&key)? {
            Some(samples) => samples,
            None => {
                let data = match data {
                    Some(ref data) => data,
                    None => data.insert(RankerData::new(args.ranked)?),
                };
                // An object the planner or the trial refuses (a broken or oversized mesh) is
                // reported and left out, as the evaluation leaves it out.
                let made = object
                    .load()
                    .and_then(|mesh| data.samples(&renderer, &object.name, &mesh));
                match made {
                    Ok(samples) => journal.put(&key, &samples)?,
                    Err(e) => {
                        eprintln!("skipping {} {}: {e}", object.set, object.name);
                        skipped += 1;
                        continue;
                    }
                }
            }
        };
        let held = samples.iter().filter(|s| s.held == Some(true)).count();
        eprintln!(
            "[{}/{}] {} {}: {} candidates, {held} held",
            done + 1,
            found.len(),
            object.set,
            object.name,
            samples.len()
        );
        all.extend(samples);
    }
    let path = args.out.join("rescored.jsonl");
    let mut lines = String::new();
    for sample in &all {
        lines.push_str(&serde_json::to_string(sample)?);
        lines.push('\n');
    }
    write_atomically(&path, lines.as_bytes())?;
    let held = all.iter().filter(|s| s.held == Some(true)).count();
    let tried = all
        .iter()
        .filter(|s| s.held.is_some() && s.failed_at.as_deref() != Some("Settle"))
        .count();
    println!(
        "{} objects ({skipped} skipped), {} candidates ({held} held of {tried} tried): {}",
        found.len() - skipped,
        all.len(),
        path.display()
    );
    Ok(())
}
