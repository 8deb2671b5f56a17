//! The fuzz loop: run a target on an input with every check, keep the inputs that reach a new
//! outcome, mutate, repeat until the time is up.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::alloc;
use crate::mutate::mutate;
use crate::targets::Target;

/// An input that takes longer than this is a finding (the "hang over 1 s").
pub const SLOW: Duration = Duration::from_secs(1);

/// A single allocation larger than this is a finding: no file a reader is given justifies it
/// (a 4096 x 4096 float64 depth image is 128 MiB).
pub const LARGEST_ALLOCATION_BYTES: usize = 256 << 20;

/// The corpus keeps at most this many inputs (the seeds and the first input of each outcome).
const MAX_CORPUS: usize = 2048;

/// What one input did.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// The reader accepted it.
    Accepted,
    /// The reader refused it with this message.
    Refused(String),
}

/// A check an input failed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Finding {
    /// The target.
    pub target: String,
    /// What went wrong, one line.
    pub problem: String,
    /// The input.
    pub input: Vec<u8>,
}

/// Runs `target` on `input` (written to the target's file in `work`) with every check: no
/// panic, under [`SLOW`], no allocation over [`LARGEST_ALLOCATION_BYTES`], and a refusal is one
/// line that names the file it is about (a path inside `work`).
///
/// # Errors
/// The problem, one line.
pub fn check_one(target: &Target, work: &Path, input: &[u8]) -> Result<Outcome, String> {
    let path = work.join(target.file_name);
    std::fs::write(&path, input).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    let live = alloc::reset();
    let start = Instant::now();
    let result = std::panic::catch_unwind(|| (target.run)(&path));
    let elapsed = start.elapsed();
    let usage = alloc::usage(live);
    let outcome = match result {
        Ok(Ok(())) => Outcome::Accepted,
        Ok(Err(message)) => Outcome::Refused(message),
        Err(payload) => {
            let message = payload
                .downcast_ref::<&str>()
                .map(ToString::to_string)
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_default();
            return Err(format!("panic: {message}"));
        }
    };
    if elapsed > SLOW {
        return Err(format!("slow: {} ms", elapsed.as_millis()));
    }
    if usage.largest_bytes > LARGEST_ALLOCATION_BYTES {
        return Err(format!(
            "allocated {} MiB at once for a {}-byte input",
            usage.largest_bytes >> 20,
            input.len()
        ));
    }
    if let Outcome::Refused(message) = &outcome {
        let work_text = work.display().to_string();
        if !message.contains(&work_text) && !message.contains(target.file_name) {
            return Err(format!("the error names no file: {message}"));
        }
        if message.contains('\n') {
            return Err(format!("the error is not one line: {message:?}"));
        }
    }
    Ok(outcome)
}

/// What a fuzz run did.
#[derive(Clone, Debug, Default)]
pub struct Summary {
    /// Inputs run.
    pub executions: u64,
    /// Inputs the reader accepted.
    pub accepted: u64,
    /// Distinct outcomes seen (accepted, and each refusal with numbers and paths blanked).
    pub outcomes: usize,
    /// Inputs in the corpus at the end.
    pub corpus: usize,
    /// Inputs that failed a check (at most one per distinct problem).
    pub findings: Vec<Finding>,
    /// The slowest input, milliseconds.
    pub slowest_ms: u128,
}

/// An outcome with the numbers and the work folder blanked: the fuzz loop's stand-in for
/// coverage (an input whose refusal reads differently went somewhere new).
fn signature(outcome: &Outcome, work: &Path) -> String {
    match outcome {
        Outcome::Accepted => "accepted".into(),
        Outcome::Refused(message) => {
            let message = message.replace(&work.display().to_string(), "");
            let mut blanked = String::with_capacity(message.len());
            // What a message quotes from the input (`key`, "value") is the input, not a path.
            let mut quoted: Option<char> = None;
            for c in message.chars() {
                if let Some(close) = quoted {
                    if c == close {
                        quoted = None;
                        blanked.push(c);
                    }
                    continue;
                }
                if matches!(c, '`' | '"') {
                    quoted = Some(c);
                    blanked.push(c);
                } else if c.is_ascii_digit() {
                    if !blanked.ends_with('#') {
                        blanked.push('#');
                    }
                } else {
                    blanked.push(c);
                }
            }
            blanked.chars().take(160).collect()
        }
    }
}

/// Fuzzes `target` for `budget` from its seeds (and `extra_seeds`), deterministically for a
/// `seed` apart from where the time runs out. `on_input` is called with each input before it
/// runs (the driver's watchdog keeps it).
pub fn fuzz(
    target: &Target,
    work: &Path,
    budget: Duration,
    seed: u64,
    extra_seeds: Vec<Vec<u8>>,
    mut on_input: impl FnMut(&[u8]),
) -> Summary {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut summary = Summary::default();
    let mut seen = BTreeSet::new();
    let mut problems = BTreeSet::new();
    let mut corpus: Vec<Vec<u8>> = (target.seeds)();
    corpus.extend(extra_seeds);
    let start = Instant::now();
    let mut queue: Vec<Vec<u8>> = corpus.clone();
    while start.elapsed() < budget {
        let input = queue.pop().unwrap_or_else(|| {
            let mut input = corpus[rng.random_range(0..corpus.len())].clone();
            mutate(
                &mut input,
                &corpus,
                target.dictionary,
                target.max_len,
                &mut rng,
            );
            input
        });
        on_input(&input);
        let run_start = Instant::now();
        let checked = check_one(target, work, &input);
        summary.slowest_ms = summary.slowest_ms.max(run_start.elapsed().as_millis());
        summary.executions += 1;
        match checked {
            Ok(outcome) => {
                summary.accepted += u64::from(outcome == Outcome::Accepted);
                if seen.insert(signature(&outcome, work)) && corpus.len() < MAX_CORPUS {
                    corpus.push(input);
                }
            }
            Err(problem) => {
                let key = signature(&Outcome::Refused(problem.clone()), work);
                if problems.insert(key) {
                    summary.findings.push(Finding {
                        target: target.name.into(),
                        problem,
                        input,
                    });
                }
            }
        }
        if corpus.is_empty() {
            corpus.push(Vec::new());
        }
    }
    summary.outcomes = seen.len();
    summary.corpus = corpus.len();
    summary
}

/// The committed regression inputs of a target: `regressions/<target>/*`.
pub fn regression_inputs(root: &Path, target: &str) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(root.join(target))
        .map(|entries| {
            entries
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.is_file())
                .collect()
        })
        .unwrap_or_default();
    files.sort();
    files
}
