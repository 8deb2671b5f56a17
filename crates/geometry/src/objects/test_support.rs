//! Mesh checks shared by the object tests.

use std::collections::HashMap;

use crate::mesh::TriangleMesh;

/// Asserts that every undirected edge is used by exactly two triangles, once in each direction
/// (closed, edge-manifold and consistently oriented).
pub(crate) fn assert_closed_and_oriented(mesh: &TriangleMesh) {
    let mut directed: HashMap<(u32, u32), u32> = HashMap::new();
    for t in mesh.triangles() {
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            *directed.entry((a, b)).or_default() += 1;
        }
    }
    for (&(a, b), &count) in &directed {
        assert_eq!(
            count, 1,
            "edge {a}->{b} is used {count} times in one direction"
        );
        assert_eq!(
            directed.get(&(b, a)).copied(),
            Some(1),
            "edge {a}->{b} has no opposite"
        );
    }
}

/// The enclosed volume by the divergence theorem (positive when normals point outwards).
pub(crate) fn signed_volume(mesh: &TriangleMesh) -> f32 {
    let sum: f64 = mesh
        .triangles()
        .iter()
        .map(|t| {
            let [a, b, c] = mesh.triangle_corners(*t).map(|v| v.as_dvec3());
            a.dot(b.cross(c))
        })
        .sum();
    (sum / 6.0) as f32
}
