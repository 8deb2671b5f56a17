//! Pieces the command-line tools share: choosing the object (a mesh file or a built-in one).

use std::path::PathBuf;

use mvgrasp_geometry::objects::{Category, generate};
use mvgrasp_geometry::{LoadOptions, TriangleMesh, load_mesh_with};

/// Which object a command works on: `--mesh PATH [--scale S]`, or a built-in object
/// (`--category`, `--index`, `--seed`; the default is the mug, index 0, seed 0).
#[derive(clap::Args, Debug, Clone)]
pub struct ObjectArgs {
    /// A mesh file (OBJ, STL or URDF, metres). Default: the built-in object below.
    #[arg(long)]
    pub mesh: Option<PathBuf>,
    /// Multiply the mesh's coordinates by this (0.001 for millimetres).
    #[arg(long, default_value_t = 1.0)]
    pub scale: f32,
    /// Built-in object category when no --mesh is given.
    #[arg(long, default_value = "mug")]
    pub category: String,
    /// Built-in object index within its category.
    #[arg(long, default_value_t = 0)]
    pub index: u32,
    /// Seed: of the built-in object, and of everything random the command does.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
}

impl ObjectArgs {
    /// The object's display name (the file stem, or the built-in name and seed), a short name
    /// for files, and its mesh.
    ///
    /// # Errors
    /// A one-line message for the user: the loader's error (naming the file) or a bad
    /// `--category`.
    pub fn load(&self) -> Result<(String, String, TriangleMesh), String> {
        match &self.mesh {
            Some(path) => {
                let options = LoadOptions {
                    scale: self.scale,
                    ..Default::default()
                };
                let mesh = load_mesh_with(path, &options).map_err(|e| e.to_string())?;
                let stem = path
                    .file_stem()
                    .map_or("mesh".into(), |s| s.to_string_lossy().into_owned());
                Ok((stem.clone(), stem, mesh))
            }
            None => {
                let category: Category = self
                    .category
                    .parse()
                    .map_err(|e| format!("--category: {e}"))?;
                let object =
                    generate(category, self.index, self.seed).map_err(|e| e.to_string())?;
                Ok((
                    format!("{} (built-in, seed {})", object.name, self.seed),
                    object.name.clone(),
                    object.mesh,
                ))
            }
        }
    }
}
