//! Mesh input and its expansion, on the CPU, into the vertex stream the GPU draws: every
//! triangle gets its own three vertices (flat shading), in world coordinates, with the face
//! normal, its colour and the mesh's instance id.

use crate::camera::{affine_error, transform_point};
use crate::error::{RenderError, Result};
use crate::look::Material;
use crate::shadow::Bounds;

/// Colours of a mesh, sRGB-free 8-bit RGB multiplied by the shading.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Colors<'a> {
    /// One colour per vertex (`positions.len()` of them), interpolated across faces.
    PerVertex(&'a [[u8; 3]]),
    /// One colour per triangle (`indices.len()` of them).
    PerFace(&'a [[u8; 3]]),
    /// One colour for the whole mesh.
    Uniform([u8; 3]),
}

/// Which sides of a mesh's triangles are drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Sides {
    /// Both sides: right for any mesh, whatever its winding (open scans, planes).
    #[default]
    Both,
    /// Front faces only: for a closed surface wound counter-clockwise seen from outside (a
    /// watertight mesh with positive signed volume). Back faces are never visible on such a
    /// surface, and skipping them about halves the work of a CPU rasteriser.
    Front,
}

/// One mesh to upload: plain slices, its placement in the world and its id in the mask.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeshInput<'a> {
    /// Vertex positions in the mesh frame, metres.
    pub positions: &'a [[f32; 3]],
    /// Triangles as indices into `positions` (any winding with [`Sides::Both`]).
    pub indices: &'a [[u32; 3]],
    /// Which sides of the triangles are drawn.
    pub sides: Sides,
    /// The mesh's colours.
    pub colors: Colors<'a>,
    /// Row-major affine transform placing the mesh in the world (scale allowed).
    pub world_from_mesh: [[f32; 4]; 4],
    /// Id written to the mask where this mesh is visible: 1..=255 (0 is the background).
    pub instance_id: u8,
    /// Its texture and highlight under [`crate::Lighting::World`] ([`Material::MATTE`]: flat).
    pub material: Material,
}

/// Bytes of one GPU vertex: position (3 x f32), normal (3 x f32), colour (4 x u8), id (u32),
/// material (8 x u8).
pub(crate) const VERTEX_BYTES: usize = 40;

/// The expanded vertex stream: the [`Sides::Front`] meshes' vertices first, then the others.
#[derive(Debug)]
pub(crate) struct Expanded {
    /// Native-endian bytes, [`VERTEX_BYTES`] a vertex.
    pub bytes: Vec<u8>,
    /// Vertices of the front-only meshes, at the start of the stream.
    pub front_vertices: usize,
    /// All vertices.
    pub vertices: usize,
    /// A sphere holding every vertex.
    pub bounds: Bounds,
}

/// Checks every mesh and expands them all into one flat-shaded vertex stream, front-only meshes
/// first.
pub(crate) fn expand(meshes: &[MeshInput<'_>]) -> Result<Expanded> {
    if meshes.is_empty() {
        return Err(RenderError::InvalidParameter {
            op: "upload",
            name: "meshes",
            value: "[]".into(),
            expected: "at least one mesh",
        });
    }
    for (i, mesh) in meshes.iter().enumerate() {
        validate(mesh, i)?;
    }
    let vertices: usize = meshes.iter().map(|m| 3 * m.indices.len()).sum();
    let mut bytes = Vec::with_capacity(vertices * VERTEX_BYTES);
    let (front, both): (Vec<&MeshInput<'_>>, Vec<_>) =
        meshes.iter().partition(|m| m.sides == Sides::Front);
    let front_vertices = front.iter().map(|m| 3 * m.indices.len()).sum();
    let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
    for mesh in front.into_iter().chain(both) {
        let material = mesh.material.vertex_bytes();
        let world: Vec<[f32; 3]> = mesh
            .positions
            .iter()
            .map(|&p| transform_point(&mesh.world_from_mesh, p))
            .collect();
        for p in &world {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        for (t, tri) in mesh.indices.iter().enumerate() {
            let corners = tri.map(|i| world[i as usize]);
            let normal = face_normal(corners);
            for (c, &vi) in tri.iter().enumerate() {
                let rgb = match mesh.colors {
                    Colors::PerVertex(cs) => cs[vi as usize],
                    Colors::PerFace(cs) => cs[t],
                    Colors::Uniform(rgb) => rgb,
                };
                push_vertex(&mut bytes, corners[c], normal, rgb, mesh.instance_id);
                bytes.extend_from_slice(&material);
            }
        }
    }
    let center: [f32; 3] = std::array::from_fn(|k| 0.5 * (lo[k] + hi[k]));
    let radius = (0..3)
        .map(|k| (0.5 * (hi[k] - lo[k])).powi(2))
        .sum::<f32>()
        .sqrt();
    Ok(Expanded {
        bytes,
        front_vertices,
        vertices,
        bounds: Bounds { center, radius },
    })
}

/// Checks one mesh: not empty, finite positions, indices in range, colour counts, transform,
/// instance id.
fn validate(mesh: &MeshInput<'_>, mesh_index: usize) -> Result<()> {
    let bad = |reason: String| RenderError::InvalidMesh { mesh_index, reason };
    if mesh.instance_id == 0 {
        return Err(bad(
            "instance_id is 0, which is the background; use 1..=255".into(),
        ));
    }
    if mesh.positions.is_empty() || mesh.indices.is_empty() {
        return Err(bad(format!(
            "empty: {} positions and {} triangles, needs at least one of each",
            mesh.positions.len(),
            mesh.indices.len()
        )));
    }
    if let Some((v, p)) = mesh
        .positions
        .iter()
        .enumerate()
        .find(|(_, p)| p.iter().any(|x| !x.is_finite()))
    {
        return Err(bad(format!("position {v} is not finite: {p:?}")));
    }
    let n = mesh.positions.len();
    for (t, tri) in mesh.indices.iter().enumerate() {
        if let Some(&i) = tri.iter().find(|&&i| i as usize >= n) {
            return Err(bad(format!(
                "triangle {t} has index {i} out of range for {n} positions"
            )));
        }
    }
    let (kind, got, expected) = match mesh.colors {
        Colors::PerVertex(cs) => ("per-vertex", cs.len(), n),
        Colors::PerFace(cs) => ("per-face", cs.len(), mesh.indices.len()),
        Colors::Uniform(_) => ("uniform", 1, 1),
    };
    if got != expected {
        return Err(bad(format!("{got} {kind} colours, expected {expected}")));
    }
    mesh.material.validate(mesh_index)?;
    if let Some(reason) = affine_error(&mesh.world_from_mesh) {
        return Err(bad(format!(
            "world_from_mesh is not an affine transform: {reason}"
        )));
    }
    if let Some((v, p)) = mesh
        .positions
        .iter()
        .map(|&p| transform_point(&mesh.world_from_mesh, p))
        .enumerate()
        .find(|(_, p)| p.iter().any(|x| !x.is_finite()))
    {
        return Err(bad(format!(
            "position {v} is not finite in the world: {p:?}"
        )));
    }
    Ok(())
}

/// Unit normal of a triangle (right-hand rule), or zero for a degenerate one.
fn face_normal([a, b, c]: [[f32; 3]; 3]) -> [f32; 3] {
    let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
    let n = [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ];
    let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    if len > 0.0 && len.is_finite() {
        n.map(|x| x / len)
    } else {
        [0.0; 3]
    }
}

/// Appends one vertex in the layout of `shader.wgsl`'s `VertexIn`, but for its material.
fn push_vertex(out: &mut Vec<u8>, p: [f32; 3], n: [f32; 3], rgb: [u8; 3], id: u8) {
    for x in p.iter().chain(n.iter()) {
        out.extend_from_slice(&x.to_ne_bytes());
    }
    out.extend_from_slice(&[rgb[0], rgb[1], rgb[2], 255]);
    out.extend_from_slice(&u32::from(id).to_ne_bytes());
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::IDENTITY;

    const TRI: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

    fn mesh<'a>(positions: &'a [[f32; 3]], indices: &'a [[u32; 3]]) -> MeshInput<'a> {
        MeshInput {
            positions,
            indices,
            sides: Sides::Both,
            colors: Colors::Uniform([10, 20, 30]),
            world_from_mesh: IDENTITY,
            instance_id: 7,
            material: Material::MATTE,
        }
    }

    fn f32_at(bytes: &[u8], offset: usize) -> f32 {
        f32::from_ne_bytes([
            bytes[offset],
            bytes[offset + 1],
            bytes[offset + 2],
            bytes[offset + 3],
        ])
    }

    #[test]
    fn a_triangle_expands_to_three_flat_vertices() {
        let mut m = mesh(&TRI, &[[0, 1, 2]]);
        m.world_from_mesh[2][3] = 0.5;
        let Expanded {
            bytes, vertices: n, ..
        } = expand(&[m]).unwrap();
        assert_eq!(n, 3);
        assert_eq!(bytes.len(), 3 * VERTEX_BYTES);
        let v1 = VERTEX_BYTES;
        assert_eq!(f32_at(&bytes, v1), 1.0);
        assert_eq!(f32_at(&bytes, v1 + 8), 0.5); // z moved by world_from_mesh
        assert_eq!(f32_at(&bytes, v1 + 20), 1.0); // normal +z
        assert_eq!(&bytes[v1 + 24..v1 + 28], &[10, 20, 30, 255]);
        assert_eq!(bytes[v1 + 28], 7);
    }

    #[test]
    fn per_face_and_per_vertex_colours_go_where_they_belong() {
        let quad = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ];
        let tris = [[0, 1, 2], [0, 2, 3]];
        let faces = [[1, 1, 1], [2, 2, 2]];
        let mut m = mesh(&quad, &tris);
        m.colors = Colors::PerFace(&faces);
        let bytes = expand(&[m]).unwrap().bytes;
        assert_eq!(bytes[3 * VERTEX_BYTES + 24], 2);
        let verts = [[9, 0, 0], [8, 0, 0], [7, 0, 0], [6, 0, 0]];
        m.colors = Colors::PerVertex(&verts);
        let bytes = expand(&[m]).unwrap().bytes;
        // second triangle, third corner is vertex 3
        assert_eq!(bytes[5 * VERTEX_BYTES + 24], 6);
    }

    #[test]
    fn bad_meshes_are_rejected_with_their_index() {
        let ok = mesh(&TRI, &[[0, 1, 2]]);
        assert!(expand(&[]).is_err());
        let out_of_range = [[0, 1, 3]];
        let err = expand(&[ok, mesh(&TRI, &out_of_range)])
            .unwrap_err()
            .to_string();
        assert!(err.contains("mesh 1") && err.contains("index 3"), "{err}");
        let nan = [[0.0, 0.0, f32::NAN], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        assert!(expand(&[mesh(&nan, &[[0, 1, 2]])]).is_err());
        assert!(expand(&[mesh(&TRI, &[])]).is_err());
        assert!(expand(&[mesh(&[], &[[0, 0, 0]])]).is_err());
        let mut zero = ok;
        zero.instance_id = 0;
        assert!(expand(&[zero]).is_err());
        let mut colours = ok;
        colours.colors = Colors::PerVertex(&[[0, 0, 0]]);
        assert!(expand(&[colours]).is_err());
        let mut singular = ok;
        singular.world_from_mesh[0][0] = 0.0;
        assert!(expand(&[singular]).is_err());
        let mut huge = ok;
        huge.world_from_mesh[0][0] = f32::MAX;
        huge.positions = &[[f32::MAX, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        assert!(expand(&[huge]).is_err());
    }

    #[test]
    fn a_degenerate_triangle_has_a_zero_normal() {
        assert_eq!(
            face_normal([[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]]),
            [0.0; 3]
        );
    }
}
