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
mod elu;
mod instance_norm;
mod linear;
mod local_response_norm;
mod pool2d;
mod relu;
mod softmax;

pub use batch_norm::{BatchNorm, batch_norm, batch_norm_reference};
pub use concat::{concat, concat_into};
pub use conv2d::{Conv2dParams, conv2d, conv2d_into, conv2d_reference};
pub use elu::elu;
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
pub use softmax::softmax;
