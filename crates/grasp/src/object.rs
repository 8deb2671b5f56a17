//! The object a grasp is planned on: its mesh in the object frame with everything grasp analysis
//! asks of it again and again (ray casts, mass facts, a length scale for torques).

use std::path::Path;

use mvgrasp_geometry::{MassFacts, RayCaster, TriangleMesh, Vec3};

use crate::error::{GraspError, Result};

/// Density used for mass when a caller gives none: water, about right for household objects.
pub const DEFAULT_DENSITY_KG_M3: f32 = 1000.0;

/// Smallest and largest object extent grasp analysis accepts, metres.
pub const OBJECT_EXTENT_RANGE_M: (f32, f32) = (0.005, 1.0);

/// A rigid object prepared for grasp analysis (frame: the mesh's own).
pub struct GraspObject {
    mesh: TriangleMesh,
    caster: RayCaster,
    mass: MassFacts,
    torque_scale_m: f32,
}

impl GraspObject {
    /// Prepares `mesh` at [`DEFAULT_DENSITY_KG_M3`].
    ///
    /// # Errors
    /// See [`GraspObject::with_density`].
    pub fn new(mesh: TriangleMesh) -> Result<Self> {
        Self::with_density(mesh, DEFAULT_DENSITY_KG_M3)
    }

    /// Prepares `mesh` as a solid of uniform density.
    ///
    /// A mesh that is not watertight is accepted (scans often have holes): its mass facts are
    /// those of its convex hull ([`GraspObject::is_watertight`] says so) and antipodal contacts
    /// are still found by ray casts, from either side of a triangle.
    ///
    /// # Errors
    /// [`GraspError::Object`] when the object is smaller than 5 mm or larger than 1 m across,
    /// encloses no volume, or parry rejects its triangles; each names the mesh's file.
    pub fn with_density(mesh: TriangleMesh, density_kg_m3: f32) -> Result<Self> {
        let extent = mesh.aabb().extents().max_element();
        let (lo, hi) = OBJECT_EXTENT_RANGE_M;
        if !(lo..=hi).contains(&extent) {
            return Err(GraspError::Object {
                detail: format!(
                    "its largest extent is {extent} m; grasp analysis takes objects {lo} m to {hi} m across"
                ),
                path: mesh.origin().to_path_buf(),
            });
        }
        let object_error = |e: mvgrasp_geometry::GeometryError| GraspError::Object {
            detail: e.to_string(),
            path: mesh.origin().to_path_buf(),
        };
        let mass = mesh.mass_facts(density_kg_m3).map_err(object_error)?;
        let caster = RayCaster::new(&mesh).map_err(object_error)?;
        let torque_scale_m = mesh
            .vertices()
            .iter()
            .map(|v| v.distance(mass.center_of_mass))
            .fold(0.0f32, f32::max);
        Ok(Self {
            mesh,
            caster,
            mass,
            torque_scale_m,
        })
    }

    /// The mesh, object frame.
    pub fn mesh(&self) -> &TriangleMesh {
        &self.mesh
    }

    /// Ray casts against the mesh.
    pub fn caster(&self) -> &RayCaster {
        &self.caster
    }

    /// Volume, mass, centre of mass and inertia.
    pub fn mass(&self) -> &MassFacts {
        &self.mass
    }

    /// The centre of mass, object frame.
    pub fn center_of_mass(&self) -> Vec3 {
        self.mass.center_of_mass
    }

    /// The object's length scale for wrenches: the largest distance from the centre of mass to
    /// a vertex, metres. Torques are divided by it so forces and torques weigh alike in
    /// Ferrari-Canny's epsilon (Dex-Net's `torque_scaling`).
    pub fn torque_scale_m(&self) -> f32 {
        self.torque_scale_m
    }

    /// Whether the mesh bounds a solid (else mass facts come from the convex hull).
    pub fn is_watertight(&self) -> bool {
        // Mass facts come from the convex hull exactly when the mesh is not watertight.
        !self.mass.from_convex_hull
    }

    /// The file the mesh came from (empty for generated meshes).
    pub fn origin(&self) -> &Path {
        self.mesh.origin()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use parry3d::shape::Cuboid;

    fn cube(half: f32) -> TriangleMesh {
        let (v, t) = Cuboid::new(Vec3::splat(half)).to_trimesh();
        TriangleMesh::new(v, t).unwrap()
    }

    #[test]
    fn a_box_has_its_mass_and_torque_scale() {
        let object = GraspObject::new(cube(0.025)).unwrap();
        assert!((object.mass().mass_kg - 0.125).abs() < 1e-4);
        assert!((object.torque_scale_m() - 0.025 * 3f32.sqrt()).abs() < 1e-5);
        assert!(object.is_watertight());
    }

    #[test]
    fn tiny_and_huge_objects_are_refused_with_their_size() {
        for half in [0.001, 2.0] {
            let err = GraspObject::new(cube(half)).err().unwrap().to_string();
            assert!(err.contains("largest extent"), "{err}");
        }
    }
}
