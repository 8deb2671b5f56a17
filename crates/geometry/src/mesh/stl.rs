//! STL, ASCII or binary, read with stl_io.

use std::path::Path;

use parry3d::math::Vec3;

use super::TriangleMesh;
use crate::error::{GeometryError, Result};

/// Reads an STL file; stl_io merges identical vertices, so closed meshes stay closed.
pub(super) fn read_stl(path: &Path) -> Result<TriangleMesh> {
    let mut file = std::fs::File::open(path).map_err(|source| GeometryError::Io {
        op: "open",
        source,
        path: path.to_path_buf(),
    })?;
    let indexed = stl_io::read_stl(&mut file).map_err(|e| GeometryError::Parse {
        format: "STL",
        detail: e.to_string(),
        path: path.to_path_buf(),
    })?;
    let vertices = indexed
        .vertices
        .iter()
        .map(|v| Vec3::new(v[0], v[1], v[2]))
        .collect::<Vec<_>>();
    let mut triangles = Vec::with_capacity(indexed.faces.len());
    for (triangle, face) in indexed.faces.iter().enumerate() {
        let mut t = [0u32; 3];
        for (slot, &index) in t.iter_mut().zip(&face.vertices) {
            *slot = u32::try_from(index).map_err(|_| GeometryError::IndexOutOfRange {
                triangle,
                index: index as u64,
                vertex_count: vertices.len(),
                path: path.to_path_buf(),
            })?;
        }
        triangles.push(t);
    }
    TriangleMesh::from_parts(vertices, triangles, path)
}
