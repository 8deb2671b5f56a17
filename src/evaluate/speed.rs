//! The speed suite: how long each stage of a plan takes on this machine, and the networks
//! beside their torch twins.
//!
//! Each policy plans on the default run's object (the built-in mug, in its most probable
//! resting pose) once to warm up and then `runs` times with the same seed; each stage's median
//! is recorded ([`crate::planner::PlanTimings`]: rendering the views, predicting their depth
//! from RGB, fusing them, planning, and the analytic and physics checks). Each shipped GQ-CNN
//! then scores seeded batches in the planner's runtime and, where torch installs, in torch on
//! the same inputs and threads (`benches/gqcnn/bench_torch.py`, run from the repository: the
//! training code's module and the exported weights in `models/`), as `benches/gqcnn/run.sh`
//! times them.
//!
//! Timings are measured, not seeded: a new run gives other figures. The suite's record is
//! kept like every other, so a resumed run reports the figures it recorded.

use std::path::{Path, PathBuf};
use std::process::Command;

use mvgrasp_geometry::objects::default_object;
use mvgrasp_infer::bench::{median, time_gqcnn};
use mvgrasp_render::Renderer;
use serde::{Deserialize, Serialize};

use super::grasps::ReadyPolicy;
use crate::error::Result;

/// The batch sizes each network is timed at: one crop (latency) and a planner's batch.
pub const BATCHES: [usize; 2] = [1, 256];

/// The torch script that times a network as [`time_gqcnn`] does, from the repository's root.
pub const TORCH_SCRIPT: &str = "benches/gqcnn/bench_torch.py";

/// The suite's sizes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpeedSuite {
    /// Timed plans per policy (after one warm-up).
    pub runs: usize,
    /// Timed seconds per network and batch size (at least 5 calls).
    pub network_seconds: f64,
}

/// One policy's stages: medians over the timed plans, milliseconds.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StageRow {
    /// The policy's name.
    pub policy: String,
    /// Rendering the views (colour views when the depth comes from RGB).
    pub render_ms: f64,
    /// Predicting the views' depth from RGB (0 on rendered depth).
    pub depth_ms: f64,
    /// Fusing the views (0 for a planner that does not).
    pub fuse_ms: f64,
    /// Sampling, cropping and scoring candidates in every view, the hand check and
    /// re-scoring.
    pub plan_ms: f64,
    /// The analytic and physics checks of the best grasp.
    pub check_ms: f64,
    /// Everything: each plan's sum, its median.
    pub total_ms: f64,
}

/// One network at one batch size in one runtime.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NetworkRow {
    /// The shipped network's name.
    pub network: String,
    /// `mvgrasp`, `torch`, or `torch-ftz` (torch with denormals flushed, as mvgrasp's runtime
    /// flushes them at load).
    pub runtime: String,
    /// Crops per call.
    pub batch: usize,
    /// The median call, milliseconds.
    pub median_ms: f64,
    /// Crops per second at the median call.
    pub crops_per_s: f64,
    /// The mean probability of the crops (the runtimes agree when they scored alike).
    pub mean_p: f64,
}

/// What the suite measured.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SpeedRecord {
    /// The processor, as the system names it.
    pub cpu: String,
    /// The threads the planner and both runtimes ran on.
    pub threads: usize,
    /// Timed plans per policy.
    pub runs: usize,
    /// Each policy's stages.
    pub stages: Vec<StageRow>,
    /// Each network in each runtime.
    pub networks: Vec<NetworkRow>,
    /// The peer's version (`torch 2.x`), or why it did not run.
    pub peer: String,
}

impl SpeedSuite {
    /// Times `policies` on the default run's object and the shipped GQ-CNNs, with the torch
    /// peer where it runs.
    ///
    /// # Errors
    /// A renderer, network or trial error (a missing peer is recorded, not an error).
    pub fn run(&self, renderer: &Renderer, policies: &[ReadyPolicy]) -> Result<SpeedRecord> {
        let object = default_object()?;
        let mut stages = Vec::new();
        for policy in policies {
            let mut timings = Vec::new();
            for run in 0..=self.runs {
                let report = policy.plan(renderer, &object.mesh, 0, 0)?;
                if run > 0 {
                    timings.push(report.timings);
                }
            }
            let ms = |f: &dyn Fn(&crate::planner::PlanTimings) -> f64| {
                1e3 * median(timings.iter().map(f).collect())
            };
            stages.push(StageRow {
                policy: policy.policy.name.clone(),
                render_ms: ms(&|t| t.render_s - t.depth_s),
                depth_ms: ms(&|t| t.depth_s),
                fuse_ms: ms(&|t| t.fuse_s),
                plan_ms: ms(&|t| t.plan_s - t.fuse_s),
                check_ms: ms(&|t| t.check_s),
                total_ms: ms(&|t| t.render_s + t.plan_s + t.check_s),
            });
        }
        let threads = rayon::current_num_threads();
        let mut networks = Vec::new();
        let mut peer = None;
        for model in mvgrasp_planner::models::ALL {
            let net = model.load()?;
            for batch in BATCHES {
                let timing = time_gqcnn(&net, batch, 0, (0.3, self.network_seconds))?;
                networks.push(NetworkRow {
                    network: model.name.into(),
                    runtime: "mvgrasp".into(),
                    batch,
                    median_ms: 1e3 * timing.median_s,
                    crops_per_s: timing.crops_per_s(batch),
                    mean_p: timing.mean_p,
                });
            }
            for flush in [false, true] {
                match torch_rows(model.name, threads, self.network_seconds, flush) {
                    Ok((version, rows)) => {
                        peer.get_or_insert(version);
                        networks.extend(rows);
                    }
                    Err(why) => {
                        peer.get_or_insert(format!("torch did not run: {why}"));
                    }
                }
            }
        }
        Ok(SpeedRecord {
            cpu: cpu_name(),
            threads,
            runs: self.runs,
            stages,
            networks,
            peer: peer.unwrap_or_default(),
        })
    }
}

/// The Python that runs the peer: `$MVGRASP_PYTHON`, else the repository's `.venv` (made by
/// `.ci/run`), else `python3`.
fn python() -> PathBuf {
    if let Some(python) = std::env::var_os("MVGRASP_PYTHON") {
        return python.into();
    }
    let venv = Path::new(".venv/bin/python");
    if venv.is_file() {
        venv.into()
    } else {
        "python3".into()
    }
}

/// torch's rows for the shipped network `name` (and torch's version), or why it did not run.
fn torch_rows(
    name: &str,
    threads: usize,
    seconds: f64,
    flush_denormal: bool,
) -> std::result::Result<(String, Vec<NetworkRow>), String> {
    let script = Path::new(TORCH_SCRIPT);
    let model = Path::new("models").join(format!("{name}.json"));
    if !script.is_file() || !model.is_file() {
        return Err(format!(
            "{} or {} not found (the peer runs from the repository's root)",
            script.display(),
            model.display()
        ));
    }
    let batches = BATCHES.map(|b| b.to_string()).join(",");
    let python = python();
    let mut command = Command::new(&python);
    command
        .arg(script)
        .arg(&model)
        .args(["--threads", &threads.to_string(), "--batches", &batches])
        .args(["--seconds", &seconds.to_string()])
        .env("PYTHONPATH", "training");
    if flush_denormal {
        command.arg("--flush-denormal");
    }
    let output = command
        .output()
        .map_err(|e| format!("{}: {e}", python.display()))?;
    if !output.status.success() {
        let stderr = String::from_utf8_lossy(&output.stderr);
        let last = stderr.lines().last().unwrap_or("no message");
        return Err(format!("{} {TORCH_SCRIPT}: {last}", python.display()));
    }
    let mut version = String::new();
    let mut rows = Vec::new();
    for line in String::from_utf8_lossy(&output.stdout).lines() {
        let value: serde_json::Value = serde_json::from_str(line)
            .map_err(|e| format!("{TORCH_SCRIPT} printed {line:?}: {e}"))?;
        let number = |key: &str| {
            value[key]
                .as_f64()
                .ok_or(format!("{TORCH_SCRIPT}: no {key}"))
        };
        version = format!("torch {}", value["torch"].as_str().unwrap_or("?"));
        rows.push(NetworkRow {
            network: name.into(),
            runtime: value["runtime"].as_str().unwrap_or("torch").into(),
            batch: number("batch")? as usize,
            median_ms: 1e3 * number("median_s")?,
            crops_per_s: number("crops_per_s")?,
            mean_p: number("mean_p")?,
        });
    }
    Ok((version, rows))
}

/// The processor's name from `/proc/cpuinfo` (Linux), or what the platform is.
fn cpu_name() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|info| {
            info.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, name)| name.trim().to_string())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_string())
}
