//! The labels against the physics outcome they are meant to predict (the issue on grasps that
//! hold): on the evaluation's object sets (`--set`, as `evaluate --set`; default the built-in
//! objects past every training index and every real mesh of ../shared/data, the object names
//! the evaluation gives them), antipodal grasps are sampled on each object at rest and
//! labelled three ways: Dex-Net 2.0's robust Ferrari-Canny label; the physics label (the share
//! of K perturbed rapier trials that hold, at least a half; the grasp datasets' label); and both
//! together. Each is compared with a high-K physics outcome drawn independently (other seeds,
//! the same perturbations): held when at least half of its trials hold. Trials whose object
//! left its resting pose before the gripper came (the trial's shape does not keep the pose)
//! are left out of both rates.
//!
//! ```text
//! cargo run --release --example label_eval -- [--set held-out --set real] [--per-category 5]
//!     [--max-meshes 0] [--n 20] [--k 10] [--outcome-k 50] [--data ../shared/data/meshes]
//!     [--json OUT.json] [--replay DIR]
//! ```
//!
//! `--replay DIR` also writes what another physics engine needs to replay every grasp's
//! unperturbed trial (`scripts/judge/pybullet_judge.py` reads it): `DIR/replay.json` (the
//! gripper, the physics parameters, and per grasp the object's files, its resting pose, the
//! grasp, the unperturbed trial's outcome and the K-trial rates) and, once per object,
//! `DIR/meshes/NAME.obj` (the mesh, object frame) and `DIR/meshes/NAME.parts.obj` (the convex
//! parts the trial collides with, one `o` group a part, object frame).
//!
//! Reports, per category or source and overall, each label's confusion table against the
//! outcome, its false-positive rate (outcome failed, label positive, over outcome failed) and
//! the share of its positives that failed.

mod common;

use common::{EvalArgs, Loaded, Rested, SetArgs, analyse_at_rest, load_sets};
use std::process::ExitCode;
use std::time::Instant;

use clap::Parser;
use mvgrasp::cli::CliResult;
use mvgrasp::evaluate::labels::{Confusion, LabelRecord, LabelSuite};
use mvgrasp::geometry::TriangleMesh;
use mvgrasp::grasp::Gripper;
use mvgrasp::grasp::physics::{
    PhysicsNoise, PhysicsObject, PhysicsOutcome, PhysicsParams, StageCounts,
};
use serde::Serialize;

/// Compare the robust label and the physics label with a high-K physics outcome.
#[derive(Parser, Debug)]
#[command(about)]
struct Args {
    #[command(flatten)]
    objects: SetArgs,
    /// Grasps sampled per object.
    #[arg(long, default_value_t = 20)]
    n: usize,
    /// Perturbed trials of the physics label.
    #[arg(long, default_value_t = 10)]
    k: usize,
    /// Perturbed trials of the outcome.
    #[arg(long, default_value_t = 50)]
    outcome_k: usize,
    /// Write what another engine needs to replay each grasp's unperturbed trial here
    /// (replay.json and meshes/).
    #[arg(long)]
    replay: Option<std::path::PathBuf>,
    #[command(flatten)]
    eval: EvalArgs,
}

/// What a replay of the unperturbed trials in another engine needs (`--replay`).
#[derive(Serialize)]
struct Replay<'a> {
    /// The gripper every grasp is tried with.
    gripper: &'a Gripper,
    /// The trial's parameters (density, table friction, lift, shake, tolerances...).
    physics: &'a PhysicsParams,
    /// The closing force each finger squeezes with, newtons.
    closing_force_n: f32,
    /// The label's and the outcome's perturbations.
    noise: &'a PhysicsNoise,
    objects: Vec<ReplayObject>,
    grasps: Vec<ReplayGrasp>,
}

/// One object of a replay.
#[derive(Serialize)]
struct ReplayObject {
    name: String,
    group: String,
    /// The mesh, object frame, relative to the replay folder.
    mesh: String,
    /// The convex parts the trial collides with, one `o` group a part, object frame.
    parts: String,
    num_parts: usize,
    /// Its resting pose on the table (the table frame is the world: z up, the top at z = 0).
    #[serde(with = "mvgrasp::geometry::pose_as_matrix")]
    table_from_object: mvgrasp::geometry::Pose3,
    /// The mesh's mass at the trial's density, kilograms.
    mass_kg: f32,
    /// Its centre of mass, object frame, metres.
    center_of_mass: [f32; 3],
    /// Its inertia about the centre of mass, object-frame axes, kg m^2 (rows).
    inertia_kg_m2: [[f32; 3]; 3],
}

/// One grasp of a replay.
#[derive(Serialize)]
struct ReplayGrasp {
    /// Index into `objects`.
    object: usize,
    /// The grasp's index on its object.
    index: usize,
    /// Gripper frame in the table frame: origin midway between the finger tips, +z the
    /// approach, +x the closing axis.
    #[serde(with = "mvgrasp::geometry::pose_as_matrix")]
    world_from_gripper: mvgrasp::geometry::Pose3,
    width_m: f32,
    robust_epsilon: f64,
    robust: bool,
    /// The unperturbed rapier trial.
    outcome: PhysicsOutcome,
    /// Of the label's K perturbed trials that got past settling, the share that held.
    physics_rate: Option<f64>,
    /// The same of the outcome's trials.
    outcome_rate: Option<f64>,
}

/// Writes `mesh` and `body`'s convex parts as OBJ files in `dir`; their names in `dir`.
fn write_replay_meshes(
    dir: &std::path::Path,
    name: &str,
    mesh: &TriangleMesh,
    body: &PhysicsObject,
) -> CliResult<(String, String)> {
    let stem: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect();
    let (mesh_name, parts_name) = (format!("{stem}.obj"), format!("{stem}.parts.obj"));
    mvgrasp::geometry::write_obj(mesh, dir.join(&mesh_name))?;
    let shape = body.shape();
    let parts: Vec<(mvgrasp::geometry::Pose3, &dyn parry3d::shape::Shape)> =
        match shape.as_compound() {
            Some(compound) => compound.shapes().iter().map(|(p, s)| (*p, &**s)).collect(),
            None => vec![(mvgrasp::geometry::Pose3::IDENTITY, &**shape)],
        };
    let mut text =
        String::from("# convex parts of the physics trial's shape; metres, object frame\n");
    let mut first = 1;
    for (i, (pose, part)) in parts.iter().enumerate() {
        let hull = part
            .as_convex_polyhedron()
            .ok_or_else(|| format!("{name}: part {i} is not a convex polyhedron"))?;
        let (points, triangles) = hull.to_trimesh();
        text.push_str(&format!("o part_{i}\n"));
        for p in &points {
            let p = pose.transform_point(*p);
            text.push_str(&format!("v {} {} {}\n", p.x, p.y, p.z));
        }
        for t in &triangles {
            text.push_str(&format!(
                "f {} {} {}\n",
                t[0] as usize + first,
                t[1] as usize + first,
                t[2] as usize + first
            ));
        }
        first += points.len();
    }
    let path = dir.join(&parts_name);
    std::fs::write(&path, text).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok((mesh_name, parts_name))
}

/// A confusion table as a row of the printed table.
fn row(table: &Confusion, name: &str, label: &str) -> String {
    let [tp, fp, fn_, tn] = table.0;
    let pct = |a: usize, b: usize| {
        if b == 0 {
            "-".to_string()
        } else {
            format!("{:.0}%", 100.0 * a as f64 / b as f64)
        }
    };
    format!(
        "| {name} | {label} | {} | {tp} | {fp} | {fn_} | {tn} | {} | {} | {} |",
        tp + fp + fn_ + tn,
        pct(tp + tn, tp + fp + fn_ + tn),
        pct(fp, fp + tn),
        pct(fp, tp + fp),
    )
}

fn main() -> ExitCode {
    mvgrasp::cli::exit(run(&Args::parse()))
}

fn run(args: &Args) -> CliResult<()> {
    let objects = load_sets(&args.objects, &args.eval.data)?;
    let suite = LabelSuite {
        grasps: args.n,
        trials: args.k,
        outcome_trials: args.outcome_k,
    };
    let config = suite.analysis_config();
    let params = config.physics.clone().unwrap_or_default();
    let noise = config.physics_noise;
    let gripper = Gripper::default();
    let started = Instant::now();
    let mut all = Vec::new();
    let mut replay = Replay {
        gripper: &gripper,
        physics: &params,
        closing_force_n: params.closing_force_n.unwrap_or(gripper.force_limit_n),
        noise: &noise,
        objects: Vec::new(),
        grasps: Vec::new(),
    };
    if let Some(dir) = &args.replay {
        let meshes = dir.join("meshes");
        std::fs::create_dir_all(&meshes).map_err(|e| format!("{}: {e}", meshes.display()))?;
    }
    for Loaded { group, name, mesh } in &objects {
        let Some(Rested {
            table_from_object,
            object,
            analysis,
            ..
        }) = analyse_at_rest(name, mesh.clone(), &gripper, &config, args.eval.seed)?
        else {
            continue;
        };
        let body = PhysicsObject::from_grasp_object(&object, &config.shape)?;
        if let Some(dir) = &args.replay {
            let (mesh_file, parts_file) =
                write_replay_meshes(&dir.join("meshes"), name, object.mesh(), &body)?;
            let mass = object.mesh().mass_facts(params.object_density_kg_m3)?;
            replay.objects.push(ReplayObject {
                name: name.clone(),
                group: group.clone(),
                mesh: format!("meshes/{mesh_file}"),
                parts: format!("meshes/{parts_file}"),
                num_parts: body.num_parts(),
                table_from_object,
                mass_kg: mass.mass_kg,
                center_of_mass: mass.center_of_mass.to_array(),
                inertia_kg_m2: mass.inertia_kg_m2,
            });
        }
        for (i, g) in analysis.grasps.iter().enumerate() {
            let label = g
                .physics_success
                .ok_or("the analysis ran no perturbed trials")?;
            let outcome =
                suite.outcome((&body, &table_from_object), (&g.grasp, i), args.eval.seed)?;
            if args.replay.is_some() {
                replay.grasps.push(ReplayGrasp {
                    object: replay.objects.len() - 1,
                    index: i,
                    world_from_gripper: g.grasp.world_from_gripper,
                    width_m: g.grasp.width_m,
                    robust_epsilon: g.quality.robust_epsilon,
                    robust: g.robust_label,
                    outcome: g.physics.ok_or("the analysis ran no unperturbed trial")?,
                    physics_rate: label.settled_rate(),
                    outcome_rate: outcome.settled_rate(),
                });
            }
            all.push(LabelRecord {
                set: "label_eval".into(),
                object: name.clone(),
                group: group.clone(),
                robust_epsilon: g.quality.robust_epsilon,
                robust: g.robust_label,
                physics_rate: label.settled_rate(),
                outcome_rate: outcome.settled_rate(),
                outcome_failures: outcome.failures,
            });
        }
        eprintln!(
            "{name}: {} grasps ({:.0} s so far)",
            analysis.grasps.len(),
            started.elapsed().as_secs_f64()
        );
    }
    // The objects' groups in their order, then all of them.
    let mut groups: Vec<String> = Vec::new();
    for o in &objects {
        if !groups.contains(&o.group) {
            groups.push(o.group.clone());
        }
    }
    groups.push("all".into());
    println!(
        "{} objects, {} grasps; physics label: K = {} perturbed trials, held when at least half \
         hold; outcome: K = {} other trials, the same rule\n",
        objects.len(),
        all.len(),
        args.k,
        args.outcome_k
    );
    println!(
        "| objects | label | grasps | + held | + failed | - held | - failed | agreement | false-positive rate | positives that failed |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    for group in &groups {
        // A grasp whose trials all lost the resting pose is not judged.
        let tables = Confusion::of(all.iter().filter(|g| group == "all" || &g.group == group));
        for (table, label) in tables.iter().zip(["robust", "physics", "both"]) {
            println!("{}", row(table, group, label));
        }
    }
    let mut failures = StageCounts::default();
    for g in &all {
        failures += g.outcome_failures;
    }
    let trials = all.len() * args.outcome_k;
    println!(
        "\noutcome trials: {trials}, failed at settle {}, approach {}, close {}, lift {}, shake {}",
        failures.settle, failures.approach, failures.close, failures.lift, failures.shake
    );
    if let Some(path) = &args.eval.json {
        let text = serde_json::to_string_pretty(&all)?;
        std::fs::write(path, text).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    if let Some(dir) = &args.replay {
        let path = dir.join("replay.json");
        let text = serde_json::to_string_pretty(&replay)?;
        std::fs::write(&path, text).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    Ok(())
}
