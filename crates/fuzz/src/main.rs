//! `fuzz`: runs the fuzz targets (`list`, `run`, `replay`). See the crate's docs.

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use clap::{Parser, Subcommand};
use mvgrasp_fuzz::{
    TARGETS, Target, check_one, fuzz, regression_inputs, regressions_dir, target, work_folder,
};

#[derive(Parser)]
#[command(
    about = "Fuzz every reader of outside bytes in mvgrasp (stable Rust, no instrumentation)."
)]
struct Cli {
    #[command(subcommand)]
    command: Command_,
}

#[derive(Subcommand)]
enum Command_ {
    /// Lists the targets.
    List,
    /// Fuzzes each target (all, or those named) in its own process for a fixed time.
    Run {
        /// Seconds per target.
        #[arg(long, default_value_t = 600)]
        seconds: u64,
        /// Only these targets (repeatable).
        #[arg(long)]
        target: Vec<String>,
        /// The mutation seed.
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Where findings and the summary go.
        #[arg(long, default_value = "target/fuzz")]
        out: PathBuf,
    },
    /// Runs one target on files (a regression input, a finding) with every check.
    Replay {
        /// The target.
        target: String,
        /// Input files.
        files: Vec<PathBuf>,
    },
    /// Internal: one target's fuzz loop, run by `run` in a child process.
    #[command(hide = true)]
    Worker {
        target: String,
        seconds: u64,
        seed: u64,
        out: PathBuf,
    },
}

fn main() -> ExitCode {
    // Panics are findings, caught and reported by the loop: keep their noise off the terminal.
    std::panic::set_hook(Box::new(|_| {}));
    match Cli::parse().command {
        Command_::List => {
            for t in TARGETS {
                println!("{:<20} {}", t.name, t.about);
            }
            ExitCode::SUCCESS
        }
        Command_::Run {
            seconds,
            target,
            seed,
            out,
        } => run(seconds, &target, seed, &out),
        Command_::Replay {
            target: name,
            files,
        } => replay(&name, &files),
        Command_::Worker {
            target: name,
            seconds,
            seed,
            out,
        } => worker(&name, seconds, seed, &out),
    }
}

fn find(name: &str) -> Result<&'static Target, ExitCode> {
    target(name).ok_or_else(|| {
        let names: Vec<&str> = TARGETS.iter().map(|t| t.name).collect();
        eprintln!(
            "fuzz: no target {name:?}; the targets: {}",
            names.join(", ")
        );
        ExitCode::from(2)
    })
}

/// The long pass: each target in a child process; a child that dies (abort, stack overflow,
/// a hang the watchdog ends) is a crash, recorded with the input it was running.
fn run(seconds: u64, names: &[String], seed: u64, out: &Path) -> ExitCode {
    let targets: Vec<&Target> = if names.is_empty() {
        TARGETS.iter().collect()
    } else {
        match names.iter().map(|n| find(n)).collect::<Result<_, _>>() {
            Ok(t) => t,
            Err(code) => return code,
        }
    };
    let Ok(exe) = std::env::current_exe() else {
        eprintln!("fuzz: cannot find its own executable");
        return ExitCode::from(2);
    };
    if let Err(e) = std::fs::create_dir_all(out) {
        eprintln!("fuzz: cannot create {}: {e}", out.display());
        return ExitCode::from(2);
    }
    println!(
        "| target | seconds | executions | exec/s | accepted | outcomes | slowest (ms) | findings |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    let mut failed = 0;
    let mut rows = Vec::new();
    for t in targets {
        let started = Instant::now();
        let status = Command::new(&exe)
            .args(["worker", t.name, &seconds.to_string(), &seed.to_string()])
            .arg(out)
            .status();
        let summary_path = out.join(t.name).join("summary.json");
        let row = match (status, std::fs::read_to_string(&summary_path)) {
            (Ok(status), Ok(text)) if status.success() => {
                serde_json::from_str::<serde_json::Value>(&text).unwrap_or_default()
            }
            (status, _) => {
                // The child died: its last input is the work folder's file.
                let input = out.join(t.name).join("work").join(t.name).join(t.file_name);
                let saved = out.join(t.name).join("crash-input");
                let copied = std::fs::copy(&input, &saved).is_ok();
                serde_json::json!({
                    "executions": 0, "accepted": 0, "outcomes": 0, "slowest_ms": 0,
                    "findings": [format!("the process died ({status:?}) after {:.0} s{}",
                        started.elapsed().as_secs_f64(),
                        if copied { format!("; its input is {}", saved.display()) } else { String::new() })],
                })
            }
        };
        let findings = row["findings"].as_array().map_or(0, Vec::len);
        failed += usize::from(findings > 0);
        let executions = row["executions"].as_u64().unwrap_or(0);
        let line = format!(
            "| {} | {} | {} | {:.0} | {} | {} | {} | {} |",
            t.name,
            seconds,
            executions,
            executions as f64 / started.elapsed().as_secs_f64().max(1e-9),
            row["accepted"],
            row["outcomes"],
            row["slowest_ms"],
            findings
        );
        println!("{line}");
        for finding in row["findings"].as_array().into_iter().flatten() {
            println!("    {}", finding.as_str().unwrap_or_default());
        }
        rows.push(line);
    }
    let table = out.join("summary.md");
    let _ = std::fs::write(&table, rows.join("\n") + "\n");
    if failed > 0 {
        println!(
            "{failed} target(s) with findings; inputs under {}",
            out.display()
        );
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    }
}

/// One target's loop, with a watchdog that ends the process when one input runs over 10 s
/// (the parent then records a hang with the input on disk).
fn worker(name: &str, seconds: u64, seed: u64, out: &Path) -> ExitCode {
    let t = match find(name) {
        Ok(t) => t,
        Err(code) => return code,
    };
    let dir = out.join(t.name);
    let work = match work_folder(&dir.join("work"), t) {
        Ok(work) => work,
        Err(e) => {
            eprintln!("fuzz: cannot prepare {}: {e}", dir.display());
            return ExitCode::from(2);
        }
    };
    let started_input = Arc::new(Mutex::new(Instant::now()));
    let watched = Arc::clone(&started_input);
    std::thread::spawn(move || {
        loop {
            std::thread::sleep(Duration::from_millis(500));
            let running_for = watched.lock().map(|s| s.elapsed()).unwrap_or_default();
            if running_for > Duration::from_secs(10) {
                eprintln!("fuzz: an input ran over 10 s (a hang)");
                std::process::abort();
            }
        }
    });
    let extra: Vec<Vec<u8>> = regression_inputs(&regressions_dir(), t.name)
        .iter()
        .filter_map(|p| std::fs::read(p).ok())
        .collect();
    let summary = fuzz(t, &work, Duration::from_secs(seconds), seed, extra, |_| {
        if let Ok(mut s) = started_input.lock() {
            *s = Instant::now();
        }
    });
    let mut findings = Vec::new();
    for (i, finding) in summary.findings.iter().enumerate() {
        let path = dir.join(format!("finding-{i:02}"));
        let _ = std::fs::write(&path, &finding.input);
        findings.push(format!("{} ({})", finding.problem, path.display()));
    }
    let json = serde_json::json!({
        "executions": summary.executions,
        "accepted": summary.accepted,
        "outcomes": summary.outcomes,
        "corpus": summary.corpus,
        "slowest_ms": summary.slowest_ms,
        "findings": findings,
    });
    let written = std::fs::File::create(dir.join("summary.json"))
        .and_then(|mut f| f.write_all(json.to_string().as_bytes()));
    if let Err(e) = written {
        eprintln!("fuzz: cannot write {}: {e}", dir.display());
        return ExitCode::from(2);
    }
    ExitCode::SUCCESS
}

fn replay(name: &str, files: &[PathBuf]) -> ExitCode {
    let t = match find(name) {
        Ok(t) => t,
        Err(code) => return code,
    };
    let parent = std::env::temp_dir().join(format!("mvgrasp-fuzz-replay-{}", std::process::id()));
    let work = match work_folder(&parent, t) {
        Ok(work) => work,
        Err(e) => {
            eprintln!("fuzz: cannot prepare {}: {e}", parent.display());
            return ExitCode::from(2);
        }
    };
    let mut failed = false;
    for file in files {
        let input = match std::fs::read(file) {
            Ok(input) => input,
            Err(e) => {
                eprintln!("fuzz: cannot read {}: {e}", file.display());
                return ExitCode::from(2);
            }
        };
        match check_one(t, &work, &input) {
            Ok(outcome) => println!("{}: ok ({outcome:?})", file.display()),
            Err(problem) => {
                failed = true;
                println!("{}: FAILED: {problem}", file.display());
            }
        }
    }
    let _ = std::fs::remove_dir_all(&parent);
    if failed {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    }
}
