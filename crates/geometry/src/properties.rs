//! Mesh facts a grasp planner needs: topology (watertightness), bounding box, volume, centre of
//! mass and inertia, convex hull, and a convex decomposition for physics.

use std::collections::HashMap;

use parry3d::bounding_volume::Aabb;
use parry3d::mass_properties::MassProperties;
use parry3d::math::Vec3;
use parry3d::transformation::try_convex_hull;
use parry3d::transformation::vhacd::{VHACD, VHACDParameters};

use crate::error::{GeometryError, Result};
use crate::mesh::TriangleMesh;

/// How the edges of a mesh are shared, after welding vertices at identical positions.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Topology {
    /// Edges used by exactly one triangle (holes).
    pub boundary_edges: usize,
    /// Edges used by three or more triangles.
    pub non_manifold_edges: usize,
    /// Edges used twice in the same direction (neighbouring triangles wound inconsistently).
    pub misoriented_edges: usize,
}

impl Topology {
    /// A closed, edge-manifold, consistently wound surface: it bounds a solid.
    pub fn is_watertight(&self) -> bool {
        self.boundary_edges == 0 && self.non_manifold_edges == 0 && self.misoriented_edges == 0
    }
}

/// Volume, mass, centre of mass and inertia of a mesh as a solid of uniform density.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MassFacts {
    /// Volume, cubic metres.
    pub volume_m3: f32,
    /// Mass at the given density, kilograms.
    pub mass_kg: f32,
    /// Centre of mass in the mesh frame, metres.
    pub center_of_mass: Vec3,
    /// Inertia tensor about the centre of mass, mesh-frame axes, kg m^2 (rows).
    pub inertia_kg_m2: [[f32; 3]; 3],
    /// True when the mesh is not watertight and these figures are those of its convex hull.
    pub from_convex_hull: bool,
}

/// Bounds on the cost of a convex decomposition (parry's VHACD).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DecompositionParams {
    /// Voxels along the longest side (cost grows with its cube); 16 to 128.
    pub resolution: u32,
    /// The most convex parts returned; 1 to 64.
    pub max_parts: u32,
    /// The concavity below which a part is not split further, metres-like (VHACD's unit).
    pub concavity: f32,
}

impl Default for DecompositionParams {
    fn default() -> Self {
        Self {
            resolution: 48,
            max_parts: 16,
            concavity: 0.01,
        }
    }
}

impl TriangleMesh {
    /// The axis-aligned bounding box, metres.
    pub fn aabb(&self) -> Aabb {
        let (mins, maxs) = self.vertices().iter().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), v| (lo.min(*v), hi.max(*v)),
        );
        Aabb::new(mins, maxs)
    }

    /// Counts boundary, non-manifold and misoriented edges (vertices at identical positions are
    /// welded first, since OBJ files often duplicate them along texture seams).
    pub fn topology(&self) -> Topology {
        let mut ids: HashMap<[u32; 3], u32> = HashMap::new();
        let welded: Vec<u32> = self
            .vertices()
            .iter()
            .map(|v| {
                let next = ids.len() as u32;
                *ids.entry(v.to_array().map(f32::to_bits)).or_insert(next)
            })
            .collect();
        // Per undirected edge: (uses, uses in the low->high direction).
        let mut edges: HashMap<(u32, u32), (u32, u32)> = HashMap::new();
        for t in self.triangles() {
            let w = t.map(|i| welded[i as usize]);
            for (a, b) in [(w[0], w[1]), (w[1], w[2]), (w[2], w[0])] {
                let entry = edges.entry((a.min(b), a.max(b))).or_insert((0, 0));
                entry.0 += 1;
                entry.1 += u32::from(a < b);
            }
        }
        let mut topology = Topology::default();
        for (uses, forward) in edges.into_values() {
            match uses {
                1 => topology.boundary_edges += 1,
                2 if forward != 1 => topology.misoriented_edges += 1,
                2 => {}
                _ => topology.non_manifold_edges += 1,
            }
        }
        topology
    }

    /// Whether the mesh bounds a solid (see [`Topology::is_watertight`]).
    pub fn is_watertight(&self) -> bool {
        self.topology().is_watertight()
    }

    /// Volume, mass, centre of mass and inertia at `density_kg_m3`. A mesh that is not
    /// watertight has no well-defined inside: its convex hull's figures are returned, flagged.
    ///
    /// # Errors
    /// [`GeometryError::InvalidParameter`] for a density that is not finite and positive;
    /// [`GeometryError::Degenerate`] for a flat mesh with no volume.
    pub fn mass_facts(&self, density_kg_m3: f32) -> Result<MassFacts> {
        if !(density_kg_m3.is_finite() && density_kg_m3 > 0.0) {
            return Err(GeometryError::InvalidParameter {
                op: "mass properties",
                name: "density_kg_m3",
                value: density_kg_m3.to_string(),
                expected: "a finite number > 0",
            });
        }
        let watertight = self.is_watertight();
        let hull;
        let solid = if watertight {
            self
        } else {
            hull = self.convex_hull()?;
            &hull
        };
        let props =
            MassProperties::from_trimesh(density_kg_m3, solid.vertices(), solid.triangles());
        let mass_kg = props.mass();
        if !(mass_kg.is_finite() && mass_kg > 0.0) {
            return Err(GeometryError::Degenerate {
                op: "mass properties",
                detail: "the mesh encloses no volume".into(),
                path: self.origin().to_path_buf(),
            });
        }
        let inertia = props.reconstruct_inertia_matrix();
        Ok(MassFacts {
            volume_m3: mass_kg / density_kg_m3,
            mass_kg,
            center_of_mass: props.local_com,
            inertia_kg_m2: [0, 1, 2].map(|r| inertia.row(r).to_array()),
            from_convex_hull: !watertight,
        })
    }

    /// The convex hull, as a mesh with outward normals.
    ///
    /// # Errors
    /// [`GeometryError::Degenerate`] when the vertices are flat or collinear.
    pub fn convex_hull(&self) -> Result<TriangleMesh> {
        let degenerate = |detail: String| GeometryError::Degenerate {
            op: "convex hull",
            detail,
            path: self.origin().to_path_buf(),
        };
        let (vertices, triangles) =
            try_convex_hull(self.vertices()).map_err(|e| degenerate(e.to_string()))?;
        let hull = TriangleMesh::from_parts(vertices, triangles, self.origin())
            .map_err(|e| degenerate(format!("the hull is flat ({e})")))?;
        let extent = hull.aabb().extents().max_element();
        if hull.signed_volume_m3() <= 1e-6 * extent.powi(3) {
            return Err(degenerate(
                "the points are flat: their hull has no volume".into(),
            ));
        }
        Ok(hull)
    }

    /// The signed volume enclosed by the triangles (divergence theorem), cubic metres: positive
    /// for a closed mesh with outward normals, negative for one turned inside out.
    pub fn signed_volume_m3(&self) -> f32 {
        let sum: f64 = self
            .triangles()
            .iter()
            .map(|t| {
                let [a, b, c] = self.triangle_corners(*t).map(|v| v.as_dvec3());
                a.dot(b.cross(c))
            })
            .sum();
        (sum / 6.0) as f32
    }

    /// Approximates the mesh by at most `params.max_parts` convex parts (parry's VHACD on a
    /// voxel grid of `params.resolution` along the longest side, so cost is bounded).
    ///
    /// # Errors
    /// [`GeometryError::InvalidParameter`] for parameters out of range;
    /// [`GeometryError::Degenerate`] when no part has volume.
    pub fn convex_decomposition(&self, params: &DecompositionParams) -> Result<Vec<TriangleMesh>> {
        let invalid = |name, value: String, expected| GeometryError::InvalidParameter {
            op: "convex decomposition",
            name,
            value,
            expected,
        };
        if !(16..=128).contains(&params.resolution) {
            return Err(invalid(
                "resolution",
                params.resolution.to_string(),
                "16 to 128",
            ));
        }
        if !(1..=64).contains(&params.max_parts) {
            return Err(invalid(
                "max_parts",
                params.max_parts.to_string(),
                "1 to 64",
            ));
        }
        if !(params.concavity.is_finite() && params.concavity > 0.0) {
            return Err(invalid(
                "concavity",
                params.concavity.to_string(),
                "a finite number > 0",
            ));
        }
        let vhacd_params = VHACDParameters {
            resolution: params.resolution,
            max_convex_hulls: params.max_parts,
            concavity: params.concavity,
            ..VHACDParameters::default()
        };
        let decomposition =
            VHACD::decompose(&vhacd_params, self.vertices(), self.triangles(), false);
        let parts: Vec<TriangleMesh> = decomposition
            .compute_convex_hulls(1)
            .into_iter()
            .filter_map(|(vertices, triangles)| {
                TriangleMesh::from_parts(vertices, triangles, self.origin()).ok()
            })
            .collect();
        if parts.is_empty() {
            return Err(GeometryError::Degenerate {
                op: "convex decomposition",
                detail: "no convex part has volume".into(),
                path: self.origin().to_path_buf(),
            });
        }
        Ok(parts)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use parry3d::bounding_volume::BoundingVolume;
    use parry3d::shape::Cuboid;

    fn box_mesh(half: Vec3) -> TriangleMesh {
        let (v, t) = Cuboid::new(half).to_trimesh();
        TriangleMesh::new(v, t).unwrap()
    }

    #[test]
    fn a_box_is_watertight_with_exact_volume_and_inertia() {
        let mesh = box_mesh(Vec3::new(0.05, 0.02, 0.01));
        assert!(mesh.is_watertight());
        let facts = mesh.mass_facts(1000.0).unwrap();
        let volume = 0.1 * 0.04 * 0.02;
        assert!(
            (facts.volume_m3 - volume).abs() < 1e-9,
            "{}",
            facts.volume_m3
        );
        assert!(facts.center_of_mass.length() < 1e-6);
        // Solid box: I_xx = m (b^2 + c^2) / 12.
        let ixx = facts.mass_kg * (0.04f32.powi(2) + 0.02f32.powi(2)) / 12.0;
        assert!((facts.inertia_kg_m2[0][0] - ixx).abs() < 1e-3 * ixx);
        assert!(!facts.from_convex_hull);
    }

    #[test]
    fn a_box_with_a_missing_face_is_not_watertight_and_uses_its_hull() {
        let full = box_mesh(Vec3::splat(0.03));
        let open =
            TriangleMesh::new(full.vertices().to_vec(), full.triangles()[2..].to_vec()).unwrap();
        let topology = open.topology();
        assert_eq!(topology.boundary_edges, 4);
        assert!(!topology.is_watertight());
        let facts = open.mass_facts(1000.0).unwrap();
        assert!(facts.from_convex_hull);
        assert!((facts.volume_m3 - 0.06f32.powi(3)).abs() < 1e-8);
    }

    #[test]
    fn flipped_triangle_is_misoriented() {
        let full = box_mesh(Vec3::splat(0.03));
        let mut triangles = full.triangles().to_vec();
        triangles[0].swap(1, 2);
        let mesh = TriangleMesh::new(full.vertices().to_vec(), triangles).unwrap();
        assert_eq!(mesh.topology().misoriented_edges, 3);
    }

    #[test]
    fn bad_density_and_flat_hull_are_errors() {
        let mesh = box_mesh(Vec3::splat(0.03));
        assert!(matches!(
            mesh.mass_facts(-1.0),
            Err(GeometryError::InvalidParameter { .. })
        ));
        let flat = TriangleMesh::new(
            vec![
                Vec3::ZERO,
                Vec3::X * 0.05,
                Vec3::Y * 0.05,
                Vec3::new(0.05, 0.05, 0.0),
            ],
            vec![[0, 1, 2], [1, 3, 2]],
        )
        .unwrap();
        assert!(matches!(
            flat.convex_hull(),
            Err(GeometryError::Degenerate { .. })
        ));
        assert!(matches!(
            flat.mass_facts(1000.0),
            Err(GeometryError::Degenerate { .. })
        ));
    }

    #[test]
    fn decomposition_of_an_l_shape_gives_parts_within_its_bounds() {
        let a = box_mesh(Vec3::new(0.05, 0.01, 0.01));
        let b = box_mesh(Vec3::new(0.01, 0.05, 0.01)).transformed(
            &parry3d::math::Pose3::from_translation(Vec3::new(0.04, 0.04, 0.0)),
        );
        let l = TriangleMesh::concatenate(&[a, b], std::path::Path::new("l")).unwrap();
        let parts = l
            .convex_decomposition(&DecompositionParams::default())
            .unwrap();
        assert!(
            parts.len() >= 2,
            "an L needs at least two convex parts, got {}",
            parts.len()
        );
        let bounds = l.aabb().loosened(0.005);
        for part in &parts {
            assert!(bounds.contains(&part.aabb()));
        }
        let bad = DecompositionParams {
            resolution: 4096,
            ..Default::default()
        };
        assert!(matches!(
            l.convex_decomposition(&bad),
            Err(GeometryError::InvalidParameter { .. })
        ));
    }
}
