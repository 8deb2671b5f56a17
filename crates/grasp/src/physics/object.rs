//! [`PhysicsObject`]: an object's collision shape and unit-density mass, built once and shared by
//! every trial on it.

use mvgrasp_geometry::{DecompositionParams, MassFacts, Pose3, RayCaster, TriangleMesh, Vec3};
use parry3d::mass_properties::MassProperties;
use parry3d::math::Mat3;
use parry3d::query::PointQuery;
use parry3d::shape::{Shape, SharedShape};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

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

/// How far a collision shape's surface strays from the mesh it stands for: distances from
/// points spread evenly over the shape's surface to the mesh's surface, metres.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ShapeError {
    /// Points measured.
    pub samples: usize,
    /// Median distance.
    pub median_m: f32,
    /// 95th percentile.
    pub p95_m: f32,
    /// Largest.
    pub max_m: f32,
}

impl PhysicsObject {
    /// The one-sided distance from this object's collision surface to `mesh`'s surface (see
    /// [`ShapeError`]), from `samples` points drawn evenly over the surface of the union of
    /// its parts (a part's face inside another part is not surface) with `seed`.
    ///
    /// A convex hull's error is how far it bridges the mesh's concavities; a decomposition's
    /// is that of its parts' bulges and gaps.
    ///
    /// # Errors
    /// [`GraspError::Object`] when `mesh` cannot be queried (no triangle).
    pub fn shape_error(
        &self,
        mesh: &TriangleMesh,
        samples: usize,
        seed: u64,
    ) -> Result<ShapeError> {
        let caster = RayCaster::new(mesh).map_err(|e| GraspError::Object {
            detail: e.to_string(),
            path: mesh.origin().to_path_buf(),
        })?;
        let target = caster.trimesh();
        let parts: Vec<(Pose3, &dyn Shape)> = match self.shape.as_compound() {
            Some(compound) => compound
                .shapes()
                .iter()
                .map(|(pose, shape)| (*pose, &**shape as &dyn Shape))
                .collect(),
            None => vec![(Pose3::IDENTITY, &*self.shape as &dyn Shape)],
        };
        // Every face of every part, with its area: the sampling distribution.
        let mut faces: Vec<(usize, [Vec3; 3], f32)> = Vec::new();
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
                    faces.push((index, corners, area));
                }
            }
        }
        let total: f32 = faces.iter().map(|f| f.2).sum();
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut distances = Vec::with_capacity(samples);
        let mut cumulative = Vec::with_capacity(faces.len());
        let mut running = 0.0f32;
        for face in &faces {
            running += face.2;
            cumulative.push(running);
        }
        for _ in 0..samples {
            if faces.is_empty() {
                break;
            }
            let pick = rng.random_range(0.0..total);
            let f = cumulative
                .partition_point(|&c| c < pick)
                .min(faces.len() - 1);
            let (part, [a, b, c], _) = faces[f];
            let (mut u, mut v): (f32, f32) = (rng.random(), rng.random());
            if u + v > 1.0 {
                (u, v) = (1.0 - u, 1.0 - v);
            }
            let point = a + (b - a) * u + (c - a) * v;
            // A point a hair outward of its face, inside another part, is not on the surface.
            let outward = (b - a).cross(c - a).normalize_or_zero() * 1.0e-5;
            let buried = parts.iter().enumerate().any(|(other, (pose, shape))| {
                other != part && shape.contains_point(pose, point + outward)
            });
            if !buried {
                distances.push(target.distance_to_local_point(point, false));
            }
        }
        distances.sort_by(f32::total_cmp);
        let at = |q: f32| {
            distances
                .get(((distances.len() as f32 - 1.0) * q).round() as usize)
                .copied()
                .unwrap_or(0.0)
        };
        Ok(ShapeError {
            samples: distances.len(),
            median_m: at(0.5),
            p95_m: at(0.95),
            max_m: distances.last().copied().unwrap_or(0.0),
        })
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
    fn a_box_is_its_own_hull_and_a_hull_bridges_an_l_shapes_corner() {
        let cube = box_mesh(Vec3::splat(0.025));
        let object = PhysicsObject::new(&cube, &Default::default()).unwrap();
        let error = object.shape_error(&cube, 2000, 1).unwrap();
        assert!(error.max_m < 1e-5, "{error:?}");
        assert!(error.samples == 2000, "{error:?}");
        // An L of two 10 x 2 cm bars simulated as one hull: the middle of the hull's diagonal
        // face is 4 cm from both bars.
        let a = box_mesh(Vec3::new(0.05, 0.01, 0.01));
        let b = box_mesh(Vec3::new(0.01, 0.05, 0.01))
            .transformed(&Pose3::from_translation(Vec3::new(0.04, 0.04, 0.0)));
        let l = TriangleMesh::concatenate(&[a, b], std::path::Path::new("l")).unwrap();
        let hull = PhysicsObject {
            shape: SharedShape::convex_hull(l.vertices()).unwrap(),
            parts: 1,
            unit_mass: object.unit_mass,
        };
        let error = hull.shape_error(&l, 4000, 1).unwrap();
        assert!(
            error.max_m > 0.035 && error.max_m < 0.0401 && error.p95_m > 0.02,
            "{error:?}"
        );
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
