//! Depth from RGB views with the learned multi-view stereo network (`mvgrasp_infer::Mvs`,
//! trained by `training/mvgrasp_training/train_mvs.py`; the shipped weights:
//! `models/mvs_small`).
//!
//! The views are prepared as the training prepared them ([`crate::lsm`]'s preparation: colours
//! to `[0, 1]`, each image area-averaged to the network's input size and its intrinsics scaled
//! to match, poses in the table frame). The network's depth and confidence are resized
//! bilinearly back to each camera's resolution; with a mask, an object pixel interpolates only
//! the network's object pixels around it (those whose area is mostly the object's), so that the
//! object's edge does not blend with the table behind it, and the pixels off the object get the
//! table plane's depth, as the other predictors give them. A pixel whose confidence is below
//! the caller's threshold is left missing (0): the planner's fused model treats it as unseen
//! space, which the hand may not enter.

use std::sync::Arc;

use mvgrasp_infer::ops::resize_area;
use mvgrasp_infer::{Mvs, Tensor};

use crate::depth_from_rgb::{DepthFrom, DepthFromRgb, PredictedDepth};
use crate::error::{Error, Result};
use crate::lsm::{network_inputs, to_camera_size};
use crate::stereo::{RgbView, table_depth};

/// One view's prediction at its camera's resolution.
#[derive(Clone, Debug, PartialEq)]
pub struct MvsView {
    /// Metres along the optical axis; 0 where the confidence fell below the threshold.
    pub depth_m: Vec<f32>,
    /// The network's confidence in `[0, 1]` (off the object, with a mask: 1, the table).
    pub confidence: Vec<f32>,
}

/// The network's depth and confidence of every view at the view's resolution, in the order of
/// `views`; pixels of confidence below `min_confidence` left missing (0).
///
/// # Errors
/// [`Error::Stereo`] for fewer than two views; the runtime's errors for cameras whose optical
/// axes do not meet.
pub fn mvs_depths(mvs: &Mvs, views: &[RgbView], min_confidence: f32) -> Result<Vec<MvsView>> {
    if views.len() < 2 {
        return Err(Error::Stereo {
            problem: format!(
                "the multi-view stereo network needs at least 2 views, got {}",
                views.len()
            ),
        });
    }
    let arch = mvs.architecture();
    let (aw, ah) = (arch.image_width, arch.image_height);
    let (images, cameras) = network_inputs(views, aw, ah)?;
    let predicted = mvs.predict(&images, &cameras)?;
    let depths = views
        .iter()
        .zip(predicted.depth.data().chunks_exact(aw * ah))
        .map(|(view, depth)| on_object_resolution(view, depth, aw, ah))
        .collect::<Result<Vec<_>>>()?;
    views
        .iter()
        .zip(depths)
        .zip(predicted.confidence.data().chunks_exact(aw * ah))
        .map(|((view, mut depth_m), confidence)| {
            let mut confidence = to_camera_size(confidence, aw, ah, &view.camera)?;
            let on_object = |i: usize| view.mask.as_ref().is_none_or(|mask| mask[i]);
            for (i, (d, c)) in depth_m.iter_mut().zip(&mut confidence).enumerate() {
                if !on_object(i) {
                    *c = 1.0;
                } else if *c < min_confidence {
                    *d = 0.0;
                }
            }
            Ok(MvsView {
                depth_m,
                confidence,
            })
        })
        .collect()
}

/// One view's network depth (`width` x `height`) at its camera's resolution: bilinear, as
/// `F.interpolate(align_corners=False)`; with a mask, an object pixel takes only the taps on
/// network pixels that are mostly object (the mask area-averaged to the network's size, at
/// least a half), weights renormalised (all four when none is), and the pixels off the object
/// the table plane's depth.
fn on_object_resolution(
    view: &RgbView,
    depth: &[f32],
    width: usize,
    height: usize,
) -> Result<Vec<f32>> {
    let k = &view.camera.intrinsics;
    let (w, h) = (k.width as usize, k.height as usize);
    let Some(mask) = &view.mask else {
        return to_camera_size(depth, width, height, &view.camera);
    };
    let coverage: Vec<f32> = mask.iter().map(|&m| f32::from(u8::from(m))).collect();
    let coverage = resize_area(&Tensor::new(&[1, 1, h, w], coverage)?, height, width)?;
    let on_object: Vec<bool> = coverage.data().iter().map(|&c| c >= 0.5).collect();
    let taps = |o: usize, input: usize, output: usize| {
        let src = ((o as f32 + 0.5) * input as f32 / output as f32 - 0.5).max(0.0);
        let lo = (src as usize).min(input - 1);
        let hi = (lo + 1).min(input - 1);
        (lo, hi, src - lo as f32)
    };
    let table = table_depth(&view.camera);
    let mut out = vec![0.0f32; w * h];
    for y in 0..h {
        let (y0, y1, fy) = taps(y, height, h);
        for x in 0..w {
            let i = y * w + x;
            if !mask[i] {
                out[i] = table[i].unwrap_or(0.0);
                continue;
            }
            let (x0, x1, fx) = taps(x, width, w);
            let corners = [
                (y0 * width + x0, (1.0 - fy) * (1.0 - fx)),
                (y0 * width + x1, (1.0 - fy) * fx),
                (y1 * width + x0, fy * (1.0 - fx)),
                (y1 * width + x1, fy * fx),
            ];
            let (mut sum, mut weight) = (0.0f32, 0.0f32);
            for &(j, wt) in &corners {
                if on_object[j] {
                    sum += wt * depth[j];
                    weight += wt;
                }
            }
            out[i] = if weight > 1e-6 {
                sum / weight
            } else {
                corners.iter().map(|&(j, wt)| wt * depth[j]).sum()
            };
        }
    }
    Ok(out)
}

/// The multi-view stereo network as a depth method: pixels whose confidence is below
/// `min_confidence` left missing ([`mvs_depths`]).
#[derive(Clone, Debug)]
pub struct MvsDepth {
    /// The network.
    pub net: Arc<Mvs>,
    /// Pixels whose confidence is below this are left missing (0).
    pub min_confidence: f32,
}

impl DepthFromRgb for MvsDepth {
    fn name(&self) -> &str {
        DepthFrom::Mvs.name()
    }

    fn predict(&self, views: &[RgbView]) -> Result<Vec<PredictedDepth>> {
        Ok(mvs_depths(&self.net, views, self.min_confidence)?
            .into_iter()
            .map(|view| PredictedDepth::with_confidence(view.depth_m, view.confidence))
            .collect())
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use mvgrasp_geometry::{Camera, Intrinsics, IntrinsicsPreset, Vec3};

    use super::*;
    use crate::lsm::at_camera_resolution;

    #[test]
    fn an_object_pixel_at_the_edge_takes_the_object_depth_not_the_table_behind_it() {
        let k = Intrinsics::preset(IntrinsicsPreset::PhoxiS);
        let camera = Camera::look_at(k, Vec3::new(0.0, 0.0, 0.6), Vec3::ZERO, Vec3::Y).unwrap();
        let (w, h) = (k.width as usize, k.height as usize);
        // A box 101 x 77 pixels at an odd offset, so its edges cut the network's pixels.
        let mask: Vec<bool> = (0..w * h)
            .map(|i| (201..302).contains(&(i % w)) && (151..228).contains(&(i / w)))
            .collect();
        let view = RgbView {
            camera,
            rgb: vec![[0; 3]; w * h],
            mask: Some(mask.clone()),
        };
        let (nw, nh) = (128, 96);
        let coverage = resize_area(
            &Tensor::new(
                &[1, 1, h, w],
                mask.iter().map(|&m| f32::from(u8::from(m))).collect(),
            )
            .unwrap(),
            nh,
            nw,
        )
        .unwrap();
        let network: Vec<f32> = coverage
            .data()
            .iter()
            .map(|&c| if c >= 0.5 { 0.4 } else { 0.6 })
            .collect();
        let depth = on_object_resolution(&view, &network, nw, nh).unwrap();
        let on_box: Vec<f32> = (0..w * h).filter(|&i| mask[i]).map(|i| depth[i]).collect();
        let exact = on_box.iter().filter(|&&d| (d - 0.4).abs() < 1e-6).count();
        assert!(
            exact as f64 > 0.97 * on_box.len() as f64,
            "{exact} of {}",
            on_box.len()
        );
        // Plain bilinear resizing blends the edge with the table: fewer exact pixels.
        let plain = at_camera_resolution(std::slice::from_ref(&view), &network, nw, nh).unwrap();
        let blended = (0..w * h)
            .filter(|&i| mask[i] && (plain[0][i] - 0.4).abs() >= 1e-6)
            .count();
        assert!(blended > on_box.len() - exact, "{blended}");
        // Off the box: the table plane (the camera looks straight down from 0.6 m).
        assert!((depth[0] - 0.6).abs() < 0.05, "{}", depth[0]);
    }
}
