//! Networks built from the op set: their descriptions, weights and forward passes.

pub mod description;
pub mod gqcnn;
mod image_stream;
pub mod lsm;
pub mod mvs;
pub mod sweep_refiner;
pub mod weights;

pub use description::{
    Architecture, ConvSpec, GQCNN_FORMAT, GqcnnDescription, InputSpec, Normalisation,
};
pub use gqcnn::{Gqcnn, GqcnnWorkspace};
pub use lsm::{LSM_FORMAT, Lsm, LsmArchitecture, LsmDescription};
pub use mvs::{MVS_FORMAT, Mvs, MvsArchitecture, MvsDepth, MvsDescription};
pub use sweep_refiner::{
    RefinedSweep, SWEEP_REFINER_FORMAT, SweepRefiner, SweepRefinerArchitecture,
    SweepRefinerDescription,
};
pub use weights::Weights;
