//! What the evaluation examples share.

/// The real meshes of the evaluations, paths under `../shared/data/meshes` (all in metres;
/// the first two lie flat wider than the hand opens).
pub use mvgrasp::evaluate::objects::REAL_MESHES;
/// The Wilson score interval at 95% confidence.
#[allow(unused_imports)] // each example compiles this module; not every one takes these
pub use mvgrasp::evaluate::report::wilson_95;

/// The options of the label evaluations (`grasp_eval`, `label_eval`).
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
