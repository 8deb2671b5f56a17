//! What the multi-view planner's re-score is worth, measured in physics: on calibration
//! objects (built-in objects 40 to 44 of each category: past every training index, apart from
//! `plan_eval`'s development set (50 on) and report set (30 on)), the fused planner re-scores the
//! best candidates of each view on virtual views, and every re-scored candidate is tried in
//! rapier. It fits a logistic model of the outcome on the score's logit and the approach's tilt
//! from straight down (Newton's method; the virtual views' network saw only vertical approaches
//! in training, so a tilt penalty was the hypothesis), and prints how well it describes the
//! trials. `--write FILE` saves the fit as JSON; `--trials-out FILE` the trials as CSV, which
//! `--trials-in FILE` fits again without the physics.
//!
//! ```text
//! cargo run --release --example calibrate_fused -- [--per-category 5] [--first-index 40]
//!     [--trials-out trials.csv] [--write fit.json]
//! ```

use std::path::PathBuf;
use std::process::ExitCode;

use clap::Parser;
use mvgrasp::geometry::objects::{Category, generate};
use mvgrasp::grasp::GraspObject;
use mvgrasp::grasp::physics::FailureStage;
use mvgrasp::planner::{
    FusionParams, GqcnnPolicy, PlanParams, VirtualScorer, check_grasps, models, plan_grasp,
};
use serde::Serialize;

/// The fitted model: `P(held) = sigmoid(logit_weight * logit(score) + tilt_weight_per_rad *
/// tilt + bias)`.
#[derive(Clone, Copy, Debug, Serialize)]
struct Calibration {
    logit_weight: f32,
    tilt_weight_per_rad: f32,
    bias: f32,
}

impl Calibration {
    fn apply(&self, score: f32, tilt_rad: f32) -> f32 {
        let q = score.clamp(1e-4, 1.0 - 1e-4);
        let z = self.logit_weight * (q / (1.0 - q)).ln()
            + self.tilt_weight_per_rad * tilt_rad
            + self.bias;
        1.0 / (1.0 + (-z).exp())
    }
}
use mvgrasp::render::{Backend, Renderer};

#[derive(Parser, Debug)]
#[command(about)]
struct Args {
    /// Built-in objects per category.
    #[arg(long, default_value_t = 5)]
    per_category: u32,
    /// The first object index of each category.
    #[arg(long, default_value_t = 40)]
    first_index: u32,
    /// Views fused.
    #[arg(long, default_value_t = 5)]
    views: usize,
    /// Write the fitted calibration (JSON) here.
    #[arg(long)]
    write: Option<PathBuf>,
    /// Write every trial (score, tilt_rad, held) as CSV here.
    #[arg(long)]
    trials_out: Option<PathBuf>,
    /// Fit to the trials of such a CSV instead of running them.
    #[arg(long)]
    trials_in: Option<PathBuf>,
}

fn main() -> ExitCode {
    mvgrasp::cli::exit(run(&Args::parse()))
}

/// One tried candidate: its object, the re-score, the tilt (radians), whether it held.
struct Trial {
    object: String,
    score: f32,
    tilt_rad: f32,
    held: bool,
}

fn run(args: &Args) -> Result<(), String> {
    let trials = match &args.trials_in {
        Some(path) => read_trials(path)?,
        None => run_trials(args)?,
    };
    if let Some(path) = &args.trials_out {
        let mut csv = String::from("object,score,tilt_rad,held\n");
        for t in &trials {
            csv += &format!(
                "{},{},{},{}\n",
                t.object,
                t.score,
                t.tilt_rad,
                u8::from(t.held)
            );
        }
        std::fs::write(path, csv).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    report(args, &trials)
}

/// Trials written by `--trials-out`.
fn read_trials(path: &std::path::Path) -> Result<Vec<Trial>, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    text.lines()
        .skip(1)
        .enumerate()
        .map(|(i, line)| {
            let bad = || {
                format!(
                    "{}: line {}: expected object,score,tilt_rad,held",
                    path.display(),
                    i + 2
                )
            };
            let fields: Vec<&str> = line.split(',').collect();
            let [object, score, tilt, held] = fields[..] else {
                return Err(bad());
            };
            Ok(Trial {
                object: object.to_string(),
                score: score.parse().map_err(|_| bad())?,
                tilt_rad: tilt.parse().map_err(|_| bad())?,
                held: held == "1",
            })
        })
        .collect()
}

/// Plans on every calibration object and tries every re-scored candidate.
fn run_trials(args: &Args) -> Result<Vec<Trial>, String> {
    let renderer = Renderer::new(Backend::Auto).map_err(|e| e.to_string())?;
    let mut params = PlanParams::default();
    params.views.count = args.views;
    params.views.radius_m = 0.65;
    params.max_views = args.views;
    params.fusion = Some(FusionParams::default());
    let gripper = params.labels.gripper().map_err(|e| e.to_string())?;
    let net = models::MVGQCNN.load().map_err(|e| e.to_string())?;
    let mut policy = GqcnnPolicy::new(net, gripper.max_opening_m).map_err(|e| e.to_string())?;
    let scorer = VirtualScorer::shipped(gripper.max_opening_m).map_err(|e| e.to_string())?;
    policy.fuse_with(scorer);
    let mut trials = Vec::new();
    for category in Category::ALL {
        for index in args.first_index..args.first_index + args.per_category {
            let o = generate(category, index, 0).map_err(|e| e.to_string())?;
            let report = match plan_grasp(&renderer, &o.mesh, &policy, &params) {
                Ok(r) => r,
                Err(e) => {
                    println!("{:<16} error: {e}", o.name);
                    continue;
                }
            };
            let rescored: Vec<_> = report
                .candidates
                .iter()
                .filter(|c| c.view_quality.is_some())
                .copied()
                .collect();
            let object = GraspObject::new(o.mesh).map_err(|e| e.to_string())?;
            let labels = check_grasps(
                &object,
                &report.table_from_object,
                &rescored,
                &gripper,
                &params,
            )
            .map_err(|e| e.to_string())?;
            let before = trials.len();
            for (c, label) in rescored.iter().zip(labels) {
                // A trial whose object left its resting pose before the hand came tests the
                // pose, not the grasp.
                let Some(p) = label.physics else { continue };
                if p.failed_at == Some(FailureStage::Settle) {
                    continue;
                }
                trials.push(Trial {
                    object: o.name.clone(),
                    score: c.quality,
                    tilt_rad: (-c.grasp.approach().z).clamp(-1.0, 1.0).acos(),
                    held: p.success,
                });
            }
            let new = &trials[before..];
            println!(
                "{:<16} {:>3} tried, {:>3} held",
                o.name,
                new.len(),
                new.iter().filter(|t| t.held).count()
            );
        }
    }
    Ok(trials)
}

/// Fits, prints the fit and how well it describes the trials, and writes it if asked.
fn report(args: &Args, trials: &[Trial]) -> Result<(), String> {
    if trials.is_empty() {
        return Err("no trial".into());
    }
    let calibration = fit(trials);
    let held = trials.iter().filter(|t| t.held).count();
    println!(
        "\n{} trials, {held} held ({:.0}%)",
        trials.len(),
        100.0 * held as f64 / trials.len() as f64
    );
    println!(
        "fit: P(held) = sigmoid({:.3} * logit(score) + {:.3} * tilt_rad + {:.3})",
        calibration.logit_weight, calibration.tilt_weight_per_rad, calibration.bias
    );
    let log_loss = |p: &dyn Fn(&Trial) -> f32| {
        trials
            .iter()
            .map(|t| {
                let q = f64::from(p(t)).clamp(1e-6, 1.0 - 1e-6);
                if t.held { -q.ln() } else { -(1.0 - q).ln() }
            })
            .sum::<f64>()
            / trials.len() as f64
    };
    println!(
        "log loss on these trials: raw score {:.3}, calibrated {:.3}",
        log_loss(&|t| t.score),
        log_loss(&|t| calibration.apply(t.score, t.tilt_rad))
    );
    println!("reliability: predicted (calibrated) against held, by bin");
    for (lo, hi) in [(0.0, 0.5), (0.5, 0.7), (0.7, 0.85), (0.85, 1.01)] {
        let bin: Vec<&Trial> = trials
            .iter()
            .filter(|t| (lo..hi).contains(&calibration.apply(t.score, t.tilt_rad)))
            .collect();
        let mean = bin
            .iter()
            .map(|t| calibration.apply(t.score, t.tilt_rad))
            .sum::<f32>()
            / bin.len().max(1) as f32;
        let rate = bin.iter().filter(|t| t.held).count() as f32 / bin.len().max(1) as f32;
        println!(
            "  {lo:.2}-{hi:.2}: {:>4} trials, predicted {mean:.2}, held {rate:.2}",
            bin.len()
        );
    }
    within_objects(trials);
    if let Some(path) = &args.write {
        let json = serde_json::to_string_pretty(&calibration).map_err(|e| e.to_string())?;
        std::fs::write(path, json + "\n").map_err(|e| format!("{}: {e}", path.display()))?;
        println!("wrote {}", path.display());
    }
    Ok(())
}

/// Logistic regression of `held` on (logit(score), tilt, 1): Newton's method from zero with
/// step halving (the loss never rises), and a small ridge for a separable set.
fn fit(trials: &[Trial]) -> Calibration {
    let features = |t: &Trial| {
        let q = f64::from(t.score).clamp(1e-4, 1.0 - 1e-4);
        [(q / (1.0 - q)).ln(), f64::from(t.tilt_rad), 1.0]
    };
    let rows: Vec<([f64; 3], f64)> = trials
        .iter()
        .map(|t| (features(t), if t.held { 1.0 } else { 0.0 }))
        .collect();
    const RIDGE: f64 = 1e-3;
    let loss = |w: &[f64; 3]| {
        rows.iter()
            .map(|(x, y)| {
                let z: f64 = x.iter().zip(w).map(|(a, b)| a * b).sum();
                // log(1 + e^z) - y z, stably.
                z.max(0.0) + (-z.abs()).exp().ln_1p() - y * z
            })
            .sum::<f64>()
            + 0.5 * RIDGE * w.iter().map(|v| v * v).sum::<f64>()
    };
    let mut w = [0.0f64; 3];
    for _ in 0..100 {
        let mut grad = [0.0f64; 3];
        let mut hess = [[0.0f64; 3]; 3];
        for (x, y) in &rows {
            let z: f64 = x.iter().zip(&w).map(|(a, b)| a * b).sum();
            let p = 1.0 / (1.0 + (-z).exp());
            for i in 0..3 {
                grad[i] += (p - y) * x[i];
                for j in 0..3 {
                    hess[i][j] += p * (1.0 - p) * x[i] * x[j];
                }
            }
        }
        for i in 0..3 {
            grad[i] += RIDGE * w[i];
            hess[i][i] += RIDGE;
        }
        let step = solve3(hess, grad);
        let before = loss(&w);
        let mut scale = 1.0;
        let mut next = w;
        while scale > 1e-6 {
            next = std::array::from_fn(|i| w[i] - scale * step[i]);
            if loss(&next) <= before {
                break;
            }
            scale /= 2.0;
        }
        let moved = (0..3).map(|i| (next[i] - w[i]).abs()).fold(0.0, f64::max);
        w = next;
        if moved < 1e-9 {
            break;
        }
    }
    Calibration {
        logit_weight: w[0] as f32,
        tilt_weight_per_rad: w[1] as f32,
        bias: w[2] as f32,
    }
}

/// `a x = b` for a symmetric positive definite 3 x 3 `a` (Cramer's rule).
fn solve3(a: [[f64; 3]; 3], b: [f64; 3]) -> [f64; 3] {
    let det = |m: [[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det(a);
    std::array::from_fn(|k| {
        let mut m = a;
        for (row, &v) in m.iter_mut().zip(&b) {
            row[k] = v;
        }
        det(m) / d
    })
}

/// What pooling hides: per object, whether a higher score means a better grasp (the AUC of the
/// score between held and failed candidates, averaged over objects), the first choice's rate,
/// and the rate of candidates by tilt.
fn within_objects(trials: &[Trial]) {
    let mut by_object: std::collections::BTreeMap<&str, Vec<&Trial>> = Default::default();
    for t in trials {
        by_object.entry(&t.object).or_default().push(t);
    }
    let mut aucs = Vec::new();
    let mut first_held = 0;
    let mut first_held_top_down = 0;
    for ts in by_object.values() {
        let (held, failed): (Vec<&&Trial>, Vec<&&Trial>) = ts.iter().partition(|t| t.held);
        if !held.is_empty() && !failed.is_empty() {
            let wins: f64 = held
                .iter()
                .flat_map(|h| failed.iter().map(move |f| (h.score, f.score)))
                .map(|(a, b)| match a.total_cmp(&b) {
                    std::cmp::Ordering::Greater => 1.0,
                    std::cmp::Ordering::Equal => 0.5,
                    std::cmp::Ordering::Less => 0.0,
                })
                .sum();
            aucs.push(wins / (held.len() * failed.len()) as f64);
        }
        let first = ts.iter().max_by(|a, b| a.score.total_cmp(&b.score));
        first_held += usize::from(first.is_some_and(|t| t.held));
        let first_top_down = ts
            .iter()
            .filter(|t| t.tilt_rad.to_degrees() < 15.0)
            .max_by(|a, b| a.score.total_cmp(&b.score));
        first_held_top_down += usize::from(first_top_down.is_some_and(|t| t.held));
    }
    println!(
        "within objects: AUC of the score {:.3} (mean over {} objects with both outcomes); the \
         best-scored candidate held on {first_held} of {} objects, the best-scored within 15 \
         degrees of vertical on {first_held_top_down}",
        aucs.iter().sum::<f64>() / aucs.len().max(1) as f64,
        aucs.len(),
        by_object.len()
    );
    // The first choice when a tilted candidate (over 15 degrees) must win by a margin.
    let margins = [0.02f32, 0.05, 0.1, 0.2];
    let held_with_margin: Vec<usize> = margins
        .iter()
        .map(|&margin| {
            by_object
                .values()
                .filter(|ts| {
                    let key = |t: &&&Trial| {
                        t.score
                            - if t.tilt_rad.to_degrees() > 15.0 {
                                margin
                            } else {
                                0.0
                            }
                    };
                    ts.iter()
                        .max_by(|a, b| key(a).total_cmp(&key(b)))
                        .is_some_and(|t| t.held)
                })
                .count()
        })
        .collect();
    println!(
        "  a tilted first choice must win by {margins:?}: held on {held_with_margin:?} objects"
    );
    for (lo, hi) in [(0.0f32, 15.0f32), (15.0, 45.0), (45.0, 91.0)] {
        let bin: Vec<&Trial> = trials
            .iter()
            .filter(|t| (lo..hi).contains(&t.tilt_rad.to_degrees()))
            .collect();
        println!(
            "  tilt {lo:>2.0}-{hi:>2.0} deg: {:>4} candidates, {:.0}% held",
            bin.len(),
            100.0 * bin.iter().filter(|t| t.held).count() as f64 / bin.len().max(1) as f64
        );
    }
}
