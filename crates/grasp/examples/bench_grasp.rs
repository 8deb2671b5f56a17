//! Grasp analysis throughput on this machine: antipodal candidates, robust-quality evaluations
//! (25 perturbed samples each) and physics trials (close, lift, shake) per second, on one
//! thread and on all of them (rayon). Prints a Markdown table.
//!
//! cargo run --release -p mvgrasp-grasp --example bench_grasp -- [MESH ...]
//!
//! Without arguments it uses the built-in mug; mesh paths (OBJ/STL/URDF, metres) are added.

use std::process::ExitCode;
use std::time::Instant;

use mvgrasp_geometry::objects::default_object;
use mvgrasp_geometry::{RestingPoses, TriangleMesh, load_mesh};
use mvgrasp_grasp::physics::{FailureStage, PhysicsObject, PhysicsParams, simulate_grasp};
use mvgrasp_grasp::quality::{RobustQualityParams, robust_qualities};
use mvgrasp_grasp::{Grasp, GraspObject, Gripper, SamplingParams, sample_antipodal};
use rayon::prelude::*;

/// Any error, for the one `error: ...` line.
type CliResult<T> = Result<T, Box<dyn std::error::Error + Send + Sync>>;

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("error: {message}");
            ExitCode::from(2)
        }
    }
}

fn run() -> CliResult<()> {
    let mut meshes: Vec<(String, TriangleMesh)> = Vec::new();
    let mug = default_object()?;
    meshes.push((format!("{} (built-in)", mug.name), mug.mesh));
    for path in std::env::args().skip(1) {
        let mesh = load_mesh(&path)?;
        let name = path.rsplit('/').next().unwrap_or(&path).to_string();
        meshes.push((name, mesh));
    }
    let threads = rayon::current_num_threads();
    println!(
        "| object | triangles | threads | candidates/s (tries) | grasps/s | robust evals/s (25 samples) | full physics trials/s | median ms/trial |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for (name, mesh) in meshes {
        let triangles = mesh.triangles().len();
        let rest = RestingPoses::of(&mesh)?;
        let pose = rest.get(0)?.1.table_from_object;
        let object = GraspObject::new(mesh)?;
        let physics_object = PhysicsObject::from_grasp_object(&object, &Default::default())?;
        let mut thread_counts = vec![1];
        if threads > 1 {
            thread_counts.push(threads);
        }
        for n in thread_counts {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(n).build()?;
            let row = pool.install(|| measure(&object, &physics_object, &pose))?;
            println!(
                "| {name} | {triangles} | {n} | {:.0} | {:.0} | {:.0} | {:.1} | {:.1} |",
                row.tries_per_s,
                row.grasps_per_s,
                row.robust_per_s,
                row.trials_per_s,
                row.median_trial_ms
            );
        }
    }
    Ok(())
}

struct Row {
    tries_per_s: f64,
    grasps_per_s: f64,
    robust_per_s: f64,
    trials_per_s: f64,
    median_trial_ms: f64,
}

fn measure(
    object: &GraspObject,
    physics_object: &PhysicsObject,
    table_from_object: &mvgrasp_geometry::Pose3,
) -> CliResult<Row> {
    let gripper = Gripper::default();
    let params = SamplingParams {
        target_grasps: 300,
        max_tries: 20_000,
        ..SamplingParams::default()
    };
    let started = Instant::now();
    let report = sample_antipodal(object, &gripper, &params, Some(table_from_object), 1)?;
    let seconds = started.elapsed().as_secs_f64();
    let poses: Vec<_> = report
        .grasps
        .iter()
        .map(|g| g.grasp.world_from_gripper)
        .collect();
    let quality = RobustQualityParams::default();
    let started = Instant::now();
    let rounds = 3;
    for round in 0..rounds {
        robust_qualities(object, &poses, &gripper, &quality, round)?;
    }
    let robust_per_s = (rounds as usize * poses.len()) as f64 / started.elapsed().as_secs_f64();
    let physics = PhysicsParams::default();
    // Time full trials only (those that get past the approach, which costs no simulated time).
    let trials: Vec<Grasp> = report
        .grasps
        .iter()
        .map(|g| Grasp {
            world_from_gripper: *table_from_object * g.grasp.world_from_gripper,
            width_m: g.grasp.width_m,
        })
        .filter(|grasp| {
            simulate_grasp(physics_object, table_from_object, grasp, &gripper, &physics).is_ok_and(
                |o| {
                    !matches!(
                        o.failed_at,
                        Some(FailureStage::Settle | FailureStage::Approach)
                    )
                },
            )
        })
        .take(60)
        .collect();
    let started = Instant::now();
    let mut trial_ms = trials
        .par_iter()
        .map(|grasp| {
            let t = Instant::now();
            simulate_grasp(physics_object, table_from_object, grasp, &gripper, &physics)
                .map(|_| t.elapsed().as_secs_f64() * 1e3)
        })
        .collect::<Result<Vec<f64>, _>>()?;
    let trials_per_s = trials.len() as f64 / started.elapsed().as_secs_f64();
    trial_ms.sort_by(f64::total_cmp);
    Ok(Row {
        tries_per_s: report.tries as f64 / seconds,
        grasps_per_s: report.grasps.len() as f64 / seconds,
        robust_per_s,
        trials_per_s,
        median_trial_ms: trial_ms
            .get(trial_ms.len() / 2)
            .copied()
            .unwrap_or(f64::NAN),
    })
}
