//! The physics trial's object shapes: a mesh's convex hull where that stays on the surface,
//! else a shell of convex slabs that follow it (`shell_parts`); and the measure of how far a
//! shape strays from the mesh ([`ShapeError`]).
//!
//! A convex decomposition of the volume (VHACD) cannot follow a surface closely: its parts come
//! from voxels, so they bulge a voxel past the surface, and an open scan has no volume to
//! voxelise. The shell covers the surface itself: the mesh's triangles are grouped into nearly
//! flat patches, and each patch becomes the convex hull of its vertices and of the same
//! vertices pushed a few millimetres into the object. A patch whose hull would stand more than
//! the tolerance outside the mesh (a concave patch) is split into one slab per triangle, whose
//! outer face is the triangle itself. The shell's outside is the mesh's surface, whatever the
//! mesh is: watertight, open or not manifold.

use std::collections::{HashMap, VecDeque};

use mvgrasp_geometry::{Pose3, TriangleMesh, Vec3};
use parry3d::query::{PointQuery, RayCast};
use parry3d::shape::{Shape, SharedShape, TriMesh, TriMeshFlags};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::error::{GraspError, Result};

/// How the physics trial shapes an object (see [`crate::physics::PhysicsObject::new`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ShapeParams {
    /// Shape a non-convex object as a shell of slabs along its surface (within `tolerance_m`);
    /// when false (the default) as VHACD's convex parts, which bulge a few millimetres past the
    /// surface. Off by default: the fingers pass through the shell (side grasps on a 6.8 cm
    /// can end with the fingers 0 to 3 cm apart, whatever the slabs' thickness): rapier's
    /// contacts with thin convex parts come from parry 0.31's GJK, which misreads them (the
    /// trial's approach backs it with separating axes, `crate::separation`; the contacts
    /// cannot be). See docs/grasp-analysis.md, the physics trial.
    pub shell: bool,
    /// No part may stand further than this outside the mesh, metres.
    pub tolerance_m: f32,
    /// A slab reaches this far into the object (less where the object is thinner), metres.
    pub thickness_m: f32,
    /// A patch spans at most this, metres.
    pub max_patch_m: f32,
    /// A patch's triangles face within this angle of its first one, degrees.
    pub max_patch_turn_deg: f32,
}

impl Default for ShapeParams {
    /// 1 mm tolerance, 4 mm slabs, patches up to 12 cm across turning up to 60 degrees.
    fn default() -> Self {
        Self {
            shell: false,
            tolerance_m: 1.0e-3,
            thickness_m: 4.0e-3,
            max_patch_m: 0.12,
            max_patch_turn_deg: 60.0,
        }
    }
}

impl ShapeParams {
    /// Checks every field.
    ///
    /// # Errors
    /// [`GraspError::InvalidParameter`] naming the first bad field.
    pub fn validate(&self) -> Result<()> {
        for (name, value) in [
            ("tolerance_m", self.tolerance_m),
            ("thickness_m", self.thickness_m),
            ("max_patch_m", self.max_patch_m),
            ("max_patch_turn_deg", self.max_patch_turn_deg),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(GraspError::InvalidParameter {
                    op: "object shape",
                    name,
                    value: value.to_string(),
                    expected: "a finite number > 0",
                });
            }
        }
        Ok(())
    }
}

/// How far a collision shape strays from the mesh it stands for, metres, from points spread
/// evenly over both surfaces.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ShapeError {
    /// Points measured on the collision shape's surface.
    pub samples: usize,
    /// Median of the bulge: how far a point of the collision shape's surface stands outside
    /// the mesh (0 inside it, where no finger can reach).
    pub bulge_median_m: f32,
    /// 95th percentile of the bulge.
    pub bulge_p95_m: f32,
    /// Largest bulge.
    pub bulge_max_m: f32,
    /// 95th percentile of the gap: how far a point of the mesh's surface lies outside the
    /// collision shape (surface the trial's object lacks).
    pub gap_p95_m: f32,
}

/// The mesh with outward normals, for signed distances.
pub(crate) struct SignedMesh {
    trimesh: TriMesh,
    /// -1 when the mesh's triangles wind inwards.
    sign: f32,
    /// The triangles' corners, for winding numbers; empty unless the mesh is closed (no hole,
    /// no misoriented edge): an open mesh's winding number is a half near its holes.
    corners: Vec<[Vec3; 3]>,
}

impl SignedMesh {
    /// The mesh as parry's triangle mesh.
    pub fn into_trimesh(self) -> TriMesh {
        self.trimesh
    }

    pub fn new(mesh: &TriangleMesh) -> Result<Self> {
        let sign = if signed_volume(mesh) < 0.0 { -1.0 } else { 1.0 };
        let trimesh = TriMesh::with_flags(
            mesh.vertices().to_vec(),
            mesh.triangles().to_vec(),
            TriMeshFlags::ORIENTED | TriMeshFlags::MERGE_DUPLICATE_VERTICES,
        )
        .or_else(|_| TriMesh::new(mesh.vertices().to_vec(), mesh.triangles().to_vec()))
        .map_err(|e| GraspError::Object {
            detail: format!("cannot be queried: {e}"),
            path: mesh.origin().to_path_buf(),
        })?;
        let topology = mesh.topology();
        let closed = topology.boundary_edges == 0 && topology.misoriented_edges == 0;
        let corners = if closed {
            mesh.triangles()
                .iter()
                .map(|&t| mesh.triangle_corners(t))
                .collect()
        } else {
            Vec::new()
        };
        Ok(Self {
            trimesh,
            sign,
            corners,
        })
    }

    /// Distance to the surface, positive outside, negative inside. Inside: behind the nearest
    /// surface point's outward pseudo-normal, or, for a point that test puts outside, a winding
    /// number of at least a half (a mesh of overlapping closed pieces, as convex-part models
    /// are, fools the first test inside one piece near another's surface).
    pub fn signed_distance(&self, point: Vec3) -> f32 {
        let projection = self.trimesh.project_local_point(point, false);
        let distance = projection.point.distance(point);
        let inside = projection.is_inside != (self.sign < 0.0);
        if inside || (distance > 1.0e-5 && self.winding_inside(point)) {
            -distance
        } else {
            distance
        }
    }

    /// Whether `point` stands more than `margin` outside the mesh (as [`Self::signed_distance`]
    /// decides, but testing the winding number only where it matters).
    pub fn sticks_out(&self, point: Vec3, margin: f32) -> bool {
        let projection = self.trimesh.project_local_point(point, false);
        projection.point.distance(point) > margin
            && projection.is_inside == (self.sign < 0.0)
            && !self.winding_inside(point)
    }

    /// Whether a closed mesh's winding number at `point` is at least a half (never for an open
    /// mesh).
    fn winding_inside(&self, point: Vec3) -> bool {
        !self.corners.is_empty() && self.winding_number(point) >= 0.5
    }

    /// The mesh's generalised winding number at `point`: the solid angle its triangles subtend,
    /// over 4 pi, signed by their outward side (1 inside a closed mesh, 0 outside).
    fn winding_number(&self, point: Vec3) -> f32 {
        let total: f64 = self
            .corners
            .iter()
            .map(|corners| {
                let [a, b, c] = corners.map(|v| (v - point).as_dvec3());
                let (la, lb, lc) = (a.length(), b.length(), c.length());
                let det = a.dot(b.cross(c));
                let div = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
                2.0 * det.atan2(div)
            })
            .sum();
        (total / (4.0 * std::f64::consts::PI)) as f32 * self.sign
    }
}

fn signed_volume(mesh: &TriangleMesh) -> f32 {
    mesh.triangles()
        .iter()
        .map(|&t| {
            let [a, b, c] = mesh.triangle_corners(t);
            a.dot(b.cross(c)) / 6.0
        })
        .sum()
}

/// The convex parts of the shell of `mesh` (see the module docs), object frame.
///
/// # Errors
/// [`GraspError::InvalidParameter`] for bad `params`; [`GraspError::Object`] when the mesh has
/// no triangle with area.
pub(crate) fn shell_parts(
    mesh: &TriangleMesh,
    signed: &SignedMesh,
    params: &ShapeParams,
) -> Result<Vec<SharedShape>> {
    params.validate()?;
    let vertices = mesh.vertices();
    let triangles = mesh.triangles();
    let flip = signed.sign;
    let normals: Vec<Vec3> = triangles
        .iter()
        .map(|&t| {
            let [a, b, c] = mesh.triangle_corners(t);
            (b - a).cross(c - a).normalize_or_zero() * flip
        })
        .collect();
    // Triangles sharing an edge (by vertex position, so split vertices still join).
    let key = |v: u32| vertices[v as usize].to_array().map(f32::to_bits);
    let mut by_edge: HashMap<([u32; 3], [u32; 3]), Vec<usize>> = HashMap::new();
    for (i, t) in triangles.iter().enumerate() {
        if normals[i] == Vec3::ZERO {
            continue;
        }
        for k in 0..3 {
            let (a, b) = (key(t[k]), key(t[(k + 1) % 3]));
            by_edge
                .entry(if a < b { (a, b) } else { (b, a) })
                .or_default()
                .push(i);
        }
    }
    let mut neighbours: Vec<Vec<usize>> = vec![Vec::new(); triangles.len()];
    for tris in by_edge.values() {
        for &a in tris {
            for &b in tris {
                if a != b {
                    neighbours[a].push(b);
                }
            }
        }
    }
    for list in &mut neighbours {
        // By index, whatever order the edge map gave: the patches must not depend on it.
        list.sort_unstable();
        list.dedup();
    }
    let shell = Shell {
        mesh,
        signed,
        params,
        normals,
        neighbours,
    };
    let all: Vec<usize> = (0..triangles.len())
        .filter(|&t| shell.normals[t] != Vec3::ZERO)
        .collect();
    let mut parts = Vec::new();
    let mut rng = ChaCha8Rng::seed_from_u64(0x5EED);
    shell.cover(
        &all,
        params.max_patch_m,
        params.max_patch_turn_deg,
        &mut parts,
        &mut rng,
    );
    if parts.is_empty() {
        return Err(GraspError::Object {
            detail: "no triangle with area".into(),
            path: mesh.origin().to_path_buf(),
        });
    }
    Ok(parts)
}

/// A patch narrower than this that still bulges is split into its triangles' slabs, metres.
const MIN_PATCH_M: f32 = 0.004;

/// What covering a mesh with slabs needs.
struct Shell<'a> {
    mesh: &'a TriangleMesh,
    signed: &'a SignedMesh,
    params: &'a ShapeParams,
    /// Outward unit normals (zero for triangles without area).
    normals: Vec<Vec3>,
    /// Triangles sharing an edge, by index.
    neighbours: Vec<Vec<usize>>,
}

impl Shell<'_> {
    /// Covers `triangles` with slabs: grown into patches of at most `span_m` across whose
    /// triangles face within `turn_deg` of their first one; a patch whose slab bulges is covered
    /// again with half the span and turn, and below [`MIN_PATCH_M`] triangle by triangle.
    fn cover(
        &self,
        triangles: &[usize],
        span_m: f32,
        turn_deg: f32,
        parts: &mut Vec<SharedShape>,
        rng: &mut ChaCha8Rng,
    ) {
        let cos_turn = turn_deg.to_radians().cos();
        let mut member: HashMap<usize, bool> = triangles.iter().map(|&t| (t, false)).collect();
        let corners = |t: usize| self.mesh.triangle_corners(self.mesh.triangles()[t]);
        for &seed in triangles {
            if member.get(&seed) != Some(&false) {
                continue;
            }
            let seed_normal = self.normals[seed];
            let [a, b, c] = corners(seed);
            let centre = (a + b + c) / 3.0;
            let mut patch = vec![seed];
            member.insert(seed, true);
            let mut queue = VecDeque::from([seed]);
            while let Some(t) = queue.pop_front() {
                for &n in &self.neighbours[t] {
                    if member.get(&n) != Some(&false)
                        || self.normals[n].dot(seed_normal) < cos_turn
                        || corners(n).iter().any(|v| v.distance(centre) > span_m / 2.0)
                    {
                        continue;
                    }
                    member.insert(n, true);
                    patch.push(n);
                    queue.push_back(n);
                }
            }
            // Pushed in along the patch's mean normal (a scan's triangles' own normals are noisy).
            let mean = patch
                .iter()
                .map(|&t| {
                    let [a, b, c] = corners(t);
                    (b - a).cross(c - a) * self.signed.sign
                })
                .sum::<Vec3>()
                .normalize_or(seed_normal);
            let whole = slab(self.mesh, self.signed, &patch, mean, self.params)
                .filter(|s| bulge_within(s, self.signed, self.params.tolerance_m, rng));
            match whole {
                Some(shape) => parts.push(shape),
                None if patch.len() > 1 && span_m / 2.0 >= MIN_PATCH_M => {
                    self.cover(&patch, span_m / 2.0, turn_deg / 2.0, parts, rng);
                }
                None => parts.extend(patch.iter().filter_map(|&t| {
                    triangle_slab(self.mesh, self.signed, t, self.normals[t], self.params)
                })),
            }
        }
    }
}

/// One triangle's slab ([`slab`]), made thinner (down to an eighth, and [`MIN_SLAB_M`]) until none of its inner
/// corners stands outside the mesh by more than the tolerance: at a concave crease or a sharp
/// edge a full-depth slab can come out through a neighbouring face.
fn triangle_slab(
    mesh: &TriangleMesh,
    signed: &SignedMesh,
    triangle: usize,
    normal: Vec3,
    params: &ShapeParams,
) -> Option<SharedShape> {
    let corners = mesh.triangle_corners(mesh.triangles()[triangle]);
    let mut depth = slab_depth(signed, &corners, normal, params.thickness_m);
    for _ in 0..3 {
        let inside = corners
            .iter()
            .all(|c| !signed.sticks_out(*c - normal * depth, params.tolerance_m));
        if inside || depth <= MIN_SLAB_M {
            break;
        }
        depth = (depth / 2.0).max(MIN_SLAB_M);
    }
    hull_with_inner(corners.to_vec(), normal, depth)
}

/// The convex hull of `patch`'s vertices and of the same vertices pushed along `-normal` into
/// the object ([`slab_depth`]).
fn slab(
    mesh: &TriangleMesh,
    signed: &SignedMesh,
    patch: &[usize],
    normal: Vec3,
    params: &ShapeParams,
) -> Option<SharedShape> {
    let mut points: Vec<Vec3> = patch
        .iter()
        .flat_map(|&t| mesh.triangle_corners(mesh.triangles()[t]))
        .collect();
    points.sort_by(|a, b| {
        a.to_array()
            .partial_cmp(&b.to_array())
            .unwrap_or(std::cmp::Ordering::Equal)
    });
    points.dedup();
    let depth = slab_depth(signed, &points, normal, params.thickness_m);
    hull_with_inner(points, normal, depth)
}

/// How deep a slab under `points` goes: `thickness_m`, or under half the object's depth where a
/// ray from one of them into the object meets its far side sooner; never under [`MIN_SLAB_M`].
/// A ray that meets the surface within [`MIN_SLAB_M`] has grazed a neighbouring face at an
/// edge, not crossed the object, and is not counted (the bulge check catches a slab that comes
/// out).
fn slab_depth(signed: &SignedMesh, points: &[Vec3], normal: Vec3, thickness_m: f32) -> f32 {
    let mut depth = thickness_m;
    for p in points {
        let ray = parry3d::query::Ray::new(*p - normal * 1.0e-5, -normal);
        if let Some(hit) = signed
            .trimesh
            .cast_local_ray(&ray, 2.0 * thickness_m, false)
            .filter(|&hit| hit >= MIN_SLAB_M)
        {
            depth = depth.min(0.45 * hit);
        }
    }
    depth.max(MIN_SLAB_M)
}

/// The thinnest slab, metres: parry's distance and contact queries fail on nearly flat convex
/// polyhedra (a 0.05 mm slab along a can's rim read as touching a finger 4 mm away).
const MIN_SLAB_M: f32 = 1.0e-3;

/// The convex hull of `points` and of the same points pushed `depth` along `-normal`.
fn hull_with_inner(mut points: Vec<Vec3>, normal: Vec3, depth: f32) -> Option<SharedShape> {
    let inner: Vec<Vec3> = points.iter().map(|p| *p - normal * depth).collect();
    points.extend(inner);
    SharedShape::convex_hull(&points)
}

/// Whether no point of `shape`'s surface (its corners, and samples about one per 4 mm^2, at
/// least 32) stands further than `tolerance_m` outside the mesh.
pub(crate) fn bulge_within(
    shape: &SharedShape,
    signed: &SignedMesh,
    tolerance_m: f32,
    rng: &mut ChaCha8Rng,
) -> bool {
    // Every corner (a thin spike has little area for the samples to land on), then the faces.
    let corners_inside = shape.as_convex_polyhedron().is_none_or(|hull| {
        hull.points()
            .iter()
            .all(|p| !signed.sticks_out(*p, tolerance_m))
    });
    if !corners_inside {
        return false;
    }
    let faces = faces_of(&[(Pose3::IDENTITY, &**shape)]);
    let area: f32 = faces.iter().map(|f| f.area).sum();
    let count = ((area / 4.0e-6) as usize).clamp(32, 4096);
    sample_faces(&faces, count, rng).all(|(_, p)| !signed.sticks_out(p, tolerance_m))
}

/// A face of a convex part, in the object frame.
pub(crate) struct Face {
    pub part: usize,
    pub corners: [Vec3; 3],
    pub area: f32,
}

/// The faces of every part (convex polyhedra; other shapes are skipped).
pub(crate) fn faces_of(parts: &[(Pose3, &dyn Shape)]) -> Vec<Face> {
    let mut faces = Vec::new();
    for (index, (pose, shape)) in parts.iter().enumerate() {
        let Some(hull) = shape.as_convex_polyhedron() else {
            continue;
        };
        let (vertices, triangles) = hull.to_trimesh();
        for t in triangles {
            let corners = t.map(|i| pose.transform_point(vertices[i as usize]));
            let area = 0.5
                * (corners[1] - corners[0])
                    .cross(corners[2] - corners[0])
                    .length();
            if area > 0.0 {
                faces.push(Face {
                    part: index,
                    corners,
                    area,
                });
            }
        }
    }
    faces
}

/// `count` points spread evenly by area over `faces`, each with its face.
pub(crate) fn sample_faces<'a>(
    faces: &'a [Face],
    count: usize,
    rng: &'a mut ChaCha8Rng,
) -> impl Iterator<Item = (&'a Face, Vec3)> + 'a {
    let mut cumulative = Vec::with_capacity(faces.len());
    let mut total = 0.0f32;
    for face in faces {
        total += face.area;
        cumulative.push(total);
    }
    (0..if faces.is_empty() { 0 } else { count }).map(move |_| {
        let pick = rng.random_range(0.0..total);
        let face = &faces[cumulative
            .partition_point(|&c| c < pick)
            .min(faces.len() - 1)];
        let (mut u, mut v): (f32, f32) = (rng.random(), rng.random());
        if u + v > 1.0 {
            (u, v) = (1.0 - u, 1.0 - v);
        }
        let [a, b, c] = face.corners;
        (face, a + (b - a) * u + (c - a) * v)
    })
}

/// The bulge and gap of `shape` (one convex part or a compound of them) against `mesh` (see
/// [`ShapeError`]).
pub(crate) fn shape_error(
    shape: &SharedShape,
    mesh: &TriangleMesh,
    signed: &SignedMesh,
    samples: usize,
    seed: u64,
) -> ShapeError {
    let parts: Vec<(Pose3, &dyn Shape)> = match shape.as_compound() {
        Some(compound) => compound
            .shapes()
            .iter()
            .map(|(pose, part)| (*pose, &**part as &dyn Shape))
            .collect(),
        None => vec![(Pose3::IDENTITY, &**shape as &dyn Shape)],
    };
    let parts = &parts[..];
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let faces = faces_of(parts);
    let mut bulges: Vec<f32> = Vec::with_capacity(samples);
    for (face, point) in sample_faces(&faces, samples, &mut rng) {
        // A point a hair outward of its face, inside another part, is not on the surface.
        let [a, b, c] = face.corners;
        let outward = (b - a).cross(c - a).normalize_or_zero() * 1.0e-5;
        let probe = point + outward;
        let buried = match shape.as_compound() {
            // The compound's tree finds the parts near the point.
            Some(compound) => compound
                .shapes()
                .iter()
                .enumerate()
                .filter(|(other, _)| *other != face.part)
                .any(|(_, (pose, part))| {
                    part.compute_aabb(pose).contains_local_point(probe)
                        && part.contains_point(pose, probe)
                }),
            None => false,
        };
        if !buried {
            bulges.push(signed.signed_distance(point).max(0.0));
        }
    }
    let mesh_faces: Vec<Face> = mesh
        .triangles()
        .iter()
        .map(|&t| {
            let corners = mesh.triangle_corners(t);
            let area = 0.5
                * (corners[1] - corners[0])
                    .cross(corners[2] - corners[0])
                    .length();
            Face {
                part: 0,
                corners,
                area,
            }
        })
        .filter(|f| f.area > 0.0)
        .collect();
    let mut gaps: Vec<f32> = sample_faces(&mesh_faces, samples, &mut rng)
        .map(|(_, p)| shape.distance_to_point(&Pose3::IDENTITY, p, true))
        .collect();
    bulges.sort_by(f32::total_cmp);
    gaps.sort_by(f32::total_cmp);
    ShapeError {
        samples: bulges.len(),
        bulge_median_m: quantile(&bulges, 0.5),
        bulge_p95_m: quantile(&bulges, 0.95),
        bulge_max_m: bulges.last().copied().unwrap_or(0.0),
        gap_p95_m: quantile(&gaps, 0.95),
    }
}

fn quantile(sorted: &[f32], q: f32) -> f32 {
    sorted
        .get(((sorted.len() as f32 - 1.0) * q).round() as usize)
        .copied()
        .unwrap_or(0.0)
}
