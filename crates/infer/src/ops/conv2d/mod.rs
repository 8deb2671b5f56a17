//! 2-D convolution over NCHW tensors with torch's weight layout: a direct reference and the
//! im2col + faer matrix product the networks run.

mod geometry;
mod im2col;
mod reference;

pub use geometry::Conv2dParams;
pub use im2col::{conv2d, conv2d_into};
pub use reference::conv2d_reference;

#[cfg(test)]
mod tests;
