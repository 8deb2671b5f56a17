//! What the evaluation examples share.

/// The real meshes of the evaluations, paths under `../shared/data/meshes` (all in metres).
/// The first two (YCB's cracker and sugar boxes) have no Panda grasp lying down: wider than
/// its 8 cm from above, and from the side its palm meets the table.
pub const REAL_MESHES: [&str; 12] = [
    "ycb/meshes/003_cracker_box_textured.obj",
    "ycb/meshes/004_sugar_box_textured.obj",
    "ycb/meshes/005_tomato_soup_can_textured.obj",
    "ycb/meshes/006_mustard_bottle_textured.obj",
    "ycb/meshes/009_gelatin_box_textured.obj",
    "ycb/meshes/010_potted_meat_can_textured.obj",
    "dexnet/test/models/bar_clamp.obj",
    "dexnet/meshes/example/box.obj",
    "robosuite/objects/meshes/bottle.obj",
    "robosuite/objects/meshes/can.stl",
    "robosuite/objects/meshes/milk.stl",
    "pybullet/objects/mug.urdf",
];

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

/// The Wilson score interval of `k` successes in `n` trials at 95 % confidence, as fractions
/// (`(0, 1)` for no trials).
#[allow(dead_code)] // see EvalArgs
pub fn wilson_95(k: usize, n: usize) -> (f64, f64) {
    if n == 0 {
        return (0.0, 1.0);
    }
    let (k, n, z) = (k as f64, n as f64, 1.959_964);
    let p = k / n;
    let centre = (p + z * z / (2.0 * n)) / (1.0 + z * z / n);
    let half = z / (1.0 + z * z / n) * (p * (1.0 - p) / n + z * z / (4.0 * n * n)).sqrt();
    ((centre - half).max(0.0), (centre + half).min(1.0))
}
