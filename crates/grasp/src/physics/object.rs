//! [`PhysicsObject`]: an object's collision shape and unit-density mass, built once and shared by
//! every trial on it.

use mvgrasp_geometry::{DecompositionParams, MassFacts, Pose3, TriangleMesh, Vec3};
use parry3d::mass_properties::MassProperties;
use parry3d::math::Mat3;
use parry3d::shape::SharedShape;

use crate::error::{GraspError, Result};
use crate::object::{GraspObject, OBJECT_EXTENT_RANGE_M};

/// A mesh whose convex hull encloses at most this much more volume than the mesh itself is
/// simulated as its hull.
const CONVEX_VOLUME_RATIO: f32 = 1.02;

/// An object ready for physics trials (frame: the mesh's own): convex parts for collisions and
/// the mesh's own mass facts at a density of 1 kg/m^3 (scaled by each trial's density).
///
/// Collision uses a convex decomposition ([`TriangleMesh::convex_decomposition`]); a mesh that
/// is already convex (its hull is within 2 % of its volume), or whose decomposition fails, is
/// simulated as its convex hull. Mass, centre of mass and inertia come from the mesh itself, not
/// from the parts, so they do not depend on how well the parts fit.
#[derive(Clone)]
pub struct PhysicsObject {
    shape: SharedShape,
    parts: usize,
    unit_mass: MassFacts,
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
    /// [`GraspError::InvalidParameter`] for decomposition parameters out of range.
    pub fn new(mesh: &TriangleMesh, decomposition: &DecompositionParams) -> Result<Self> {
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
        let unit_mass = mesh
            .mass_facts(1.0)
            .map_err(|e| object_error(e.to_string()))?;
        let hull = mesh
            .convex_hull()
            .map_err(|e| object_error(e.to_string()))?;
        // A mesh that is not watertight has its hull's mass facts, so it is simulated as its hull
        // too. Known cost: an open scan of a mug loses its cavity. Decomposing such scans instead
        // (VHACD on an open surface) made the YCB mustard and robosuite bottle topple while
        // settling in poses that are stable as meshes, which cost more agreement than it won.
        let convex = hull.signed_volume_m3() <= CONVEX_VOLUME_RATIO * unit_mass.volume_m3;
        let parts = if convex {
            vec![hull]
        } else {
            match mesh.convex_decomposition(decomposition) {
                Ok(parts) => parts,
                Err(mvgrasp_geometry::GeometryError::InvalidParameter {
                    op,
                    name,
                    value,
                    expected,
                }) => {
                    return Err(GraspError::InvalidParameter {
                        op,
                        name,
                        value,
                        expected,
                    });
                }
                Err(_) => vec![hull],
            }
        };
        let mut shapes: Vec<(Pose3, SharedShape)> = parts
            .iter()
            .filter_map(|part| SharedShape::convex_hull(part.vertices()))
            .map(|shape| (Pose3::IDENTITY, shape))
            .collect();
        let count = shapes.len();
        let shape = match shapes.pop() {
            Some((_, only)) if count == 1 => only,
            Some(last) => {
                shapes.push(last);
                SharedShape::compound(shapes)
            }
            None => {
                return Err(object_error(
                    "no convex part of its decomposition has volume".into(),
                ));
            }
        };
        Ok(Self {
            shape,
            parts: count,
            unit_mass,
        })
    }

    /// Prepares a [`GraspObject`]'s mesh (see [`PhysicsObject::new`]).
    ///
    /// # Errors
    /// See [`PhysicsObject::new`].
    pub fn from_grasp_object(
        object: &GraspObject,
        decomposition: &DecompositionParams,
    ) -> Result<Self> {
        Self::new(object.mesh(), decomposition)
    }

    /// The number of convex parts that collide (1 for a convex object).
    pub fn num_parts(&self) -> usize {
        self.parts
    }

    /// The collision shape, object frame: one convex hull, or a compound of convex parts.
    pub fn shape(&self) -> &SharedShape {
        &self.shape
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

    #[test]
    fn an_l_shape_is_decomposed() {
        let a = box_mesh(Vec3::new(0.05, 0.01, 0.01));
        let b = box_mesh(Vec3::new(0.01, 0.05, 0.01))
            .transformed(&Pose3::from_translation(Vec3::new(0.04, 0.04, 0.0)));
        let l = TriangleMesh::concatenate(&[a, b], std::path::Path::new("l")).unwrap();
        let object = PhysicsObject::new(&l, &Default::default()).unwrap();
        assert!(object.num_parts() >= 2, "{object:?}");
    }
}
