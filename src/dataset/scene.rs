//! An object resting on a table, coloured as the seed paper does: random per-vertex or per-face
//! colours, one colouring for the training views and a novel one for the test views.

use mvgrasp_geometry::{Pose3, RestingPoses, TriangleMesh};
pub use mvgrasp_planner::seed::{name_hash, splitmix};
use mvgrasp_render::{Colors, IDENTITY, Material, MeshInput, Sides, random_colors};
use serde::Serialize;

use crate::convert::{row_major, sides_of};
use crate::error::Result;

/// Mask value of the object.
pub const OBJECT_ID: u8 = 1;
/// Mask value of the table.
pub const TABLE_ID: u8 = 2;
/// The table's colour.
const TABLE_RGB: [u8; 3] = [150, 150, 150];
/// Half the side of the datasets' table square, metres.
pub const TABLE_HALF_SIDE_M: f32 = 0.4;

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
}

/// Owned vertex data for the renderer: an object's mesh in its pose, and a table square.
pub struct SceneData {
    positions: Vec<[f32; 3]>,
    world_from_object: [[f32; 4]; 4],
    table_positions: [[f32; 3]; 4],
    sides: Sides,
}

/// The table's two triangles.
const TABLE_TRIANGLES: [[u32; 3]; 2] = [[0, 1, 2], [0, 2, 3]];

impl SceneData {
    /// The placed object's vertices and pose, and a table square around it at z = 0.
    pub fn new(object: &PlacedObject) -> Self {
        Self::of_mesh(&object.mesh, &object.table_from_object, TABLE_HALF_SIDE_M)
    }

    /// `mesh` at `table_from_object` and a table square `2 * table_half_side_m` wide at z = 0.
    pub fn of_mesh(mesh: &TriangleMesh, table_from_object: &Pose3, table_half_side_m: f32) -> Self {
        let h = table_half_side_m;
        Self {
            positions: mesh.vertices().iter().map(|v| v.to_array()).collect(),
            world_from_object: row_major(table_from_object),
            sides: sides_of(mesh),
            table_positions: [[-h, -h, 0.0], [h, -h, 0.0], [h, h, 0.0], [-h, h, 0.0]],
        }
    }

    /// The meshes to upload: the placed object with `colors` (per its mode), and the table if
    /// asked.
    pub fn inputs<'a>(
        &'a self,
        object: &'a PlacedObject,
        colors: &'a [[u8; 3]],
        table: bool,
    ) -> Vec<MeshInput<'a>> {
        let colors = match object.color_mode {
            ColorMode::PerVertex => Colors::PerVertex(colors),
            ColorMode::PerFace => Colors::PerFace(colors),
        };
        self.mesh_inputs(object.mesh.triangles(), colors, table)
    }

    /// The meshes to upload: the object (`triangles` of the mesh this was made from) with
    /// `colors`, and the table if asked.
    pub fn mesh_inputs<'a>(
        &'a self,
        triangles: &'a [[u32; 3]],
        colors: Colors<'a>,
        table: bool,
    ) -> Vec<MeshInput<'a>> {
        let mut inputs = vec![MeshInput {
            positions: &self.positions,
            indices: triangles,
            sides: self.sides,
            colors,
            world_from_mesh: self.world_from_object,
            instance_id: OBJECT_ID,
            material: Material::MATTE,
        }];
        if table {
            inputs.push(MeshInput {
                positions: &self.table_positions,
                indices: &TABLE_TRIANGLES,
                sides: Sides::Both,
                colors: Colors::Uniform(TABLE_RGB),
                world_from_mesh: IDENTITY,
                instance_id: TABLE_ID,
                material: Material::MATTE,
            });
        }
        inputs
    }
}
