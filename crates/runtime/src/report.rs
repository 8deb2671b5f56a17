//! What the planner knows about an object before it plans: mesh facts, stable poses, and the
//! cameras of the paper's training and test layouts placed around it.

use mvgrasp_geometry::{
    Camera, HemisphereLayout, Intrinsics, StablePose, StablePoseParams, TriangleMesh, Vec3,
    stable_poses,
};
use serde::Serialize;

use crate::error::Result;

/// How to describe an object.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReportParams {
    /// Density for mass and inertia, kg/m^3 (default 1000: water, typical of plastic goods).
    pub density_kg_m3: f32,
    /// Which stable poses to keep.
    pub stable_poses: StablePoseParams,
    /// The camera.
    pub intrinsics: Intrinsics,
    /// Seed for the camera layouts (the test layout uses `seed + 1`, so its views are novel).
    pub views_seed: u64,
}

impl Default for ReportParams {
    fn default() -> Self {
        Self {
            density_kg_m3: 1000.0,
            stable_poses: StablePoseParams::default(),
            intrinsics: Intrinsics::phoxi_s(),
            views_seed: 0,
        }
    }
}

/// One stable pose, as reported.
#[derive(Clone, Debug, Serialize)]
pub struct PoseReport {
    /// Probability of resting in this pose.
    pub probability: f32,
    /// Outward normal of the resting face, object frame.
    pub face_normal: [f32; 3],
    /// Smallest tipping rotation, degrees.
    pub tipping_angle_deg: f32,
    /// Rolls or topples at a touch: no grasps are planned in this pose.
    pub marginal: bool,
    /// Places the object on the table (row-major 4x4).
    #[serde(with = "mvgrasp_geometry::pose_as_matrix")]
    pub table_from_object: mvgrasp_geometry::Pose3,
}

/// Everything [`ObjectReport::describe`] finds.
#[derive(Clone, Debug, Serialize)]
pub struct ObjectReport {
    /// The object's name.
    pub name: String,
    /// Triangles in the mesh.
    pub triangles: usize,
    /// Whether the mesh bounds a solid.
    pub watertight: bool,
    /// Bounding-box size, metres.
    pub extents_m: [f32; 3],
    /// Volume, cubic metres.
    pub volume_m3: f32,
    /// Mass at the report's density, kilograms.
    pub mass_kg: f32,
    /// Centre of mass, object frame, metres.
    pub center_of_mass_m: [f32; 3],
    /// True when the mesh is open and volume and mass are its convex hull's.
    pub mass_from_convex_hull: bool,
    /// Stable poses, most probable first.
    pub stable_poses: Vec<PoseReport>,
    /// The point every view looks at: the centre of mass of the object resting in its likeliest
    /// pose on a table at z = 0, metres.
    pub view_target_m: [f32; 3],
    /// The paper's 20 training views, centred on the object resting in its likeliest pose.
    pub training_views: Vec<Camera>,
    /// The paper's 10 novel test views, the first exactly top-down.
    pub test_views: Vec<Camera>,
}

impl ObjectReport {
    /// Describes `mesh` (named `name`).
    ///
    /// # Errors
    /// Any geometry error: a flat mesh, bad parameters.
    pub fn describe(name: &str, mesh: &TriangleMesh, params: &ReportParams) -> Result<Self> {
        let facts = mesh.mass_facts(params.density_kg_m3)?;
        let poses = stable_poses(mesh, &params.stable_poses)?;
        // Look at the centre of mass of the object resting in its most likely pose.
        let target = poses
            .first()
            .map_or(facts.center_of_mass, |p: &StablePose| {
                p.table_from_object.transform_point(facts.center_of_mass)
            });
        let training_views = HemisphereLayout::paper_training().cameras(
            params.intrinsics,
            target,
            params.views_seed,
        )?;
        let test_views = HemisphereLayout::paper_test().cameras(
            params.intrinsics,
            target,
            params.views_seed.wrapping_add(1),
        )?;
        Ok(Self {
            name: name.to_string(),
            triangles: mesh.triangles().len(),
            watertight: mesh.is_watertight(),
            extents_m: mesh.aabb().extents().to_array(),
            volume_m3: facts.volume_m3,
            mass_kg: facts.mass_kg,
            center_of_mass_m: facts.center_of_mass.to_array(),
            mass_from_convex_hull: facts.from_convex_hull,
            stable_poses: poses
                .iter()
                .map(|p| PoseReport {
                    probability: p.probability,
                    face_normal: p.face_normal.to_array(),
                    tipping_angle_deg: p.tipping_angle_rad.to_degrees(),
                    marginal: p.marginal,
                    table_from_object: p.table_from_object,
                })
                .collect(),
            view_target_m: target.to_array(),
            training_views,
            test_views,
        })
    }

    /// A human-readable summary, a few lines.
    pub fn summary(&self) -> String {
        let [x, y, z] = self.extents_m.map(|e| e * 100.0);
        let mut out = format!(
            "{}: {} triangles, {}, {x:.1} x {y:.1} x {z:.1} cm, {:.1} cm^3, {:.0} g{}\n",
            self.name,
            self.triangles,
            if self.watertight {
                "watertight"
            } else {
                "NOT watertight"
            },
            self.volume_m3 * 1e6,
            self.mass_kg * 1e3,
            if self.mass_from_convex_hull {
                " (of its convex hull)"
            } else {
                ""
            },
        );
        out += &format!("stable poses ({}):\n", self.stable_poses.len());
        out += "   #  probability  tipping  face normal (object frame)\n";
        for (i, p) in self.stable_poses.iter().enumerate() {
            let [nx, ny, nz] = p.face_normal;
            out += &format!(
                "  {i:>2}  {:>11.3}  {:>5.1} deg  ({nx:+.2}, {ny:+.2}, {nz:+.2})  {}\n",
                p.probability,
                p.tipping_angle_deg,
                if p.marginal {
                    "marginal: rolls or topples, not planned"
                } else {
                    "stable"
                },
            );
        }
        let describe = |views: &[Camera]| {
            let elevations: Vec<f32> = views
                .iter()
                .map(|c| (-c.optical_axis().z).clamp(-1.0, 1.0).asin().to_degrees())
                .collect();
            let lo = elevations.iter().copied().fold(f32::INFINITY, f32::min);
            let hi = elevations.iter().copied().fold(f32::NEG_INFINITY, f32::max);
            let target = Vec3::from_array(self.view_target_m);
            let radius = views
                .first()
                .map_or(0.0, |c| (c.position() - target).length());
            format!(
                "{} views, {radius:.2} m away, elevation {lo:.0} to {hi:.0} deg",
                views.len()
            )
        };
        out += &format!("training views: {}\n", describe(&self.training_views));
        out += &format!(
            "test views:     {} (the first is top-down)\n",
            describe(&self.test_views)
        );
        out
    }
}
