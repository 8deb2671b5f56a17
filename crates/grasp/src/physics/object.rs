//! [`PhysicsObject`]: an object's collision shape and unit-density mass, built once and shared by
//! every trial on it.

use mvgrasp_geometry::{MassFacts, Pose3, TriangleMesh, Vec3};
use parry3d::mass_properties::MassProperties;
use parry3d::math::Mat3;
use std::sync::Arc;

use parry3d::shape::{SharedShape, TriMesh};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::physics::shell::{self, ShapeError, ShapeParams, SignedMesh};

use crate::error::{GraspError, Result};
use crate::object::{GraspObject, OBJECT_EXTENT_RANGE_M};

/// An object ready for physics trials (frame: the mesh's own): its collision shape and the
/// mesh's own mass facts at a density of 1 kg/m^3 (scaled by each trial's density).
///
/// The collision shape is the mesh's convex hull when no point of the hull stands further than
/// [`ShapeParams::tolerance_m`] outside the mesh; else, by default, the hull when it adds at most
/// 2 % to the volume and VHACD's convex parts otherwise, or with [`ShapeParams::shell`] a shell
/// of convex slabs along the surface ([`crate::physics::shell`]). The approach is checked
/// against the mesh's own surface. Mass, centre of mass and inertia come from the mesh itself,
/// not from the shape.
#[derive(Clone)]
pub struct PhysicsObject {
    shape: SharedShape,
    parts: usize,
    unit_mass: MassFacts,
    /// The mesh's own surface, for the approach: the hand's path is checked against the true
    /// surface, not the collision shape (which may bulge past it).
    surface: Arc<TriMesh>,
}

impl std::fmt::Debug for PhysicsObject {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PhysicsObject")
            .field("parts", &self.parts)
            .field("unit_mass", &self.unit_mass)
            .finish_non_exhaustive()
    }
}

impl PhysicsObject {
    /// Prepares `mesh` (see the type's docs).
    ///
    /// # Errors
    /// [`GraspError::Object`], naming the mesh's file, when the mesh is outside the sizes grasp
    /// analysis takes ([`OBJECT_EXTENT_RANGE_M`]), encloses no volume or has a flat hull;
    /// [`GraspError::InvalidParameter`] for bad `params`.
    pub fn new(mesh: &TriangleMesh, params: &ShapeParams) -> Result<Self> {
        params.validate()?;
        let object_error = |detail: String| GraspError::Object {
            detail,
            path: mesh.origin().to_path_buf(),
        };
        let extent = mesh.aabb().extents().max_element();
        let (lo, hi) = OBJECT_EXTENT_RANGE_M;
        if !(lo..=hi).contains(&extent) {
            return Err(object_error(format!(
                "its largest extent is {extent} m; physics takes objects {lo} m to {hi} m across"
            )));
        }
        // A mesh that is not watertight has its hull's mass facts.
        let unit_mass = mesh
            .mass_facts(1.0)
            .map_err(|e| object_error(e.to_string()))?;
        let hull = mesh
            .convex_hull()
            .map_err(|e| object_error(e.to_string()))?;
        let hull = SharedShape::convex_hull(hull.vertices())
            .ok_or_else(|| object_error("its convex hull is flat".into()))?;
        let signed = SignedMesh::new(mesh)?;
        let mut rng = ChaCha8Rng::seed_from_u64(0x5EED);
        if shell::bulge_within(&hull, &signed, params.tolerance_m, &mut rng) {
            return Ok(Self {
                shape: hull,
                parts: 1,
                unit_mass,
                surface: Arc::new(signed.into_trimesh()),
            });
        }
        let parts = if params.shell {
            shell::shell_parts(mesh, &signed, params)?
        } else {
            vhacd_parts(mesh, &unit_mass, hull)
        };
        let count = parts.len();
        let shape = SharedShape::compound(
            parts
                .into_iter()
                .map(|part| (Pose3::IDENTITY, part))
                .collect(),
        );
        Ok(Self {
            shape,
            parts: count,
            unit_mass,
            surface: Arc::new(signed.into_trimesh()),
        })
    }

    /// Prepares a [`GraspObject`]'s mesh (see [`PhysicsObject::new`]).
    ///
    /// # Errors
    /// See [`PhysicsObject::new`].
    pub fn from_grasp_object(object: &GraspObject, params: &ShapeParams) -> Result<Self> {
        Self::new(object.mesh(), params)
    }

    /// The number of convex parts that collide (1 for a convex object).
    pub fn num_parts(&self) -> usize {
        self.parts
    }

    /// The collision shape, object frame: one convex hull, or a compound of convex parts.
    pub fn shape(&self) -> &SharedShape {
        &self.shape
    }

    /// The mesh's surface, object frame.
    pub(crate) fn surface(&self) -> &Arc<TriMesh> {
        &self.surface
    }

    /// The convex parts with their poses, object frame.
    pub(crate) fn parts(&self) -> Vec<(Pose3, SharedShape)> {
        match self.shape.as_compound() {
            Some(compound) => compound.shapes().to_vec(),
            None => vec![(Pose3::IDENTITY, self.shape.clone())],
        }
    }

    /// The centre of mass, object frame, metres.
    pub fn center_of_mass(&self) -> Vec3 {
        self.unit_mass.center_of_mass
    }

    /// Volume, cubic metres.
    pub fn volume_m3(&self) -> f32 {
        self.unit_mass.volume_m3
    }

    /// Mass properties at `density_kg_m3`, object frame.
    pub(crate) fn mass_properties(&self, density_kg_m3: f32) -> MassProperties {
        let rows = self.unit_mass.inertia_kg_m2.map(Vec3::from_array);
        // The inertia tensor is symmetric: its rows are its columns.
        let inertia = Mat3::from_cols(rows[0], rows[1], rows[2]) * density_kg_m3;
        MassProperties::with_inertia_matrix(
            self.unit_mass.center_of_mass,
            self.unit_mass.mass_kg * density_kg_m3,
            inertia,
        )
    }
}

/// The shapes without the shell: the hull when it encloses at most 2 % more than the mesh (or the
/// decomposition fails), else VHACD's convex parts at default settings.
fn vhacd_parts(mesh: &TriangleMesh, unit_mass: &MassFacts, hull: SharedShape) -> Vec<SharedShape> {
    let hull_volume = hull.mass_properties(1.0).mass();
    if hull_volume <= 1.02 * unit_mass.volume_m3 {
        return vec![hull];
    }
    let parts: Vec<SharedShape> = mesh
        .convex_decomposition(&mvgrasp_geometry::DecompositionParams::default())
        .map(|parts| {
            parts
                .iter()
                .filter_map(|part| SharedShape::convex_hull(part.vertices()))
                .collect()
        })
        .unwrap_or_default();
    if parts.is_empty() { vec![hull] } else { parts }
}

impl PhysicsObject {
    /// How far this object's collision shape strays from `mesh` (the mesh it was made from),
    /// from `samples` points spread over each surface with `seed` (see [`ShapeError`]).
    ///
    /// # Errors
    /// [`GraspError::Object`] when `mesh` cannot be queried.
    pub fn shape_error(
        &self,
        mesh: &TriangleMesh,
        samples: usize,
        seed: u64,
    ) -> Result<ShapeError> {
        shape_error(&self.shape, mesh, samples, seed)
    }
}

/// How far `shape` (one convex polyhedron or a compound of them, the mesh's frame) strays from
/// `mesh`, from `samples` points spread over each surface with `seed` (see [`ShapeError`]): to
/// compare other shapes of the same mesh.
///
/// # Errors
/// [`GraspError::Object`] when `mesh` cannot be queried.
pub fn shape_error(
    shape: &SharedShape,
    mesh: &TriangleMesh,
    samples: usize,
    seed: u64,
) -> Result<ShapeError> {
    let signed = SignedMesh::new(mesh)?;
    Ok(shell::shape_error(shape, mesh, &signed, samples, seed))
}

#[cfg(test)]
mod tests {
    use super::*;
    use parry3d::shape::Cuboid;

    fn box_mesh(half: Vec3) -> TriangleMesh {
        let (v, t) = Cuboid::new(half).to_trimesh();
        TriangleMesh::new(v, t).unwrap()
    }

    #[test]
    fn a_box_is_one_hull_with_its_mass() {
        let object =
            PhysicsObject::new(&box_mesh(Vec3::splat(0.025)), &Default::default()).unwrap();
        assert_eq!(object.num_parts(), 1);
        let props = object.mass_properties(1000.0);
        assert!((props.mass() - 0.125).abs() < 1e-4, "{}", props.mass());
    }

    /// An L of two 10 x 2 cm arms, 2 cm thick: one closed mesh (the L outline extruded).
    fn l_shape() -> TriangleMesh {
        let outline = [
            [-0.05, -0.01],
            [0.05, -0.01],
            [0.05, 0.09],
            [0.03, 0.09],
            [0.03, 0.01],
            [-0.05, 0.01],
        ];
        let n = outline.len() as u32;
        let mut vertices: Vec<Vec3> = outline
            .iter()
            .map(|[x, y]| Vec3::new(*x, *y, -0.01))
            .collect();
        vertices.extend(outline.iter().map(|[x, y]| Vec3::new(*x, *y, 0.01)));
        // The outline's triangles, counter-clockwise from above.
        let cap = [[0, 1, 4], [0, 4, 5], [1, 2, 3], [1, 3, 4]];
        let mut triangles: Vec<[u32; 3]> = Vec::new();
        for [a, b, c] in cap {
            triangles.push([a + n, b + n, c + n]);
            triangles.push([a, c, b]);
        }
        for a in 0..n {
            let b = (a + 1) % n;
            triangles.push([a, b, b + n]);
            triangles.push([a, b + n, a + n]);
        }
        TriangleMesh::new(vertices, triangles).unwrap()
    }

    #[test]
    fn a_box_is_its_own_hull_and_a_hull_bridges_an_l_shapes_corner() {
        let cube = box_mesh(Vec3::splat(0.025));
        let object = PhysicsObject::new(&cube, &Default::default()).unwrap();
        let error = object.shape_error(&cube, 2000, 1).unwrap();
        assert!(
            error.bulge_max_m < 1e-5 && error.gap_p95_m < 1e-5,
            "{error:?}"
        );
        assert_eq!(error.samples, 2000);
        // The L as one hull: the middle of the hull's diagonal face is 4 cm from both bars.
        let l = l_shape();
        let hull = PhysicsObject {
            shape: SharedShape::convex_hull(l.vertices()).unwrap(),
            parts: 1,
            unit_mass: object.unit_mass,
            surface: object.surface.clone(),
        };
        let error = hull.shape_error(&l, 4000, 1).unwrap();
        assert!(
            error.bulge_max_m > 0.035 && error.bulge_max_m < 0.0401 && error.bulge_p95_m > 0.02,
            "{error:?}"
        );
    }

    #[test]
    fn the_shell_follows_a_concave_mesh_and_an_open_one_within_the_tolerance() {
        let l = l_shape();
        let params = ShapeParams {
            shell: true,
            ..ShapeParams::default()
        };
        let object = PhysicsObject::new(&l, &params).unwrap();
        assert!(object.num_parts() >= 2, "{object:?}");
        let error = object.shape_error(&l, 4000, 1).unwrap();
        assert!(
            error.bulge_max_m <= params.tolerance_m && error.gap_p95_m < 1e-4,
            "{error:?}"
        );
        // A box without its top: an open scan.
        let cube = box_mesh(Vec3::splat(0.025));
        let normals = cube.triangle_normals();
        let open: Vec<[u32; 3]> = cube
            .triangles()
            .iter()
            .zip(&normals)
            .filter(|(_, n)| n.z < 0.5)
            .map(|(t, _)| *t)
            .collect();
        let open = TriangleMesh::new(cube.vertices().to_vec(), open).unwrap();
        let object = PhysicsObject::new(&open, &params).unwrap();
        let error = object.shape_error(&open, 4000, 1).unwrap();
        assert!(
            error.bulge_max_m <= params.tolerance_m && error.gap_p95_m < 1e-4,
            "{object:?}: {error:?}"
        );
    }
}
