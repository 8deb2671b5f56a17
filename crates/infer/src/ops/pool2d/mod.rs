//! 2-D max and average pooling over NCHW tensors, with torch's semantics (`nn.MaxPool2d`,
//! `nn.AvgPool2d`, floor mode).

mod avg;
mod max;
mod params;
mod reference;

pub use avg::{avg_pool2d, avg_pool2d_into};
pub use max::{max_pool2d, max_pool2d_into};
pub use params::{AvgPoolDivisor, Pool2dParams};
pub use reference::{avg_pool2d_reference, max_pool2d_reference};

#[cfg(test)]
mod tests;
