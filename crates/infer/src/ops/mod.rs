//! The ops, one a file (a folder when an op has cases). Where a fast form differs from the
//! definition, a `_reference` form beside it computes the definition plainly, and the tests
//! hold the fast one to it.
//!
//! Ops that change values one by one work in place; the others write into a caller's output
//! tensor (`_into`, resized as needed and keeping its allocation), with a wrapper that
//! allocates.

mod batch_norm;
pub(crate) mod check;
mod concat;
mod conv2d;
mod conv3d;
mod conv_gru;
mod elu;
mod gates;
mod instance_norm;
mod linear;
mod local_response_norm;
pub mod plane_sweep;
mod pool2d;
mod relu;
mod resize;
mod softmax;
mod voxel_grid;

pub use batch_norm::{BatchNorm, batch_norm, batch_norm_reference};
pub use concat::{concat, concat_into};
pub use conv_gru::{ConvGru3d, ConvGruScratch};
pub use conv2d::{Conv2dParams, conv2d, conv2d_into, conv2d_reference};
pub use conv3d::{
    Conv3dParams, conv_transpose3d, conv_transpose3d_into, conv_transpose3d_reference, conv3d,
    conv3d_into, conv3d_reference,
};
pub use elu::elu;
pub use gates::{sigmoid, sigmoid_reference, tanh, tanh_reference};
pub use instance_norm::{InstanceNorm, instance_norm, instance_norm_reference};
pub use linear::{linear, linear_into, linear_reference};
pub use local_response_norm::{
    LocalResponseNorm, local_response_norm, local_response_norm_into, local_response_norm_reference,
};
pub use pool2d::{
    AvgPoolDivisor, Pool2dParams, avg_pool2d, avg_pool2d_into, avg_pool2d_reference, max_pool2d,
    max_pool2d_into, max_pool2d_reference,
};
pub use relu::relu;
pub use resize::{resize_area, resize_bilinear};
pub use softmax::softmax;
pub use voxel_grid::{CameraMatrices, VoxelGrid, project_rays, unproject};

/// The first `len` values of `scratch`, which grows to hold them but never shrinks: a buffer
/// shared by layers of different sizes would otherwise be zero-filled again each time it grew
/// (megabytes an image, for Dex-Net's second convolution).
pub(crate) fn stretch(scratch: &mut Vec<f32>, len: usize) -> &mut [f32] {
    if scratch.len() < len {
        scratch.resize(len, 0.0);
    }
    &mut scratch[..len]
}
