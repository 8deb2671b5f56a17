//! An object resting on a table, coloured as the seed paper does: random per-vertex or per-face
//! colours, one colouring for the training views and a novel one for the test views.

use mvgrasp_geometry::{Pose3, RestingPoses, TriangleMesh};
pub use mvgrasp_planner::seed::{name_hash, splitmix};
use mvgrasp_render::{Colors, MeshInput, random_colors};
use serde::Serialize;

use crate::error::Result;
use crate::scene::{SceneData, TABLE_HALF_SIDE_M};

/// How an object's surface is coloured.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ColorMode {
    /// A random colour per vertex, blended across faces.
    PerVertex,
    /// A random colour per triangle.
    PerFace,
}

/// An object placed on the table, with its two colourings.
pub struct PlacedObject {
    /// The mesh, object frame.
    pub mesh: TriangleMesh,
    /// Where it rests: the most probable stable pose that is not marginal (or the most probable
    /// one when all are).
    pub table_from_object: Pose3,
    /// Probability of that pose.
    pub pose_probability: f32,
    /// Whether that pose is marginal (only when the object has no other).
    pub pose_marginal: bool,
    /// Per-vertex or per-face.
    pub color_mode: ColorMode,
    /// Seed of the training-view colours.
    pub train_color_seed: u64,
    /// Seed of the novel test-view colours.
    pub test_color_seed: u64,
}

impl PlacedObject {
    /// Places `mesh` in its likeliest stable pose, colour seeds derived from `seed`.
    ///
    /// # Errors
    /// A geometry error when the mesh has no stable pose (flat meshes).
    pub fn new(mesh: TriangleMesh, seed: u64) -> Result<Self> {
        let (_, &pose) = RestingPoses::of(&mesh)?.get(0)?;
        let color_mode = if splitmix(seed) & 1 == 0 {
            ColorMode::PerVertex
        } else {
            ColorMode::PerFace
        };
        Ok(Self {
            mesh,
            table_from_object: pose.table_from_object,
            pose_probability: pose.probability,
            pose_marginal: pose.marginal,
            color_mode,
            train_color_seed: splitmix(seed ^ 0x7261_696e),
            test_color_seed: splitmix(seed ^ 0x7465_7374),
        })
    }

    /// The colours of one colouring.
    pub fn colors(&self, color_seed: u64) -> Vec<[u8; 3]> {
        let n = match self.color_mode {
            ColorMode::PerVertex => self.mesh.vertices().len(),
            ColorMode::PerFace => self.mesh.triangles().len(),
        };
        random_colors(color_seed, n)
    }

    /// The vertex data of this object in its pose, and the RGB-D datasets' table around it.
    pub fn scene_data(&self) -> SceneData {
        SceneData::of_mesh(&self.mesh, &self.table_from_object, TABLE_HALF_SIDE_M)
    }

    /// The meshes to upload from `data` (this object's [`Self::scene_data`]): the object with
    /// `colors` (per its mode), and the table if asked.
    pub fn inputs<'a>(
        &'a self,
        data: &'a SceneData,
        colors: &'a [[u8; 3]],
        table: bool,
    ) -> Vec<MeshInput<'a>> {
        let colors = match self.color_mode {
            ColorMode::PerVertex => Colors::PerVertex(colors),
            ColorMode::PerFace => Colors::PerFace(colors),
        };
        data.mesh_inputs(self.mesh.triangles(), colors, table)
    }
}
