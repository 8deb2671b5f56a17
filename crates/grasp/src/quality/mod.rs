//! Grasp quality on meshes: contacts of closing jaws, force closure, Ferrari-Canny epsilon
//! (Dex-Net's `ferrari_canny_L1`) and its robust mean under pose and friction noise, the label
//! of Dex-Net 2.0.
//!
//! The pieces, in the order a grasp meets them:
//! - [`find_contacts`]: close the jaws along the closing line (two ray casts).
//! - [`force_closure`]: the line between the contacts inside both friction cones.
//! - [`contact_wrenches`] and [`ferrari_canny_l1`]: linearised cones and soft-finger torsion,
//!   and the distance from the origin to the boundary of their 6-D convex hull (f64): from the
//!   polar polytope's vertices, enumerated exactly from the two-contact structure (no general
//!   hull; [`wrench_set_epsilon`] is the brute-force reference it is tested against).
//! - [`grasp_quality`], [`robust_quality`], [`robust_qualities`]: one grasp nominally, under
//!   [`RobustQualityParams`]' noise, and many grasps in parallel.

mod closure;
mod contacts;
mod ferrari_canny;
mod params;
mod polar;
mod robust;
mod wrench;

pub use closure::{force_closure, validate_friction_coef};
pub use contacts::{Contact, ContactPair, MIN_CONTACT_WIDTH_M, find_contacts};
pub use ferrari_canny::{MAX_BRUTE_FORCE_WRENCHES, ferrari_canny_l1, wrench_set_epsilon};
pub use params::RobustQualityParams;
pub use robust::{
    GraspQuality, RobustQuality, grasp_quality, grasp_seed, robust_qualities, robust_quality,
};
pub use wrench::{MAX_CONE_FACES, TorsionModel, WRENCH_DIM, WrenchParams, contact_wrenches};
