//! `plan`: the main job. With no arguments it rests the built-in default object (a procedural
//! mug) on a table in its most probable stable pose, renders 5 colour views of it (the first
//! top-down) 0.65 m away, predicts their depth from the colour images alone
//! (`DepthFrom::DEFAULT`: the predictor whose grasps held most often on held-out objects),
//! plans a grasp with the multi-view planner (the views fused, candidates from every view and
//! the fused points, ranked by their modelled chance to hold: the planner whose grasps held
//! most often on held-out objects, on depth and on RGB), and checks it analytically (robust
//! Ferrari-Canny, collision) and in physics (rapier: close, lift, shake); the same run on the
//! rendered (true) depth is printed beside it. `--out DIR` writes `grasps.json`, the overlays,
//! the MCAP log and `views.png` (the colour views above their predicted depth, the best grasps
//! drawn in every view). `--depth-from rendered` plans on a depth camera's views instead,
//! `--no-fuse` with the top-down GQ-CNN alone in the top-down view (0.7 m away),
//! `--depth-from refined|mvs|lsm|baseline` with another predictor.
//!
//! `--depth FILE --intrinsics FILE [--camera-pose FILE] [--mask FILE]` plans on a sensor's
//! depth image instead: the table is fitted in the image (the world is put on it when the
//! camera's pose is not given), the object is the mask's pixels or what stands on the table,
//! and nothing is simulated (there is no mesh). `--rgb DIR` plans on a folder of RGB views
//! with their cameras.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::Parser;
use mvgrasp::cli::{CliResult, ObjectArgs};
use mvgrasp::geometry::{Intrinsics, IntrinsicsPreset};
use mvgrasp::grasps_file::{GraspsFile, write_contact_sheet, write_overlay};
use mvgrasp::infer::Gqcnn;
use mvgrasp::mcap_log::write_plan_log;
use mvgrasp::planner::{
    ChanceSource, DepthFrom, DepthPredictor, ObjectSource, PlanOptions, PlanParams, PlanReport,
    Planner, ScoredGrasp, SensorFiles, SensorPlanParams, View, models, plan_grasp, plan_on_rgb_dir,
    plan_on_sensor_depth, plan_on_views_dir,
};
use mvgrasp::render::{Backend, Renderer};
use mvgrasp::{ObjectReport, ReportParams};
use serde::Serialize;

mod summary;
use summary::{depth_from_words, sensor_summary, summary, truth_comparison};

/// Plan a 6-DoF parallel-jaw grasp for an object seen by cameras around it.
#[derive(Parser, Debug)]
#[command(version, about)]
struct Args {
    #[command(flatten)]
    object: ObjectArgs,
    /// Camera intrinsics preset: phoxi_s, primesense, realsense_d435.
    #[arg(long, default_value = "phoxi_s")]
    camera: String,
    /// The network: a shipped one (gqcnn_small_topdown, gqcnn_small_multiview) or an export's
    /// JSON (training/: NAME.json beside NAME.safetensors). Default: gqcnn_small_multiview for
    /// the multi-view planner (it proposes the candidates of every view); gqcnn_small_topdown
    /// with --no-fuse and on a depth image.
    #[arg(long)]
    model: Option<String>,
    /// The multi-view planner: the views (5 unless --views says otherwise, the first
    /// top-down, 0.65 m away) fused into one model of the scene; every candidate's open hand
    /// checked against it (nothing observed, no unseen space, above the table); the best 10 of
    /// each view re-scored by the top-down GQ-CNN on virtual views along their approaches (the
    /// mean over 4 perturbed copies) and ranked by the shipped ranker's chance to hold. The
    /// default for a mesh's views and for folders of views; with --depth, on the one image.
    #[arg(long, conflicts_with = "no_fuse")]
    fuse: bool,
    /// Plan with the GQ-CNN alone, the views not fused: the top-down GQ-CNN in the top-down
    /// view 0.7 m away (the seed paper's single-view planner), or a multi-view GQ-CNN in each
    /// view on its own (`--model gqcnn_small_multiview`: the seed paper's multi-view policy).
    #[arg(long, conflicts_with = "rgb")]
    no_fuse: bool,
    /// Plan in the first N of the 10 test views (1: the top-down view alone). Default: 5 for
    /// the multi-view planner; with --no-fuse, 1 for a GQ-CNN, 10 for a multi-view GQ-CNN.
    #[arg(long)]
    views: Option<usize>,
    /// Camera distance from the object, metres. Default: 0.7 for a GQ-CNN, 0.65 for a
    /// multi-view GQ-CNN (the middle of what each was trained on).
    #[arg(long)]
    distance_m: Option<f32>,
    /// The pose to rest the object in, among those offered (the same list as `grasps --pose`):
    /// 0 is the most probable that is not marginal (a marginal one for an object with no
    /// other).
    #[arg(long, default_value_t = 0)]
    stable_pose: usize,
    /// Skip the physics trial of the chosen grasp.
    #[arg(long)]
    no_physics: bool,
    /// Answer "no grasp" (exit code 3, the outputs still written) unless the best grasp's
    /// chance to hold reaches this (0 to 1): the multi-view planner's modelled chance (its
    /// ranker, `models/ranker_fused.json`), with --no-fuse the top-down GQ-CNN's quality, each
    /// mapped to the trial's outcomes (`models/probability_fused.json`,
    /// `models/probability_topdown.json`) for the default settings on the plane sweep's or
    /// rendered depth and for a depth camera's images
    #[arg(long)]
    min_probability: Option<f32>,
    /// Return the best-scored grasp without checking the open hand against the observed depth.
    #[arg(long)]
    no_hand_check: bool,
    /// Graphics backend: auto, vulkan, gl, metal, dx12 (or MVGRASP_RENDER_BACKEND).
    #[arg(long, default_value = "auto")]
    backend: String,
    /// Print the full report as JSON on stdout instead of the summary.
    #[arg(long)]
    json: bool,
    /// Refine each view's candidates by Dex-Net 2.0's cross-entropy method (250 sampled, then
    /// 3 rounds of 50 drawn from a Gaussian mixture fitted to the best 25%, 40% as many
    /// components) and take the best of all.
    #[arg(long)]
    cem: bool,
    /// Plan on a sensor's depth image instead of rendering one: `.npy` float32 metres, shape
    /// (H, W) or (H, W, 1), or a 16-bit PNG in millimetres; NaN, infinities and 0 are missing.
    #[arg(long, requires = "intrinsics", conflicts_with_all = ["mesh", "views", "distance_m", "stable_pose"])]
    depth: Option<PathBuf>,
    /// With --depth: the camera's intrinsics, a Berkeley `.intr` or a JSON with `K` (3x3),
    /// `width` and `height`.
    #[arg(long, requires = "depth")]
    intrinsics: Option<PathBuf>,
    /// With --depth: the camera's pose, a Berkeley `.tf` (camera to world) or a JSON with a
    /// 4x4 `world_from_camera`. Without it the world frame is put on the table fitted in the
    /// image.
    #[arg(long, requires = "depth")]
    camera_pose: Option<PathBuf>,
    /// Plan over a folder of views instead: `cameras.json` (the cameras as `render` writes
    /// them, poses included) and per camera `NNN_depth.npy` (metres) or `NNN_depth.png`, and
    /// optionally `NNN_mask.png`; a `render` dataset's `train` or `test` folder is one.
    #[arg(long, conflicts_with_all = ["depth", "mesh", "views", "distance_m", "stable_pose"])]
    views_dir: Option<PathBuf>,
    /// Plan on RGB views instead: a folder with `cameras.json` (the cameras posed in the table
    /// frame, as `render` writes them) and per camera `NNN_rgb.png`, optionally `NNN_mask.png`
    /// (a `render` dataset's `test` folder is one); their depth predicted (`--depth-from`),
    /// then the multi-view planner.
    #[arg(long, conflicts_with_all = ["depth", "mesh", "views", "distance_m", "stable_pose", "views_dir"])]
    rgb: Option<PathBuf>,
    /// How the depth planned on is made from RGB views (at least 2): `baseline`, the classical
    /// plane sweep inside the masks' visual hull (the default: its depth gave the grasps that
    /// held most often); `refined`, the plane sweep refined by the shipped network (a correction
    /// and a confidence per pixel); `mvs`, the shipped multi-view stereo network; `lsm`, the
    /// shipped Learnt Stereo Machine; or, for a built-in object or a mesh, `rendered` (true depth, a depth
    /// camera). On a mesh the views are rendered in colour (random colours), their depth
    /// predicted, the multi-view planner plans over them (`--no-fuse`: the top-down GQ-CNN in
    /// the top-down one), and the summary also gives the same run on the rendered depth.
    #[arg(long, conflicts_with_all = ["depth", "views_dir"])]
    depth_from: Option<String>,
    /// On a mesh, render the colour views with the photographic look (textured, glossy,
    /// lit by the room with shadows, a background, sensor noise, blur and JPEG;
    /// docs/depth-from-rgb.md) instead of random colours under each camera's light.
    #[arg(long, conflicts_with_all = ["depth", "views_dir", "rgb"])]
    photo: bool,
    /// Write `grasps.json` (the ranked grasps with their poses; docs/planning.md, "grasps.json") and, for
    /// sensor depth, a picture of the best grasps over each view (`overlay_N.png`) and an MCAP
    /// log for robot tooling (`plan.mcap`: depth, calibrations, poses, table, grasps) into this
    /// folder.
    #[arg(long)]
    out: Option<PathBuf>,
    /// With --depth: the object's mask, a PNG whose non-zero pixels are the object (both
    /// contacts must lie on it). Without it the object is what stands on the table.
    #[arg(long, requires = "depth")]
    mask: Option<PathBuf>,
}

/// The network `--model` names, or the default for the planner.
fn model_of(args: &Args) -> String {
    args.model
        .clone()
        .unwrap_or_else(|| options_of(args).default_model().to_string())
}

/// No grasp survived: a result, not an error (exit code 3, the outputs still written).
const NO_GRASP: u8 = 3;

fn main() -> ExitCode {
    match run(&Args::parse()) {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::from(NO_GRASP),
        Err(message) => mvgrasp::cli::exit(Err(message)),
    }
}

#[derive(Serialize)]
struct Report<'a> {
    object: &'a ObjectReport,
    model: &'a str,
    /// `lsm`, `baseline` or `rendered`: the depth planned on.
    depth_from: &'a str,
    plan: &'a PlanReport,
    /// The best grasp's chance to hold (the multi-view planner's ranker, or the top-down
    /// GQ-CNN's mapped quality), where this planner has one.
    #[serde(skip_serializing_if = "Option::is_none")]
    hold_probability: Option<f32>,
    /// With depth from RGB: the same run on the rendered (true) depth.
    #[serde(skip_serializing_if = "Option::is_none")]
    on_rendered_depth: Option<&'a PlanReport>,
}

/// The best grasp's chance to hold from `source` (`None`: this planner has none, or the best
/// was not ranked).
fn hold_probability(
    best: Option<&ScoredGrasp>,
    source: Option<ChanceSource>,
) -> CliResult<Option<f32>> {
    let (Some(best), Some(source)) = (best, source) else {
        return Ok(None);
    };
    Ok(source.of(best)?)
}

/// `--min-probability`: checked before planning (a value in [0, 1], and a planner with a
/// chance to hold); after it, whether the best grasp reaches it, with a line saying why not.
fn check_min_probability(
    args: &Args,
    source: Option<ChanceSource>,
    chance: Option<f32>,
) -> CliResult<(bool, String)> {
    let Some(min) = args.min_probability else {
        return Ok((true, String::new()));
    };
    if !(0.0..=1.0).contains(&min) {
        return Err(format!("--min-probability {min}: expected a chance from 0 to 1").into());
    }
    if source.is_none() {
        return Err(
            "--min-probability: only the multi-view planner and the top-down GQ-CNN with \
                    the default run's settings (on the plane sweep's or rendered depth) or on \
                    a depth camera's image have a chance to hold"
                .into(),
        );
    }
    Ok(match chance {
        Some(p) if p < min => (
            false,
            format!("no grasp reaches a chance of {min:.2} to hold: the best's is {p:.2}\n"),
        ),
        _ => (true, String::new()),
    })
}

/// Plans; `Ok(false)` when no grasp was found.
fn run(args: &Args) -> CliResult<bool> {
    if let Some(depth) = &args.depth {
        return run_on_sensor_depth(args, depth);
    }
    if let Some(dir) = args.views_dir.as_ref().or(args.rgb.as_ref()) {
        return run_on_views_dir(args, dir);
    }
    let preset: IntrinsicsPreset = args.camera.parse().map_err(|e| format!("--camera: {e}"))?;
    let intrinsics = Intrinsics::preset(preset);
    let object = args.object.load()?;
    let description = ObjectReport::describe(
        &object.display_name,
        &object.mesh,
        &ReportParams {
            intrinsics,
            views_seed: args.object.seed,
            ..Default::default()
        },
    )?;
    let depth_from = depth_from_of(args)?;
    if args.photo && depth_from.is_none() {
        return Err("--photo renders the colour views depth is predicted from; \
                    --depth-from rendered has none"
            .into());
    }
    let options = PlanOptions {
        camera: preset,
        views: args.views,
        distance_m: args.distance_m,
        stable_pose: args.stable_pose,
        physics: !args.no_physics,
        depth_from,
        photo: args.photo,
        ..options_of(args)
    };
    let (model_name, net) = load_model(&model_of(args))?;
    let source = options.chance_source(&model_name, false);
    check_min_probability(args, source, None)?;
    let (planner, params) = options.on_mesh(net)?;
    let backend = Backend::parse(&args.backend).ok_or_else(|| {
        format!(
            "--backend: unknown backend {:?} (expected auto, vulkan, gl, metal, dx12)",
            args.backend
        )
    })?;
    let renderer = Renderer::new(backend)?;
    let plan = plan_grasp(&renderer, &object.mesh, &planner, &params)?;
    // Depth from RGB: the same run on the rendered depth, beside it.
    let on_truth = match params.depth_from_rgb {
        Some(_) => {
            let truth = PlanParams {
                depth_from_rgb: None,
                ..params.clone()
            };
            Some(plan_grasp(&renderer, &object.mesh, &planner, &truth)?)
        }
        None => None,
    };
    let depth_from = options.depth_from.map_or("rendered", DepthFrom::name);
    let chance = hold_probability(plan.best.as_ref(), source)?;
    let (reaches, verdict) = check_min_probability(args, source, chance)?;
    if args.json {
        let report = Report {
            object: &description,
            model: &model_name,
            depth_from,
            plan: &plan,
            hold_probability: chance,
            on_rendered_depth: on_truth.as_ref(),
        };
        let json = serde_json::to_string_pretty(&report)?;
        println!("{json}");
    } else {
        print!("{}", description.summary());
        print!(
            "{}",
            summary(
                &model_name,
                planner.policy().net(),
                &plan,
                params.views.radius_m,
                (options.fuse, params.plan_views)
            )
        );
        print!("{}", chance_words(chance, source));
        if let (Some(from), Some(truth)) = (options.depth_from, &on_truth) {
            print!("{}", truth_comparison(from, &plan, truth));
        }
        print!("{verdict}");
    }
    if let Some(out) = &args.out {
        write_outputs(
            out,
            &GraspsFile::of_rendered(&plan),
            &plan.scene_views,
            &plan.top,
        )?;
        if !plan.rgb_views.is_empty() {
            let picture = out.join("views.png");
            write_contact_sheet(&picture, &plan.rgb_views, &plan.scene_views, &plan.top)?;
        }
    }
    Ok(plan.best.is_some() && reaches)
}

/// The summary's line on the best grasp's chance to hold (none without one).
fn chance_words(chance: Option<f32>, source: Option<ChanceSource>) -> String {
    match (chance, source) {
        (Some(p), Some(source)) => format!("chance to hold: {p:.2} ({})\n", source.describe()),
        _ => String::new(),
    }
}

/// Writes `grasps.json` and, for each of `views`, a picture of `grasps` over its depth
/// (`overlay_N.png`) into `out`, and with views the MCAP log of the plan (`plan.mcap`).
fn write_outputs(
    out: &Path,
    file: &GraspsFile,
    views: &[View],
    grasps: &[ScoredGrasp],
) -> CliResult<()> {
    std::fs::create_dir_all(out).map_err(|e| format!("{}: {e}", out.display()))?;
    let json = file.to_json()?;
    let path = out.join("grasps.json");
    std::fs::write(&path, json).map_err(|e| format!("{}: {e}", path.display()))?;
    for (i, view) in views.iter().enumerate() {
        let picture = out.join(format!("overlay_{i}.png"));
        write_overlay(&picture, &view.depth, i, grasps)?;
    }
    if !views.is_empty() {
        write_plan_log(&out.join("plan.mcap"), views, file.table.as_ref(), grasps)?;
    }
    Ok(())
}

/// `--depth-from`: the predictor, or `None` for rendered depth (a mesh only).
fn depth_from_of(args: &Args) -> CliResult<Option<DepthFrom>> {
    match args.depth_from.as_deref() {
        None => Ok(Some(DepthFrom::DEFAULT)),
        Some("rendered") if args.rgb.is_none() => Ok(None),
        Some(name) => Ok(name.parse().map(Some).map_err(|e| {
            let rendered = if args.rgb.is_none() {
                ", or rendered"
            } else {
                ""
            };
            format!("--depth-from: {e}{rendered}")
        })?),
    }
}

/// The options every kind of plan shares.
fn options_of(args: &Args) -> PlanOptions {
    // Views (a mesh's, a folder of depth or RGB views) go to the multi-view planner, whose
    // grasps held most often on held-out objects on depth and on RGB, unless --no-fuse; one
    // depth image to the top-down GQ-CNN, unless --fuse.
    let fuse = if args.depth.is_some() {
        args.fuse
    } else {
        !args.no_fuse
    };
    PlanOptions {
        fuse,
        cem: args.cem,
        hand_check: !args.no_hand_check,
        seed: args.object.seed,
        ..PlanOptions::default()
    }
}

/// The network, planner, gripper and settings of planning on sensor depth (`--depth`,
/// `--views-dir`).
fn sensor_setup(
    args: &Args,
) -> CliResult<(String, Planner, mvgrasp::grasp::Gripper, SensorPlanParams)> {
    let (model_name, net) = load_model(&model_of(args))?;
    let (planner, gripper, params) = options_of(args).on_depth(net)?;
    Ok((model_name, planner, gripper, params))
}

/// `plan --depth`: a grasp on a sensor's depth image; `Ok(false)` when none was found.
fn run_on_sensor_depth(args: &Args, depth: &Path) -> CliResult<bool> {
    let (model_name, planner, gripper, params) = sensor_setup(args)?;
    let source = options_of(args).chance_source(&model_name, true);
    check_min_probability(args, source, None)?;
    let files = SensorFiles {
        depth: depth.to_path_buf(),
        intrinsics: args.intrinsics.clone().unwrap_or_default(),
        camera_pose: args.camera_pose.clone(),
        mask: args.mask.clone(),
    };
    let report = plan_on_sensor_depth(&planner, &gripper, &files, &params)?;
    let file = GraspsFile::of_sensor(&report);
    let chance = hold_probability(report.best.as_ref(), source)?;
    let (reaches, verdict) = check_min_probability(args, source, chance)?;
    if args.json {
        println!("{}", file.to_json()?);
    } else {
        print!("{}", sensor_summary(&model_name, &files, &report));
        print!("{}{verdict}", chance_words(chance, source));
    }
    if let Some(out) = &args.out {
        write_outputs(out, &file, std::slice::from_ref(&report.view), &report.top)?;
    }
    Ok(report.best.is_some() && reaches)
}

/// `plan --views-dir`: a grasp over a folder of views; `Ok(false)` when none was found.
fn run_on_views_dir(args: &Args, dir: &Path) -> CliResult<bool> {
    use std::fmt::Write;
    let (model_name, planner, gripper, params) = sensor_setup(args)?;
    let rgb_from = match args.rgb {
        Some(_) => Some(depth_from_of(args)?.unwrap_or(DepthFrom::DEFAULT)),
        None => None,
    };
    let source = options_of(args).chance_source_on_views(&model_name, rgb_from);
    check_min_probability(args, source, None)?;
    let (report, depth) = if let Some(from) = rgb_from {
        let predictor = DepthPredictor::shipped(from)?;
        let rgb = plan_on_rgb_dir(&planner, &gripper, dir, &params, &predictor)?;
        let depth = format!(
            "depth: predicted from RGB by {} in {:.2} s\n",
            depth_from_words(from),
            rgb.depth_s
        );
        (rgb.plan, depth)
    } else {
        let report = plan_on_views_dir(&planner, &gripper, dir, &params)?;
        (report, String::new())
    };
    let file = GraspsFile::of_views(&report);
    let chance = hold_probability(report.best.as_ref(), source)?;
    let (reaches, verdict) = check_min_probability(args, source, chance)?;
    if args.json {
        println!("{}", file.to_json()?);
    } else {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "views: {} ({} cameras), plan: {model_name}",
            dir.display(),
            report.views.len()
        );
        s.push_str(&depth);
        let _ = writeln!(
            s,
            "   view  elevation  table inliers  object pixels  candidates  best in the top 10"
        );
        for (i, view) in report.views.iter().enumerate() {
            let best = report
                .top
                .iter()
                .find(|c| c.view == i)
                .map_or("-".into(), |c| format!("{:.3}", c.quality));
            let (source, pixels) = report.objects[i];
            let _ = writeln!(
                s,
                "   {i:>4}  {:>5.1} deg  {:>12.1}%  {:>8} ({})  {:>10}  {best:>18}",
                view.theta_rad().to_degrees(),
                100.0 * report.tables[i].inlier_share,
                pixels,
                match source {
                    ObjectSource::MaskFile => "mask",
                    ObjectSource::AboveTheTable => "table",
                },
                report.candidates_per_view[i]
            );
        }
        match &report.best {
            Some(best) => {
                let p = best.grasp.center();
                let paper = best.grasp.to_paper();
                let _ = writeln!(
                    s,
                    "best grasp: view {}, quality {:.3}, width {:.1} cm, p = ({:+.3}, {:+.3}, {:+.3}) m, phi {:.1} deg, theta {:.1} deg",
                    best.view,
                    best.quality,
                    100.0 * best.grasp.width_m,
                    p.x,
                    p.y,
                    p.z,
                    paper.phi_rad.to_degrees(),
                    paper.theta_rad.to_degrees()
                );
            }
            None => {
                let _ = writeln!(
                    s,
                    "no grasp: {} candidates rejected: {}",
                    report.rejections.total(),
                    report.rejections.describe()
                );
            }
        }
        print!("{s}{}{verdict}", chance_words(chance, source));
    }
    if let Some(out) = &args.out {
        write_outputs(out, &file, &report.views, &report.top)?;
    }
    Ok(report.best.is_some() && reaches)
}

/// A shipped network by name, or an export's JSON by path.
fn load_model(model: &str) -> CliResult<(String, Gqcnn)> {
    if let Some(shipped) = models::shipped(model) {
        let net = shipped.load()?;
        return Ok((shipped.name.to_string(), net));
    }
    let path = Path::new(model);
    if path.extension().is_some_and(|e| e == "json") {
        let net = Gqcnn::load(path)?;
        return Ok((path.display().to_string(), net));
    }
    let names: Vec<&str> = models::ALL.iter().map(|m| m.name).collect();
    Err(format!(
        "--model: {model:?} is neither a shipped network ({}) nor an export's .json",
        names.join(", ")
    )
    .into())
}
