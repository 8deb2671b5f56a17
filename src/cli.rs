//! Pieces the command-line tools share: choosing the object (a mesh file or a built-in one),
//! and the exit convention (a user error is one `error: ...` line and exit code 2).

use std::path::PathBuf;
use std::process::ExitCode;

use mvgrasp_geometry::objects::{Category, generate};
use mvgrasp_geometry::{LoadOptions, TriangleMesh, load_mesh_with};

/// An object chosen on the command line.
#[derive(Debug, Clone)]
pub struct LoadedObject {
    /// For people: the file stem, or the built-in name and its seed.
    pub display_name: String,
    /// For file names: the file stem, or the built-in name.
    pub name: String,
    /// The mesh, metres.
    pub mesh: TriangleMesh,
}

/// The exit of a command whose `run` gave `result`: success, or the message on one
/// `error: ...` line and exit code 2.
pub fn exit(result: Result<(), String>) -> ExitCode {
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("error: {message}");
            ExitCode::from(2)
        }
    }
}

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
    /// The chosen object.
    ///
    /// # Errors
    /// A one-line message for the user: the loader's error (naming the file) or a bad
    /// `--category`.
    pub fn load(&self) -> Result<LoadedObject, String> {
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
                Ok(LoadedObject {
                    display_name: stem.clone(),
                    name: stem,
                    mesh,
                })
            }
            None => {
                let category: Category = self
                    .category
                    .parse()
                    .map_err(|e| format!("--category: {e}"))?;
                let object =
                    generate(category, self.index, self.seed).map_err(|e| e.to_string())?;
                Ok(LoadedObject {
                    display_name: format!("{} (built-in, seed {})", object.name, self.seed),
                    name: object.name,
                    mesh: object.mesh,
                })
            }
        }
    }
}
