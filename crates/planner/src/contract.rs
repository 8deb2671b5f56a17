//! The network's input contract, and the crops it implies for any camera.
//!
//! A GQ-CNN only knows crops like its training crops: a window of `crop_window_px` pixels of a
//! camera with focal length `focal_px`, scaled to `crop_size_px`. At depth `z` that window
//! spans `crop_window_px * z / focal_px` metres. A camera with another focal length sees the
//! same metres in another number of pixels, so the planner scales the window by the focal
//! ratio (gqcnn's users met the alternative: "bad grasps on other cameras", gqcnn #15, #26,
//! #50, #100).

use mvgrasp_geometry::Intrinsics;
use mvgrasp_infer::Gqcnn;
use serde::Serialize;

use crate::crop::CropParams;
use crate::error::{PlannerError, Result};

/// Largest relative difference between fx and fy the planner accepts: it scales one window.
const MAX_PIXEL_ASPECT_ERROR: f32 = 0.02;

/// What a network expects of its inputs.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct InputContract {
    /// The training crops: window and crop side, pixels of the training camera.
    pub crop: CropParams,
    /// Focal length of the training camera, pixels.
    pub focal_px: f32,
}

impl InputContract {
    /// The contract of `net`: the crops its export recorded, else the grasp datasets' defaults
    /// (Dex-Net 2.0's 96-pixel window scaled to 32 x 32, on the PhoXi S at fx = 552.5), which
    /// the exports made before the contract was recorded were trained on, and which a network
    /// taking other crops does not fit.
    pub fn of(net: &Gqcnn) -> Self {
        match net.input_spec() {
            Some(spec) => Self {
                crop: CropParams {
                    window_px: spec.crop_window_px,
                    size_px: spec.crop_size_px,
                },
                focal_px: spec.focal_px,
            },
            None => Self {
                crop: CropParams::default(),
                focal_px: Intrinsics::phoxi_s().fx,
            },
        }
    }

    /// The crop to cut from images of a camera with `intrinsics`: the training window scaled
    /// by the focal ratio, so that it spans the same metres at the same depth.
    ///
    /// # Errors
    /// [`PlannerError::Camera`] when the camera's pixels are not square (fx and fy differ by
    /// more than 2%) or its focal length is so short that the window would have fewer pixels
    /// than the crop (the network would see an upsampled, blurred crop).
    pub fn crop_for(&self, intrinsics: &Intrinsics) -> Result<CropParams> {
        let (fx, fy) = (intrinsics.fx, intrinsics.fy);
        if (fx - fy).abs() > MAX_PIXEL_ASPECT_ERROR * fx.max(fy) {
            return Err(PlannerError::Camera {
                fx,
                fy,
                detail: "pixels that are not square (fx and fy differ by more than 2%)",
            });
        }
        let window = (self.crop.window_px as f32 * fx / self.focal_px).round();
        if window.is_nan() || window < self.crop.size_px as f32 {
            return Err(PlannerError::Camera {
                fx,
                fy,
                detail: "a focal length too short for the network: its crop window would have \
                         fewer pixels than the crop",
            });
        }
        Ok(CropParams {
            window_px: window as u32,
            size_px: self.crop.size_px,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::crop::crop_depth;
    use crate::depth_image::DepthImage;
    use crate::test_scenes::box_on_table;
    use mvgrasp_geometry::IntrinsicsPreset;

    /// A 4 cm x 6 cm box 5 cm tall on a table 0.7 m below a camera looking straight down,
    /// as `intrinsics` sees it.
    fn box_seen_by(intrinsics: Intrinsics) -> DepthImage {
        box_on_table(intrinsics, [0.02, 0.03], None)
    }

    fn mean_abs_difference(a: &[f32], b: &[f32]) -> f32 {
        a.iter().zip(b).map(|(x, y)| (x - y).abs()).sum::<f32>() / a.len() as f32
    }

    /// The same scene through the PhoXi S (fx 552.5) and a RealSense (fx 385): crops scaled
    /// by the focal ratio agree; the training window cut from the RealSense does not.
    #[test]
    fn crops_of_two_cameras_agree_when_the_window_follows_the_focal_length() {
        let contract = InputContract {
            crop: CropParams::default(),
            focal_px: 552.5,
        };
        let phoxi = Intrinsics::preset(IntrinsicsPreset::PhoxiS);
        let realsense = Intrinsics::preset(IntrinsicsPreset::RealsenseD435);
        let (a, b) = (box_seen_by(phoxi), box_seen_by(realsense));
        let phoxi_crop = contract.crop_for(&phoxi).unwrap();
        let realsense_crop = contract.crop_for(&realsense).unwrap();
        assert_eq!(phoxi_crop, CropParams::default());
        assert_eq!(realsense_crop.window_px, 67);
        for angle in [0.0f32, 0.4, 1.2] {
            let reference = crop_depth(&a, [phoxi.cx, phoxi.cy], angle, &phoxi_crop);
            let adapted = crop_depth(&b, [realsense.cx, realsense.cy], angle, &realsense_crop);
            let unadapted = crop_depth(&b, [realsense.cx, realsense.cy], angle, &phoxi_crop);
            let good = mean_abs_difference(&reference, &adapted);
            let bad = mean_abs_difference(&reference, &unadapted);
            // The box edge is 5 cm high: a crop pixel on the wrong side of it costs 5 cm.
            assert!(
                good < 1.5e-3,
                "angle {angle}: adapted crops differ by {good} m"
            );
            assert!(
                bad > 5.0 * good && bad > 4e-3,
                "unadapted {bad} m vs adapted {good} m"
            );
        }
    }

    #[test]
    fn cameras_the_network_cannot_use_are_refused_with_a_reason() {
        let contract = InputContract {
            crop: CropParams::default(),
            focal_px: 552.5,
        };
        let mut k = Intrinsics::preset(IntrinsicsPreset::Primesense);
        assert_eq!(contract.crop_for(&k).unwrap().window_px, 91);
        k.fy *= 1.1;
        let err = contract.crop_for(&k).unwrap_err().to_string();
        assert!(err.contains("not square"), "{err}");
        k.fx = 150.0;
        k.fy = 150.0;
        let err = contract.crop_for(&k).unwrap_err().to_string();
        assert!(err.contains("too short"), "{err}");
    }
}
