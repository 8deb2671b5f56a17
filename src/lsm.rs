//! Depth from RGB views with the Learnt Stereo Machine (`mvgrasp_infer::Lsm`, trained by
//! `training/mvgrasp_training/train_lsm.py`; the shipped weights: `models/lsm_small`).
//!
//! The views are prepared as the training prepared them: colours to `[0, 1]`, each image
//! area-averaged to the network's input size (128 x 96 for the shipped network: 640 x 480
//! by 5 x 5 blocks) and its intrinsics scaled to match, poses in the table frame. The network's
//! depth maps are resized bilinearly back to each camera's resolution. With a mask, the pixels
//! off the object get the table plane's depth (as the baseline gives them), since the network's
//! depth range is the sphere around its grid and the table reaches beyond it.

use mvgrasp_infer::ops::{CameraMatrices, resize_area, resize_bilinear};
use mvgrasp_infer::{Lsm, Tensor};

use crate::error::{Error, Result};
use crate::stereo::{RgbView, table_depth};

/// The network's depth of every view at the view's resolution (metres along the optical axis;
/// 0 nowhere), in the order of `views`.
///
/// # Errors
/// [`Error::Stereo`] for fewer than two views (the grid is placed where the cameras' axes
/// meet); the runtime's errors for cameras that do not place it.
pub fn lsm_depths(lsm: &Lsm, views: &[RgbView]) -> Result<Vec<Vec<f32>>> {
    if views.len() < 2 {
        return Err(Error::Stereo {
            problem: format!(
                "the Learnt Stereo Machine needs at least 2 views, got {}",
                views.len()
            ),
        });
    }
    let arch = lsm.architecture();
    let (aw, ah) = (arch.image_width, arch.image_height);
    let mut images = Vec::with_capacity(views.len() * 3 * aw * ah);
    let mut cameras = Vec::with_capacity(views.len());
    for view in views {
        let k = &view.camera.intrinsics;
        let (w, h) = (k.width as usize, k.height as usize);
        let mut planes = vec![0.0f32; 3 * w * h];
        for (i, pixel) in view.rgb.iter().enumerate() {
            for (c, &value) in pixel.iter().enumerate() {
                planes[c * w * h + i] = f32::from(value) / 255.0;
            }
        }
        let image = resize_area(&Tensor::new(&[1, 3, h, w], planes)?, ah, aw)?;
        images.extend_from_slice(image.data());
        cameras.push(camera_matrices(
            view,
            aw as f32 / w as f32,
            ah as f32 / h as f32,
        ));
    }
    let images = Tensor::new(&[views.len(), 3, ah, aw], images)?;
    let predicted = lsm.predict(&images, &cameras)?;
    views
        .iter()
        .zip(predicted.data().chunks_exact(aw * ah))
        .map(|(view, depth)| {
            let k = &view.camera.intrinsics;
            let (w, h) = (k.width as usize, k.height as usize);
            let small = Tensor::new(&[1, 1, ah, aw], depth.to_vec())?;
            let mut depth = resize_bilinear(&small, h, w)?.into_data();
            if let Some(mask) = &view.mask {
                let table = table_depth(&view.camera);
                for ((d, &on_object), t) in depth.iter_mut().zip(mask).zip(table) {
                    if !on_object {
                        *d = t.unwrap_or(0.0);
                    }
                }
            }
            Ok(depth)
        })
        .collect()
}

/// The view's camera as the runtime takes it: intrinsics scaled by `sx` x `sy` (pixel centres
/// at integers, as the training's `scale_intrinsics`) and the table-to-camera transform.
fn camera_matrices(view: &RgbView, sx: f32, sy: f32) -> CameraMatrices {
    let k = &view.camera.intrinsics;
    let m = view.camera.camera_from_world().to_mat4();
    CameraMatrices {
        k: [
            [k.fx * sx, 0.0, (k.cx + 0.5) * sx - 0.5],
            [0.0, k.fy * sy, (k.cy + 0.5) * sy - 0.5],
            [0.0, 0.0, 1.0],
        ],
        camera_from_world: std::array::from_fn(|r| m.row(r).to_array()),
    }
}
