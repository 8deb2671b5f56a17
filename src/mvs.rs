//! Depth from RGB views with the learned multi-view stereo network (`mvgrasp_infer::Mvs`,
//! trained by `training/mvgrasp_training/train_mvs.py`; the shipped weights:
//! `models/mvs_small`).
//!
//! The views are prepared as the training prepared them ([`crate::lsm`]'s preparation: colours
//! to `[0, 1]`, each image area-averaged to the network's input size and its intrinsics scaled
//! to match, poses in the table frame). The network's depth and confidence are resized
//! bilinearly back to each camera's resolution; with a mask, the pixels off the object get the
//! table plane's depth, as the other predictors give them. A pixel whose confidence is below
//! the caller's threshold is left missing (0): the planner's fused model treats it as unseen
//! space, which the hand may not enter.

use mvgrasp_infer::Mvs;

use crate::error::{Error, Result};
use crate::lsm::{at_camera_resolution, network_inputs};
use crate::stereo::RgbView;

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
    let depths = at_camera_resolution(views, predicted.depth.data(), aw, ah)?;
    let unmasked: Vec<RgbView> = views
        .iter()
        .map(|view| RgbView {
            camera: view.camera,
            rgb: Vec::new(),
            mask: None,
        })
        .collect();
    let confidences = at_camera_resolution(&unmasked, predicted.confidence.data(), aw, ah)?;
    Ok(views
        .iter()
        .zip(depths.into_iter().zip(confidences))
        .map(|(view, (mut depth_m, mut confidence))| {
            let on_object = |i: usize| view.mask.as_ref().is_none_or(|mask| mask[i]);
            for (i, (d, c)) in depth_m.iter_mut().zip(&mut confidence).enumerate() {
                if !on_object(i) {
                    *c = 1.0;
                } else if *c < min_confidence {
                    *d = 0.0;
                }
            }
            MvsView {
                depth_m,
                confidence,
            }
        })
        .collect())
}
