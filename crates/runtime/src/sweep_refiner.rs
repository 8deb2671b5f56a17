//! Depth from RGB views by the plane sweep and a learned refinement of it
//! (`--depth-from refined`; the network `mvgrasp_infer::SweepRefiner`, trained by
//! `training/mvgrasp_training/train_sweep_refiner.py`).
//!
//! The sweep ([`crate::stereo`]) measures; the network judges. Per view, every pixel of the
//! object's box (its mask's bounding box and [`MARGIN_PX`] around it) gets a summary of what
//! the sweep found there ([`view_features`]): its cheapest plane (the winner) and that plane's
//! cost, whether another view confirmed the winner, the visual hull's depth, the colours, and
//! how each of these sits against the pixel's base depth (the confirmed depth, else the
//! hull's, else the winner's) and the box's median base depth. A context-aggregation network
//! (3 x 3 convolutions of growing dilation, about 65 pixels of context) turns that into a
//! correction to the base depth and a confidence: it learns which unconfirmed winners to
//! believe, where the hull is a fair guess and how the confirmed surface around a hole
//! continues. Pixels off the object keep the sweep's table plane; below `min_confidence` an
//! object pixel is left missing (unseen space to the multi-view planner) or, for a network that
//! plans in one view, takes the visual hull's depth ([`Unsure`]).

use std::sync::Arc;

use mvgrasp_infer::{SweepRefiner, Tensor};

use crate::depth_from_rgb::{DepthFrom, DepthFromRgb, PredictedDepth};
use crate::error::{Error, Result};
use crate::stereo::{RgbView, SweepParams, SweptDepth, sweep_depths};

/// The features' names, in channel order ([`view_features`]).
pub const FEATURES: [&str; 12] = [
    "object",
    "has_winner",
    "confirmed",
    "winner_cost",
    "winner_offset",
    "has_hull",
    "hull_offset",
    "base_offset",
    "red",
    "green",
    "blue",
    "has_base",
];

/// The unit of the features' depth offsets and of the network's correction, metres.
pub const STEP_M: f32 = 0.01;

/// Offsets are clamped to this many [`STEP_M`] either way.
const MAX_OFFSET_STEPS: f32 = 10.0;

/// Pixels around the object's bounding box that the network sees.
pub const MARGIN_PX: usize = 16;

/// One view's features for the network: the box `(u0, v0, width, height)` in the image,
/// the features `[FEATURES.len(), height, width]` row-major, and each box pixel's base depth
/// (metres; 0 where the sweep found nothing: not predicted).
#[derive(Clone, Debug, PartialEq)]
pub struct ViewFeatures {
    /// Left column of the box.
    pub u0: usize,
    /// Top row of the box.
    pub v0: usize,
    /// Box width, pixels.
    pub width: usize,
    /// Box height, pixels.
    pub height: usize,
    /// `[FEATURES.len(), height, width]`.
    pub features: Vec<f32>,
    /// Base depth per box pixel, metres (0: none).
    pub base_m: Vec<f32>,
}

/// Whether pixel `i` is the object's: its mask's, or without a mask where the sweep found a winner.
fn is_object(view: &RgbView, swept: &SweptDepth, i: usize) -> bool {
    view.mask
        .as_ref()
        .map_or(swept.winner_m[i] > 0.0, |mask| mask[i])
}

/// The features of one view from its sweep (run with the consistency check and without
/// `hull_where_unconfirmed`, as [`RefinedSweep`] runs it); `None` when the view has no object
/// pixel (a mask) or no winner anywhere (no mask).
pub fn view_features(view: &RgbView, swept: &SweptDepth) -> Option<ViewFeatures> {
    let k = &view.camera.intrinsics;
    let (w, h) = (k.width as usize, k.height as usize);
    let object = |i: usize| is_object(view, swept, i);
    let (mut u0, mut v0, mut u1, mut v1) = (usize::MAX, usize::MAX, 0, 0);
    for v in 0..h {
        for u in 0..w {
            if object(v * w + u) {
                (u0, v0, u1, v1) = (u0.min(u), v0.min(v), u1.max(u + 1), v1.max(v + 1));
            }
        }
    }
    if u0 == usize::MAX {
        return None;
    }
    let (u0, v0) = (u0.saturating_sub(MARGIN_PX), v0.saturating_sub(MARGIN_PX));
    let (u1, v1) = ((u1 + MARGIN_PX).min(w), (v1 + MARGIN_PX).min(h));
    let (bw, bh) = (u1 - u0, v1 - v0);
    let n = bw * bh;
    let image = |i: usize| (i / bw + v0) * w + (i % bw + u0);
    let base_m: Vec<f32> = (0..n)
        .map(|i| {
            let at = image(i);
            if !object(at) {
                0.0
            } else if swept.depth_m[at] > 0.0 {
                swept.depth_m[at]
            } else if swept.hull_m[at] > 0.0 {
                swept.hull_m[at]
            } else {
                swept.winner_m[at]
            }
        })
        .collect();
    let mut bases: Vec<f32> = base_m.iter().copied().filter(|&b| b > 0.0).collect();
    let middle = if bases.is_empty() {
        0.0
    } else {
        let mid = bases.len() / 2;
        *bases.select_nth_unstable_by(mid, f32::total_cmp).1
    };
    let offset = |a: f32, b: f32| ((a - b) / STEP_M).clamp(-MAX_OFFSET_STEPS, MAX_OFFSET_STEPS);
    let mut features = vec![0.0f32; FEATURES.len() * n];
    for i in 0..n {
        let at = image(i);
        let b = base_m[i];
        let (winner, hull) = (swept.winner_m[at], swept.hull_m[at]);
        let on = object(at);
        let rgb = view.rgb[at];
        let values = [
            f32::from(u8::from(on)),
            f32::from(u8::from(on && winner > 0.0)),
            f32::from(u8::from(on && swept.depth_m[at] > 0.0)),
            if on && winner > 0.0 {
                swept.cost[at] / 2.0
            } else {
                1.0
            },
            if on && winner > 0.0 && b > 0.0 {
                offset(winner, b)
            } else {
                0.0
            },
            f32::from(u8::from(on && hull > 0.0)),
            if on && hull > 0.0 && b > 0.0 {
                offset(hull, b)
            } else {
                0.0
            },
            if b > 0.0 { offset(b, middle) } else { 0.0 },
            f32::from(rgb[0]) / 255.0 - 0.5,
            f32::from(rgb[1]) / 255.0 - 0.5,
            f32::from(rgb[2]) / 255.0 - 0.5,
            f32::from(u8::from(b > 0.0)),
        ];
        for (c, value) in values.into_iter().enumerate() {
            features[c * n + i] = value;
        }
    }
    Some(ViewFeatures {
        u0,
        v0,
        width: bw,
        height: bh,
        features,
        base_m,
    })
}

/// One view's refined depth at its camera's resolution.
#[derive(Clone, Debug, PartialEq)]
pub struct RefinedView {
    /// Metres along the optical axis; 0 where unknown or below the confidence threshold.
    pub depth_m: Vec<f32>,
    /// The network's confidence in `[0, 1]` (1 off the object, where the table plane is given;
    /// 0 where nothing was predicted).
    pub confidence: Vec<f32>,
}

/// What an object pixel below the confidence threshold gets.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Unsure {
    /// Nothing (0): unseen space, for the multi-view planner.
    Missing,
    /// The visual hull's depth (never beyond the surface, so the hand keeps clear of it), or
    /// nothing where the hull does not reach: for a network planning in one view, which needs
    /// every pixel.
    Hull,
}

/// The sweep and its refinement, as a depth predictor holds them.
#[derive(Clone, Debug)]
pub struct RefinedSweep {
    /// The network.
    pub net: Arc<SweepRefiner>,
    /// An object pixel whose confidence is below this is `unsure` (0 keeps all).
    pub min_confidence: f32,
    /// What a pixel below `min_confidence` gets.
    pub unsure: Unsure,
}

impl RefinedSweep {
    /// The sweep's settings the network was trained on: the defaults.
    pub fn sweep_params() -> SweepParams {
        SweepParams::default()
    }

    /// Every view's refined depth, in the order of `views`.
    ///
    /// # Errors
    /// As [`sweep_depths`]; [`Error::Stereo`] if the network's input size is not
    /// [`FEATURES`]'s.
    pub fn depths(&self, views: &[RgbView]) -> Result<Vec<RefinedView>> {
        let inputs = self.net.architecture().inputs;
        if inputs != FEATURES.len() {
            return Err(Error::Stereo {
                problem: format!(
                    "the sweep refiner takes {inputs} features, this build gives {}",
                    FEATURES.len()
                ),
            });
        }
        let swept = sweep_depths(views, &Self::sweep_params())?;
        views
            .iter()
            .zip(&swept)
            .map(|(view, swept)| self.refine(view, swept))
            .collect()
    }

    fn refine(&self, view: &RgbView, swept: &SweptDepth) -> Result<RefinedView> {
        let k = &view.camera.intrinsics;
        let w = k.width as usize;
        let object = |i: usize| is_object(view, swept, i);
        let mut depth_m: Vec<f32> = swept
            .depth_m
            .iter()
            .enumerate()
            .map(|(i, &d)| if object(i) { 0.0 } else { d })
            .collect();
        let mut confidence: Vec<f32> = (0..depth_m.len())
            .map(|i| if object(i) { 0.0 } else { 1.0 })
            .collect();
        let Some(f) = view_features(view, swept) else {
            return Ok(RefinedView {
                depth_m,
                confidence,
            });
        };
        let input = Tensor::new(&[1, FEATURES.len(), f.height, f.width], f.features)?;
        let out = self.net.predict(&input)?;
        let pixels = out.correction_m.data().iter().zip(out.confidence.data());
        for (i, ((&correction, &c), &base)) in pixels.zip(&f.base_m).enumerate() {
            let at = (i / f.width + f.v0) * w + (i % f.width + f.u0);
            if base <= 0.0 || !object(at) {
                continue;
            }
            confidence[at] = c;
            if c >= self.min_confidence {
                depth_m[at] = (base + correction).max(0.0);
            } else if self.unsure == Unsure::Hull {
                depth_m[at] = swept.hull_m[at];
            }
        }
        Ok(RefinedView {
            depth_m,
            confidence,
        })
    }
}

impl DepthFromRgb for RefinedSweep {
    fn name(&self) -> &str {
        DepthFrom::Refined.name()
    }

    /// [`RefinedSweep::depths`], with the network's confidence.
    fn predict(&self, views: &[RgbView]) -> Result<Vec<PredictedDepth>> {
        Ok(self
            .depths(views)?
            .into_iter()
            .map(|view| PredictedDepth::with_confidence(view.depth_m, view.confidence))
            .collect())
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)] // tests may fail loudly

    use mvgrasp_planner::models;

    use super::*;
    use crate::stereo::tests_support::views;

    #[test]
    fn the_features_frame_the_object_and_take_the_confirmed_depth_else_the_hull() {
        let (rgb, _) = views(5);
        let swept = sweep_depths(&rgb, &RefinedSweep::sweep_params()).unwrap();
        let (view, swept) = (&rgb[1], &swept[1]);
        let f = view_features(view, swept).unwrap();
        let w = view.camera.intrinsics.width as usize;
        let mask = view.mask.as_ref().unwrap();
        let n = f.width * f.height;
        assert_eq!(f.features.len(), FEATURES.len() * n);
        let channel = |name: &str| {
            let c = FEATURES.iter().position(|&x| x == name).unwrap();
            &f.features[c * n..(c + 1) * n]
        };
        let mut seen = 0;
        for i in 0..n {
            let at = (i / f.width + f.v0) * w + (i % f.width + f.u0);
            assert_eq!(channel("object")[i] > 0.0, mask[at]);
            let want = if !mask[at] {
                0.0
            } else if swept.depth_m[at] > 0.0 {
                swept.depth_m[at]
            } else if swept.hull_m[at] > 0.0 {
                swept.hull_m[at]
            } else {
                swept.winner_m[at]
            };
            assert_eq!(f.base_m[i], want);
            assert_eq!(channel("has_base")[i] > 0.0, want > 0.0);
            assert_eq!(
                channel("confirmed")[i] > 0.0,
                mask[at] && swept.depth_m[at] > 0.0
            );
            for name in ["winner_offset", "hull_offset", "base_offset"] {
                assert!(channel(name)[i].abs() <= MAX_OFFSET_STEPS, "{name}");
            }
            seen += usize::from(mask[at]);
        }
        // Every object pixel lies in the box, with the margin around it where the image allows.
        assert_eq!(seen, mask.iter().filter(|&&m| m).count());
        assert!(f.u0 > 0 && f.v0 > 0 && channel("object")[0] == 0.0);
    }

    #[test]
    fn the_shipped_refiner_keeps_the_table_and_leaves_unsure_pixels_missing() {
        let (rgb, truth) = views(5);
        let net = Arc::new(models::SWEEP_REFINER.load().unwrap());
        let all = RefinedSweep {
            net: Arc::clone(&net),
            min_confidence: 0.0,
            unsure: Unsure::Missing,
        }
        .depths(&rgb)
        .unwrap();
        let none = RefinedSweep {
            net: Arc::clone(&net),
            min_confidence: 1.5,
            unsure: Unsure::Missing,
        }
        .depths(&rgb)
        .unwrap();
        let hull = RefinedSweep {
            net,
            min_confidence: 1.5,
            unsure: Unsure::Hull,
        }
        .depths(&rgb)
        .unwrap();
        let swept = sweep_depths(&rgb, &RefinedSweep::sweep_params()).unwrap();
        let mut errors = Vec::new();
        for (((view, truth), (all, none)), (swept, hull)) in rgb
            .iter()
            .zip(&truth)
            .zip(all.iter().zip(&none))
            .zip(swept.iter().zip(&hull))
        {
            let mask = view.mask.as_ref().unwrap();
            for (i, &on) in mask.iter().enumerate() {
                if on {
                    assert_eq!(none.depth_m[i], 0.0);
                    assert_eq!(hull.depth_m[i], swept.hull_m[i]);
                    if all.depth_m[i] > 0.0 {
                        errors.push((all.depth_m[i] - truth[i]).abs());
                    }
                } else {
                    assert_eq!(all.depth_m[i], swept.depth_m[i]);
                    assert_eq!(none.depth_m[i], swept.depth_m[i]);
                    assert_eq!(all.confidence[i], 1.0);
                }
            }
        }
        errors.sort_by(f32::total_cmp);
        let median = errors[errors.len() / 2];
        // The textured box from 5 views 0.5 m away: the sweep gets its top to a fraction of a
        // millimetre; the refinement must not spoil that.
        assert!(median < 2e-3, "median error {median} m");
    }
}
