//! Grasp-centred, grasp-aligned crops of a depth image (Dex-Net 2.0's image transform).
//!
//! Crop pixel `(row i, column j)` of a crop of side `S` cut from a window of side `W` around a
//! grasp at image point `c` with in-image angle `phi` shows the image at
//! `c + R(phi) * ((j - S/2) * W/S, (i - S/2) * W/S)`: pixel `(S/2, S/2)` is the grasp centre
//! and the grasp axis runs along the crop's rows (+j towards the grasp's +x jaw). Image
//! coordinates are the project's: pixel `(u, v)` has its centre at `(u, v)`. Each crop pixel
//! is the mean of `round(W/S)^2` bilinear samples spread over its footprint (an area filter);
//! a sample next to an empty pixel (0) takes its nearest pixel instead, and empty samples are
//! left out of the mean.
//!
//! This is the GQ-CNN's input contract: the grasp datasets cut their training crops with it,
//! and the planner cuts the crops it scores with it.

use serde::{Deserialize, Serialize};

use crate::depth_image::DepthImage;
use mvgrasp_geometry::rounding::floor;

/// How a grasp's crop is cut (Dex-Net 2.0: a 96 x 96 window scaled to 32 x 32).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CropParams {
    /// Side of the window in the rendered image, pixels.
    pub window_px: u32,
    /// Side of the stored crop, pixels (even, so that pixel `(size/2, size/2)` is the centre).
    pub size_px: u32,
}

impl Default for CropParams {
    fn default() -> Self {
        Self {
            window_px: 96,
            size_px: 32,
        }
    }
}

/// The similarity between crop and image coordinates of one grasp (see the module docs).
#[derive(Clone, Copy, Debug)]
struct CropFrame {
    center: [f32; 2],
    cos: f32,
    sin: f32,
    /// Image pixels per crop pixel.
    scale: f32,
    /// Crop coordinate of the grasp centre.
    half: f32,
}

impl CropFrame {
    fn new(center_px: [f32; 2], angle_rad: f32, params: &CropParams) -> Self {
        let (sin, cos) = angle_rad.sin_cos();
        Self {
            center: center_px,
            cos,
            sin,
            scale: params.window_px as f32 / params.size_px as f32,
            half: params.size_px as f32 / 2.0,
        }
    }

    fn image_point(self, [x, y]: [f32; 2]) -> [f32; 2] {
        let dx = (x - self.half) * self.scale;
        let dy = (y - self.half) * self.scale;
        [
            self.center[0] + self.cos * dx - self.sin * dy,
            self.center[1] + self.sin * dx + self.cos * dy,
        ]
    }

    fn crop_point(self, [u, v]: [f32; 2]) -> [f32; 2] {
        let du = u - self.center[0];
        let dv = v - self.center[1];
        [
            (self.cos * du + self.sin * dv) / self.scale + self.half,
            (-self.sin * du + self.cos * dv) / self.scale + self.half,
        ]
    }
}

/// The image point that crop coordinates `(x = column, y = row)` show (see the module docs).
pub fn crop_to_image(
    center_px: [f32; 2],
    angle_rad: f32,
    params: &CropParams,
    xy: [f32; 2],
) -> [f32; 2] {
    CropFrame::new(center_px, angle_rad, params).image_point(xy)
}

/// The crop coordinates `(x = column, y = row)` of image point `uv` (the inverse of
/// [`crop_to_image`]).
pub fn image_to_crop(
    center_px: [f32; 2],
    angle_rad: f32,
    params: &CropParams,
    uv: [f32; 2],
) -> [f32; 2] {
    CropFrame::new(center_px, angle_rad, params).crop_point(uv)
}

/// Cuts the crop of the grasp at `center_px`, `angle_rad` from `depth`; `size_px^2` values,
/// row-major (an empty crop for a `size_px` of 0).
pub fn crop_depth(
    depth: &DepthImage,
    center_px: [f32; 2],
    angle_rad: f32,
    params: &CropParams,
) -> Vec<f32> {
    let frame = CropFrame::new(center_px, angle_rad, params);
    let size = params.size_px as usize;
    if size == 0 {
        return Vec::new();
    }
    let offsets = sample_offsets(params);
    // The rotation's products, once per sample column and per sample row instead of once per
    // sample: the values `CropFrame::image_point` forms, added in its order, so the crop is
    // the same to the bit (tested against the sample-by-sample form).
    let along = |k: usize, d: f32| (k as f32 + d - frame.half) * frame.scale;
    let columns: Vec<[f32; 2]> = (0..size)
        .flat_map(|j| offsets.iter().map(move |&d| along(j, d)))
        .map(|dx| [frame.cos * dx, frame.sin * dx])
        .collect();
    let rows: Vec<[f32; 2]> = (0..size)
        .flat_map(|i| offsets.iter().map(move |&d| along(i, d)))
        .map(|dy| [frame.sin * dy, frame.cos * dy])
        .collect();
    let mut out = Vec::with_capacity(size * size);
    for row in rows.chunks_exact(offsets.len()) {
        for column in columns.chunks_exact(offsets.len()) {
            let points = row.iter().flat_map(|&[sin_dy, cos_dy]| {
                column.iter().map(move |&[cos_dx, sin_dx]| {
                    [
                        frame.center[0] + cos_dx - sin_dy,
                        frame.center[1] + sin_dx + cos_dy,
                    ]
                })
            });
            out.push(mean_of_samples(depth, points));
        }
    }
    out
}

/// Where a crop pixel's `round(W/S)^2` samples sit within it along each axis, in crop pixels
/// from its centre.
fn sample_offsets(params: &CropParams) -> Vec<f32> {
    let per_side = (params.window_px as f32 / params.size_px as f32)
        .round()
        .max(1.0) as usize;
    (0..per_side)
        .map(|k| (k as f32 + 0.5) / per_side as f32 - 0.5)
        .collect()
}

/// The mean of the non-empty [`sample`]s at `points` (summed in their order), 0 when all are
/// empty: one crop pixel.
fn mean_of_samples(depth: &DepthImage, points: impl Iterator<Item = [f32; 2]>) -> f32 {
    let mut sum = 0.0f64;
    let mut count = 0u32;
    for uv in points {
        let value = sample(depth, uv);
        if value > 0.0 {
            sum += f64::from(value);
            count += 1;
        }
    }
    if count == 0 {
        0.0
    } else {
        (sum / f64::from(count)) as f32
    }
}

/// Bilinear sample at `uv`; the nearest pixel when a neighbour is empty; 0 outside the image.
fn sample(depth: &DepthImage, [u, v]: [f32; 2]) -> f32 {
    let at = |x: i64, y: i64| depth.at(x, y);
    if !(u.is_finite() && v.is_finite()) {
        return 0.0;
    }
    let (fu, fv) = (floor(u), floor(v));
    let (x0, y0) = (fu as i64, fv as i64);
    let (fx, fy) = (u - fu, v - fv);
    let (w, h) = (i64::from(depth.width()), i64::from(depth.height()));
    // Inside the image (nearly always): the four corners straight from the slice.
    let corners = if x0 >= 0 && y0 >= 0 && x0 + 1 < w && y0 + 1 < h {
        let data = depth.as_slice();
        let (i, w) = ((y0 * w + x0) as usize, w as usize);
        [data[i], data[i + 1], data[i + w], data[i + w + 1]]
    } else {
        [
            at(x0, y0),
            at(x0 + 1, y0),
            at(x0, y0 + 1),
            at(x0 + 1, y0 + 1),
        ]
    };
    if corners.iter().all(|&d| d > 0.0) {
        let top = corners[0] * (1.0 - fx) + corners[1] * fx;
        let bottom = corners[2] * (1.0 - fx) + corners[3] * fx;
        top * (1.0 - fy) + bottom * fy
    } else {
        at(u.round() as i64, v.round() as i64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mvgrasp_geometry::Intrinsics;

    fn image(width: u32, height: u32, depth_m: Vec<f32>) -> DepthImage {
        let (cx, cy) = (width as f32 / 2.0, height as f32 / 2.0);
        let k = Intrinsics::new(500.0, 500.0, cx, cy, width, height, 0.1, 2.0).unwrap();
        DepthImage::new(k, depth_m).unwrap()
    }

    #[test]
    fn crop_and_image_coordinates_invert_each_other() {
        let params = CropParams::default();
        let (c, a) = ([200.5, 140.25], 0.7);
        let xy = image_to_crop(c, a, &params, crop_to_image(c, a, &params, [3.0, 29.5]));
        assert!(
            (xy[0] - 3.0).abs() < 1e-4 && (xy[1] - 29.5).abs() < 1e-4,
            "{xy:?}"
        );
        assert_eq!(crop_to_image(c, a, &params, [16.0, 16.0]), c);
    }

    #[test]
    fn a_ramp_is_sampled_along_the_grasp_axis() {
        // Depth rises 1 mm a pixel along u: a crop at angle 0 rises 3 mm a crop pixel along
        // its rows and is constant down its columns; at 90 degrees the other way round.
        let (w, h) = (200u32, 150u32);
        let depth: Vec<f32> = (0..h)
            .flat_map(|_| (0..w).map(|u| 0.5 + 0.001 * u as f32))
            .collect();
        let params = CropParams::default();
        let depth = image(w, h, depth);
        let crop = crop_depth(&depth, [100.0, 75.0], 0.0, &params);
        assert!(
            (crop[16 * 32 + 16] - 0.6).abs() < 1e-5,
            "{}",
            crop[16 * 32 + 16]
        );
        assert!((crop[16 * 32 + 17] - crop[16 * 32 + 16] - 0.003).abs() < 1e-5);
        assert!((crop[17 * 32 + 16] - crop[16 * 32 + 16]).abs() < 1e-6);
        let turned = crop_depth(&depth, [100.0, 75.0], std::f32::consts::FRAC_PI_2, &params);
        assert!((turned[17 * 32 + 16] - turned[16 * 32 + 16] + 0.003).abs() < 1e-5);
    }

    #[test]
    fn outside_the_image_is_empty() {
        let depth = image(64, 64, vec![0.7f32; 64 * 64]);
        let crop = crop_depth(&depth, [2.0, 2.0], 0.0, &CropParams::default());
        assert_eq!(crop[0], 0.0);
        assert_eq!(crop[16 * 32 + 16], 0.7);
    }

    /// The crop sample by sample through `CropFrame::image_point` (the form before the
    /// rotation's products were hoisted).
    fn crop_depth_by_samples(
        depth: &DepthImage,
        center_px: [f32; 2],
        angle_rad: f32,
        params: &CropParams,
    ) -> Vec<f32> {
        let frame = CropFrame::new(center_px, angle_rad, params);
        let size = params.size_px as usize;
        let offsets = sample_offsets(params);
        let mut out = Vec::new();
        for i in 0..size {
            for j in 0..size {
                let points = offsets.iter().flat_map(|&dy| {
                    offsets
                        .iter()
                        .map(move |&dx| frame.image_point([j as f32 + dx, i as f32 + dy]))
                });
                out.push(mean_of_samples(depth, points));
            }
        }
        out
    }

    #[test]
    fn hoisted_crops_are_the_sample_by_sample_ones_to_the_bit() {
        // A bumpy surface with holes (every 7th pixel empty, a missing block) near the borders.
        let (w, h) = (120u32, 90u32);
        let depth: Vec<f32> = (0..w * h)
            .map(|p| {
                let (u, v) = ((p % w) as f32, (p / w) as f32);
                let hole = p % 7 == 0 || ((40.0..55.0).contains(&u) && (20.0..30.0).contains(&v));
                if hole {
                    0.0
                } else {
                    0.6 + 0.01 * (0.3 * u).sin() * (0.2 * v).cos()
                }
            })
            .collect();
        let depth = image(w, h, depth);
        for params in [
            CropParams::default(),
            CropParams {
                window_px: 40,
                size_px: 16,
            },
            CropParams {
                window_px: 10,
                size_px: 20,
            },
        ] {
            for (k, center) in [[60.0, 45.0], [3.3, 88.1], [119.5, -2.0], [47.25, 24.75]]
                .into_iter()
                .enumerate()
            {
                for angle in [
                    0.0f32,
                    0.3,
                    -1.2,
                    std::f32::consts::FRAC_PI_2,
                    2.9 + k as f32,
                ] {
                    let got = crop_depth(&depth, center, angle, &params);
                    let want = crop_depth_by_samples(&depth, center, angle, &params);
                    let bits = |c: &[f32]| c.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
                    assert_eq!(bits(&got), bits(&want), "{params:?} {center:?} {angle}");
                }
            }
        }
    }
}
