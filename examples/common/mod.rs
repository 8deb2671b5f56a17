//! What the evaluation examples share.

/// The Wilson score interval at 95% confidence.
#[allow(unused_imports)] // each example compiles this module; not every one takes these
pub use mvgrasp::evaluate::report::wilson_95;

/// The objects an example works on: the evaluation's object sets, by name (`evaluate --set`).
#[derive(clap::Args, Debug)]
#[allow(dead_code)] // each example compiles this module; not every one takes these options
pub struct SetArgs {
    /// An object set (repeat), as `evaluate --set` names them: held-out (built-in objects past
    /// every training index), dev, builtin:N (built-in objects from index N), real (every real
    /// mesh of the shared folder), dev-real, or folder:PATH. Default: held-out and real.
    #[arg(long = "set")]
    pub sets: Vec<String>,
    /// Built-in objects per category in the built-in sets.
    #[arg(long, default_value_t = 5)]
    pub per_category: u32,
    /// At most this many meshes of each file set (0: all).
    #[arg(long, default_value_t = 0)]
    pub max_meshes: usize,
}

/// An object of the sets, loaded: its group (the category, or the real mesh's source or
/// household category), its name in its set, and its mesh.
#[allow(dead_code)] // see SetArgs
pub struct Loaded {
    pub group: String,
    pub name: String,
    pub mesh: mvgrasp::geometry::TriangleMesh,
}

/// The objects of `args`' sets under the shared mesh folder `data`, each loaded; a mesh that
/// cannot be read is skipped with a note on standard error.
///
/// # Errors
/// A name that is not a set, or a manifest or folder that cannot be read.
#[allow(dead_code)] // see SetArgs
pub fn load_sets(args: &SetArgs, data: &std::path::Path) -> Result<Vec<Loaded>, String> {
    let names = if args.sets.is_empty() {
        vec!["held-out".to_string(), "real".to_string()]
    } else {
        args.sets.clone()
    };
    let found = mvgrasp::cli::objects_of_sets(&names, args.per_category, data, args.max_meshes)
        .map_err(|e| e.to_string())?;
    let mut loaded = Vec::new();
    for object in found {
        match object.load() {
            Ok(mesh) => loaded.push(Loaded {
                group: object.group.clone(),
                name: object.name.clone(),
                mesh,
            }),
            Err(e) => eprintln!("skipping {}: {e}", object.name),
        }
    }
    Ok(loaded)
}

/// The options of the label evaluation (`label_eval`).
#[derive(clap::Args, Debug)]
#[allow(dead_code)] // each example compiles this module; not every one takes these options
pub struct EvalArgs {
    /// Seed of sampling, quality and physics.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// The shared mesh folder (meshes missing from it are skipped).
    #[arg(long, default_value = "../shared/data/meshes")]
    pub data: std::path::PathBuf,
    /// Write every row as JSON here.
    #[arg(long)]
    pub json: Option<std::path::PathBuf>,
}

/// An object analysed in its most probable resting pose.
#[allow(dead_code)] // see EvalArgs
pub struct Rested {
    pub pose_index: usize,
    pub table_from_object: mvgrasp::geometry::Pose3,
    pub object: mvgrasp::grasp::GraspObject,
    pub analysis: mvgrasp::grasp::Analysis,
}

/// [`mvgrasp::grasp::analyse`] of `mesh` in its most probable resting pose; `None` (with a
/// note) for an object that only rolls: grasps are judged on objects that rest steadily.
#[allow(dead_code)] // see EvalArgs
pub fn analyse_at_rest(
    name: &str,
    mesh: mvgrasp::geometry::TriangleMesh,
    gripper: &mvgrasp::grasp::Gripper,
    config: &mvgrasp::grasp::AnalysisConfig,
    seed: u64,
) -> Result<Option<Rested>, String> {
    let rest = mvgrasp::geometry::RestingPoses::of(&mesh).map_err(|e| format!("{name}: {e}"))?;
    if rest.only_marginal() {
        eprintln!("skipping {name}: every stable pose is marginal");
        return Ok(None);
    }
    let (pose_index, pose) = rest.get(0).map_err(|e| format!("{name}: {e}"))?;
    let object = mvgrasp::grasp::GraspObject::new(mesh).map_err(|e| format!("{name}: {e}"))?;
    let analysis = mvgrasp::grasp::analyse(&object, &pose.table_from_object, gripper, config, seed)
        .map_err(|e| format!("{name}: {e}"))?;
    Ok(Some(Rested {
        pose_index,
        table_from_object: pose.table_from_object,
        object,
        analysis,
    }))
}

/// Writes a little-endian float32 array of `shape` as a NumPy `.npy` file (format 1.0), to a
/// temporary name first and then renamed, so that a killed run leaves no half file.
#[allow(dead_code)] // each example compiles this module; not every one writes arrays
pub fn write_npy_f32(
    path: &std::path::Path,
    shape: &[usize],
    values: &[f32],
) -> Result<(), String> {
    let dims: Vec<String> = shape.iter().map(ToString::to_string).collect();
    let trailing = if shape.len() == 1 { "," } else { "" };
    let mut header = format!(
        "{{'descr': '<f4', 'fortran_order': False, 'shape': ({}{trailing}), }}",
        dims.join(", ")
    );
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let length = u16::try_from(header.len()).map_err(|e| e.to_string())?;
    let mut bytes = Vec::with_capacity(10 + header.len() + 4 * values.len());
    bytes.extend_from_slice(b"\x93NUMPY\x01\x00");
    bytes.extend_from_slice(&length.to_le_bytes());
    bytes.extend_from_slice(header.as_bytes());
    for v in values {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    let partial = path.with_extension("npy.partial");
    std::fs::write(&partial, bytes)
        .map_err(|e| format!("cannot write {}: {e}", partial.display()))?;
    std::fs::rename(&partial, path).map_err(|e| format!("cannot write {}: {e}", path.display()))
}
