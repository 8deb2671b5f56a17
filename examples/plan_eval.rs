//! The planner's ablations, checked in physics: for the evaluation's object sets (`--set`, as
//! `evaluate --set`; default the built-in objects past every training index and every real
//! mesh of ../shared/data), each policy plans one grasp in the object's most probable pose,
//! and the grasp is checked with the dataset's analytic label and a rapier trial (close,
//! lift, shake). `evaluate` measures the shipped planners; this program measures the settings
//! beside them (the seed paper's per-view policy, other view counts, cameras, crops, the
//! trial's shapes, the re-scoring's knobs, a candidate network's export).
//!
//! ```text
//! cargo run --release --example plan_eval -- [--set held-out --set real] [--per-category 5]
//!     [--max-meshes 0] [--data ../shared/data/meshes]
//!     [--camera phoxi_s|primesense|realsense_d435] [--top-down-only] [--shell] [--grip-surface] [--top10]
//!     [--gqcnn EXPORT.json] [--mvgqcnn EXPORT.json]
//! ```
//!
//! `--camera` renders every view with another camera's intrinsics: the planner scales its
//! crops to the camera (the network's input contract), and this measures what that keeps.
//!
//! Policies (`--policy`, repeated; all by default):
//! - `topdown`: the top-down GQ-CNN with the top-down view alone, 0.7 m above the object
//!   (Dex-Net 2.0's setting and its training distance);
//! - `per-view`: the multi-view GQ-CNN over the paper's 10 test views, each view planned on
//!   its own (the seed paper's policy);
//! - `fused-3`, `fused-5`, `fused-10`: the multi-view planner: 3, 5 or 10 views on the
//!   hemisphere (the first top-down) fused, every candidate checked against the fused model
//!   (the open hand must stay out of space no view saw), the best re-scored on virtual views
//!   along their approach axes (`--rescore`);
//! - `rgb-`, `refined-`, `mvs-` or `lsm-` before `topdown-N` or `fused-N`: the same on the
//!   depth of N colour views predicted by the plane sweep, the refined sweep, the multi-view
//!   stereo network or the Learnt Stereo Machine.

mod common;

use common::{Loaded, SetArgs, load_sets, wilson_95};
use mvgrasp::cli::CliResult;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::Parser;
use mvgrasp::geometry::{Intrinsics, IntrinsicsPreset};
use mvgrasp::grasp::GraspObject;
use mvgrasp::grasp::physics::FailureStage;
use mvgrasp::infer::Gqcnn;
use mvgrasp::planner::{
    CemParams, DepthFrom, DepthPredictor, FusionParams, GqcnnPolicy, MultiViewPlanner, PlanParams,
    Planner, RgbInput, ShippedModel, VirtualScorer, check_grasps, models, plan_grasp,
};
use mvgrasp::render::{Backend, Renderer};
use mvgrasp_planner::{Ranker, tilt_rad};

/// Plan with each policy on unseen objects; check the chosen grasps in physics.
#[derive(Parser, Debug)]
#[command(about)]
struct Args {
    #[command(flatten)]
    objects: SetArgs,
    /// The shared mesh folder (the real sets are empty when it is absent).
    #[arg(long, default_value = "../shared/data/meshes")]
    data: PathBuf,
    /// Distance of the multi-view policies' cameras, metres (`plan`'s: 0.65; the paper's test
    /// views: 0.5).
    #[arg(long, default_value_t = 0.65)]
    mv_radius_m: f32,
    /// The cameras' intrinsics preset (phoxi_s, the networks' training camera; primesense;
    /// realsense_d435).
    #[arg(long, default_value = "phoxi_s")]
    camera: String,
    /// Only the top-down GQ-CNN (`plan`'s default policy).
    #[arg(long)]
    top_down_only: bool,
    /// Cut the training window in pixels whatever the camera (what the planner did before it
    /// scaled crops by the focal ratio), for comparison.
    #[arg(long)]
    unscaled_crops: bool,
    /// Return the best-scored grasp without the hand check against the observed depth.
    #[arg(long)]
    no_hand_check: bool,
    /// Shape the objects in the physics trial as a shell of slabs along the surface (within
    /// 1 mm) instead of the hull or VHACD's parts.
    #[arg(long)]
    shell: bool,
    /// The hand in the physics trial grips the mesh's own surface instead of the collision
    /// shape (`PhysicsParams::grip_true_surface`; slower).
    #[arg(long)]
    grip_surface: bool,
    /// Also try the planner's next choices in physics: the precision of its top 10 (the best
    /// ten candidates that pass the hand check), per object.
    #[arg(long)]
    top10: bool,
    /// Refine candidates by Dex-Net 2.0's cross-entropy method (`plan --cem`).
    #[arg(long)]
    cem: bool,
    /// The top-down GQ-CNN's network from this export (`NAME.json`) instead of the shipped one.
    #[arg(long)]
    gqcnn: Option<PathBuf>,
    /// The multi-view GQ-CNN's network from this export (`NAME.json`) instead of the shipped
    /// one (a candidate measured before it ships).
    #[arg(long)]
    mvgqcnn: Option<PathBuf>,
    /// The policies (topdown, per-view, fused-3, fused-5, fused-10, and lsm-fused-N or
    /// rgb-fused-N: the fused planner on depth predicted from N RGB views by the Learnt Stereo
    /// Machine or the plane-sweep baseline; lsm-topdown-N or rgb-topdown-N: the top-down GQ-CNN
    /// in the first, top-down, of those N predicted views); all but the RGB ones when none is
    /// given.
    #[arg(long = "policy")]
    policies: Vec<String>,
    /// The network that re-scores the fused policies' best candidates on virtual views:
    /// gqcnn (the top-down GQ-CNN), mvgqcnn, or none (rank by the multi-view GQ-CNN's score
    /// on the view the candidate came from).
    #[arg(long, default_value = "gqcnn")]
    rescore: String,
    /// Candidates re-scored per view.
    #[arg(long, default_value_t = 10)]
    rescore_candidates: usize,
    /// Perturbed copies averaged into each re-score (0: the candidate alone; default: the
    /// planner's, `VirtualViewParams::perturbations`).
    #[arg(long)]
    perturbations: Option<usize>,
    /// Candidate grasp axes the multi-view GQ-CNN samples per view in the fused policies (each
    /// at 3 depths; default: the planner's, `VirtualViewParams::grasps_per_view`).
    #[arg(long)]
    fused_grasps: Option<usize>,
    /// A second network scores the virtual views too (gqcnn or mvgqcnn): the re-score is the
    /// geometric mean of the two.
    #[arg(long)]
    second_scorer: Option<String>,
    /// The re-scoring network proposes no candidates of its own in the top-down view.
    #[arg(long)]
    no_top_down_proposals: bool,
    /// The fused policies' hand check lets the hand into space no view has seen.
    #[arg(long)]
    allow_unknown: bool,
    /// The RGB policies colour the objects per triangle instead of per vertex.
    #[arg(long)]
    rgb_per_face: bool,
    /// The RGB policies' views are rendered with the photographic look
    /// (`mvgrasp::scene::photoreal`) instead of the flat one.
    #[arg(long)]
    photo: bool,
    /// The fused policies rank their re-scored candidates by the re-score alone, without the
    /// shipped ranker (`models/ranker_fused.json`).
    #[arg(long)]
    no_ranker: bool,
}

/// A policy of the evaluation: its label, network, views, their distance, and whether the
/// views are fused.
struct Policy {
    label: String,
    model: ShippedModel,
    views: usize,
    radius_m: f32,
    fused: bool,
    /// Depth predicted from RGB (by this predictor) instead of rendered.
    rgb: Option<DepthFrom>,
    /// Plan in the first view only (the top-down one), the others informing the predicted
    /// depth.
    top_down_of_rgb: bool,
}

/// The policies named on the command line (all without names, the top-down one alone with
/// --top-down-only).
fn policies(args: &Args) -> CliResult<Vec<Policy>> {
    let names: Vec<&str> = if args.top_down_only {
        vec!["topdown"]
    } else if args.policies.is_empty() {
        vec!["topdown", "per-view", "fused-3", "fused-5", "fused-10"]
    } else {
        args.policies.iter().map(String::as_str).collect()
    };
    names
        .into_iter()
        .map(|name| {
            Ok(match name {
                "topdown" => Policy {
                    label: "GQ-CNN, top-down".into(),
                    model: models::GQCNN_TOPDOWN,
                    views: 1,
                    radius_m: 0.7,
                    fused: false,
                    rgb: None,
                    top_down_of_rgb: false,
                },
                "per-view" => Policy {
                    label: "MV-GQ-CNN, 10 views".into(),
                    model: models::MVGQCNN,
                    views: 10,
                    radius_m: args.mv_radius_m,
                    fused: false,
                    rgb: None,
                    top_down_of_rgb: false,
                },
                _ => {
                    let rgb = if name.starts_with("lsm-") {
                        Some(DepthFrom::Lsm)
                    } else if name.starts_with("rgb-") {
                        Some(DepthFrom::Baseline)
                    } else if name.starts_with("mvs-") {
                        Some(DepthFrom::Mvs)
                    } else if name.starts_with("refined-") {
                        Some(DepthFrom::Refined)
                    } else {
                        None
                    };
                    let rest = name
                        .trim_start_matches("rgb-")
                        .trim_start_matches("lsm-")
                        .trim_start_matches("mvs-")
                        .trim_start_matches("refined-");
                    // topdown-N: the top-down GQ-CNN in the first (top-down) of N RGB views.
                    let top_down = rgb.is_some() && rest.starts_with("topdown-");
                    let views = rest
                        .strip_prefix(if top_down { "topdown-" } else { "fused-" })
                        .and_then(|n| n.parse::<usize>().ok())
                        .filter(|&n| n > 0)
                        .ok_or_else(|| {
                            format!(
                                "--policy {name}: expected topdown, per-view, fused-N, \
                                 lsm-fused-N, rgb-fused-N, mvs-fused-N, refined-fused-N, \
                                 lsm-topdown-N, rgb-topdown-N, mvs-topdown-N or \
                                 refined-topdown-N (N views)"
                            )
                        })?;
                    let kind = if top_down { "top-down GQ-CNN" } else { "fused" };
                    Policy {
                        label: match rgb {
                            Some(DepthFrom::Lsm) => format!("{kind}, {views} RGB views, LSM"),
                            Some(DepthFrom::Mvs) => format!("{kind}, {views} RGB views, MVS"),
                            Some(DepthFrom::Refined) => {
                                format!("{kind}, {views} RGB views, refined sweep")
                            }
                            Some(DepthFrom::Baseline) => {
                                format!("{kind}, {views} RGB views, baseline")
                            }
                            None => format!("fused, {views} views"),
                        },
                        model: if top_down {
                            models::GQCNN_TOPDOWN
                        } else {
                            models::MVGQCNN
                        },
                        views,
                        radius_m: args.mv_radius_m,
                        fused: !top_down,
                        rgb,
                        top_down_of_rgb: top_down,
                    }
                }
            })
        })
        .collect()
}

/// The upper ends of the approach-tilt bins but the last, degrees from straight down.
const TILT_BINS_DEG: [f32; 2] = [15.0, 45.0];

/// One category's share of a tally.
#[derive(Default, Clone, Copy)]
struct Group {
    planned: usize,
    /// Sum of the chosen grasps' predicted quality.
    quality: f64,
    held: usize,
    tried: usize,
}

#[derive(Default)]
struct Tally {
    planned: usize,
    /// Chosen grasps the exact-mesh collision check passes.
    free: usize,
    robust: usize,
    /// Trials whose object stayed in its pose until the gripper came.
    tried: usize,
    held: usize,
    /// Objects it found no grasp for (counted as not held in the per-object rate).
    unplanned: usize,
    seconds: f64,
    /// With --top10: per object, the share of its top choices (up to 10) that held.
    top10: Vec<f64>,
    /// Per group: the built-in category, or the real mesh's source or household category.
    by_group: BTreeMap<String, Group>,
    /// (held, tried) by the chosen approach's tilt from straight down ([`TILT_BINS_DEG`]).
    by_tilt: [(usize, usize); 3],
}

fn main() -> ExitCode {
    mvgrasp::cli::exit(run(&Args::parse()))
}

fn run(args: &Args) -> CliResult<()> {
    let objects = load_sets(&args.objects, &args.data)?;
    let preset: IntrinsicsPreset = args.camera.parse().map_err(|e| format!("--camera: {e}"))?;
    let renderer = Renderer::new(Backend::Auto)?;
    let policies = policies(args)?;
    println!(
        "camera: {} (every view), crops {}",
        preset.name(),
        if args.unscaled_crops {
            "unscaled (the training window in pixels)"
        } else {
            "scaled to the camera's focal length"
        }
    );
    let rescorer = match args.rescore.as_str() {
        "none" => None,
        "gqcnn" => Some(models::GQCNN_TOPDOWN),
        "mvgqcnn" => Some(models::MVGQCNN),
        other => {
            return Err(format!("--rescore {other}: expected gqcnn, mvgqcnn or none").into());
        }
    };
    // Each policy's settings, gripper and network, prepared once for every object.
    let mut prepared = Vec::new();
    for p in &policies {
        let mut params = PlanParams {
            max_views: p.views,
            intrinsics: Intrinsics::preset(preset),
            hand_check: !args.no_hand_check,
            ..Default::default()
        };
        params.labels.physics_shape.shell = args.shell;
        params.depth_from_rgb = match p.rgb {
            Some(from) => {
                let depth = DepthPredictor::shipped(from)?;
                Some(RgbInput {
                    // As `plan` does: one network planning in one view gets complete depth.
                    depth: if p.top_down_of_rgb {
                        depth.for_one_view()
                    } else {
                        depth
                    },
                    per_face: args.rgb_per_face,
                    photo: args.photo,
                })
            }
            None => None,
        };
        params.labels.physics.grip_true_surface = args.grip_surface;
        params.views.radius_m = p.radius_m;
        if p.top_down_of_rgb {
            // The views spread over the whole cap as the fused policies' are; the plan in the
            // first, top-down one.
            params.views.count = p.views;
            params.plan_views = Some(1);
        }
        if p.fused {
            // The views spread over the whole cap, not the first of ten.
            params.views.count = p.views;
            params.fusion = Some(FusionParams {
                allow_unknown: args.allow_unknown,
                ..Default::default()
            });
        }
        let gripper = params.labels.gripper.clone();
        let load = |model: ShippedModel| -> CliResult<Gqcnn> {
            let replacement = if model.name == models::GQCNN_TOPDOWN.name {
                &args.gqcnn
            } else {
                &args.mvgqcnn
            };
            Ok(match replacement {
                Some(path) => Gqcnn::load(path)?,
                None => model.load()?,
            })
        };
        let mut policy = GqcnnPolicy::new(load(p.model)?, gripper.max_opening_m)?;
        policy.cem = args.cem.then(CemParams::default);
        if args.unscaled_crops {
            policy.contract.focal_px = params.intrinsics.fx;
        }
        let planner: Planner = if p.fused
            && let Some(model) = rescorer
        {
            let mut scorer = VirtualScorer::new(load(model)?, gripper.max_opening_m)?;
            scorer.params.candidates_per_view = args.rescore_candidates;
            if let Some(n) = args.perturbations {
                scorer.params.perturbations = n;
            }
            if let Some(n) = args.fused_grasps {
                scorer.params.grasps_per_view = n;
            }
            scorer.params.propose_top_down = !args.no_top_down_proposals;
            if !args.no_ranker {
                scorer.ranker = Some(Ranker::shipped()?);
            }
            let second = match args.second_scorer.as_deref() {
                None => None,
                Some("gqcnn") => Some(load(models::GQCNN_TOPDOWN)?),
                Some("mvgqcnn") => Some(load(models::MVGQCNN)?),
                Some(other) => {
                    return Err(
                        format!("--second-scorer {other}: expected gqcnn or mvgqcnn").into(),
                    );
                }
            };
            scorer.set_second(second)?;
            MultiViewPlanner::new(policy, scorer).into()
        } else {
            policy.into()
        };
        prepared.push((params, gripper, planner));
    }
    let mut tallies: Vec<Tally> = policies.iter().map(|_| Tally::default()).collect();
    println!(
        "object                         policy                 quality  free  robust  physics"
    );
    for Loaded { group, name, mesh } in &objects {
        // For --top10's checks (plan_grasp prepares its own for the best grasp).
        let object = args
            .top10
            .then(|| GraspObject::new(mesh.clone()))
            .transpose()?;
        for ((Policy { label, .. }, (params, gripper, policy)), tally) in
            policies.iter().zip(&prepared).zip(&mut tallies)
        {
            let report = match plan_grasp(&renderer, mesh, policy, params) {
                Ok(r) => r,
                Err(e) => {
                    println!("{name:<30} {label:<22} error: {e}");
                    continue;
                }
            };
            tally.seconds += report.timings.plan_s;
            let Some(best) = report.best else {
                println!("{name:<30} {label:<22} no candidate");
                tally.unplanned += 1;
                continue;
            };
            tally.planned += 1;
            let robust = report.analytic.is_some_and(|a| a.robust);
            let free = report.analytic.is_some_and(|a| a.collision_free);
            let held = report.physics.is_some_and(|p| p.success);
            // A trial whose object toppled from its analytic stable pose while settling tests
            // the pose, not the grasp: left out of the physics rate.
            let settled = report
                .physics
                .is_some_and(|p| p.failed_at != Some(FailureStage::Settle));
            tally.robust += usize::from(robust);
            tally.free += usize::from(free);
            tally.tried += usize::from(settled);
            tally.held += usize::from(held);
            let in_group = tally.by_group.entry(group.clone()).or_default();
            in_group.planned += 1;
            in_group.quality += f64::from(best.quality);
            in_group.held += usize::from(held);
            in_group.tried += usize::from(settled);
            let physics = report
                .physics
                .map_or("-".to_string(), |p| match p.failed_at {
                    None => "held".into(),
                    Some(stage) => format!("{stage:?}"),
                });
            let top10 = if let Some(object) = object.as_ref().filter(|_| args.top10) {
                let labels = check_grasps(
                    object,
                    &report.table_from_object,
                    &report.top,
                    gripper,
                    params,
                )?;
                // As for the best grasp: a trial that lost the resting pose is left out.
                let trials: Vec<bool> = labels
                    .iter()
                    .filter_map(|l| l.physics)
                    .filter(|p| p.failed_at != Some(FailureStage::Settle))
                    .map(|p| p.success)
                    .collect();
                let held = trials.iter().filter(|&&h| h).count();
                if !trials.is_empty() {
                    tally.top10.push(held as f64 / trials.len() as f64);
                }
                format!("  top {}: {held} held", trials.len())
            } else {
                String::new()
            };
            // The approach's angle from straight down.
            let tilt_deg = tilt_rad(&best.grasp).to_degrees();
            let bin = TILT_BINS_DEG.iter().take_while(|&&b| tilt_deg > b).count();
            tally.by_tilt[bin].0 += usize::from(held);
            tally.by_tilt[bin].1 += usize::from(settled);
            println!(
                "{name:<30} {label:<22} {:>7.3}  {:>4}  {:>6}  tilt {tilt_deg:>4.0}  {physics}{top10}",
                best.quality,
                if free { "yes" } else { "no" },
                if robust { "yes" } else { "no" }
            );
        }
    }
    println!("\n{} objects", objects.len());
    println!(
        "policy                 planned  collision-free  robust label  held in physics (of trials)  95% interval  held (of objects)  plan time/object"
    );
    let pct = |k: usize, n: usize| 100.0 * k as f64 / n.max(1) as f64;
    let interval = |k: usize, n: usize| {
        let (lo, hi) = wilson_95(k, n);
        format!("{:.0}-{:.0}%", 100.0 * lo, 100.0 * hi)
    };
    for (Policy { label, .. }, t) in policies.iter().zip(&tallies) {
        println!(
            "{label:<22} {:>7}  {:>13.0}%  {:>11.0}%  {:>9.0}% ({:>2} of {:>2})  {:>12}  {:>6.0}% ({:>2} of {:>2})  {:>14.2} s",
            t.planned,
            pct(t.free, t.planned),
            pct(t.robust, t.planned),
            pct(t.held, t.tried),
            t.held,
            t.tried,
            interval(t.held, t.tried),
            pct(t.held, t.tried + t.unplanned),
            t.held,
            t.tried + t.unplanned,
            t.seconds / objects.len().max(1) as f64
        );
    }
    println!(
        "(of trials: toppled trials and objects without a plan apart; of objects: an object \
         without a plan counts as not held, toppled trials still apart)"
    );
    println!("\nheld in physics per category (of trials)");
    for (Policy { label, .. }, t) in policies.iter().zip(&tallies) {
        println!("{label}");
        for (group, g) in &t.by_group {
            let (held, tried) = (g.held, g.tried);
            println!(
                "  {group:<14} {:>4.0}% ({held:>2} of {tried:>2})  {:>9}",
                pct(held, tried),
                interval(held, tried)
            );
        }
    }
    println!("\nheld in physics by the approach's tilt from straight down (of trials)");
    for (Policy { label, .. }, t) in policies.iter().zip(&tallies) {
        let [a, b, c] = t.by_tilt;
        println!(
            "{label:<22}  0-15 deg {:>2} of {:>2}   15-45 deg {:>2} of {:>2}   over 45 deg {:>2} of {:>2}",
            a.0, a.1, b.0, b.1, c.0, c.1
        );
    }
    print_table2(&policies, &tallies);
    if args.top10 {
        println!("\nprecision of the top choices (up to 10 per object, mean over objects)");
        for (Policy { label, .. }, t) in policies.iter().zip(&tallies) {
            let mean = t.top10.iter().sum::<f64>() / t.top10.len().max(1) as f64;
            println!(
                "{label:<22} {:>5.0}% over {} objects",
                100.0 * mean,
                t.top10.len()
            );
        }
    }
    Ok(())
}

/// The seed paper's Table 2 for its six categories (its hole punch is the stapler here, the
/// nearest category): the chosen grasp's predicted quality (mean over objects) and the physics
/// success, per policy side by side.
fn print_table2(policies: &[Policy], tallies: &[Tally]) {
    const SIX: [(&str, &str); 6] = [
        ("bowl", "bowl"),
        ("toy chair", "toy_chair"),
        ("mug", "mug"),
        ("squash", "squash"),
        ("hole punch", "stapler"),
        ("toy car", "toy_car"),
    ];
    println!(
        "\nthe seed's Table 2: predicted quality of the chosen grasp (mean) / held in physics"
    );
    print!("{:<12}", "category");
    for p in policies {
        print!("  {:>24}", p.label);
    }
    println!();
    for (paper, ours) in SIX {
        print!("{paper:<12}");
        for t in tallies {
            let g = t.by_group.get(ours).copied().unwrap_or_default();
            let quality = g.quality / g.planned.max(1) as f64;
            print!(
                "  {:>24}",
                format!("{quality:.3} / {} of {}", g.held, g.tried)
            );
        }
        println!();
    }
}
