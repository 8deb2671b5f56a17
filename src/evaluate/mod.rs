//! `evaluate`: the project's evaluation from one command. Suites of work over named object
//! sets, each piece recorded as it finishes ([`journal`]), and a report folder written from
//! the records alone ([`report`]): `report.md`, the same as a self-contained `report.html`,
//! pictures of the chosen grasps, and `results.json` with every record. The same settings and
//! seeds give the same bytes, resumed or not (timings are kept out of the records).
//!
//! The grasp suite ([`grasps`]): each policy (a `plan` command) plans one grasp per object,
//! offered resting pose and seed, and the project's trial tries it; a missing grasp counts as
//! a failure. With `coverage`, an exhaustive search on the true mesh says which objects some
//! grasp in reach can hold.
//!
//! The depth suite ([`depth`]) scores depth from RGB against the rendered depth (the seed
//! paper's Table 1); the clutter suite ([`clutter`]) runs VGN and GIGA's clutter-removal
//! rounds; the labels suite ([`labels`]) judges the labels the networks learn by an outcome of
//! more trials; the speed suite ([`speed`]) times each stage of the policies' plans and the
//! networks beside torch.

pub mod clutter;
pub mod depth;
pub mod grasps;
pub mod journal;
pub mod labels;
pub mod objects;
pub mod report;
pub mod speed;

use std::path::{Path, PathBuf};

use mvgrasp_geometry::RestingPoses;
use mvgrasp_grasp::GraspObject;
use mvgrasp_render::Renderer;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::planner::DepthFrom;
use grasps::{EvalPolicy, GraspRecord, PlacedObject, PoseKind, ReadyPolicy};
use journal::Journal;
use objects::{ObjectRef, ObjectSet};

/// What an evaluation runs: its object sets, policies, seeds and poses. Written to the report
/// folder's `config.json`; a folder holding another config's records is refused.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EvalConfig {
    /// Object sets by name ([`ObjectSet`]: held-out, dev, real, dev-real, folder:PATH).
    pub sets: Vec<String>,
    /// Built-in objects per category in the built-in sets.
    pub per_category: u32,
    /// The shared mesh folder the `real` set reads.
    pub data: PathBuf,
    /// At most this many meshes of each file set (`real`, `folder:`; 0: all), for quick runs.
    pub max_meshes: usize,
    /// The policies ([`grasps::POLICIES`]).
    pub policies: Vec<String>,
    /// The plans' seeds; each object is planned once per seed.
    pub seeds: Vec<u64>,
    /// Every offered resting pose of at least 5% probability, not only the most probable.
    pub all_poses: bool,
    /// The exhaustive search for a grasp that holds, per object and pose (coverage).
    pub coverage: bool,
    /// The suites to run: `grasps`, `depth`.
    #[serde(default = "grasps_only")]
    pub suites: Vec<String>,
    /// The depth suite's numbers of input views.
    #[serde(default = "paper_shots")]
    pub depth_views: Vec<usize>,
    /// The depth suite's camera distance, metres (the paper's test views: 0.5).
    #[serde(default = "paper_distance_m")]
    pub depth_distance_m: f32,
    /// The depth suite's views with the photographic look ([`crate::scene::photoreal`]:
    /// textures, gloss, room lights, a background, sensor noise, blur, JPEG) instead of random
    /// colours under each camera's light.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub depth_photo: bool,
    /// The clutter suite's scenes ([`clutter::SCENES`]).
    #[serde(default = "every_scene")]
    pub clutter_scenes: Vec<String>,
    /// Its numbers of depth views (1: the top-down GQ-CNN alone; more: fused).
    #[serde(default = "one_view")]
    pub clutter_views: Vec<usize>,
    /// Its rounds per scene and number of views.
    #[serde(default = "small_rounds")]
    pub clutter_rounds: usize,
    /// Objects per round (VGN and GIGA: 5).
    #[serde(default = "five")]
    pub clutter_objects: usize,
    /// Its cameras' intrinsics preset (`phoxi_s`, `primesense`, `realsense_d435`).
    #[serde(default = "clutter_camera")]
    pub clutter_camera: String,
    /// Its cameras' distance from the table's centre, metres.
    #[serde(default = "clutter_distance_m")]
    pub clutter_distance_m: f32,
    /// Its top-down GQ-CNN sees each grasp's crop as from within its training cameras'
    /// distances (0.65 to 0.75 m; [`crate::planner::GqcnnPolicy::depth_range_m`]).
    #[serde(default)]
    pub clutter_training_depths: bool,
    /// Its depth from RGB: a `plan --depth-from` method (`baseline`, `refined`, `mvs`, `lsm`)
    /// predicting every view's depth from colour views of the scene (the objects in random
    /// colours on the grey table), given the foreground (what is not the table) as its masks,
    /// the planner still none; every number of views at least 2. `None`: rendered depth.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub clutter_depth_from: Option<String>,
    /// The labels suite's grasps sampled per object.
    #[serde(default = "ten")]
    pub label_grasps: usize,
    /// Its perturbed trials of the physics label.
    #[serde(default = "ten")]
    pub label_trials: usize,
    /// Its perturbed trials of the outcome the labels are judged by.
    #[serde(default = "twenty")]
    pub label_outcome_trials: usize,
    /// The speed suite's timed plans per policy.
    #[serde(default = "five")]
    pub speed_runs: usize,
}

fn ten() -> usize {
    10
}

fn twenty() -> usize {
    20
}

fn clutter_camera() -> String {
    clutter::DEFAULT_CAMERA.0.name().into()
}

fn clutter_distance_m() -> f32 {
    clutter::DEFAULT_CAMERA.1
}

fn every_scene() -> Vec<String> {
    clutter::SCENES.map(String::from).to_vec()
}

fn one_view() -> Vec<usize> {
    vec![1]
}

fn small_rounds() -> usize {
    5
}

fn five() -> usize {
    5
}

/// The suites of a config written before the depth suite was one.
fn grasps_only() -> Vec<String> {
    vec!["grasps".into()]
}

/// The seed paper's Table 1 shots and the planner's 5 views.
fn paper_shots() -> Vec<usize> {
    vec![1, 3, 5, 9]
}

fn paper_distance_m() -> f32 {
    0.5
}

/// The suites [`evaluate`] knows.
pub const SUITES: [&str; 5] = ["grasps", "depth", "clutter", "labels", "speed"];

impl EvalConfig {
    /// The small default: 1 held-out built-in object per category and the first 6 real meshes,
    /// the default run and the same planner on rendered depth, seed 0, the most probable pose.
    pub fn small(data: PathBuf) -> Self {
        Self {
            sets: vec!["held-out".into(), "real".into()],
            per_category: 1,
            data,
            max_meshes: 6,
            policies: vec!["rgb-fused".into(), "depth-fused".into()],
            seeds: vec![0],
            all_poses: false,
            coverage: false,
            suites: SUITES.map(String::from).to_vec(),
            depth_views: paper_shots(),
            depth_distance_m: paper_distance_m(),
            depth_photo: false,
            clutter_scenes: every_scene(),
            clutter_views: one_view(),
            clutter_rounds: small_rounds(),
            clutter_objects: five(),
            clutter_camera: clutter_camera(),
            clutter_distance_m: clutter_distance_m(),
            clutter_training_depths: false,
            clutter_depth_from: None,
            label_grasps: ten(),
            label_trials: ten(),
            label_outcome_trials: twenty(),
            speed_runs: five(),
        }
    }
}

/// Progress of a run, for a terminal or a log.
pub trait Progress {
    /// `done` of `total` pieces finished; `what` the piece just finished.
    fn step(&mut self, done: usize, total: usize, what: &str);
}

/// Plain lines on standard error (CI logs).
pub struct Lines;

impl Progress for Lines {
    fn step(&mut self, done: usize, total: usize, what: &str) {
        eprintln!("[{done}/{total}] {what}");
    }
}

/// Everything an evaluation found, in its work order.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Results {
    /// The settings.
    pub config: EvalConfig,
    /// The policies: name, `plan` command, what it plans on.
    pub policies: Vec<(String, String, String)>,
    /// Each object and pose planned on.
    pub objects: Vec<PlacedObject>,
    /// Each plan and its trial.
    pub grasps: Vec<GraspRecord>,
    /// The depth suite's records, per object and number of views.
    pub depth: Vec<depth::DepthRecord>,
    /// The clutter suite's rounds.
    #[serde(default)]
    pub clutter: Vec<clutter::RoundRecord>,
    /// The labels suite's grasps.
    #[serde(default)]
    pub labels: Vec<labels::LabelRecord>,
    /// The speed suite's timings.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub speed: Option<speed::SpeedRecord>,
    /// Objects (or clutter rounds) that could not be evaluated, and why.
    pub skipped: Vec<(String, String)>,
}

/// Runs `config` into the folder `out`, resuming from its records, and writes the report.
///
/// # Errors
/// A folder holding another config's records, unknown set or policy names, a renderer or
/// network that cannot start, or a report that cannot be written.
pub fn evaluate(config: &EvalConfig, out: &Path, progress: &mut dyn Progress) -> Result<Results> {
    evaluate_with(config, out, progress, RunOptions::default())
}

/// How a run spreads its work.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RunOptions {
    /// Objects evaluated at once on this machine, each on its own thread (0 and 1: one).
    pub jobs: usize,
    /// This run is one shard of a run spread over machines.
    pub shard: Option<Shard>,
}

/// One of `count` shards of a run: the objects (and clutter rounds) whose place in the work's
/// order leaves `index` over `count`. Each shard appends its records to its own journal in
/// the report folder (`shards/K-of-N.jsonl`, on a filesystem the machines share) and writes no
/// report; a run without a shard reads every shard's records, does what is missing (and the
/// speed suite) and writes the report: the same bytes as one machine's run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// This shard, from 0.
    pub index: usize,
    /// How many shards there are.
    pub count: usize,
}

impl std::str::FromStr for Shard {
    type Err = String;

    fn from_str(text: &str) -> std::result::Result<Self, String> {
        let parsed = text
            .split_once('/')
            .and_then(|(k, n)| Some((k.parse().ok()?, n.parse().ok()?)));
        match parsed {
            Some((index, count)) if index < count => Ok(Self { index, count }),
            _ => Err(format!(
                "{text:?}: expected K/N, shard K of N counted from 0 (0/2 and 1/2)"
            )),
        }
    }
}

impl Shard {
    /// Whether the `i`-th piece of work is this shard's.
    fn takes(&self, i: usize) -> bool {
        i % self.count == self.index
    }

    /// Its journal's path in the report folder `out`.
    fn journal(&self, out: &Path) -> PathBuf {
        out.join("shards")
            .join(format!("{}-of-{}.jsonl", self.index, self.count))
    }
}

/// [`evaluate`] spread as `run` says: the same records and report whatever the number of jobs
/// or shards (each object's pieces are its own; the records' lines come in the order they
/// finish). A shard's run returns its own results and writes no report.
///
/// # Errors
/// As [`evaluate`].
pub fn evaluate_with(
    config: &EvalConfig,
    out: &Path,
    progress: &mut dyn Progress,
    run: RunOptions,
) -> Result<Results> {
    let invalid = |problem: String| Error::Evaluate { problem };
    // Every name checked before anything is written.
    for set in &config.sets {
        set.parse::<ObjectSet>()
            .map_err(|e| invalid(format!("set {e}")))?;
    }
    let policies: Vec<EvalPolicy> = config
        .policies
        .iter()
        .map(|p| p.parse().map_err(|e| invalid(format!("policy {e}"))))
        .collect::<Result<_>>()?;
    if policies.is_empty() || config.seeds.is_empty() {
        return Err(invalid("no policy or no seed to evaluate".into()));
    }
    if let Some(suite) = config.suites.iter().find(|s| !SUITES.contains(&s.as_str())) {
        return Err(invalid(format!(
            "suite {suite:?}: expected one of {}",
            SUITES.join(", ")
        )));
    }
    let scenes: Vec<clutter::ClutterScene> = config
        .clutter_scenes
        .iter()
        .map(|s| s.parse().map_err(|e| invalid(format!("clutter scene {e}"))))
        .collect::<Result<_>>()?;
    if let Some(n) = config.clutter_views.iter().find(|n| !(1..=9).contains(*n)) {
        return Err(invalid(format!("clutter views {n}: expected 1 to 9")));
    }
    if config.speed_runs == 0 {
        return Err(invalid("speed runs 0: the suite needs at least one".into()));
    }
    if config.clutter_objects == 0 {
        return Err(invalid(
            "clutter objects 0: a round needs at least one".into(),
        ));
    }
    if [
        config.label_grasps,
        config.label_trials,
        config.label_outcome_trials,
    ]
    .contains(&0)
    {
        return Err(invalid(
            "labels: grasps, trials and outcome trials must each be at least 1".into(),
        ));
    }
    if let Some(n) = config.depth_views.iter().find(|n| !(1..=10).contains(*n)) {
        return Err(invalid(format!(
            "depth views {n}: expected 1 to 10 (there are 10 test views)"
        )));
    }
    let camera: mvgrasp_geometry::IntrinsicsPreset = config
        .clutter_camera
        .parse()
        .map_err(|e| invalid(format!("clutter camera: {e}")))?;
    if !(0.3..=1.5).contains(&config.clutter_distance_m) {
        return Err(invalid(format!(
            "clutter distance {} m: expected 0.3 to 1.5",
            config.clutter_distance_m
        )));
    }
    let clutter_depth_from: Option<DepthFrom> = match &config.clutter_depth_from {
        Some(name) => Some(
            name.parse()
                .map_err(|e| invalid(format!("clutter depth from {e}")))?,
        ),
        None => None,
    };
    if let (Some(from), Some(n)) = (
        clutter_depth_from,
        config.clutter_views.iter().find(|n| **n < 2),
    ) {
        return Err(invalid(format!(
            "clutter views {n} with depth from RGB ({}): predicting depth needs at least 2 views",
            from.name()
        )));
    }
    // Written only once the settings are known good: a refused run leaves no config behind.
    std::fs::create_dir_all(out).map_err(Error::io("create", out))?;
    check_config(config, out)?;
    let objects: Vec<ObjectRef> = objects::objects_of_sets(
        &config.sets,
        config.per_category,
        &config.data,
        config.max_meshes,
    )?;
    let renderer = Renderer::new(mvgrasp_render::Backend::Auto)?;
    let run_grasps = config.suites.iter().any(|s| s == "grasps");
    // The speed suite times one machine: the run that writes the report.
    let run_speed = config.suites.iter().any(|s| s == "speed") && run.shard.is_none();
    // The policies' networks, loaded only for the grasp and speed suites.
    let ready: Vec<ReadyPolicy> = if run_grasps || run_speed {
        policies
            .into_iter()
            .map(ReadyPolicy::new)
            .collect::<Result<_>>()?
    } else {
        Vec::new()
    };
    // The shards' journals, read beside this run's own.
    let shards = out.join("shards");
    let mut others: Vec<PathBuf> = match std::fs::read_dir(&shards) {
        Ok(entries) => entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|e| e == "jsonl"))
            .collect(),
        Err(_) => Vec::new(),
    };
    others.sort();
    let own = match run.shard {
        Some(shard) => {
            std::fs::create_dir_all(&shards).map_err(Error::io("create", &shards))?;
            others.push(out.join("records.jsonl"));
            shard.journal(out)
        }
        None => out.join("records.jsonl"),
    };
    others.retain(|p| *p != own);
    let journal = Journal::open_with(&own, &others)?;
    let mine = |i: usize| run.shard.is_none_or(|s| s.takes(i));
    let pictures = out.join("pictures");
    std::fs::create_dir_all(&pictures).map_err(Error::io("create", &pictures))?;
    let mut results = Results {
        config: config.clone(),
        policies: ready
            .iter()
            .map(|r| {
                let (command, about) = grasps::POLICIES
                    .iter()
                    .find(|(n, ..)| *n == r.policy.name)
                    .map_or(("", ""), |(_, c, a)| (*c, *a));
                (
                    r.policy.name.clone(),
                    command.to_string(),
                    about.to_string(),
                )
            })
            .collect(),
        objects: Vec::new(),
        grasps: Vec::new(),
        depth: Vec::new(),
        clutter: Vec::new(),
        labels: Vec::new(),
        speed: None,
        skipped: Vec::new(),
    };
    let depth_suite = if config.suites.iter().any(|s| s == "depth") {
        Some(depth::DepthSuite::new(
            config.depth_distance_m,
            config.depth_photo,
        )?)
    } else {
        None
    };
    let run_clutter = config.suites.iter().any(|s| s == "clutter");
    let rounds: Vec<(clutter::ClutterScene, usize, usize)> = if run_clutter {
        scenes
            .iter()
            .flat_map(|&scene| {
                config.clutter_views.iter().flat_map(move |&views| {
                    (0..config.clutter_rounds).map(move |round| (scene, views, round))
                })
            })
            .collect()
    } else {
        Vec::new()
    };
    let label_suite = config
        .suites
        .iter()
        .any(|s| s == "labels")
        .then_some(labels::LabelSuite {
            grasps: config.label_grasps,
            trials: config.label_trials,
            outcome_trials: config.label_outcome_trials,
        });
    // A depth record's key names the methods' count (records made before the refined sweep
    // was one are made again) and its views' distance and look unless they are the defaults,
    // so that records copied from a run of other settings are made again.
    let mut depth_setting = format!("{}|", depth::METHODS.len());
    if config.depth_distance_m != paper_distance_m() {
        depth_setting.push_str(&format!("{}m|", config.depth_distance_m));
    }
    if config.depth_photo {
        depth_setting.push_str("photo|");
    }
    let per_object = run_grasps || depth_suite.is_some() || label_suite.is_some();
    // This run's share of the objects and rounds (the clutter rounds draw from all objects).
    let my_objects: Vec<&ObjectRef> = objects
        .iter()
        .enumerate()
        .filter(|(i, _)| mine(*i))
        .map(|(_, o)| o)
        .collect();
    let rounds: Vec<_> = rounds
        .into_iter()
        .enumerate()
        .filter(|(i, _)| mine(*i))
        .map(|(_, r)| r)
        .collect();
    // Real photographs with a depth sensor's images beside the shared meshes
    // (`real_rgb/*/`), for the depth suite of the run that writes the report.
    let photographs: Vec<PathBuf> = match (&depth_suite, run.shard) {
        (Some(_), None) => photograph_folders(&config.data),
        _ => Vec::new(),
    };
    let total = if per_object { my_objects.len() } else { 0 }
        + rounds.len()
        + photographs.len()
        + usize::from(run_speed);
    // The first object of each set (of the whole run, whichever shard this is).
    let mut first_of_set = std::collections::HashSet::new();
    let mut sets_seen = std::collections::HashSet::new();
    for object in &objects {
        if sets_seen.insert(object.set.clone()) {
            first_of_set.insert(format!("{}|{}", object.set, object.name));
        }
    }
    // One object's pieces of every per-object suite, or why it could not be evaluated.
    let one = |object: &&ObjectRef| -> ObjectDone {
        let id = format!("{}|{}", object.set, object.name);
        let mut done = ObjectDone::default();
        let mut work = || -> Result<()> {
            if run_grasps {
                let (placed, records) =
                    evaluate_object(object, &id, config, &ready, &renderer, &journal, &pictures)?;
                done.placed = placed;
                done.grasps = records;
            }
            if let Some(suite) = &depth_suite {
                let key = format!("depth|{depth_setting}{id}");
                // The first object of each set gets the error sheet, drawn again when missing.
                let sheet = first_of_set
                    .contains(&id)
                    .then(|| missing_sheet(&pictures, (&object.set, &object.name), config))
                    .flatten();
                let sheet = sheet.as_ref().map(|(path, n)| (path.as_path(), *n));
                done.depth = match journal.get(&key)? {
                    Some(records) => {
                        if let Some((_, n)) = sheet {
                            let mesh = object.load()?;
                            let what = (&*object.set, &*object.name);
                            suite.run(&renderer, what, &mesh, &[n], (0, sheet))?;
                        }
                        records
                    }
                    None => {
                        let mesh = object.load()?;
                        let records = suite.run(
                            &renderer,
                            (&object.set, &object.name),
                            &mesh,
                            &config.depth_views,
                            (0, sheet),
                        )?;
                        journal.put(&key, &records)?
                    }
                };
            }
            if let Some(suite) = &label_suite {
                // The key names the settings and the seed, so that records copied into a run
                // of other settings are not taken for its own.
                let key = format!(
                    "labels|{}x{}x{}|{}|{id}",
                    suite.grasps, suite.trials, suite.outcome_trials, config.seeds[0]
                );
                done.labels = match journal.get(&key)? {
                    Some(records) => records,
                    None => {
                        let records = suite.run(
                            (&object.set, &object.name, &object.group),
                            object.load()?,
                            config.seeds[0],
                        )?;
                        journal.put(&key, &records)?
                    }
                };
            }
            Ok(())
        };
        // An object the evaluation cannot use (a broken mesh file) is reported, not fatal.
        if let Err(e) = work() {
            let why = match e {
                Error::Evaluate { problem } => problem,
                e => e.to_string(),
            };
            done.skipped = Some((id, why));
        }
        done
    };
    let to_do: &[&ObjectRef] = if per_object { &my_objects } else { &[] };
    // The objects on `jobs` threads, their records taken in the objects' order: the same
    // results whatever the number of jobs.
    in_order(to_do, run.jobs, one, |i, done| {
        results.objects.extend(done.placed);
        results.grasps.extend(done.grasps);
        results.depth.extend(done.depth);
        results.labels.extend(done.labels);
        results.skipped.extend(done.skipped);
        let object = &to_do[i];
        progress.step(i + 1, total, &format!("{} {}", object.set, object.name));
    });
    if let Some(suite) = &depth_suite {
        for (done, dir) in photographs.iter().enumerate() {
            let name = dir
                .file_name()
                .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
            let key = format!("depth-photographs|{depth_setting}{name}");
            let work = || -> Result<Vec<depth::DepthRecord>> {
                let sheet = missing_sheet(&pictures, (depth::REAL_PHOTOS, &name), config);
                let sheet = sheet.as_ref().map(|(path, n)| (path.as_path(), *n));
                if let Some(records) = journal.get(&key)? {
                    if let Some((_, n)) = sheet {
                        suite.run_photographs(&name, dir, &[n], sheet)?;
                    }
                    return Ok(records);
                }
                let records = suite.run_photographs(&name, dir, &config.depth_views, sheet)?;
                journal.put(&key, &records)
            };
            match work() {
                Ok(records) => results.depth.extend(records),
                Err(e) => results.skipped.push((key.clone(), e.to_string())),
            }
            progress.step(to_do.len() + done + 1, total, &key);
        }
    }
    // The clutter suite's planners and objects, built only when a round is missing.
    let mut suite: Option<clutter::ClutterSuite> = None;
    let before = total - rounds.len() - usize::from(run_speed);
    // A round's key names its cameras and crops unless they are the defaults (the first
    // rounds were recorded so).
    let mut setting = String::new();
    if (camera, config.clutter_distance_m) != clutter::DEFAULT_CAMERA {
        setting.push_str(&format!("{}@{}|", camera.name(), config.clutter_distance_m));
    }
    if config.clutter_training_depths {
        setting.push_str("training-depths|");
    }
    if let Some(from) = clutter_depth_from {
        setting.push_str(&format!("rgb-{}|", from.name()));
    }
    for (done, &(scene, views, round)) in rounds.iter().enumerate() {
        let key = format!("clutter|{}|{views}|{setting}{round}", scene.name());
        let mut work = || -> Result<clutter::RoundRecord> {
            if let Some(record) = journal.get(&key)? {
                return Ok(record);
            }
            let suite = match suite {
                Some(ref suite) => suite,
                None => suite.insert(clutter::ClutterSuite::new(
                    &objects,
                    &config.clutter_views,
                    config
                        .clutter_training_depths
                        .then_some(clutter::TRAINING_DEPTHS_M),
                    clutter_depth_from,
                )?),
            };
            let record = suite.round(
                &renderer,
                (scene, views, config.clutter_objects, round),
                (camera, config.clutter_distance_m),
            )?;
            journal.put(&key, &record)
        };
        match work() {
            Ok(record) => results.clutter.push(record),
            Err(e) => results.skipped.push((key.clone(), e.to_string())),
        }
        progress.step(before + done + 1, total, &key);
    }
    if let Some(suite) = &suite {
        results.skipped.extend(
            suite
                .unusable()
                .into_iter()
                .map(|(name, why)| (format!("clutter|{name}"), why)),
        );
    }
    if run_speed {
        let key = format!("speed|{}", config.speed_runs);
        let work = || -> Result<speed::SpeedRecord> {
            if let Some(record) = journal.get(&key)? {
                return Ok(record);
            }
            let suite = speed::SpeedSuite {
                runs: config.speed_runs,
                network_seconds: 1.0,
            };
            journal.put(&key, &suite.run(&renderer, &ready)?)
        };
        match work() {
            Ok(record) => results.speed = Some(record),
            Err(e) => results.skipped.push((key.clone(), e.to_string())),
        }
        progress.step(total, total, &key);
    }
    if run.shard.is_none() {
        report::write(&results, out)?;
    }
    Ok(results)
}

/// Refuses a folder whose `config.json` differs from `config`; writes it into a new one.
fn check_config(config: &EvalConfig, out: &Path) -> Result<()> {
    let path = out.join("config.json");
    let text =
        serde_json::to_string_pretty(config).map_err(Error::json("write", "config", &path))?;
    match std::fs::read_to_string(&path) {
        Ok(found) if serde_json::from_str::<EvalConfig>(&found).is_ok_and(|c| c == *config) => {
            Ok(())
        }
        Ok(_) => Err(Error::Evaluate {
            problem: format!(
                "{}: this folder holds a run with other settings; choose another --out or \
                 delete the folder",
                path.display()
            ),
        }),
        // Through a file of this process's own and a rename: the shards of a run spread over
        // machines may write it at once, and none may read half of it.
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            let tmp = out.join(format!("config.json.{}.tmp", std::process::id()));
            std::fs::write(&tmp, text).map_err(Error::io("write", &tmp))?;
            std::fs::rename(&tmp, &path).map_err(Error::io("rename", &tmp))
        }
        Err(e) => Err(Error::io("read", &path)(e)),
    }
}

/// One object: its poses (from the journal, or found and recorded), each pose's plans, and a
/// picture of the first seed's grasps.
fn evaluate_object(
    object: &ObjectRef,
    id: &str,
    config: &EvalConfig,
    ready: &[ReadyPolicy],
    renderer: &Renderer,
    journal: &Journal,
    pictures: &Path,
) -> Result<(Vec<PlacedObject>, Vec<GraspRecord>)> {
    // Loaded only when some piece of work is missing.
    let mut loaded: Option<GraspObject> = None;
    // Its resting poses, found once when some piece of work needs them.
    let mut rest: Option<RestingPoses> = None;
    let poses_key = format!("poses|{id}");
    let placed: Vec<PlacedObject> = match journal.get(&poses_key)? {
        Some(placed) => placed,
        None => {
            let grasp_object = load(object, &mut loaded)?;
            let rest = rest.insert(RestingPoses::of(grasp_object.mesh())?);
            let gripper = ready[0].gripper();
            let mut placed = Vec::new();
            for k in grasps::poses_to_try(rest, config.all_poses) {
                let (_, pose) = rest.get(k)?;
                let holdable = if config.coverage {
                    Some(grasps::any_grasp_holds(
                        grasp_object,
                        &pose.table_from_object,
                        ready[0].params(),
                        0,
                    )?)
                } else {
                    None
                };
                placed.push(PlacedObject {
                    object: object.name.clone(),
                    set: object.set.clone(),
                    group: object.group.clone(),
                    pose: k,
                    pose_probability: pose.probability,
                    kind: PoseKind::of(
                        grasp_object,
                        &pose.table_from_object,
                        gripper.max_opening_m,
                    ),
                    holdable,
                });
            }
            journal.put(&poses_key, &placed)?
        }
    };
    let mut records = Vec::new();
    for p in &placed {
        let mut first_seed = Vec::new();
        for &seed in &config.seeds {
            for policy in ready {
                let key = format!("grasp|{id}|{}|{}|{seed}", p.pose, policy.policy.name);
                let record = match journal.get(&key)? {
                    Some(record) => record,
                    None => {
                        let grasp_object = load(object, &mut loaded)?;
                        let record =
                            policy.run(renderer, grasp_object, (&object.name, p.pose, seed))?;
                        journal.put(&key, &record)?
                    }
                };
                if seed == config.seeds[0] {
                    first_seed.push(record.grasp);
                }
                records.push(record);
            }
        }
        let picture = pictures.join(report::picture_name(p));
        if !picture.is_file() {
            let grasp_object = load(object, &mut loaded)?;
            let rest = match rest {
                Some(ref rest) => rest,
                None => rest.insert(RestingPoses::of(grasp_object.mesh())?),
            };
            let (_, pose) = rest.get(p.pose)?;
            // Each policy's hand in its colour (the report's legend).
            let hands: Vec<_> = first_seed
                .iter()
                .zip(report::POLICY_COLORS.iter().cycle())
                .filter_map(|(g, &color)| g.map(|g| (g, color)))
                .collect();
            crate::grasp_image::write_colored_grasp_picture(
                &picture,
                grasp_object.mesh(),
                &pose.table_from_object,
                &hands,
                ready[0].gripper(),
            )?;
        }
    }
    Ok((placed, records))
}

/// `object`'s mesh ready for the trial, loaded on first use.
fn load<'a>(object: &ObjectRef, loaded: &'a mut Option<GraspObject>) -> Result<&'a GraspObject> {
    if let Some(loaded) = loaded {
        return Ok(loaded);
    }
    Ok(loaded.insert(GraspObject::new(object.load()?)?))
}

/// One object's records of the per-object suites, or why it was skipped.
#[derive(Default)]
struct ObjectDone {
    placed: Vec<PlacedObject>,
    grasps: Vec<GraspRecord>,
    depth: Vec<depth::DepthRecord>,
    labels: Vec<labels::LabelRecord>,
    skipped: Option<(String, String)>,
}

/// Runs `work` on each of `items` on `jobs` threads and hands each result to `take`, on this
/// thread and in the items' order, as soon as it and those before it are done.
fn in_order<T: Sync, R: Send>(
    items: &[T],
    jobs: usize,
    work: impl Fn(&T) -> R + Sync,
    mut take: impl FnMut(usize, R),
) {
    use std::sync::atomic::{AtomicUsize, Ordering};
    if jobs <= 1 || items.len() <= 1 {
        for (i, item) in items.iter().enumerate() {
            take(i, work(item));
        }
        return;
    }
    let next = AtomicUsize::new(0);
    let (sender, receiver) = std::sync::mpsc::channel();
    std::thread::scope(|scope| {
        for _ in 0..jobs.min(items.len()) {
            let (sender, next, work) = (sender.clone(), &next, &work);
            scope.spawn(move || {
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some(item) = items.get(i) else { break };
                    if sender.send((i, work(item))).is_err() {
                        break;
                    }
                }
            });
        }
        drop(sender);
        // Results that came before an earlier one, held until it comes.
        let mut waiting = std::collections::BTreeMap::new();
        let mut due = 0;
        for (i, result) in receiver {
            waiting.insert(i, result);
            while let Some(result) = waiting.remove(&due) {
                take(due, result);
                due += 1;
            }
        }
    });
}

/// The error sheet of `object` in `set` and the number of views it is drawn from, when the
/// sheet is not in `pictures` yet.
fn missing_sheet(
    pictures: &Path,
    (set, object): (&str, &str),
    config: &EvalConfig,
) -> Option<(PathBuf, usize)> {
    let n = depth::sheet_views(&config.depth_views);
    let path = pictures.join(depth::sheet_name(set, object, n));
    (!path.is_file()).then_some((path, n))
}

/// The folders of real photographs beside the shared mesh folder `data`: every folder of
/// `data/../real_rgb` with a `cameras.json`, sorted (none when there is no such folder).
fn photograph_folders(data: &Path) -> Vec<PathBuf> {
    let root = data.join("..").join("real_rgb");
    let mut found: Vec<PathBuf> = match std::fs::read_dir(&root) {
        Ok(entries) => entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.join("cameras.json").is_file())
            .collect(),
        Err(_) => Vec::new(),
    };
    found.sort();
    found
}
