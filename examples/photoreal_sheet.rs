//! A contact sheet of the photographic look (`mvgrasp::scene::photoreal`) beside the
//! datasets' flat one: each row one built-in object of the sweep refiner's library (seed 2) in
//! a random resting pose, its first column the flat look of the first camera, then that camera
//! and the next ones in the photographic look, each tile the middle of a PhoXi S view 0.6 m
//! away.
//!
//! ```text
//! cargo run --release --example photoreal_sheet -- --out docs/photoreal.png [--rows 5] [--seed 0]
//! ```
//!
//! Deterministic by seed (on one renderer).

use std::path::PathBuf;
use std::process::ExitCode;

use clap::Parser;
use mvgrasp::cli::CliResult;
use mvgrasp::geometry::objects::{Category, generate};
use mvgrasp::geometry::{HemisphereLayout, Intrinsics, IntrinsicsPreset, RestingPoses};
use mvgrasp::images::write_png8;
use mvgrasp::planner::{DepthPredictor, RgbInput, render_rgb};
use mvgrasp::render::{Backend, Renderer};
use mvgrasp::scene::photoreal::render_photoreal;
use mvgrasp::stereo::SweepParams;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Write a contact sheet of the photographic look.
#[derive(Parser, Debug)]
#[command(about)]
struct Args {
    /// The PNG to write.
    #[arg(long)]
    out: PathBuf,
    /// Objects (rows).
    #[arg(long, default_value_t = 5)]
    rows: usize,
    /// Photographic views per object (columns after the flat one).
    #[arg(long, default_value_t = 3)]
    views: usize,
    /// Seed of every draw.
    #[arg(long, default_value_t = 0)]
    seed: u64,
}

/// A tile's size: the middle of a 516 x 386 view.
const TILE: (usize, usize) = (240, 180);

fn main() -> ExitCode {
    mvgrasp::cli::exit(run(&Args::parse()))
}

fn run(args: &Args) -> CliResult<()> {
    let renderer = Renderer::new(Backend::Auto)?;
    let intrinsics = Intrinsics::preset(IntrinsicsPreset::PhoxiS);
    let columns = args.views + 1;
    let (sheet_w, sheet_h) = (columns * TILE.0, args.rows * TILE.1);
    let mut sheet = vec![255u8; sheet_w * sheet_h * 3];
    for row in 0..args.rows {
        let mut rng = ChaCha8Rng::seed_from_u64(args.seed ^ (row as u64) << 24);
        let category = Category::ALL[row % Category::ALL.len()];
        let object = generate(category, rng.random_range(0..20), 2)?;
        let rest = RestingPoses::of(&object.mesh)?;
        let (_, pose) = rest.get(0)?;
        let target = pose
            .table_from_object
            .transform_point(object.mesh.aabb().center());
        let layout = HemisphereLayout {
            count: args.views,
            radius_m: 0.6,
            include_top_down: false,
            ..HemisphereLayout::paper_training()
        };
        let cameras = layout.cameras(intrinsics, target, rng.random())?;
        let seed = rng.random();
        let flat = render_rgb(
            &renderer,
            &object.mesh,
            &pose.table_from_object,
            &cameras[..1],
            &RgbInput {
                depth: DepthPredictor::Baseline(SweepParams::default()),
                per_face: false,
                photo: false,
            },
            seed,
        )?;
        let photo = render_photoreal(
            &renderer,
            &object.mesh,
            &pose.table_from_object,
            &cameras,
            seed,
        )?
        .views;
        for (column, (view, _)) in flat.iter().chain(&photo).enumerate() {
            let k = &view.camera.intrinsics;
            let (w, h) = (k.width as usize, k.height as usize);
            let (u0, v0) = ((w - TILE.0) / 2, (h - TILE.1) / 2);
            for y in 0..TILE.1 {
                for x in 0..TILE.0 {
                    let pixel = view.rgb[(v0 + y) * w + u0 + x];
                    let at = ((row * TILE.1 + y) * sheet_w + column * TILE.0 + x) * 3;
                    sheet[at..at + 3].copy_from_slice(&pixel);
                }
            }
        }
    }
    write_png8(&args.out, sheet_w as u32, sheet_h as u32, 3, &sheet)?;
    eprintln!("wrote {} ({sheet_w} x {sheet_h})", args.out.display());
    Ok(())
}
