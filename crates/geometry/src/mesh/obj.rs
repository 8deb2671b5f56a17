//! Wavefront OBJ: reading with tobj, writing by hand (the format is a few lines).

use std::io::Write;
use std::path::Path;

use parry3d::math::Vec3;

use super::TriangleMesh;
use crate::error::{GeometryError, Result};

/// Reads every object of an OBJ file into one mesh (materials and textures are ignored, and
/// may be absent).
pub(super) fn read_obj(path: &Path) -> Result<TriangleMesh> {
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
    };
    let (models, _materials) = match tobj::load_obj(path, &options) {
        Ok(loaded) => loaded,
        Err(tobj::LoadError::FaceVertexOutOfBounds) => return Err(out_of_range_error(path)),
        Err(e) => {
            return Err(GeometryError::Parse {
                format: "OBJ",
                detail: e.to_string(),
                path: path.to_path_buf(),
            });
        }
    };
    let mut vertices = Vec::new();
    let mut triangles = Vec::new();
    for model in &models {
        let offset = vertices.len() as u32;
        vertices.extend(
            model
                .mesh
                .positions
                .chunks_exact(3)
                .map(|p| Vec3::new(p[0], p[1], p[2])),
        );
        triangles.extend(
            model
                .mesh
                .indices
                .chunks_exact(3)
                .map(|t| [t[0] + offset, t[1] + offset, t[2] + offset]),
        );
    }
    TriangleMesh::from_parts(vertices, triangles, path)
}

/// tobj only says "out of bounds"; find the first offending face to name it.
fn out_of_range_error(path: &Path) -> GeometryError {
    let text = std::fs::read_to_string(path).unwrap_or_default();
    let mut vertex_count = 0usize;
    let mut face = 0usize;
    for line in text.lines() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => vertex_count += 1,
            Some("f") => {
                for word in words {
                    let Some(Ok(index)) = word.split('/').next().map(str::parse::<i64>) else {
                        continue;
                    };
                    let resolved = if index < 0 {
                        vertex_count as i64 + index
                    } else {
                        index - 1
                    };
                    if resolved < 0 || resolved as usize >= vertex_count {
                        return GeometryError::IndexOutOfRange {
                            triangle: face,
                            index: index.unsigned_abs(),
                            vertex_count,
                            path: path.to_path_buf(),
                        };
                    }
                }
                face += 1;
            }
            _ => {}
        }
    }
    GeometryError::Parse {
        format: "OBJ",
        detail: "a face vertex index is out of bounds".into(),
        path: path.to_path_buf(),
    }
}

/// Writes `mesh` as an OBJ file (vertices in metres, 1-based faces), atomically: to a temporary
/// name first, then renamed, so a reader never sees half a file.
///
/// # Errors
/// [`GeometryError::Io`] naming the file.
pub fn write_obj(mesh: &TriangleMesh, path: impl AsRef<Path>) -> Result<()> {
    let path = path.as_ref();
    let io = |op, source| GeometryError::Io {
        op,
        source,
        path: path.to_path_buf(),
    };
    let mut text = String::with_capacity(mesh.vertices().len() * 40 + mesh.triangles().len() * 24);
    text.push_str("# written by mvgrasp; units: metres\n");
    for v in mesh.vertices() {
        text.push_str(&format!("v {} {} {}\n", v.x, v.y, v.z));
    }
    for t in mesh.triangles() {
        text.push_str(&format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1));
    }
    let mut tmp_name = path.as_os_str().to_owned();
    tmp_name.push(".tmp");
    let tmp = std::path::PathBuf::from(tmp_name);
    let mut file = std::fs::File::create(&tmp).map_err(|e| io("create", e))?;
    file.write_all(text.as_bytes())
        .map_err(|e| io("write", e))?;
    file.sync_all().map_err(|e| io("write", e))?;
    std::fs::rename(&tmp, path).map_err(|e| io("rename", e))
}
