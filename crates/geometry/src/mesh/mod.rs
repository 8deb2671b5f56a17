//! Triangle meshes: the validated [`TriangleMesh`], loaders for OBJ, STL and URDF, and OBJ output.

mod load;
mod obj;
mod stl;
mod urdf;
mod validate;

pub use load::{LoadOptions, UrdfGeometryKind, load_mesh, load_mesh_with};
pub use obj::write_obj;
pub use urdf::UrdfModel;

use std::path::{Path, PathBuf};

use parry3d::math::{Pose3, Vec3};

use crate::error::{Result, in_memory};

/// A triangle mesh in metres whose vertices are all finite, whose indices are all in range and
/// which has at least one triangle of non-zero area (degenerate triangles are dropped on
/// construction).
///
/// Triangles are counter-clockwise seen from outside, so normals point out of a closed mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct TriangleMesh {
    vertices: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    origin: PathBuf,
}

impl TriangleMesh {
    /// Builds a mesh from vertex positions (metres) and triangles, checking every vertex and
    /// index and dropping zero-area triangles.
    ///
    /// # Errors
    /// [`GeometryError::NoTriangles`](crate::GeometryError::NoTriangles),
    /// [`NonFiniteVertices`](crate::GeometryError::NonFiniteVertices),
    /// [`IndexOutOfRange`](crate::GeometryError::IndexOutOfRange) or
    /// [`DegenerateOnly`](crate::GeometryError::DegenerateOnly).
    pub fn new(vertices: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> Result<Self> {
        Self::from_parts(vertices, triangles, &in_memory())
    }

    /// As [`TriangleMesh::new`], naming `origin` (a file path) in errors and in later reports.
    pub fn from_parts(
        vertices: Vec<Vec3>,
        triangles: Vec<[u32; 3]>,
        origin: &Path,
    ) -> Result<Self> {
        let triangles = validate::checked_triangles(&vertices, triangles, origin)?;
        Ok(Self {
            vertices,
            triangles,
            origin: origin.to_path_buf(),
        })
    }

    /// The vertex positions, metres.
    pub fn vertices(&self) -> &[Vec3] {
        &self.vertices
    }

    /// The triangles, as indices into [`TriangleMesh::vertices`].
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// The file this mesh was loaded from, or `<in-memory>`.
    pub fn origin(&self) -> &Path {
        &self.origin
    }

    /// The three corners of triangle `t`.
    pub fn triangle_corners(&self, t: [u32; 3]) -> [Vec3; 3] {
        t.map(|i| self.vertices[i as usize])
    }

    /// The mesh with every vertex mapped by `target_from_mesh`.
    pub fn transformed(&self, target_from_mesh: &Pose3) -> Self {
        let vertices = self
            .vertices
            .iter()
            .map(|v| target_from_mesh.transform_point(*v))
            .collect();
        Self {
            vertices,
            triangles: self.triangles.clone(),
            origin: self.origin.clone(),
        }
    }

    /// The mesh scaled about the origin by `scale` per axis. A negative product of scales mirrors
    /// the mesh, and the triangles are flipped so that normals still point outwards.
    pub fn scaled(&self, scale: Vec3) -> Self {
        let vertices = self.vertices.iter().map(|v| *v * scale).collect();
        let mirrored = scale.x * scale.y * scale.z < 0.0;
        let triangles = if mirrored {
            self.triangles.iter().map(|t| [t[0], t[2], t[1]]).collect()
        } else {
            self.triangles.clone()
        };
        Self {
            vertices,
            triangles,
            origin: self.origin.clone(),
        }
    }

    /// Several meshes as one (vertex lists concatenated, indices shifted), named after `origin`.
    ///
    /// # Errors
    /// [`GeometryError::NoTriangles`](crate::GeometryError::NoTriangles) when `parts` is empty.
    pub fn concatenate(parts: &[TriangleMesh], origin: &Path) -> Result<Self> {
        let mut vertices = Vec::new();
        let mut triangles = Vec::new();
        for part in parts {
            let offset = vertices.len() as u32;
            vertices.extend_from_slice(&part.vertices);
            triangles.extend(part.triangles.iter().map(|t| t.map(|i| i + offset)));
        }
        Self::from_parts(vertices, triangles, origin)
    }

    /// The outward unit normal of each triangle (zero for none: degenerate ones are dropped).
    pub fn triangle_normals(&self) -> Vec<Vec3> {
        self.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = self.triangle_corners(*t);
                (b - a).cross(c - a).normalize_or_zero()
            })
            .collect()
    }

    /// The total surface area, square metres.
    pub fn surface_area_m2(&self) -> f32 {
        self.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = self.triangle_corners(*t);
                0.5 * (b - a).cross(c - a).length()
            })
            .sum()
    }
}
