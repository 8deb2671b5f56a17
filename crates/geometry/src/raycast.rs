//! Ray casting against a mesh (parry's BVH over its triangles): depth checks for the renderer,
//! contact search for antipodal grasp sampling.

use parry3d::math::Vec3;
use parry3d::query::{Ray, RayCast};
use parry3d::shape::TriMesh;

use crate::error::{GeometryError, Result};
use crate::mesh::TriangleMesh;

/// A mesh prepared for many ray casts (the BVH is built once).
pub struct RayCaster {
    trimesh: TriMesh,
}

/// Where a ray first meets the surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayHit {
    /// Distance along the ray, in units of the ray direction's length (metres for a unit
    /// direction).
    pub time_of_impact: f32,
    /// The surface normal at the hit, facing the ray's origin side of the triangle.
    pub normal: Vec3,
    /// The hit point.
    pub point: Vec3,
}

impl RayCaster {
    /// Builds the BVH of `mesh`.
    ///
    /// # Errors
    /// [`GeometryError::Degenerate`] if parry rejects the triangles.
    pub fn new(mesh: &TriangleMesh) -> Result<Self> {
        let trimesh =
            TriMesh::new(mesh.vertices().to_vec(), mesh.triangles().to_vec()).map_err(|e| {
                GeometryError::Degenerate {
                    op: "ray caster",
                    detail: e.to_string(),
                    path: mesh.origin().to_path_buf(),
                }
            })?;
        Ok(Self { trimesh })
    }

    /// The parry triangle mesh behind the casts (for collision and distance queries).
    pub fn trimesh(&self) -> &TriMesh {
        &self.trimesh
    }

    /// The first surface hit by the ray from `origin` along `direction` within `max_distance`
    /// (in units of `direction`'s length), from either side of a triangle.
    pub fn cast(&self, origin: Vec3, direction: Vec3, max_distance: f32) -> Option<RayHit> {
        let ray = Ray::new(origin, direction);
        self.trimesh
            .cast_local_ray_and_get_normal(&ray, max_distance, false)
            .map(|hit| RayHit {
                time_of_impact: hit.time_of_impact,
                normal: hit.normal,
                point: ray.point_at(hit.time_of_impact),
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use parry3d::shape::Cuboid;

    #[test]
    fn a_ray_hits_a_box_face_at_the_right_distance() {
        let (v, t) = Cuboid::new(Vec3::splat(0.05)).to_trimesh();
        let caster = RayCaster::new(&TriangleMesh::new(v, t).unwrap()).unwrap();
        let hit = caster
            .cast(Vec3::new(0.01, 0.02, 1.0), -Vec3::Z, 10.0)
            .unwrap();
        assert!((hit.time_of_impact - 0.95).abs() < 1e-6);
        assert!((hit.point.z - 0.05).abs() < 1e-6 && hit.normal.z > 0.99);
        assert!(
            caster
                .cast(Vec3::new(0.2, 0.0, 1.0), -Vec3::Z, 10.0)
                .is_none()
        );
        assert!(
            caster
                .cast(Vec3::new(0.0, 0.0, 1.0), -Vec3::Z, 0.5)
                .is_none()
        );
    }
}
