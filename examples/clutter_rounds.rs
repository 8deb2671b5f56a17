//! Clutter rounds in the manner of VGN and GIGA's "packed" scenario, in mvgrasp's own trial:
//! each round packs 5 built-in held-out objects (indices 30 to 34, categories drawn at random,
//! each in its most probable resting pose, turned at random, their footprints kept apart
//! within 10 cm of the first), and grasps until the table is empty, two grasps in a row fail,
//! or the planner finds no grasp. Each grasp is planned on one top-down depth image of the
//! scene (a PhoXi S 0.7 m above the table, rendered), without a mask (`plan_on_view`: the
//! objects are what stands on the fitted table), and tried in rapier among the others
//! (`simulate_grasp_among`) on the object nearest its centre; the grasped object must come
//! out alone. A held object is taken away; after a failure the scene is as it was (the
//! trial's pushes are not carried to the next grasp, where VGN's simulator carries them) and
//! the next attempt samples its candidates with the next seed. An
//! object that does not stay in its pose before the hand comes (the trial's settle) is taken
//! away uncounted: it tests the pose, not the grasp. A scene holds fewer objects when the
//! packing finds no room for one.
//!
//! ```text
//! cargo run --release --example clutter_rounds -- [--rounds 20] [--objects 5] [--seed 0]
//!     [--model RUN/NAME.json | --fused]
//! ```
//!
//! `--fused`: five views (the top-down one and four 50 degrees up around the scene, 0.7 m
//! away), fused by the multi-view planner (`plan_on_views`, as `plan --views-dir` plans).
//!
//! Prints each grasp and, at the end, the success rate (held of grasps tried) and the share of
//! objects cleared, as VGN and GIGA report them.

use std::process::ExitCode;
use std::rc::Rc;

use clap::Parser;
use mvgrasp::cli::CliResult;
use mvgrasp::geometry::objects::{Category, generate};
use mvgrasp::geometry::{Camera, Intrinsics, IntrinsicsPreset, Pose3, Vec3};
use mvgrasp::grasp::LabelSettings;
use mvgrasp::grasp::physics::{FailureStage, PhysicsObject, simulate_grasp_among};
use mvgrasp::grasp_dataset::clutter::{ClutterParams, Neighbour, place};
use mvgrasp::planner::{
    GqcnnPolicy, PlanOptions, Planner, SensorPlanParams, View, models, plan_on_view, plan_on_views,
};
use mvgrasp::render::{Backend, Renderer};
use mvgrasp::scene::render_depths;
use parry3d::query::PointQuery;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

#[derive(Parser)]
#[command(about = "Packed clutter rounds in mvgrasp's trial (VGN/GIGA's protocol)")]
struct Args {
    /// Rounds (scenes).
    #[arg(long, default_value_t = 20)]
    rounds: usize,
    /// Objects packed per scene (at least 1).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u16).range(1..))]
    objects: u16,
    /// Seeds the scenes.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// A top-down GQ-CNN export (`NAME.json`) instead of the shipped one (one view only).
    #[arg(long, conflicts_with = "fused")]
    model: Option<std::path::PathBuf>,
    /// Five views (the top-down one and four 50 degrees up around the scene, 0.7 m away),
    /// fused by the multi-view planner, as `plan --views-dir` plans.
    #[arg(long)]
    fused: bool,
}

/// One object of a scene: its mesh resting at its pose, and its shapes for the trial.
struct Placed {
    name: String,
    /// Its mesh and the shape its distance is measured to.
    shape: Rc<Neighbour>,
    pose: Pose3,
    physics: PhysicsObject,
}

fn main() -> ExitCode {
    mvgrasp::cli::exit(run(Args::parse()))
}

fn run(args: Args) -> CliResult<()> {
    let renderer = Renderer::new(Backend::Auto)?;
    let labels = LabelSettings::default();
    let gripper = labels.gripper.clone();
    let (planner, base_params) = if args.fused {
        let options = PlanOptions {
            fuse: true,
            ..PlanOptions::default()
        };
        let (planner, _, params) = options.on_depth(models::MVGQCNN.load()?)?;
        (planner, params)
    } else {
        let net = match &args.model {
            Some(path) => mvgrasp::infer::Gqcnn::load(path)?,
            None => models::GQCNN_TOPDOWN.load()?,
        };
        let planner = Planner::from(GqcnnPolicy::new(net, gripper.max_opening_m)?);
        (planner, SensorPlanParams::default())
    };
    let k = Intrinsics::preset(IntrinsicsPreset::PhoxiS);
    let mut cameras = vec![Camera::look_at(
        k,
        Vec3::new(0.0, 0.0, 0.7),
        Vec3::ZERO,
        Vec3::Y,
    )?];
    if args.fused {
        let e = 50.0f32.to_radians();
        for azimuth in [0.0f32, 90.0, 180.0, 270.0] {
            let a = azimuth.to_radians();
            let eye = Vec3::new(e.cos() * a.cos(), e.cos() * a.sin(), e.sin()) * 0.7;
            cameras.push(Camera::look_at(k, eye, Vec3::ZERO, Vec3::Z)?);
        }
    }
    let (mut tried, mut held, mut cleared, mut total) = (0usize, 0usize, 0usize, 0usize);
    let mut unsettled = 0usize;
    for round in 0..args.rounds {
        let mut rng = ChaCha8Rng::seed_from_u64(args.seed ^ (round as u64).wrapping_mul(0x9e37));
        let mut scene = pack(usize::from(args.objects), &labels, &mut rng)?;
        total += scene.len();
        let mut failures_in_a_row = 0;
        let mut attempt = 0u64;
        while !scene.is_empty() && failures_in_a_row < 2 {
            let parts: Vec<_> = scene
                .iter()
                .map(|o| o.shape.mesh().transformed(&o.pose))
                .collect();
            let merged = mvgrasp::geometry::TriangleMesh::concatenate(&parts, parts[0].origin())?;
            let depths = render_depths(&renderer, &merged, &Pose3::IDENTITY, &cameras)?;
            let views: Vec<View> = cameras
                .iter()
                .zip(depths)
                .map(|(camera, depth)| View {
                    camera: *camera,
                    depth,
                    mask: None,
                })
                .collect();
            // Each attempt samples anew (the scene is as before a failure, so the same seed
            // would plan the same grasp).
            let params = SensorPlanParams {
                seed: attempt,
                ..base_params.clone()
            };
            attempt += 1;
            let best = if args.fused {
                plan_on_views(&planner, &gripper, views, &params)
                    .ok()
                    .and_then(|r| r.best)
            } else {
                let view = views.into_iter().next().ok_or("no view")?;
                plan_on_view(&planner, &gripper, view, true, &params)
                    .ok()
                    .and_then(|r| r.best)
            };
            let Some(best) = best else {
                println!("round {round}: no grasp with {} objects left", scene.len());
                break;
            };
            let centre = best.grasp.center();
            let target = nearest(&scene, centre);
            let others: Vec<(&PhysicsObject, Pose3)> = scene
                .iter()
                .enumerate()
                .filter(|(i, _)| *i != target)
                .map(|(_, o)| (&o.physics, o.pose))
                .collect();
            let outcome = simulate_grasp_among(
                &scene[target].physics,
                &scene[target].pose,
                &others,
                &best.grasp,
                &gripper,
                &labels.physics,
            )?;
            if outcome.failed_at == Some(FailureStage::Settle) {
                // The object did not stay in its pose before the hand came: the trial tests the
                // pose, not the grasp (as `evaluate` leaves such plans out). It leaves the scene
                // uncounted.
                println!(
                    "round {round}: {} does not rest in its pose: taken away, not counted",
                    scene[target].name
                );
                unsettled += 1;
                scene.remove(target);
                continue;
            }
            tried += 1;
            let verdict = match outcome.failed_at {
                None => "held".to_string(),
                Some(stage) => format!("failed at {}", stage.name()),
            };
            println!(
                "round {round}: {} of {} left, quality {:.3}: {verdict}",
                scene[target].name,
                scene.len(),
                best.quality
            );
            if outcome.success {
                held += 1;
                cleared += 1;
                scene.remove(target);
                failures_in_a_row = 0;
            } else {
                failures_in_a_row += 1;
            }
        }
    }
    let pct = |a: usize, b: usize| 100.0 * a as f64 / b.max(1) as f64;
    let counted = total - unsettled;
    println!(
        "{} rounds of up to {} objects: success {:.1}% ({held} of {tried} grasps), cleared \
         {:.1}% ({cleared} of {counted} objects; {unsettled} that did not rest in their pose \
         left out)",
        args.rounds,
        args.objects,
        pct(held, tried),
        pct(cleared, counted)
    );
    Ok(())
}

/// `count` held-out built-in objects packed on the table: the first at the origin in its most
/// probable resting pose, the rest around it.
fn pack(count: usize, labels: &LabelSettings, rng: &mut ChaCha8Rng) -> CliResult<Vec<Placed>> {
    let mut chosen = Vec::new();
    for _ in 0..count {
        let category = Category::ALL[rng.random_range(0..Category::ALL.len())];
        let index = 30 + rng.random_range(0..5u32);
        chosen.push((category, index));
    }
    let objects: Vec<Rc<Neighbour>> = chosen
        .iter()
        .map(|&(c, i)| Ok(Rc::new(Neighbour::new(generate(c, i, 0)?.mesh)?)))
        .collect::<CliResult<_>>()?;
    let first_pose = objects[0].most_probable_pose();
    let params = ClutterParams {
        neighbours: [count - 1, count - 1],
        spread_m: 0.1,
        gap_m: 0.005,
        tries: 50,
    };
    let mut poses = vec![(0, first_pose)];
    for p in place(objects[0].mesh(), &first_pose, &objects[1..], &params, rng) {
        poses.push((p.index + 1, p.table_from_neighbour));
    }
    poses
        .into_iter()
        .map(|(i, pose)| {
            let physics =
                PhysicsObject::from_grasp_object(objects[i].object(), &labels.physics_shape)?;
            Ok(Placed {
                name: format!("{}_{:03}", chosen[i].0.name(), chosen[i].1),
                shape: Rc::clone(&objects[i]),
                pose,
                physics,
            })
        })
        .collect()
}

/// The object of `scene` whose surface is nearest `point` (world frame).
fn nearest(scene: &[Placed], point: Vec3) -> usize {
    let distance = |o: &Placed| {
        let local = o.pose.inverse_transform_point(point);
        o.shape
            .object()
            .caster()
            .trimesh()
            .distance_to_local_point(local, true)
    };
    (0..scene.len())
        .min_by(|&a, &b| distance(&scene[a]).total_cmp(&distance(&scene[b])))
        .unwrap_or(0)
}
