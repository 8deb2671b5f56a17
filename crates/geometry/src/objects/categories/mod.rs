//! One file a category: each samples its typed parameters and builds the shape's SDF from them.

mod blob;
mod bottle;
mod bowl;
mod boxes;
mod can;
mod mug;
mod squash;
mod stapler;
mod toy_car;
mod toy_chair;

pub use blob::{BlobParams, BlobSphere, BlobWave};
pub use bottle::BottleParams;
pub use bowl::BowlParams;
pub use boxes::BoxParams;
pub use can::CanParams;
pub use mug::{HandleStyle, MugParams};
pub use squash::{SquashParams, SquashStyle};
pub use stapler::{StaplerParams, StaplerStyle};
pub use toy_car::ToyCarParams;
pub use toy_chair::{ChairBack, ToyChairParams};

use serde::Serialize;

use super::category::Category;
use super::sampling::Sampler;
use super::sdf::Sdf;
use crate::error::Result;

/// The parameters an object was built from, by category (written to manifests as is).
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(untagged)]
pub enum ObjectParams {
    /// A bottle.
    Bottle(BottleParams),
    /// A mug.
    Mug(MugParams),
    /// A bowl.
    Bowl(BowlParams),
    /// A box.
    Box(BoxParams),
    /// A can or cylinder.
    Can(CanParams),
    /// A toy car.
    ToyCar(ToyCarParams),
    /// A stapler or hole punch.
    Stapler(StaplerParams),
    /// A toy chair.
    ToyChair(ToyChairParams),
    /// A squash or gourd.
    Squash(SquashParams),
    /// A blob.
    Blob(BlobParams),
}

impl ObjectParams {
    /// Draws the parameters of one object of `category`.
    pub(crate) fn sample(category: Category, s: &mut Sampler) -> Self {
        match category {
            Category::Bottle => Self::Bottle(bottle::sample(s)),
            Category::Mug => Self::Mug(mug::sample(s)),
            Category::Bowl => Self::Bowl(bowl::sample(s)),
            Category::Box => Self::Box(boxes::sample(s)),
            Category::Can => Self::Can(can::sample(s)),
            Category::ToyCar => Self::ToyCar(toy_car::sample(s)),
            Category::Stapler => Self::Stapler(stapler::sample(s)),
            Category::ToyChair => Self::ToyChair(toy_chair::sample(s)),
            Category::Squash => Self::Squash(squash::sample(s)),
            Category::Blob => Self::Blob(blob::sample(s)),
        }
    }

    /// The category these parameters belong to.
    pub fn category(&self) -> Category {
        match self {
            Self::Bottle(_) => Category::Bottle,
            Self::Mug(_) => Category::Mug,
            Self::Bowl(_) => Category::Bowl,
            Self::Box(_) => Category::Box,
            Self::Can(_) => Category::Can,
            Self::ToyCar(_) => Category::ToyCar,
            Self::Stapler(_) => Category::Stapler,
            Self::ToyChair(_) => Category::ToyChair,
            Self::Squash(_) => Category::Squash,
            Self::Blob(_) => Category::Blob,
        }
    }

    /// The shape, base near z = 0 (the generator re-centres it after meshing).
    ///
    /// # Errors
    /// [`GeometryError::InvalidParameter`](crate::GeometryError::InvalidParameter) when the
    /// parameters give an invalid profile.
    pub fn sdf(&self) -> Result<Sdf> {
        match self {
            Self::Bottle(p) => bottle::build(p),
            Self::Mug(p) => mug::build(p),
            Self::Bowl(p) => bowl::build(p),
            Self::Box(p) => boxes::build(p),
            Self::Can(p) => can::build(p),
            Self::ToyCar(p) => toy_car::build(p),
            Self::Stapler(p) => stapler::build(p),
            Self::ToyChair(p) => toy_chair::build(p),
            Self::Squash(p) => squash::build(p),
            Self::Blob(p) => blob::build(p),
        }
    }
}
