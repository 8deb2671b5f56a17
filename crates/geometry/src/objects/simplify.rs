//! Edge-collapse simplification with quadric error metrics (Garland and Heckbert, 1997).
//!
//! Marching tetrahedra makes many small, thin triangles (about eight per square cell on a flat
//! face). Collapsing the edges whose removal moves the surface least, within a tolerance, cuts
//! the count several times over and improves triangle shape, while the link condition keeps
//! the mesh closed and edge-manifold and a normal check keeps it from folding. The greedy order
//! is total (cost, then vertex ids), so the result is deterministic.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use glam::DVec3;
use parry3d::math::Vec3;

/// Candidate edge collapses, cheapest first: (cost bits, u, v, version of u, version of v).
type EdgeHeap = BinaryHeap<Reverse<(u64, u32, u32, u32, u32)>>;

/// A symmetric 4x4 quadric, upper triangle row by row.
#[derive(Clone, Copy, Default)]
struct Quadric([f64; 10]);

impl Quadric {
    /// The squared distance to the plane through `a` with unit normal `n`.
    fn plane(n: DVec3, a: DVec3) -> Self {
        let d = -n.dot(a);
        let (x, y, z) = (n.x, n.y, n.z);
        Self([
            x * x,
            x * y,
            x * z,
            x * d,
            y * y,
            y * z,
            y * d,
            z * z,
            z * d,
            d * d,
        ])
    }

    fn add(self, o: Self) -> Self {
        Self(std::array::from_fn(|i| self.0[i] + o.0[i]))
    }

    fn error(&self, p: DVec3) -> f64 {
        let q = &self.0;
        let (x, y, z) = (p.x, p.y, p.z);
        let e = q[0] * x * x
            + 2.0 * q[1] * x * y
            + 2.0 * q[2] * x * z
            + 2.0 * q[3] * x
            + q[4] * y * y
            + 2.0 * q[5] * y * z
            + 2.0 * q[6] * y
            + q[7] * z * z
            + 2.0 * q[8] * z
            + q[9];
        e.max(0.0)
    }
}

/// Limits of [`simplify`].
#[derive(Clone, Copy, Debug)]
pub(crate) struct SimplifyLimits {
    /// Largest accepted quadric error, as a distance (metres): about how far the surface moves.
    pub tolerance_m: f32,
    /// No edge may grow longer than this (metres).
    pub max_edge_m: f32,
}

/// The smallest cosine between a triangle's normal before and after a collapse.
const MIN_NORMAL_COS: f64 = 0.5;

/// Twice the smallest area a triangle may have after a collapse, square metres.
const MIN_DOUBLE_AREA_M2: f64 = 1e-10;

struct Mesh {
    pos: Vec<DVec3>,
    tris: Vec<[u32; 3]>,
    tri_alive: Vec<bool>,
    vert_alive: Vec<bool>,
    /// Live triangles around each vertex.
    around: Vec<Vec<u32>>,
    quadric: Vec<Quadric>,
    version: Vec<u32>,
}

/// Simplifies a closed, edge-manifold mesh in place of `vertices` and `triangles`, keeping it
/// closed, edge-manifold and consistently oriented.
pub(crate) fn simplify(
    vertices: &[Vec3],
    triangles: &[[u32; 3]],
    limits: SimplifyLimits,
) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut m = Mesh::new(vertices, triangles);
    let max_cost = f64::from(limits.tolerance_m).powi(2);
    let max_edge2 = f64::from(limits.max_edge_m).powi(2);
    let mut heap: EdgeHeap = BinaryHeap::new();
    for t in triangles {
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            if a < b {
                m.push_edge(&mut heap, a, b);
            }
        }
    }
    while let Some(Reverse((cost_bits, u, v, ver_u, ver_v))) = heap.pop() {
        let (ui, vi) = (u as usize, v as usize);
        if !m.vert_alive[ui]
            || !m.vert_alive[vi]
            || m.version[ui] != ver_u
            || m.version[vi] != ver_v
        {
            continue;
        }
        if f64::from_bits(cost_bits) > max_cost {
            break;
        }
        let (p, _) = m.best_position(u, v);
        if m.can_collapse(u, v, p, max_edge2) {
            m.collapse(u, v, p);
            for w in m.neighbours(u) {
                m.push_edge(&mut heap, u.min(w), u.max(w));
            }
        }
    }
    m.compact()
}

impl Mesh {
    fn new(vertices: &[Vec3], triangles: &[[u32; 3]]) -> Self {
        let pos: Vec<DVec3> = vertices.iter().map(|v| v.as_dvec3()).collect();
        let mut around = vec![Vec::new(); pos.len()];
        let mut quadric = vec![Quadric::default(); pos.len()];
        for (i, t) in triangles.iter().enumerate() {
            let [a, b, c] = t.map(|k| pos[k as usize]);
            let n = (b - a).cross(c - a).normalize_or_zero();
            let q = Quadric::plane(n, a);
            for &k in t {
                around[k as usize].push(i as u32);
                quadric[k as usize] = quadric[k as usize].add(q);
            }
        }
        Self {
            vert_alive: vec![true; pos.len()],
            version: vec![0; pos.len()],
            pos,
            tris: triangles.to_vec(),
            tri_alive: vec![true; triangles.len()],
            around,
            quadric,
        }
    }

    /// The cheapest of the edge's midpoint and ends, with its cost.
    fn best_position(&self, u: u32, v: u32) -> (DVec3, f64) {
        let q = self.quadric[u as usize].add(self.quadric[v as usize]);
        let (pu, pv) = (self.pos[u as usize], self.pos[v as usize]);
        [0.5 * (pu + pv), pu, pv]
            .into_iter()
            .map(|p| (p, q.error(p)))
            .fold(
                (pu, f64::INFINITY),
                |best, c| if c.1 < best.1 { c } else { best },
            )
    }

    fn push_edge(&self, heap: &mut EdgeHeap, u: u32, v: u32) {
        let (_, cost) = self.best_position(u, v);
        let ver = |k: u32| self.version[k as usize];
        heap.push(Reverse((cost.to_bits(), u, v, ver(u), ver(v))));
    }

    /// The live neighbours of `u`, sorted and unique.
    fn neighbours(&self, u: u32) -> Vec<u32> {
        let mut n: Vec<u32> = self.around[u as usize]
            .iter()
            .flat_map(|&t| self.tris[t as usize])
            .filter(|&k| k != u)
            .collect();
        n.sort_unstable();
        n.dedup();
        n
    }

    fn can_collapse(&self, u: u32, v: u32, p: DVec3, max_edge2: f64) -> bool {
        // Link condition: u and v share exactly the two vertices opposite their edge, and
        // those two are not themselves joined (which would pinch the surface).
        let shared: Vec<u32> = self.around[u as usize]
            .iter()
            .filter(|&&t| self.tris[t as usize].contains(&v))
            .map(|&t| self.tris[t as usize])
            .map(|t| t.into_iter().find(|&k| k != u && k != v).unwrap_or(u))
            .collect();
        // Geometry: no surviving triangle may flip, collapse or grow too long an edge.
        for &w in &[u, v] {
            for &t in &self.around[w as usize] {
                let tri = self.tris[t as usize];
                if tri.contains(&u) && tri.contains(&v) {
                    continue;
                }
                let old = tri.map(|k| self.pos[k as usize]);
                let new = tri.map(|k| {
                    if k == u || k == v {
                        p
                    } else {
                        self.pos[k as usize]
                    }
                });
                let n_old = (old[1] - old[0]).cross(old[2] - old[0]);
                let n_new = (new[1] - new[0]).cross(new[2] - new[0]);
                let (l_old, l_new) = (n_old.length(), n_new.length());
                if l_new < MIN_DOUBLE_AREA_M2 || n_old.dot(n_new) < MIN_NORMAL_COS * l_old * l_new {
                    return false;
                }
                if (0..3).any(|i| (new[i] - new[(i + 1) % 3]).length_squared() > max_edge2) {
                    return false;
                }
            }
        }
        let (nu, nv) = (self.neighbours(u), self.neighbours(v));
        let common: Vec<u32> = nu.iter().copied().filter(|k| nv.contains(k)).collect();
        let [a, b] = shared[..] else {
            return false;
        };
        let mut opposite = [a, b];
        opposite.sort_unstable();
        if common != opposite || self.neighbours(a).contains(&b) {
            return false;
        }
        if nu.len() + nv.len() < 7 {
            return false;
        }
        true
    }

    /// Merges `v` into `u`, which moves to `p`.
    fn collapse(&mut self, u: u32, v: u32, p: DVec3) {
        let (ui, vi) = (u as usize, v as usize);
        let v_tris = std::mem::take(&mut self.around[vi]);
        for &t in &v_tris {
            let ti = t as usize;
            if self.tris[ti].contains(&u) {
                self.tri_alive[ti] = false;
                for k in self.tris[ti] {
                    self.around[k as usize].retain(|&x| x != t);
                }
            } else {
                for k in &mut self.tris[ti] {
                    if *k == v {
                        *k = u;
                    }
                }
                self.around[ui].push(t);
            }
        }
        self.around[ui].sort_unstable();
        self.pos[ui] = p;
        self.quadric[ui] = self.quadric[ui].add(self.quadric[vi]);
        self.vert_alive[vi] = false;
        self.version[ui] += 1;
    }

    /// The live vertices and triangles, renumbered in their original order.
    fn compact(self) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let mut new_index = vec![u32::MAX; self.pos.len()];
        let mut vertices = Vec::new();
        for (i, p) in self.pos.iter().enumerate() {
            if self.vert_alive[i] && !self.around[i].is_empty() {
                new_index[i] = vertices.len() as u32;
                vertices.push(p.as_vec3());
            }
        }
        let triangles = self
            .tris
            .iter()
            .zip(&self.tri_alive)
            .filter(|(_, alive)| **alive)
            .map(|(t, _)| t.map(|k| new_index[k as usize]))
            .collect();
        (vertices, triangles)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::TriangleMesh;
    use crate::objects::mesher::march;
    use crate::objects::test_support::{assert_closed_and_oriented, signed_volume};

    #[test]
    fn a_simplified_box_keeps_its_shape_with_far_fewer_triangles() {
        let h = Vec3::new(0.03, 0.02, 0.01);
        let sdf = move |p: Vec3| {
            let q = p.abs() - h;
            q.max(Vec3::ZERO).length() + q.max_element().min(0.0)
        };
        let (v, t) = march(&sdf, -h, h, 0.002).unwrap();
        let limits = SimplifyLimits {
            tolerance_m: 1e-4,
            max_edge_m: 0.01,
        };
        let (v2, t2) = simplify(&v, &t, limits);
        assert!(t2.len() * 3 < t.len(), "{} -> {}", t.len(), t2.len());
        let before = TriangleMesh::new(v, t).unwrap();
        let after = TriangleMesh::new(v2, t2.clone()).unwrap();
        assert_eq!(after.triangles().len(), t2.len());
        assert_closed_and_oriented(&after);
        let (a, b) = (signed_volume(&before), signed_volume(&after));
        assert!((a / b - 1.0).abs() < 0.01, "{a} vs {b}");
        for p in after.vertices() {
            assert!(sdf(*p).abs() < 2e-4);
        }
    }
}
