//! The built-in library of procedural household objects, so mvgrasp works with no downloaded
//! data.
//!
//! Each object is a signed distance function composed of primitives ([`Sdf`], [`revolve`]) and
//! meshed by marching tetrahedra ([`mesh_sdf`]) into a closed, welded, outward-facing mesh in
//! metres, resting on z = 0 and centred in x and y. Objects are sized for a parallel-jaw gripper
//! of 5-8.5 cm opening: every object is 1-7.5 cm across in some direction and 4-25 cm long.
//! Generation is seeded and deterministic: the object `(category, index, seed)` is always the
//! same mesh, whatever else is generated.
//!
//! ```no_run
//! use mvgrasp_geometry::objects::{Category, generate};
//! let mug = generate(Category::Mug, 3, 0)?;
//! assert_eq!(mug.name, "mug_003");
//! # Ok::<(), mvgrasp_geometry::GeometryError>(())
//! ```

mod categories;
mod category;
mod generate;
mod mesher;
mod profile;
mod sampling;
mod sdf;
mod simplify;
#[cfg(test)]
mod test_support;

pub use categories::{
    BlobParams, BlobSphere, BlobWave, BottleParams, BowlParams, BoxParams, CanParams, ChairBack,
    HandleStyle, MugParams, ObjectParams, SquashParams, SquashStyle, StaplerParams, StaplerStyle,
    ToyCarParams, ToyChairParams,
};
pub use category::Category;
pub use generate::{GeneratedObject, ObjectSpec, default_object, generate, generate_with, library};
pub use mesher::{MarchingParams, mesh_sdf, mesh_sdf_with};
pub use profile::revolve;
pub use sdf::Sdf;
