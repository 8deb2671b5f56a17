//! Depth from RGB views with the Learnt Stereo Machine (`mvgrasp_infer::Lsm`, trained by
//! `training/mvgrasp_training/train_lsm.py`; the shipped weights: `models/lsm_small`).
//!
//! The views are prepared as the training prepared them: colours to `[0, 1]`, each image
//! area-averaged to the network's input size (128 x 96 for the shipped network: 640 x 480
//! by 5 x 5 blocks) and its intrinsics scaled to match, poses in the table frame. The network's
//! depth maps are resized bilinearly back to each camera's resolution. With a mask, the pixels
//! off the object get the table plane's depth (as the baseline gives them), since the network's
//! depth range is the sphere around its grid and the table reaches beyond it.
//!
//! The grid is centred where the cameras' optical axes meet (least squares), as in training.
//! One view's axis does not place it: then the grid is centred where that axis crosses the
//! plane [`SINGLE_VIEW_CENTRE_HEIGHT_M`] above the table, the median height of the training
//! grids' centres (the objects' centres of mass, where the cameras looked).

use mvgrasp_infer::ops::{CameraMatrices, resize_area, resize_bilinear};
use mvgrasp_infer::{Lsm, Tensor};

use crate::depth_from_rgb::{DepthFrom, DepthFromRgb, PredictedDepth};
use crate::error::{Error, Result};
use crate::stereo::{RgbView, table_depth};

/// Where one view's grid is centred: this far above the table on the camera's optical axis.
/// The median over the 200 training objects of the least-squares point of their test cameras'
/// axes (1.2 to 9.0 cm; `render --per-category 20 --library-seed 2`).
pub const SINGLE_VIEW_CENTRE_HEIGHT_M: f32 = 0.026;

/// The network's depth of every view at the view's resolution (metres along the optical axis;
/// 0 nowhere), in the order of `views`.
///
/// # Errors
/// [`Error::Stereo`] for no view, or one view whose camera does not look down at the table;
/// the runtime's errors for cameras that do not place the grid.
pub fn lsm_depths(lsm: &Lsm, views: &[RgbView]) -> Result<Vec<Vec<f32>>> {
    if views.is_empty() {
        return Err(Error::Stereo {
            problem: "the Learnt Stereo Machine needs at least 1 view, got 0".into(),
        });
    }
    let arch = lsm.architecture();
    let (aw, ah) = (arch.image_width, arch.image_height);
    let (images, cameras) = network_inputs(views, aw, ah)?;
    let predicted = match views {
        [view] => lsm.predict_in(&images, &cameras, single_view_centre(view)?)?,
        _ => lsm.predict(&images, &cameras)?,
    };
    at_camera_resolution(views, predicted.data(), aw, ah)
}

/// One network map of `width` x `height` resized bilinearly to `camera`'s image.
///
/// # Errors
/// Only for a map that does not hold `width` x `height` values.
pub(crate) fn to_camera_size(
    map: &[f32],
    width: usize,
    height: usize,
    camera: &mvgrasp_geometry::Camera,
) -> Result<Vec<f32>> {
    let k = &camera.intrinsics;
    let small = Tensor::new(&[1, 1, height, width], map.to_vec())?;
    Ok(resize_bilinear(&small, k.height as usize, k.width as usize)?.into_data())
}

/// The networks' inputs of RGB views: colours to `[0, 1]`, each image area-averaged to
/// `width` x `height` (`[V, 3, height, width]`), and the cameras with their intrinsics scaled to
/// match, posed in the table frame.
///
/// # Errors
/// Only for views whose images do not fill their cameras' sizes (the readers check that).
pub(crate) fn network_inputs(
    views: &[RgbView],
    width: usize,
    height: usize,
) -> Result<(Tensor, Vec<CameraMatrices>)> {
    let mut images = Vec::with_capacity(views.len() * 3 * width * height);
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
        let image = resize_area(&Tensor::new(&[1, 3, h, w], planes)?, height, width)?;
        images.extend_from_slice(image.data());
        cameras.push(camera_matrices(
            view,
            width as f32 / w as f32,
            height as f32 / h as f32,
        ));
    }
    Ok((
        Tensor::new(&[views.len(), 3, height, width], images)?,
        cameras,
    ))
}

/// A network's per-view maps (`[V, height, width]` in `maps`) resized bilinearly to each
/// view's camera; with a mask, the pixels off the object get the table plane's depth.
///
/// # Errors
/// Only for maps that do not hold V views of `width` x `height`.
pub(crate) fn at_camera_resolution(
    views: &[RgbView],
    maps: &[f32],
    width: usize,
    height: usize,
) -> Result<Vec<Vec<f32>>> {
    views
        .iter()
        .zip(maps.chunks_exact(width * height))
        .map(|(view, depth)| {
            let mut depth = to_camera_size(depth, width, height, &view.camera)?;
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

/// Where one view's grid is centred: the point of its optical axis
/// [`SINGLE_VIEW_CENTRE_HEIGHT_M`] above the table (z = 0 of the table frame).
fn single_view_centre(view: &RgbView) -> Result<[f32; 3]> {
    let centre = view.camera.position();
    let axis = view.camera.optical_axis();
    // A camera at most 5 degrees below the horizon never meets the plane in its workspace.
    if axis.z > -0.087 || centre.z <= SINGLE_VIEW_CENTRE_HEIGHT_M {
        return Err(Error::Stereo {
            problem: format!(
                "one view: its camera (at z = {:.3} m, optical axis z = {:.3}) does not look \
                 down at the table, so it does not place the Learnt Stereo Machine's grid",
                centre.z, axis.z
            ),
        });
    }
    let t = (SINGLE_VIEW_CENTRE_HEIGHT_M - centre.z) / axis.z;
    Ok((centre + axis * t).to_array())
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

impl DepthFromRgb for Lsm {
    fn name(&self) -> &str {
        DepthFrom::Lsm.name()
    }

    /// [`lsm_depths`]; the network gives no confidence.
    fn predict(&self, views: &[RgbView]) -> Result<Vec<PredictedDepth>> {
        Ok(lsm_depths(self, views)?
            .into_iter()
            .map(PredictedDepth::depth_only)
            .collect())
    }
}
