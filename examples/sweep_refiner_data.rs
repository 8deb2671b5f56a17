//! The sweep refiner's training data: built-in objects of the LSM's library (seed 2: other
//! shapes than every evaluation's), each resting in a random offered pose, seen by 2 to 8
//! cameras 0.4 to 0.8 m away (elevations 15 to 85 degrees, the first top-down in half the
//! samples), coloured at random per vertex or per triangle; in half the samples the plane
//! sweep runs on cameras moved by up to 2 mm and 0.5 degrees (a rig's calibration error), in
//! the other half on the true ones; with `--photo-share P`, a share P of the samples is
//! rendered with the photographic look (`mvgrasp::scene::photoreal`: textures, gloss, room
//! lights, background, sensor noise, blur, JPEG) instead of the flat one; each of up to
//! `--views-per-sample` of the views is written as `SSSSS_V.npy`: float32
//! `[FEATURES + 2, h, w]`, the refiner's features (`mvgrasp::sweep_refiner::view_features`)
//! then the base depth and the rendered depth (metres) over the object's box.
//!
//! ```text
//! cargo run --release --example sweep_refiner_data -- --out ../datasets/sweep_refiner \
//!     [--samples 400] [--first-sample 0] [--seed 0] [--photo-share 0.75]
//! ```
//!
//! Deterministic by seed; a finished sample (`SSSSS.done`) is skipped (files are written to a
//! temporary name and renamed), so an interrupted run resumes. When every sample is done,
//! `dataset.json` records the settings and the features' names.

use std::path::PathBuf;
use std::process::ExitCode;

mod common;

use clap::Parser;
use mvgrasp::cli::CliResult;
use mvgrasp::geometry::objects::{Category, generate};
use mvgrasp::geometry::{
    Camera, HemisphereLayout, Intrinsics, IntrinsicsPreset, Pose3, RestingPoses, Rot3, Vec3,
};
use mvgrasp::planner::{DepthPredictor, RgbInput, render_rgb};
use mvgrasp::render::{Backend, Renderer};
use mvgrasp::scene::photoreal::render_photoreal;
use mvgrasp::stereo::{RgbView, sweep_depths};
use mvgrasp::sweep_refiner::{FEATURES, RefinedSweep, view_features};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Write the sweep refiner's training samples.
#[derive(Parser, Debug)]
#[command(about)]
struct Args {
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
    /// Samples to write (each one object, one camera rig).
    #[arg(long, default_value_t = 400)]
    samples: u32,
    /// The first sample's number (samples are independent: ranges can run apart).
    #[arg(long, default_value_t = 0)]
    first_sample: u32,
    /// Objects per category drawn from (indices 0 to N - 1 of library seed 2).
    #[arg(long, default_value_t = 20)]
    per_category: u32,
    /// Views written per sample (the first ones; all are swept).
    #[arg(long, default_value_t = 4)]
    views_per_sample: usize,
    /// Seed of every draw.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Share of the samples rendered with the photographic look (0 to 1; 0 draws nothing
    /// for it, so the flat samples are the same bytes as without the option).
    #[arg(long, default_value_t = 0.0)]
    photo_share: f64,
}

fn main() -> ExitCode {
    mvgrasp::cli::exit(run(&Args::parse()))
}

fn run(args: &Args) -> CliResult<()> {
    std::fs::create_dir_all(&args.out)
        .map_err(|e| format!("cannot create {}: {e}", args.out.display()))?;
    if !(0.0..=1.0).contains(&args.photo_share) {
        return Err(format!("--photo-share {}: expected 0 to 1", args.photo_share).into());
    }
    let renderer = Renderer::new(Backend::Auto)?;
    let intrinsics = Intrinsics::preset(IntrinsicsPreset::PhoxiS);
    for sample in args.first_sample..args.first_sample + args.samples {
        let done = args.out.join(format!("{sample:05}.done"));
        if done.exists() {
            continue;
        }
        let written = write_sample(&renderer, intrinsics, args, sample)?;
        std::fs::write(&done, format!("{written}\n"))
            .map_err(|e| format!("cannot write {}: {e}", done.display()))?;
        eprint!(".");
    }
    eprintln!();
    let manifest = serde_json::json!({
        "format": "mvgrasp-sweep-refiner-data/1",
        "samples": args.samples,
        "first_sample": args.first_sample,
        "per_category": args.per_category,
        "views_per_sample": args.views_per_sample,
        "seed": args.seed,
        "photo_share": args.photo_share,
        "library_seed": 2,
        "features": FEATURES,
        "channels_after_features": ["base_m", "truth_m"],
    });
    let path = args.out.join("dataset.json");
    let text = serde_json::to_string_pretty(&manifest)? + "\n";
    Ok(std::fs::write(&path, text).map_err(|e| format!("cannot write {}: {e}", path.display()))?)
}

fn write_sample(
    renderer: &Renderer,
    intrinsics: Intrinsics,
    args: &Args,
    sample: u32,
) -> CliResult<usize> {
    let mut rng = ChaCha8Rng::seed_from_u64(args.seed ^ (u64::from(sample) << 20) ^ 0x5f3e);
    let category = Category::ALL[rng.random_range(0..Category::ALL.len())];
    let index = rng.random_range(0..args.per_category.max(1));
    let object = generate(category, index, 2)?;
    let rest = RestingPoses::of(&object.mesh)?;
    let offered = rest.len().max(1);
    let (_, pose) = rest.get(rng.random_range(0..offered))?;
    let com = object.mesh.mass_facts(1000.0)?.center_of_mass;
    let target = pose.table_from_object.transform_point(com);
    let layout = HemisphereLayout {
        count: rng.random_range(2..=8),
        radius_m: rng.random_range(0.4..0.8),
        include_top_down: rng.random_bool(0.5),
        ..HemisphereLayout::paper_training()
    };
    let cameras = layout.cameras(intrinsics, target, rng.random())?;
    let input = RgbInput {
        depth: DepthPredictor::Baseline(RefinedSweep::sweep_params()),
        per_face: rng.random_bool(0.5),
        photo: false,
    };
    let photo = args.photo_share > 0.0 && rng.random_bool(args.photo_share);
    let (mesh, table_from_object, seed) = (&object.mesh, &pose.table_from_object, rng.random());
    let rendered = if photo {
        render_photoreal(renderer, mesh, table_from_object, &cameras, seed).map(|p| p.views)
    } else {
        render_rgb(renderer, mesh, table_from_object, &cameras, &input, seed)
    }?;
    // Half the time the sweep sees the cameras as a calibration gives them: a little off.
    let calibration_error = rng.random_bool(0.5);
    let given: Vec<RgbView> = rendered
        .iter()
        .map(|(view, _)| RgbView {
            camera: if calibration_error {
                miscalibrated(&view.camera, &mut rng)
            } else {
                view.camera
            },
            ..view.clone()
        })
        .collect();
    let swept = sweep_depths(&given, &RefinedSweep::sweep_params())?;
    let mut written = 0;
    for (v, ((view, truth), swept)) in rendered.iter().zip(&swept).enumerate() {
        if v >= args.views_per_sample {
            break;
        }
        let Some(f) = view_features(&given[v], swept) else {
            continue;
        };
        let w = view.camera.intrinsics.width as usize;
        let n = f.width * f.height;
        let mut values = f.features;
        values.extend_from_slice(&f.base_m);
        values.extend((0..n).map(|i| truth[(i / f.width + f.v0) * w + (i % f.width + f.u0)]));
        let path = args.out.join(format!("{sample:05}_{v}.npy"));
        common::write_npy_f32(&path, &[FEATURES.len() + 2, f.height, f.width], &values)?;
        written += 1;
    }
    Ok(written)
}

/// `camera` moved by up to 2 mm and turned by up to 0.5 degrees, uniformly at random.
fn miscalibrated(camera: &Camera, rng: &mut ChaCha8Rng) -> Camera {
    let mut unit = || {
        loop {
            let v = Vec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            );
            if v.length() <= 1.0 {
                return v;
            }
        }
    };
    let shift = unit() * 0.002;
    let turn = Rot3::from_scaled_axis(unit() * 0.5f32.to_radians());
    let mut moved = *camera;
    let pose = camera.world_from_camera;
    moved.world_from_camera = Pose3::from_parts(pose.translation + shift, turn * pose.rotation);
    moved
}
