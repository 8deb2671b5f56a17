//! 3-D convolution and transposed convolution over NCDHW tensors with torch's weight layouts:
//! direct references and the column-matrix + faer products the Learnt Stereo Machine runs.

mod fast;
mod geometry;
mod reference;
mod rows;
mod transposed;

pub use fast::{conv3d, conv3d_into};
pub use geometry::Conv3dParams;
pub use reference::{conv_transpose3d_reference, conv3d_reference};
pub use transposed::{conv_transpose3d, conv_transpose3d_into};

#[cfg(test)]
mod tests;
