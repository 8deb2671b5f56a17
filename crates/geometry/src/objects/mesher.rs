//! Marching tetrahedra: a closed, welded, edge-manifold triangle mesh of an SDF's zero level.
//!
//! The box is sampled on a regular grid padded by two cells, whose outermost corners are forced
//! outside so the surface always closes. Each cube is split into six tetrahedra around its
//! main diagonal (the Kuhn split, identical in every cube, so neighbouring cubes agree on face
//! diagonals). A tetrahedron face's crossing depends only on the face's own corners, so every
//! surface edge is shared by exactly two triangles; vertices are keyed by the grid edge they lie
//! on, so the mesh is welded. Triangles face positive distance (outwards). Output order follows
//! the grid (z, then y, then x), so it is deterministic.

use std::collections::HashMap;

use parry3d::math::Vec3;

use super::simplify::{SimplifyLimits, simplify};
use crate::error::{GeometryError, Result, in_memory};
use crate::mesh::TriangleMesh;

/// Settings of the mesher and of the simplification that follows it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MarchingParams {
    /// Edge length of a grid cell, metres. Parts thinner than about two cells may be lost.
    pub cell_m: f32,
    /// How far (quadric error, metres) simplification may move the surface; 0 turns it off.
    pub simplify_tolerance_m: f32,
    /// The longest edge simplification may create, metres.
    pub max_edge_m: f32,
}

impl Default for MarchingParams {
    /// A 2 mm grid, simplified within 0.1 mm with edges up to 1 cm.
    fn default() -> Self {
        Self::with_cell(0.002)
    }
}

impl MarchingParams {
    /// A grid of `cell_m` cells, simplified within 5 % of a cell with edges up to 5 cells.
    pub fn with_cell(cell_m: f32) -> Self {
        Self {
            cell_m,
            simplify_tolerance_m: 0.05 * cell_m,
            max_edge_m: 5.0 * cell_m,
        }
    }
}

/// The largest grid the mesher accepts, in corners (about 1 GB of distance values).
const MAX_CORNERS: usize = 256 * 1024 * 1024;

/// The smallest accepted cell, metres.
const MIN_CELL_M: f32 = 1e-4;

/// How close to a grid corner a vertex may come, metres: keeps every triangle well above
/// [`TriangleMesh`]'s degenerate-area threshold so none is dropped and no hole opens.
const MIN_CORNER_GAP_M: f32 = 4e-6;

/// The six tetrahedra of a cube, as corner ids (bit 0: +x, bit 1: +y, bit 2: +z), each ordered
/// so that its signed volume is positive.
const TETS: [[u8; 4]; 6] = [
    [0, 1, 3, 7],
    [0, 2, 6, 7],
    [0, 4, 5, 7],
    [0, 5, 1, 7],
    [0, 3, 2, 7],
    [0, 6, 4, 7],
];

/// For a lone corner `i`, an even permutation of the tetrahedron that puts `i` first.
const LONE_FIRST: [[usize; 4]; 4] = [[0, 1, 2, 3], [1, 0, 3, 2], [2, 3, 0, 1], [3, 2, 1, 0]];

/// Even permutations `(a, b, c, d)` of the tetrahedron, one for each pair `{a, b}`.
const PAIR_FIRST: [[usize; 4]; 6] = [
    [0, 1, 2, 3],
    [0, 2, 3, 1],
    [0, 3, 1, 2],
    [1, 2, 0, 3],
    [1, 3, 2, 0],
    [2, 3, 0, 1],
];

/// Meshes the surface `sdf(p) = 0` (negative inside) within `[bounds_min, bounds_max]` on a grid
/// of `cell_m` cells. The result is closed and welded, with normals pointing outwards.
///
/// # Errors
/// [`GeometryError::InvalidParameter`] for a bad cell or box or a grid too large,
/// [`GeometryError::Degenerate`] when the function returns NaN or the surface is empty, or a mesh
/// construction error.
pub fn mesh_sdf(
    sdf: &(dyn Fn(Vec3) -> f32 + Sync),
    bounds_min: Vec3,
    bounds_max: Vec3,
    cell_m: f32,
) -> Result<TriangleMesh> {
    let (vertices, triangles) = march(sdf, bounds_min, bounds_max, cell_m)?;
    let expected = triangles.len();
    let mesh = TriangleMesh::new(vertices, triangles)?;
    check_nothing_dropped(&mesh, expected)?;
    Ok(mesh)
}

/// As [`mesh_sdf`] with the grid of `params`, followed by its simplification.
///
/// # Errors
/// As [`mesh_sdf`], or [`GeometryError::InvalidParameter`] for a negative or non-finite
/// tolerance or edge length.
pub fn mesh_sdf_with(
    sdf: &(dyn Fn(Vec3) -> f32 + Sync),
    bounds_min: Vec3,
    bounds_max: Vec3,
    params: &MarchingParams,
) -> Result<TriangleMesh> {
    let (vertices, triangles) = march_simplified(sdf, bounds_min, bounds_max, params)?;
    let expected = triangles.len();
    let mesh = TriangleMesh::new(vertices, triangles)?;
    check_nothing_dropped(&mesh, expected)?;
    Ok(mesh)
}

/// The raw vertices and triangles of [`mesh_sdf_with`].
pub(crate) fn march_simplified(
    sdf: &(dyn Fn(Vec3) -> f32 + Sync),
    bounds_min: Vec3,
    bounds_max: Vec3,
    params: &MarchingParams,
) -> Result<(Vec<Vec3>, Vec<[u32; 3]>)> {
    for (name, value) in [
        ("simplify_tolerance_m", params.simplify_tolerance_m),
        ("max_edge_m", params.max_edge_m),
    ] {
        if !value.is_finite() || value < 0.0 {
            return Err(GeometryError::InvalidParameter {
                op: "marching tetrahedra",
                name,
                value: value.to_string(),
                expected: "a finite length >= 0",
            });
        }
    }
    let (vertices, triangles) = march(sdf, bounds_min, bounds_max, params.cell_m)?;
    if params.simplify_tolerance_m == 0.0 {
        return Ok((vertices, triangles));
    }
    let limits = SimplifyLimits {
        tolerance_m: params.simplify_tolerance_m,
        max_edge_m: params.max_edge_m,
    };
    Ok(simplify(&vertices, &triangles, limits))
}

/// Fails when [`TriangleMesh`] construction dropped triangles (which would open holes).
pub(crate) fn check_nothing_dropped(mesh: &TriangleMesh, expected: usize) -> Result<()> {
    if mesh.triangles().len() == expected {
        return Ok(());
    }
    Err(GeometryError::Degenerate {
        op: "marching tetrahedra",
        detail: format!(
            "{} of {expected} triangles were degenerate",
            expected - mesh.triangles().len()
        ),
        path: mesh.origin().to_path_buf(),
    })
}

/// The grid: corner counts per axis, first corner, cell size.
struct Grid {
    n: [usize; 3],
    origin: Vec3,
    cell: f32,
}

impl Grid {
    fn index(&self, i: usize, j: usize, k: usize) -> usize {
        i + self.n[0] * (j + self.n[1] * k)
    }

    fn position(&self, i: usize, j: usize, k: usize) -> Vec3 {
        self.origin + Vec3::new(i as f32, j as f32, k as f32) * self.cell
    }
}

/// The raw vertices and triangles of [`mesh_sdf`].
pub(crate) fn march(
    sdf: &(dyn Fn(Vec3) -> f32 + Sync),
    bounds_min: Vec3,
    bounds_max: Vec3,
    cell_m: f32,
) -> Result<(Vec<Vec3>, Vec<[u32; 3]>)> {
    let grid = make_grid(bounds_min, bounds_max, cell_m)?;
    let values = sample(sdf, &grid)?;
    let eps = (MIN_CORNER_GAP_M / grid.cell).clamp(1e-3, 0.1);
    let mut vertices: Vec<Vec3> = Vec::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    let mut edge_vertex: HashMap<u64, u32> = HashMap::new();
    let [nx, ny, nz] = grid.n;
    for k in 0..nz - 1 {
        for j in 0..ny - 1 {
            for i in 0..nx - 1 {
                let base = grid.index(i, j, k);
                let corner = |c: u8| {
                    let (di, dj, dk) = (c & 1, (c >> 1) & 1, (c >> 2) & 1);
                    base + usize::from(di) + nx * (usize::from(dj) + ny * usize::from(dk))
                };
                let f: [f32; 8] = std::array::from_fn(|c| values[corner(c as u8)]);
                let inside = f.iter().filter(|v| **v < 0.0).count();
                if inside == 0 || inside == 8 {
                    continue;
                }
                for tet in TETS {
                    let tf = tet.map(|c| f[usize::from(c)]);
                    let mut vertex = |a: usize, b: usize| -> u32 {
                        // Edges run from the corner with fewer bits set to the one with more.
                        let (lo, hi) = if tet[a].count_ones() < tet[b].count_ones() {
                            (a, b)
                        } else {
                            (b, a)
                        };
                        let lo_corner = corner(tet[lo]);
                        let key = (lo_corner as u64) * 8 + u64::from(tet[lo] ^ tet[hi]);
                        *edge_vertex.entry(key).or_insert_with(|| {
                            let (flo, fhi) = (tf[lo], tf[hi]);
                            let t = (flo / (flo - fhi)).clamp(eps, 1.0 - eps);
                            let p = |c: u8| {
                                grid.position(
                                    i + usize::from(c & 1),
                                    j + usize::from((c >> 1) & 1),
                                    k + usize::from((c >> 2) & 1),
                                )
                            };
                            let (plo, phi) = (p(tet[lo]), p(tet[hi]));
                            vertices.push(plo + (phi - plo) * t);
                            (vertices.len() - 1) as u32
                        })
                    };
                    march_tet(tf, &mut vertex, &mut triangles);
                }
            }
        }
    }
    if triangles.is_empty() {
        return Err(GeometryError::Degenerate {
            op: "marching tetrahedra",
            detail: "the distance function is nowhere negative on the grid".into(),
            path: in_memory(),
        });
    }
    if vertices.len() > u32::MAX as usize {
        return Err(GeometryError::InvalidParameter {
            op: "marching tetrahedra",
            name: "cell_m",
            value: cell_m.to_string(),
            expected: "a cell large enough for fewer than 2^32 vertices",
        });
    }
    Ok((vertices, triangles))
}

/// Emits the triangles of one positively oriented tetrahedron with corner values `f`;
/// `vertex(a, b)` gives the vertex on the edge between tetrahedron corners `a` and `b`.
fn march_tet(
    f: [f32; 4],
    vertex: &mut impl FnMut(usize, usize) -> u32,
    triangles: &mut Vec<[u32; 3]>,
) {
    let mask = (0..4).fold(0usize, |m, c| m | (usize::from(f[c] < 0.0) << c));
    match mask.count_ones() {
        1 | 3 => {
            let lone_inside = mask.count_ones() == 1;
            let lone = if lone_inside {
                mask.trailing_zeros()
            } else {
                (!mask & 0xf).trailing_zeros()
            } as usize;
            let [a, b, c, d] = LONE_FIRST[lone];
            let (ab, ac, ad) = (vertex(a, b), vertex(a, c), vertex(a, d));
            // The face (ab, ac, ad) of a positive tetrahedron faces away from `a`.
            triangles.push(if lone_inside {
                [ab, ac, ad]
            } else {
                [ab, ad, ac]
            });
        }
        2 => {
            let Some([a, b, c, d]) = PAIR_FIRST
                .iter()
                .copied()
                .find(|p| mask == (1 << p[0]) | (1 << p[1]))
            else {
                return;
            };
            // {a, b} inside: the quad (ac, ad, bd, bc) faces from {a, b} towards {c, d}.
            let (ac, ad, bd, bc) = (vertex(a, c), vertex(a, d), vertex(b, d), vertex(b, c));
            triangles.push([ac, ad, bd]);
            triangles.push([ac, bd, bc]);
        }
        _ => {}
    }
}

fn make_grid(bounds_min: Vec3, bounds_max: Vec3, cell_m: f32) -> Result<Grid> {
    const OP: &str = "marching tetrahedra";
    if !cell_m.is_finite() || cell_m < MIN_CELL_M {
        return Err(GeometryError::InvalidParameter {
            op: OP,
            name: "cell_m",
            value: cell_m.to_string(),
            expected: "a finite cell size of at least 0.1 mm",
        });
    }
    if !bounds_min.is_finite() || !bounds_max.is_finite() || bounds_min.cmpgt(bounds_max).any() {
        return Err(GeometryError::InvalidParameter {
            op: OP,
            name: "bounds",
            value: format!("{bounds_min:?}..{bounds_max:?}"),
            expected: "a finite box with min <= max",
        });
    }
    let extent = bounds_max - bounds_min;
    // Cells per axis: enough to cover the box, plus two cells of padding on each side.
    let cells = extent.to_array().map(|e| (e / cell_m).ceil() as usize + 4);
    let n = cells.map(|c| c + 1);
    let total = n.iter().try_fold(1usize, |acc, &c| acc.checked_mul(c));
    if total.is_none_or(|t| t > MAX_CORNERS) {
        return Err(GeometryError::InvalidParameter {
            op: OP,
            name: "cell_m",
            value: cell_m.to_string(),
            expected: "a cell large enough for at most 2^28 grid corners over the box",
        });
    }
    let span = Vec3::new(cells[0] as f32, cells[1] as f32, cells[2] as f32) * cell_m;
    let origin = 0.5 * (bounds_min + bounds_max) - 0.5 * span;
    Ok(Grid {
        n,
        origin,
        cell: cell_m,
    })
}

/// The distance at every grid corner (z-slabs in parallel; the values do not depend on the
/// thread count). Corners on the grid's outer faces are forced outside.
fn sample(sdf: &(dyn Fn(Vec3) -> f32 + Sync), grid: &Grid) -> Result<Vec<f32>> {
    let [nx, ny, nz] = grid.n;
    let slab = nx * ny;
    let mut values = vec![0.0f32; slab * nz];
    let threads = std::thread::available_parallelism()
        .map_or(1, |t| t.get())
        .min(nz);
    let per_thread = nz.div_ceil(threads.max(1));
    std::thread::scope(|scope| {
        for (chunk_index, chunk) in values.chunks_mut(slab * per_thread).enumerate() {
            scope.spawn(move || {
                for (local, v) in chunk.iter_mut().enumerate() {
                    let k = chunk_index * per_thread + local / slab;
                    let j = (local % slab) / nx;
                    let i = local % nx;
                    let d = sdf(grid.position(i, j, k));
                    let border = i == 0 || j == 0 || k == 0 || i + 1 == nx || j + 1 == ny;
                    *v = if border || k + 1 == nz { d.max(0.0) } else { d };
                }
            });
        }
    });
    if let Some(first) = values.iter().position(|v| !v.is_finite()) {
        return Err(GeometryError::Degenerate {
            op: "marching tetrahedra",
            detail: format!("the distance function is not finite at grid corner {first}"),
            path: in_memory(),
        });
    }
    Ok(values)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::objects::test_support::{assert_closed_and_oriented, signed_volume};

    #[test]
    fn kuhn_tetrahedra_are_positively_oriented() {
        let p = |c: u8| Vec3::new(f32::from(c & 1), f32::from((c >> 1) & 1), f32::from(c >> 2));
        for tet in TETS {
            let [a, b, c, d] = tet.map(p);
            assert!((b - a).cross(c - a).dot(d - a) > 0.5, "{tet:?}");
        }
        for perm in LONE_FIRST.iter().chain(PAIR_FIRST.iter()) {
            let inversions = (0..4)
                .flat_map(|i| (i + 1..4).map(move |j| (i, j)))
                .filter(|&(i, j)| perm[i] > perm[j])
                .count();
            assert_eq!(inversions % 2, 0, "{perm:?} is odd");
        }
    }

    #[test]
    fn sphere_volume_is_within_three_percent() {
        let r = 0.03;
        let sdf = |p: Vec3| p.length() - r;
        let mesh = mesh_sdf(&sdf, Vec3::splat(-r), Vec3::splat(r), 0.002).unwrap();
        assert_closed_and_oriented(&mesh);
        let exact = 4.0 / 3.0 * std::f32::consts::PI * r * r * r;
        let got = signed_volume(&mesh);
        assert!((got / exact - 1.0).abs() < 0.03, "{got} vs {exact}");
        for v in mesh.vertices() {
            assert!((v.length() - r).abs() < 0.002);
        }
    }

    #[test]
    fn a_shape_cut_by_the_box_is_still_closed() {
        // The box is too small for the sphere: the padding's forced-outside border closes it.
        let sdf = |p: Vec3| p.length() - 0.05;
        let mesh = mesh_sdf(&sdf, Vec3::splat(-0.02), Vec3::splat(0.02), 0.004).unwrap();
        assert_closed_and_oriented(&mesh);
        assert!(signed_volume(&mesh) > 0.0);
    }

    #[test]
    fn bad_inputs_are_errors() {
        let sdf = |p: Vec3| p.length() - 0.01;
        let (lo, hi) = (Vec3::splat(-0.01), Vec3::splat(0.01));
        assert!(mesh_sdf(&sdf, lo, hi, 0.0).is_err());
        assert!(mesh_sdf(&sdf, lo, hi, f32::NAN).is_err());
        assert!(mesh_sdf(&sdf, hi, lo, 0.001).is_err());
        assert!(mesh_sdf(&sdf, lo, Vec3::splat(f32::INFINITY), 0.001).is_err());
        assert!(mesh_sdf(&sdf, lo * 1000.0, hi * 1000.0, 0.0001).is_err());
        assert!(mesh_sdf(&|_| 1.0, lo, hi, 0.002).is_err());
        assert!(mesh_sdf(&|_| f32::NAN, lo, hi, 0.002).is_err());
    }

    #[test]
    fn output_is_deterministic() {
        let sdf = |p: Vec3| (p - Vec3::new(0.001, 0.002, 0.0)).length() - 0.02;
        let (lo, hi) = (Vec3::splat(-0.02), Vec3::splat(0.02));
        let a = mesh_sdf(&sdf, lo, hi, 0.003).unwrap();
        let b = mesh_sdf(&sdf, lo, hi, 0.003).unwrap();
        assert_eq!(a, b);
    }
}
