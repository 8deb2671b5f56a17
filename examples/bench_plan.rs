//! The planner's latency on real depth images, stage by stage: loading the files, fitting the
//! table (and finding the object on it), sampling candidates, scoring them with the network,
//! the cross-entropy method, lifting them to the world and the hand check; for 1 view and for
//! 5 views (gqcnn's real Primesense images 0 to 4, each with its own estimated pose, planned
//! together); the median of repeated runs, and grasps scored per second.
//!
//! Then one view of gqcnn's real clutter images (10 PhoXi bins, 5 Primesense piles, 640 x 480
//! or larger), planned without a mask as `plan --depth` plans it, per set.
//!
//! Then the multi-view planner on a rendered scene (the built-in default object, 5 views on
//! the hemisphere 0.65 m away, the first top-down; rendering not timed): fusing the views,
//! planning in every view with the multi-view GQ-CNN, the hand check against the fused model,
//! and re-scoring the best 10 of each view on virtual views with the top-down GQ-CNN.
//!
//! ```text
//! cargo run --release --example bench_plan -- [--data ../shared/data] [--runs 15] [--fused-only]
//! ```
//!
//! No peer runs beside it: gqcnn (TensorFlow 1) does not install here. Its published figures
//! are printed as such: Dex-Net 2.0 planned in 0.8 s a view on a GPU, 2.5 s with the
//! cross-entropy method (Mahler et al. 2017).

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use clap::Parser;
use mvgrasp::cli::CliResult;
use mvgrasp::grasp::GraspObject;
use mvgrasp::planner::{
    CemParams, Fusion, FusionParams, GqcnnPolicy, MultiViewPlanner, PlanParams, SensorFiles,
    SensorPlanParams, View, VirtualScorer, models, plan_on_sensor_depth, read_view, render_scene,
    sample_image_grasps,
};
use mvgrasp::render::{Backend, Renderer};
use mvgrasp_planner::{TableFitParams, fit_table, objects_above};

#[derive(Parser, Debug)]
#[command(about)]
struct Args {
    /// The shared data folder.
    #[arg(long, default_value = "../shared/data")]
    data: PathBuf,
    /// Timed runs per setting (the median is reported).
    #[arg(long, default_value_t = 15)]
    runs: usize,
    /// Only the multi-view planner's table (no shared data needed).
    #[arg(long)]
    fused_only: bool,
}

fn main() -> ExitCode {
    mvgrasp::cli::exit(run(&Args::parse()))
}

fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

/// Seconds per stage of one plan over `files`.
#[derive(Clone, Copy, Default)]
struct Stages {
    load: f64,
    table: f64,
    sample: f64,
    network: f64,
    plan: f64,
    check: f64,
    scored: usize,
}

fn plan_once(
    policy: &GqcnnPolicy,
    gripper: &mvgrasp::grasp::Gripper,
    files: &[SensorFiles],
) -> CliResult<Stages> {
    let mut s = Stages::default();
    let t = Instant::now();
    let read: Vec<View> = files.iter().map(read_view).collect::<Result<_, _>>()?;
    s.load = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let mut views = Vec::new();
    for view in read {
        let table = fit_table(&view.depth, None, &TableFitParams::default())?;
        let objects = objects_above(&view.depth, &table, &TableFitParams::default())?;
        let mut view = view.with_mask(objects)?;
        view.camera = table.camera(view.camera.intrinsics)?;
        views.push(view);
    }
    s.table = t.elapsed().as_secs_f64();
    // Sampling and scoring on their own, view after view (for the breakdown).
    for view in &views {
        let t = Instant::now();
        let grasps = sample_image_grasps(
            &view.depth,
            view.mask.as_ref(),
            policy.max_width_m,
            &policy.sampler,
            0,
        );
        s.sample += t.elapsed().as_secs_f64();
        let t = Instant::now();
        policy.score(view, &grasps)?;
        s.network += t.elapsed().as_secs_f64();
    }
    // The policy as `plan` runs it (views in parallel; with CEM when set), and the hand check.
    let t = Instant::now();
    let mut plan = policy.plan(&views, 0)?;
    s.plan = t.elapsed().as_secs_f64();
    s.scored = plan.candidates.len();
    let t = Instant::now();
    plan.reject_colliding(&views, None, gripper, 10);
    s.check = t.elapsed().as_secs_f64();
    Ok(s)
}

fn run(args: &Args) -> CliResult<()> {
    if args.fused_only {
        return bench_fused(args);
    }
    let root = args.data.join("real_depth/gqcnn/data");
    let images = root.join("examples/single_object/primesense");
    if !images.is_dir() {
        return Err(format!("{}: no such folder (the shared data)", images.display()).into());
    }
    let files: Vec<SensorFiles> = (0..5)
        .map(|i| SensorFiles {
            depth: images.join(format!("depth_{i}.npy")),
            intrinsics: root.join("calib/primesense/primesense.intr"),
            camera_pose: None,
            mask: None,
        })
        .collect();
    let gripper = PlanParams::default().labels.gripper;
    let net = models::GQCNN_TOPDOWN.load()?;
    let mut policy = GqcnnPolicy::new(net, gripper.max_opening_m)?;
    println!(
        "planner latency on real Primesense depth (640 x 480), {} threads, median of {} runs, ms",
        rayon::current_num_threads(),
        args.runs
    );
    println!(
        "{:<34} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>9} {:>12}",
        "setting",
        "load",
        "table",
        "sample",
        "network",
        "plan",
        "check",
        "total",
        "scored",
        "grasps/s"
    );
    for cem in [false, true] {
        policy.cem = cem.then(CemParams::default);
        for views in [1usize, 5] {
            let mut runs = Vec::new();
            plan_once(&policy, &gripper, &files[..views])?; // warm-up
            for _ in 0..args.runs {
                runs.push(plan_once(&policy, &gripper, &files[..views])?);
            }
            let m = |f: fn(&Stages) -> f64| 1000.0 * median(runs.iter().map(f).collect());
            let total = m(|s| s.load + s.table + s.plan + s.check);
            let scored = runs[0].scored;
            println!(
                "{:<34} {:>8.1} {:>8.1} {:>8.1} {:>8.1} {:>8.1} {:>8.1} {:>8.1} {:>9} {:>12.0}",
                format!("{views} view(s){}", if cem { ", CEM" } else { "" }),
                m(|s| s.load),
                m(|s| s.table),
                m(|s| s.sample),
                m(|s| s.network),
                m(|s| s.plan),
                m(|s| s.check),
                total,
                scored,
                scored as f64 / (m(|s| s.plan) / 1000.0)
            );
        }
    }
    println!(
        "(sample and network: the sampler and the network alone, view after view; plan: both as \
         `plan` runs them, views in parallel, with the cross-entropy method when set)"
    );
    println!(
        "targets: 1 view under 50 ms, 5 views under 150 ms; published, not run here: Dex-Net 2.0 \
         0.8 s a view on a GPU, 2.5 s with the cross-entropy method"
    );
    bench_clutter(args, &root, &gripper)?;
    bench_fused(args)
}

/// gqcnn's real clutter images (10 PhoXi bins, 5 Primesense piles): one view planned as `plan
/// --depth D --intrinsics K --camera-pose P` plans it, no mask (read, table and objects, plan,
/// hand check); per set, the median over its images of each image's median run.
fn bench_clutter(
    args: &Args,
    root: &std::path::Path,
    gripper: &mvgrasp::grasp::Gripper,
) -> CliResult<()> {
    let sets = [
        (
            "PhoXi bins (Dex-Net 4.0)",
            "examples/clutter/phoxi/dex-net_4.0",
            "phoxi/phoxi.intr",
            "phoxi/phoxi_to_world.tf",
        ),
        (
            "PhoXi bins (FC-GQ-CNN)",
            "examples/clutter/phoxi/fcgqcnn",
            "phoxi/phoxi.intr",
            "phoxi/phoxi_to_world.tf",
        ),
        (
            "Primesense piles",
            "examples/clutter/primesense",
            "primesense/primesense.intr",
            "primesense/primesense.tf",
        ),
    ];
    let planner = mvgrasp::planner::Planner::from(GqcnnPolicy::new(
        models::GQCNN_TOPDOWN.load()?,
        gripper.max_opening_m,
    )?);
    let params = SensorPlanParams::default();
    println!(
        "\nclutter: one real view planned without a mask (`plan --depth` with the camera's pose), \
         median of {} runs per image, ms; target 200 ms",
        args.runs
    );
    println!(
        "{:<28} {:>10} {:>8} {:>8}",
        "images", "size", "median", "slowest"
    );
    for (name, folder, intrinsics, pose) in sets {
        let mut per_image = Vec::new();
        let mut size = String::new();
        for i in 0..5 {
            let files = SensorFiles {
                depth: root.join(folder).join(format!("depth_{i}.npy")),
                intrinsics: root.join("calib").join(intrinsics),
                camera_pose: Some(root.join("calib").join(pose)),
                mask: None,
            };
            let once = || -> CliResult<(f64, String)> {
                let t = Instant::now();
                let report = plan_on_sensor_depth(&planner, gripper, &files, &params)?;
                let k = report.view.camera.intrinsics;
                Ok((
                    t.elapsed().as_secs_f64(),
                    format!("{} x {}", k.width, k.height),
                ))
            };
            size = once()?.1; // warm-up
            let runs = (0..args.runs)
                .map(|_| once().map(|(t, _)| t))
                .collect::<CliResult<Vec<f64>>>()?;
            per_image.push(median(runs));
        }
        let slowest = per_image.iter().copied().fold(0.0, f64::max);
        println!(
            "{name:<28} {size:>10} {:>8.1} {:>8.1}",
            1000.0 * median(per_image),
            1000.0 * slowest
        );
    }
    println!("(no peer runs here: gqcnn's Dex-Net 4.0 and FC-GQ-CNN need TensorFlow 1)");
    Ok(())
}

/// The multi-view planner's stages on 5 rendered views of the default object.
fn bench_fused(args: &Args) -> CliResult<()> {
    let renderer = Renderer::new(Backend::Auto)?;
    let object = mvgrasp::geometry::objects::default_object()?;
    let object = GraspObject::new(object.mesh)?;
    let mut params = PlanParams::default();
    params.views.count = 5;
    params.views.radius_m = 0.65;
    params.fusion = Some(FusionParams::default());
    let scene = render_scene(&renderer, &object, &params)?;
    let gripper = params.labels.gripper.clone();
    let net = models::MVGQCNN.load()?;
    let policy = GqcnnPolicy::new(net, gripper.max_opening_m)?;
    let scorer = VirtualScorer::shipped(gripper.max_opening_m)?;
    let keep = scorer.params.candidates_per_view;
    let planner = MultiViewPlanner::new(policy, scorer);
    let fusion_params = FusionParams::default();
    let once = || -> CliResult<[f64; 4]> {
        let t = Instant::now();
        let fusion = Fusion::build(&scene.views, &fusion_params).ok_or("nothing to fuse")?;
        let fuse = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let mut plan = planner.proposer.plan(&scene.views, 0)?;
        plan.merge(planner.scorer.propose(&scene.views, 0)?);
        let planned = t.elapsed().as_secs_f64();
        let t = Instant::now();
        plan.reject_colliding_each_view(&scene.views, Some(&fusion), &gripper, keep);
        let check = t.elapsed().as_secs_f64();
        let t = Instant::now();
        planner.scorer.rescore(&mut plan, &fusion, 0)?;
        Ok([fuse, planned, check, t.elapsed().as_secs_f64()])
    };
    once()?; // warm-up
    let runs = (0..args.runs)
        .map(|_| once())
        .collect::<Result<Vec<_>, _>>()?;
    let m = |i: usize| 1000.0 * median(runs.iter().map(|r| r[i]).collect());
    let total = 1000.0 * median(runs.iter().map(|r| r.iter().sum()).collect());
    println!(
        "\nthe multi-view planner on 5 rendered views of the default object ({} x {}), median of \
         {} runs, ms",
        params.intrinsics.width, params.intrinsics.height, args.runs
    );
    println!(
        "{:<34} {:>8} {:>8} {:>8} {:>8} {:>8}",
        "setting", "fuse", "plan", "check", "rescore", "total"
    );
    println!(
        "{:<34} {:>8.1} {:>8.1} {:>8.1} {:>8.1} {:>8.1}",
        "5 views fused, re-scored",
        m(0),
        m(1),
        m(2),
        m(3),
        total
    );
    let fusion = Fusion::build(&scene.views, &fusion_params).ok_or("nothing to fuse")?;
    let [free, unknown, occupied] = fusion.counts();
    println!(
        "fused model: {:?} cells of {:.1} mm ({free} free, {unknown} unknown, {occupied} \
         occupied), {} points for virtual views",
        fusion.dims(),
        1000.0 * fusion.voxel_m(),
        fusion.points().len()
    );
    println!("target: under 300 ms, fusion included");
    Ok(())
}
