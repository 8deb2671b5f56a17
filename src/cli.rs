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

/// Why a command failed, for its one `error: ...` line: an error of the library (whose
/// message names the file and the problem) or a message of the command's own. `?` takes
/// either: any `std::error::Error`, a `String` or a `&str`.
pub type Failure = Box<dyn std::error::Error + Send + Sync>;

/// What a command's steps return.
pub type CliResult<T> = Result<T, Failure>;

/// The exit of a command whose `run` gave `result`: success, or the message on one
/// `error: ...` line and exit code 2.
pub fn exit(result: CliResult<()>) -> ExitCode {
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
    pub fn load(&self) -> CliResult<LoadedObject> {
        match &self.mesh {
            Some(path) => {
                let options = LoadOptions {
                    scale: self.scale,
                    ..Default::default()
                };
                let mesh = load_mesh_with(path, &options)?;
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
                let object = generate(category, self.index, self.seed)?;
                Ok(LoadedObject {
                    display_name: format!("{} (built-in, seed {})", object.name, self.seed),
                    name: object.name,
                    mesh: object.mesh,
                })
            }
        }
    }
}

/// The objects of the evaluation's sets named `names` (as `evaluate --set` names them; see
/// [`crate::evaluate::objects::objects_of_sets`]), for a command: a name that is not a set is
/// an error about `--set`.
///
/// # Errors
/// That, or a manifest or folder that cannot be read.
pub fn objects_of_sets(
    names: &[String],
    per_category: u32,
    data: &std::path::Path,
    max_meshes: usize,
) -> CliResult<Vec<crate::evaluate::objects::ObjectRef>> {
    crate::evaluate::objects::objects_of_sets(names, per_category, data, max_meshes).map_err(|e| {
        match e {
            crate::Error::Evaluate { problem } => format!("--{problem}").into(),
            e => e.into(),
        }
    })
}

/// Many objects for a dataset: mesh files and folders, or the built-in library.
#[derive(clap::Args, Debug, Clone)]
pub struct LibraryArgs {
    /// Mesh files (OBJ, STL, URDF; metres) or folders searched for them. Default: the built-in
    /// object library.
    #[arg(long)]
    pub mesh: Vec<PathBuf>,
    /// Built-in objects per category (when no --mesh is given).
    #[arg(long, default_value_t = 1)]
    pub per_category: u32,
    /// Built-in categories, comma-separated (default: all).
    #[arg(long, value_delimiter = ',')]
    pub categories: Vec<Category>,
    /// Seed of the built-in objects' shapes.
    #[arg(long, default_value_t = 0)]
    pub library_seed: u64,
}

impl LibraryArgs {
    /// The objects, in a fixed order: the library by category then index, or the files as
    /// given (made absolute) with each folder's meshes sorted by path.
    ///
    /// # Errors
    /// A message naming a path that does not exist or a folder with no mesh.
    pub fn sources(&self) -> CliResult<Vec<crate::dataset::ObjectSource>> {
        use crate::dataset::ObjectSource;
        if self.mesh.is_empty() {
            let categories = if self.categories.is_empty() {
                Category::ALL.to_vec()
            } else {
                self.categories.clone()
            };
            return Ok(categories
                .into_iter()
                .flat_map(|category| {
                    (0..self.per_category).map(move |index| {
                        ObjectSource::Builtin(mvgrasp_geometry::objects::ObjectSpec {
                            category,
                            index,
                            seed: self.library_seed,
                        })
                    })
                })
                .collect());
        }
        let mut sources = Vec::new();
        for given in &self.mesh {
            // Absolute, so that a dataset records the same sources whatever the working folder
            // (a Ray worker's is not the driver's).
            let path =
                &std::fs::canonicalize(given).map_err(|e| format!("{}: {e}", given.display()))?;
            if path.is_dir() {
                let mut found = Vec::new();
                collect_meshes(path, &mut found)?;
                if found.is_empty() {
                    return Err(format!("{}: no .obj, .stl or .urdf inside", path.display()).into());
                }
                found.sort();
                sources.extend(found.into_iter().map(ObjectSource::File));
            } else {
                sources.push(ObjectSource::File(path.clone()));
            }
        }
        Ok(sources)
    }
}

fn collect_meshes(dir: &std::path::Path, found: &mut Vec<PathBuf>) -> CliResult<()> {
    let entries = std::fs::read_dir(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    for entry in entries {
        let path = entry.map_err(|e| format!("{}: {e}", dir.display()))?.path();
        if path.is_dir() {
            collect_meshes(&path, found)?;
        } else if path
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| ["obj", "stl", "urdf"].contains(&e.to_ascii_lowercase().as_str()))
        {
            found.push(path);
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dataset::ObjectSource;

    fn library(mesh: Vec<PathBuf>) -> LibraryArgs {
        LibraryArgs {
            mesh,
            per_category: 1,
            categories: Vec::new(),
            library_seed: 0,
        }
    }

    #[test]
    fn folders_expand_to_their_meshes_sorted_and_absolute() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir_all(dir.path().join("b")).unwrap();
        for f in ["b/z.stl", "a.obj", "notes.txt"] {
            std::fs::write(dir.path().join(f), "").unwrap();
        }
        let sources = library(vec![dir.path().to_path_buf()]).sources().unwrap();
        let root = std::fs::canonicalize(dir.path()).unwrap();
        assert_eq!(
            sources,
            [
                ObjectSource::File(root.join("a.obj")),
                ObjectSource::File(root.join("b/z.stl"))
            ]
        );
        let err = library(vec![dir.path().join("nowhere.obj")])
            .sources()
            .unwrap_err()
            .to_string();
        assert!(err.contains("nowhere.obj"), "{err}");
        std::fs::create_dir_all(dir.path().join("empty")).unwrap();
        let err = library(vec![dir.path().join("empty")])
            .sources()
            .unwrap_err()
            .to_string();
        assert!(err.contains("no .obj"), "{err}");
    }
}
