//! Loading a mesh from a file, whatever its format.

use std::path::Path;

use parry3d::math::Vec3;

use super::{TriangleMesh, obj, stl, urdf, validate};
use crate::error::{GeometryError, Result};

/// Which geometry of a URDF link to load.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum UrdfGeometryKind {
    /// The `<visual>` elements (what a camera sees); links without one fall back to collision.
    #[default]
    Visual,
    /// The `<collision>` elements; links without one fall back to visual.
    Collision,
}

/// How to load a mesh file.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LoadOptions {
    /// Multiplies every coordinate after loading (and after a URDF's own `scale`), e.g. 0.001
    /// for a file in millimetres.
    pub scale: f32,
    /// The smallest largest-extent accepted, metres (default 5 mm).
    pub min_extent_m: f32,
    /// The largest largest-extent accepted, metres (default 2 m).
    pub max_extent_m: f32,
    /// Which URDF geometry to use.
    pub urdf_geometry: UrdfGeometryKind,
}

impl Default for LoadOptions {
    fn default() -> Self {
        Self {
            scale: 1.0,
            min_extent_m: 0.005,
            max_extent_m: 2.0,
            urdf_geometry: UrdfGeometryKind::Visual,
        }
    }
}

/// Loads an OBJ, STL or URDF file (by extension) as one mesh in metres, with default options.
///
/// # Errors
/// A [`GeometryError`] that names the file and the fault.
pub fn load_mesh(path: impl AsRef<Path>) -> Result<TriangleMesh> {
    load_mesh_with(path, &LoadOptions::default())
}

/// Loads an OBJ, STL or URDF file (by extension) as one mesh in metres.
///
/// # Errors
/// A [`GeometryError`] that names the file and the fault: missing file, unparsable content,
/// no triangles, NaN/inf vertices, out-of-range indices, only degenerate faces, absurd size.
pub fn load_mesh_with(path: impl AsRef<Path>, options: &LoadOptions) -> Result<TriangleMesh> {
    let path = path.as_ref();
    if !(options.scale.is_finite() && options.scale > 0.0) {
        return Err(GeometryError::InvalidParameter {
            op: "load mesh",
            name: "scale",
            value: options.scale.to_string(),
            expected: "a finite number > 0",
        });
    }
    let mesh = load_unscaled(path, options.urdf_geometry)?;
    let mesh = if options.scale == 1.0 {
        mesh
    } else {
        mesh.scaled(Vec3::splat(options.scale))
    };
    validate::check_size(
        mesh.vertices(),
        options.min_extent_m,
        options.max_extent_m,
        path,
    )?;
    Ok(mesh)
}

/// Loads a file in its own units, with no size check (URDFs apply their own scales).
pub(super) fn load_unscaled(path: &Path, urdf_geometry: UrdfGeometryKind) -> Result<TriangleMesh> {
    if !path.is_file() {
        return Err(GeometryError::NotFound {
            path: path.to_path_buf(),
        });
    }
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    match extension.as_str() {
        "obj" => obj::read_obj(path),
        "stl" => stl::read_stl(path),
        "urdf" => urdf::read_urdf(path, urdf_geometry),
        _ => Err(GeometryError::UnsupportedFormat {
            extension,
            path: path.to_path_buf(),
        }),
    }
}
