//! Depth from RGB against the rendered depth (the seed paper's Table 1): for built-in objects
//! the networks never saw, the paper's 10 test views (0.5 m, the first top-down) rendered in
//! random colours with their masks; depth predicted from the first N views (3, 5, 9: the
//! top-down view and N - 1 around it; `--views 1`: the top-down view alone, the LSM only) and
//! compared with the rendered depth over the object's pixels.
//!
//! ```text
//! cargo run --release --example depth_eval -- [--per-category 3] [--per-face] [--distance-m 0.5]
//!     [--views 3,5,9] [--sweep-hull] [--photo] [--methods lsm,sweep,mvs,refined]
//!     [--refiner RUN/sweep_refiner_small.json]
//! ```
//!
//! `--photo` renders the views with the photographic look (`mvgrasp::scene::photoreal`:
//! textures, gloss, room lights, a background, sensor noise, blur and JPEG) instead of random
//! colours under each camera's headlight.
//!
//! Per method and N, over the top-down view and over all N views: the mean absolute error of
//! the predicted object pixels (millimetres), the share of object pixels predicted, the shares
//! within 2 mm and 5 mm (of all object pixels: a missing pixel is not within), the paper's
//! normalised error (here: the mean absolute error divided by the mean true depth of the object
//! pixels, so 0.0035 is 1.75 mm at 0.5 m), and the prediction's time for the N views.
//! Methods: the Learnt Stereo Machine (the shipped `models/lsm_small`, `lsm::lsm_depths`), the
//! plane sweep inside the visual hull (`stereo::sweep_depths`), the visual hull alone (its
//! nearest surface; timed with the sweep, which makes it) and the learned multi-view stereo
//! network (the shipped `models/mvs_small`, `mvs::mvs_depths`, every pixel kept whatever its
//! confidence). Each row also gives the median error of the predicted pixels. The LSM's threads: rayon's pool
//! (`RAYON_NUM_THREADS`), as the baseline's. `--methods` runs some of them (the hull comes with
//! the sweep); `--refiner` scores a training run's export instead of the shipped refiner.

use std::process::ExitCode;
use std::time::Instant;

use clap::Parser;
use mvgrasp::cli::CliResult;
use mvgrasp::evaluate::depth::DepthErrors;
use mvgrasp::geometry::objects::{Category, generate};
use mvgrasp::geometry::{HemisphereLayout, Intrinsics, IntrinsicsPreset, RestingPoses};
use mvgrasp::infer::{Parallelism, SweepRefiner};
use mvgrasp::lsm::lsm_depths;
use mvgrasp::mvs::mvs_depths;
use mvgrasp::planner::{DepthPredictor, RgbInput, models, render_rgb};
use mvgrasp::render::{Backend, Renderer};
use mvgrasp::scene::photoreal::render_photoreal;
use mvgrasp::stereo::{RgbView, SweepParams, sweep_depths};
use mvgrasp::sweep_refiner::RefinedSweep;

/// Depth from RGB views against the rendered depth, on unseen built-in objects.
#[derive(Parser, Debug)]
#[command(about)]
struct Args {
    /// Built-in objects per category (indices 30, 31, ...: never in a training set).
    #[arg(long, default_value_t = 3)]
    per_category: u32,
    /// Colour the objects per triangle instead of per vertex.
    #[arg(long)]
    per_face: bool,
    /// The cameras' distance from the object, metres (the paper's test views and the LSM's
    /// training views: 0.5; the multi-view planner's: 0.65).
    #[arg(long, default_value_t = 0.5)]
    distance_m: f32,
    /// The numbers of input views (1 to 10: the top-down view and the next test views; with one
    /// view only the LSM, stereo and carving need two).
    #[arg(long, value_delimiter = ',', default_values_t = [3usize, 5, 9])]
    views: Vec<usize>,
    /// The sweep's unconfirmed pixels at the visual hull's depth, as the default run's one-view
    /// planner gets them (`DepthPredictor::for_one_view`), instead of missing (`plan --rgb`).
    #[arg(long)]
    sweep_hull: bool,
    /// The photographic look instead of the flat one (`--per-face` is then ignored).
    #[arg(long)]
    photo: bool,
    /// The methods to run: lsm, sweep (with the visual hull), mvs, refined.
    #[arg(long, value_delimiter = ',', default_values_t = Method::ALL.map(String::from))]
    methods: Vec<String>,
    /// A sweep refiner export's JSON (NAME.json beside NAME.safetensors, as
    /// `mvgrasp_training.train_sweep_refiner --export` writes it) instead of the shipped one.
    #[arg(long)]
    refiner: Option<std::path::PathBuf>,
}

/// The methods' names on the command line, in the tables' order (the hull is the sweep's).
struct Method;

impl Method {
    const ALL: [&str; 4] = ["lsm", "sweep", "mvs", "refined"];
}

/// `errors` as the table's cells: median, MAE, predicted, within 2 mm, within 5 mm,
/// normalised.
fn row(errors: &DepthErrors) -> String {
    let n = errors.object_pixels.max(1) as f64;
    format!(
        "{:.1} | {:.2} | {:.0}% | {:.0}% | {:.0}% | {:.4}",
        errors.median_mm(),
        errors.mean_mm(),
        100.0 * errors.predicted_share(),
        100.0 * errors.within_2mm as f64 / n,
        100.0 * errors.within_5mm_share(),
        errors.normalised()
    )
}

fn main() -> ExitCode {
    mvgrasp::cli::exit(run(&Args::parse()))
}

fn run(args: &Args) -> CliResult<()> {
    let renderer = Renderer::new(Backend::Auto)?;
    let intrinsics = Intrinsics::preset(IntrinsicsPreset::PhoxiS);
    let sweep = SweepParams {
        hull_where_unconfirmed: args.sweep_hull,
        ..SweepParams::default()
    };
    let input = RgbInput {
        depth: DepthPredictor::Baseline(sweep.clone()),
        per_face: args.per_face,
        photo: false,
    };
    if let Some(unknown) = args
        .methods
        .iter()
        .find(|m| !Method::ALL.contains(&m.as_str()))
    {
        return Err(format!(
            "--methods {unknown}: expected some of {}",
            Method::ALL.join(", ")
        )
        .into());
    }
    let runs = |method: &str| args.methods.iter().any(|m| m == method);
    // [LSM, sweep, hull, MVS, refined]: the rows printed.
    let shown = [
        runs("lsm"),
        runs("sweep"),
        runs("sweep"),
        runs("mvs"),
        runs("refined"),
    ];
    let lsm = models::LSM
        .load()?
        .with_parallelism(Parallelism::all_threads());
    let mvs = models::MVS
        .load()?
        .with_parallelism(Parallelism::all_threads());
    let refiner_net = match &args.refiner {
        Some(json) => SweepRefiner::load(json)?,
        None => models::SWEEP_REFINER.load()?,
    };
    let refiner_name = match &args.refiner {
        Some(json) => json.display().to_string(),
        None => "sweep_refiner_small".to_string(),
    };
    // Every pixel kept, as the default run's one-view planner gets them.
    let refined = RefinedSweep {
        net: std::sync::Arc::new(refiner_net.with_parallelism(Parallelism::all_threads())),
        min_confidence: 0.0,
        unsure: mvgrasp::sweep_refiner::Unsure::Missing,
    };
    let counts = &args.views;
    if let Some(n) = counts.iter().find(|n| !(1..=10).contains(*n)) {
        return Err(format!("--views {n}: expected 1 to 10 (there are 10 test views)").into());
    }
    if !(args.distance_m.is_finite() && args.distance_m > 0.0) {
        return Err(format!(
            "--distance-m {}: expected a distance in metres above 0",
            args.distance_m
        )
        .into());
    }
    let layout = HemisphereLayout {
        radius_m: args.distance_m,
        ..HemisphereLayout::paper_test()
    };
    // [n][method][top-down, all views]; method 0 LSM, 1 sweep, 2 hull, 3 MVS, 4 refined sweep.
    let mut tallies: Vec<[[DepthErrors; 2]; 5]> = vec![Default::default(); counts.len()];
    // [n][LSM, baseline, hull (the baseline's), MVS, refined]
    let mut seconds = vec![[0.0f64; 5]; counts.len()];
    // [network: MVS, refined][n][confidence decile]: the object pixels (all views) and those
    // within 5 mm.
    let mut reliability = vec![vec![[[0usize; 2]; 10]; counts.len()]; 2];
    let mut objects = 0;
    for category in Category::ALL {
        for index in 30..30 + args.per_category {
            let object = generate(category, index, 0)?;
            let rest = RestingPoses::of(&object.mesh)?;
            let (_, pose) = rest.get(0)?;
            let com = object.mesh.mass_facts(1000.0)?.center_of_mass;
            let target = pose.table_from_object.transform_point(com);
            let cameras = layout.cameras(intrinsics, target, u64::from(index))?;
            let rendered = if args.photo {
                render_photoreal(
                    &renderer,
                    &object.mesh,
                    &pose.table_from_object,
                    &cameras,
                    u64::from(index),
                )
                .map(|photo| photo.views)
            } else {
                render_rgb(
                    &renderer,
                    &object.mesh,
                    &pose.table_from_object,
                    &cameras,
                    &input,
                    u64::from(index),
                )
            }?;
            objects += 1;
            for (c, &n) in counts.iter().enumerate() {
                let views: Vec<RgbView> = rendered[..n].iter().map(|(v, _)| v.clone()).collect();
                let started = Instant::now();
                let learnt = if shown[0] {
                    lsm_depths(&lsm, &views)?
                } else {
                    Vec::new()
                };
                seconds[c][0] += started.elapsed().as_secs_f64();
                // One view: the LSM alone (stereo and carving need two).
                let started = Instant::now();
                let depths = if n >= 2 && shown[1] {
                    sweep_depths(&views, &sweep)?
                } else {
                    Vec::new()
                };
                seconds[c][1] += started.elapsed().as_secs_f64();
                seconds[c][2] = seconds[c][1];
                let started = Instant::now();
                let stereo = if n >= 2 && shown[3] {
                    mvs_depths(&mvs, &views, 0.0)?
                } else {
                    Vec::new()
                };
                seconds[c][3] += started.elapsed().as_secs_f64();
                let started = Instant::now();
                let sharpened = if n >= 2 && shown[4] {
                    refined.depths(&views)?
                } else {
                    Vec::new()
                };
                seconds[c][4] += started.elapsed().as_secs_f64();
                for (i, (view, truth)) in rendered[..n].iter().enumerate() {
                    let mask = view.mask.as_deref().unwrap_or(&[]);
                    let mut methods: Vec<_> = learnt.get(i).map(|d| (0, d)).into_iter().collect();
                    if let Some(swept) = depths.get(i) {
                        methods.extend([(1, &swept.depth_m), (2, &swept.hull_m)]);
                    }
                    let confident = [
                        stereo.get(i).map(|p| (3, &p.depth_m, &p.confidence)),
                        sharpened.get(i).map(|p| (4, &p.depth_m, &p.confidence)),
                    ];
                    // The reliability table's index: 0 the MVS network, 1 the refined sweep.
                    let confident = confident
                        .into_iter()
                        .enumerate()
                        .filter_map(|(network, p)| Some((network, p?)));
                    for (network, (m, depth, confidence)) in confident {
                        methods.push((m, depth));
                        let pixels = depth.iter().zip(confidence);
                        for (((&d, &confidence), &t), &on) in pixels.zip(truth).zip(mask) {
                            if on && t > 0.0 {
                                let decile = ((confidence * 10.0) as usize).min(9);
                                let tally = &mut reliability[network][c][decile];
                                tally[0] += 1;
                                tally[1] += usize::from((d - t).abs() <= 5e-3);
                            }
                        }
                    }
                    for (m, predicted) in methods {
                        if i == 0 {
                            tallies[c][m][0].add(predicted, truth, mask);
                        }
                        tallies[c][m][1].add(predicted, truth, mask);
                    }
                }
            }
            eprint!(".");
        }
    }
    eprintln!();
    println!(
        "{objects} objects (indices 30-{}), 10 test views {:.2} m away, {}",
        29 + args.per_category,
        args.distance_m,
        if args.photo {
            "the photographic look"
        } else if args.per_face {
            "colours per triangle"
        } else {
            "colours per vertex"
        }
    );
    println!(
        "| method | input views | views scored | median (mm) | MAE (mm) | predicted | within 2 mm | within 5 mm | normalised | time (s) |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    for (c, &n) in counts.iter().enumerate() {
        let methods = [
            "LSM (lsm_small)".to_string(),
            "plane sweep in the hull".to_string(),
            "visual hull alone".to_string(),
            "MVS (mvs_small)".to_string(),
            format!("refined sweep ({refiner_name})"),
        ];
        for (m, method) in methods.iter().enumerate() {
            if (n < 2 && m > 0) || !shown[m] {
                continue;
            }
            for (s, scored) in ["top-down", "all"].iter().enumerate() {
                println!(
                    "| {method} | {n} | {scored} | {} | {:.2} |",
                    row(&tallies[c][m][s]),
                    seconds[c][m] / objects as f64
                );
            }
        }
    }
    for (network, name) in ["MVS", "refined sweep"].iter().enumerate() {
        if !shown[3 + network] {
            continue;
        }
        println!(
            "\n{name}: confidence against error (object pixels of all views): the share within 5 mm"
        );
        println!("| input views | confidence | pixels | within 5 mm |");
        println!("|---|---|---|---|");
        for (c, &n) in counts.iter().enumerate() {
            for (decile, [pixels, good]) in reliability[network][c].iter().enumerate() {
                if *pixels > 0 {
                    println!(
                        "| {n} | {:.1}-{:.1} | {pixels} | {:.0}% |",
                        decile as f64 / 10.0,
                        (decile + 1) as f64 / 10.0,
                        100.0 * *good as f64 / *pixels as f64
                    );
                }
            }
        }
    }
    Ok(())
}
