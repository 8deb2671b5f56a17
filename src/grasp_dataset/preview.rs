//! A PNG grid of a dataset's crops with their labels, so a person can see what the network will
//! learn: the top rows positives, the bottom rows negatives.
//!
//! Each tile is one crop (grey: near is bright, each crop stretched over its own depth range,
//! nothing is black), scaled up 3x, with the jaws drawn as two short vertical bars on the
//! centre row at the grasp's width. Its frame is green for a robust positive, red for a
//! negative; a small square in the top-right corner gives the physics trial (green held, red
//! failed, grey not run).

use std::path::Path;

use safetensors::SafeTensors;

use super::shard::shard_file;
use super::{Manifest, read_manifest};
use crate::error::{Error, Result, RuntimeError};
use crate::images::write_png8;

const SCALE: usize = 3;
const BORDER: usize = 2;
const GREEN: [u8; 3] = [40, 200, 60];
const RED: [u8; 3] = [220, 40, 40];
const GREY: [u8; 3] = [128, 128, 128];
const JAW: [u8; 3] = [60, 140, 255];

/// One crop to draw.
struct Tile {
    crop: Vec<f32>,
    positive: bool,
    physics: i8,
    /// Jaw positions from the centre, crop pixels.
    half_width_px: f32,
}

/// Writes `png` from the dataset in `dir`: up to `per_class` positives and as many negatives,
/// spread evenly over the finished shards, `columns` tiles a row.
///
/// # Errors
/// [`Error::Io`], [`Error::Json`] or [`Error::Safetensors`] naming the file for a missing
/// manifest or an unreadable shard, or [`Error::EmptyDataset`] when
/// it has no datapoint.
pub fn write_preview(dir: &Path, png: &Path, per_class: usize, columns: usize) -> Result<()> {
    let manifest: Manifest = read_manifest(dir)?;
    let size = manifest.config.crop.size_px as usize;
    let scale_px = manifest.config.crop.window_px as f32 / manifest.config.crop.size_px as f32;
    let k = &manifest.intrinsics;
    let mut positives = Vec::new();
    let mut negatives = Vec::new();
    let shards = manifest.shards.len().max(1);
    let take = per_class.div_ceil(shards);
    for record in &manifest.shards {
        let path = dir.join(shard_file(record.index));
        let bytes = std::fs::read(&path).map_err(Error::io("read", &path))?;
        let fail = |source: safetensors::SafeTensorError| {
            Error::from(RuntimeError::Safetensors {
                op: "read",
                source,
                path: path.clone(),
            })
        };
        let shard = SafeTensors::deserialize(&bytes).map_err(fail)?;
        let column = |name: &str| shard.tensor(name).map_err(fail);
        let crops = column("depth_crops")?;
        let labels = column("robust_label")?;
        let physics = column("physics")?;
        let widths = column("width_m")?;
        let depths = column("grasp_depth_m")?;
        let f32_at = |t: &safetensors::tensor::TensorView<'_>, i: usize| {
            let b = &t.data()[4 * i..4 * i + 4];
            f32::from_le_bytes([b[0], b[1], b[2], b[3]])
        };
        let n = labels.data().len();
        let (mut pos, mut neg) = (0, 0);
        for i in 0..n {
            let positive = labels.data()[i] == 1;
            let (count, list) = if positive {
                (&mut pos, &mut positives)
            } else {
                (&mut neg, &mut negatives)
            };
            if *count >= take {
                continue;
            }
            *count += 1;
            let crop = (0..size * size)
                .map(|j| f32_at(&crops, i * size * size + j))
                .collect();
            // The jaws sit width/2 from the centre: metres to image pixels at the grasp's
            // depth, then to crop pixels.
            let half_width_px = f32_at(&widths, i) / 2.0 * k.fx / f32_at(&depths, i) / scale_px;
            list.push(Tile {
                crop,
                positive,
                physics: physics.data()[i] as i8,
                half_width_px,
            });
        }
    }
    positives.truncate(per_class);
    negatives.truncate(per_class);
    if positives.is_empty() && negatives.is_empty() {
        return Err(Error::EmptyDataset {
            path: dir.to_path_buf(),
        });
    }
    let rows_of = |n: usize| n.div_ceil(columns);
    let rows = rows_of(positives.len()) + rows_of(negatives.len());
    let tile = size * SCALE + 2 * BORDER;
    let (width, height) = (columns * tile, rows * tile);
    let mut image = vec![0u8; width * height * 3];
    let tiles = positives
        .iter()
        .enumerate()
        .map(|(i, t)| (i / columns, i % columns, t))
        .chain(
            negatives
                .iter()
                .enumerate()
                .map(|(i, t)| (rows_of(positives.len()) + i / columns, i % columns, t)),
        );
    for (row, col, t) in tiles {
        draw_tile(&mut image, width, row * tile, col * tile, size, t);
    }
    Ok(write_png8(png, width as u32, height as u32, 3, &image)?)
}

fn draw_tile(image: &mut [u8], width: usize, top: usize, left: usize, size: usize, t: &Tile) {
    let tile = size * SCALE + 2 * BORDER;
    let mut put = |y: usize, x: usize, rgb: [u8; 3]| {
        let i = ((top + y) * width + left + x) * 3;
        image[i..i + 3].copy_from_slice(&rgb);
    };
    let frame = if t.positive { GREEN } else { RED };
    for y in 0..tile {
        for x in 0..tile {
            if y < BORDER || x < BORDER || y >= tile - BORDER || x >= tile - BORDER {
                put(y, x, frame);
            }
        }
    }
    let seen = t.crop.iter().copied().filter(|&d| d > 0.0);
    let (lo, hi) = seen.fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), d| {
        (lo.min(d), hi.max(d))
    });
    let range = (hi - lo).max(1e-4);
    for y in 0..size * SCALE {
        for x in 0..size * SCALE {
            let d = t.crop[(y / SCALE) * size + x / SCALE];
            let grey = if d > 0.0 {
                (255.0 * (1.0 - (d - lo) / range)).clamp(0.0, 255.0) as u8
            } else {
                0
            };
            put(BORDER + y, BORDER + x, [grey; 3]);
        }
    }
    let centre = (size * SCALE) as f32 / 2.0;
    for side in [-1.0f32, 1.0] {
        let x = centre + side * t.half_width_px * SCALE as f32;
        if !(0.0..(size * SCALE) as f32).contains(&x) {
            continue;
        }
        for dy in 0..(2 * SCALE) {
            let y = centre as usize + dy - SCALE;
            put(BORDER + y, BORDER + x as usize, JAW);
        }
    }
    let marker = match t.physics {
        1 => GREEN,
        0 => RED,
        _ => GREY,
    };
    for y in 0..5 {
        for x in 0..5 {
            put(BORDER + 1 + y, tile - BORDER - 6 + x, marker);
        }
    }
}
