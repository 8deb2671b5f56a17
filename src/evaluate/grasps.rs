//! The grasp suite: each policy plans one grasp per object, resting pose and seed from the
//! views it sees, and the project's trial (close, lift, shake in rapier) says whether it held.
//! Optionally an exhaustive search on the true mesh says whether any grasp in reach holds
//! (coverage).

use mvgrasp_geometry::{Pose3, RestingPoses, TriangleMesh, Vec3};
use mvgrasp_grasp::physics::{FailureStage, PhysicsObject};
use mvgrasp_grasp::{AnalysisConfig, GraspObject, Gripper, analyse, label_grasps};
use mvgrasp_planner::tilt_rad;
use mvgrasp_render::Renderer;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::planner::{
    ChanceSource, DepthFrom, PlanOptions, PlanParams, PlanReport, Planner, plan_grasp,
};

/// A planner as the evaluation names it: `plan`'s options.
#[derive(Clone, Debug, PartialEq)]
pub struct EvalPolicy {
    /// Its name on the command line and in the report.
    pub name: String,
    /// The options `plan` would be given.
    pub options: PlanOptions,
}

/// The policies the grasp suite knows: name, the `plan` command each stands for, and what it
/// plans on.
pub const POLICIES: [(&str, &str, &str); 10] = [
    (
        "rgb",
        "plan --no-fuse",
        "the top-down GQ-CNN on the plane sweep's depth from 5 RGB views",
    ),
    (
        "depth",
        "plan --no-fuse --depth-from rendered",
        "the top-down GQ-CNN on a perfect depth camera",
    ),
    (
        "rgb-fused",
        "plan",
        "the default run: the multi-view planner on the plane sweep's depth from 5 RGB views",
    ),
    (
        "depth-fused",
        "plan --depth-from rendered",
        "the multi-view planner on rendered depth",
    ),
    (
        "lsm",
        "plan --no-fuse --depth-from lsm",
        "the top-down GQ-CNN on the Learnt Stereo Machine's depth",
    ),
    (
        "lsm-fused",
        "plan --depth-from lsm",
        "the multi-view planner on the LSM's depth",
    ),
    (
        "mvs",
        "plan --no-fuse --depth-from mvs",
        "the top-down GQ-CNN on the multi-view stereo network's depth",
    ),
    (
        "mvs-fused",
        "plan --depth-from mvs",
        "the multi-view planner on its depth",
    ),
    (
        "refined",
        "plan --no-fuse --depth-from refined",
        "the top-down GQ-CNN on the plane sweep refined by its network",
    ),
    (
        "refined-fused",
        "plan --depth-from refined",
        "the multi-view planner on the refined sweep's depth",
    ),
];

impl std::str::FromStr for EvalPolicy {
    type Err = String;

    fn from_str(name: &str) -> std::result::Result<Self, String> {
        let (source, fuse) = match name.strip_suffix("-fused") {
            Some(source) => (source, true),
            None => (name, false),
        };
        let depth_from = match source {
            "rgb" => Some(DepthFrom::DEFAULT),
            "depth" => None,
            "lsm" => Some(DepthFrom::Lsm),
            "mvs" => Some(DepthFrom::Mvs),
            "refined" => Some(DepthFrom::Refined),
            _ => {
                let names: Vec<&str> = POLICIES.iter().map(|(n, ..)| *n).collect();
                return Err(format!("{name:?}: expected one of {}", names.join(", ")));
            }
        };
        Ok(Self {
            name: name.to_string(),
            options: PlanOptions {
                fuse,
                depth_from,
                ..PlanOptions::default()
            },
        })
    }
}

/// How an object rests, as far as a parallel-jaw hand from above is concerned.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PoseKind {
    /// Taller than it is wide across its footprint's long side.
    Upright,
    /// Lying: lower than that, and narrow enough across for the hand from above.
    Lying,
    /// Under 0.6 of its footprint's narrow side, which is wider than the hand opens (a box
    /// lying flat): no grasp from straight above.
    FlatWide,
    /// Open at the top: a ray down through the footprint's centre falls below a third of the
    /// height (a bowl, a mug or a cup upright).
    Rim,
    /// Under 1.5 cm high (a plate, scissors).
    Thin,
}

impl PoseKind {
    /// Every kind, in the report's order.
    pub const ALL: [Self; 5] = [
        Self::Upright,
        Self::Lying,
        Self::FlatWide,
        Self::Rim,
        Self::Thin,
    ];

    /// Its name in the report.
    pub fn name(self) -> &'static str {
        match self {
            Self::Upright => "upright",
            Self::Lying => "lying",
            Self::FlatWide => "flat and wide",
            Self::Rim => "open at the top",
            Self::Thin => "thin",
        }
    }

    /// The kind of `object` resting at `table_from_object` for a hand opening `max_opening_m`.
    pub fn of(object: &GraspObject, table_from_object: &Pose3, max_opening_m: f32) -> Self {
        let points: Vec<Vec3> = object
            .mesh()
            .vertices()
            .iter()
            .map(|&v| table_from_object.transform_point(v))
            .collect();
        let height_m = points.iter().map(|p| p.z).fold(0.0f32, f32::max);
        if height_m < 0.015 {
            return Self::Thin;
        }
        // The footprint's extents along its principal axes.
        let n = points.len().max(1) as f32;
        let (mx, my) = points
            .iter()
            .fold((0.0, 0.0), |(x, y), p| (x + p.x / n, y + p.y / n));
        let (mut sxx, mut sxy, mut syy) = (0.0f32, 0.0f32, 0.0f32);
        for p in &points {
            let (dx, dy) = (p.x - mx, p.y - my);
            sxx += dx * dx;
            sxy += dx * dy;
            syy += dy * dy;
        }
        let angle = 0.5 * (2.0 * sxy).atan2(sxx - syy);
        let (u, v) = (
            Vec3::new(angle.cos(), angle.sin(), 0.0),
            Vec3::new(-angle.sin(), angle.cos(), 0.0),
        );
        let span = |axis: Vec3| {
            let (lo, hi) = points.iter().fold((f32::MAX, f32::MIN), |(lo, hi), p| {
                let s = p.dot(axis);
                (lo.min(s), hi.max(s))
            });
            (lo, hi)
        };
        let ((u0, u1), (v0, v1)) = (span(u), span(v));
        let (wide_m, narrow_m) = ((u1 - u0).max(v1 - v0), (u1 - u0).min(v1 - v0));
        // A ray straight down through the footprint's centre, in the object's frame.
        let centre = u * (0.5 * (u0 + u1)) + v * (0.5 * (v0 + v1)) + Vec3::Z * (height_m + 0.05);
        let object_from_table = table_from_object.inverse();
        let hit = object.caster().cast(
            object_from_table.transform_point(centre),
            object_from_table.transform_vector(-Vec3::Z),
            height_m + 0.1,
        );
        let floor_m = hit.map_or(0.0, |h| table_from_object.transform_point(h.point).z);
        if floor_m < height_m / 3.0 {
            Self::Rim
        } else if height_m < 0.6 * narrow_m && narrow_m > max_opening_m {
            Self::FlatWide
        } else if height_m >= wide_m {
            Self::Upright
        } else {
            Self::Lying
        }
    }
}

/// One object in one resting pose, as the suite saw it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlacedObject {
    /// The object's name in its set.
    pub object: String,
    /// The set's name.
    pub set: String,
    /// Its category or source.
    pub group: String,
    /// The offered resting pose (0: the most probable).
    pub pose: usize,
    /// That pose's probability.
    pub pose_probability: f32,
    /// How it rests.
    pub kind: PoseKind,
    /// With coverage: whether some grasp in reach holds it ([`any_grasp_holds`]).
    pub holdable: Option<bool>,
}

/// One planned grasp and its trial.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GraspRecord {
    /// The object's name in its set.
    pub object: String,
    /// The offered resting pose.
    pub pose: usize,
    /// The policy's name.
    pub policy: String,
    /// The plan's seed (sampling and cameras).
    pub seed: u64,
    /// `held`, `no grasp`, `toppled` (the object left its pose before the hand came: the
    /// trial tests the pose, not the grasp) or the stage the grasp failed at (`close`, `lift`,
    /// `shake`, ...).
    pub outcome: String,
    /// The returned grasp's predicted quality.
    pub quality: Option<f32>,
    /// The returned grasp's chance to hold ([`mvgrasp_planner::HoldProbability`]), for the policies that have
    /// one (`rgb`, `depth`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub probability: Option<f32>,
    /// Dex-Net 2.0's analytic label of the returned grasp on the true mesh.
    pub robust: Option<bool>,
    /// The approach's angle from straight down, degrees.
    pub tilt_deg: Option<f32>,
    /// The returned grasp in the table frame (for the report's pictures).
    pub grasp: Option<mvgrasp_grasp::Grasp>,
}

impl GraspRecord {
    /// A grasp was returned.
    pub fn returned(&self) -> bool {
        self.outcome != "no grasp"
    }

    /// The trial tested the grasp (not a toppled object).
    pub fn counts(&self) -> bool {
        self.outcome != "toppled"
    }

    /// The grasp held.
    pub fn held(&self) -> bool {
        self.outcome == "held"
    }
}

/// The offered resting poses the suite tries for `rest`: the most probable, or with `all`
/// every offered pose of at least 5% probability (the most probable always).
pub fn poses_to_try(rest: &RestingPoses, all: bool) -> Vec<usize> {
    rest.iter()
        .enumerate()
        .filter(|&(k, (_, pose))| k == 0 || (all && pose.probability >= 0.05))
        .map(|(k, _)| k)
        .collect()
}

/// A policy ready to plan: its network and settings.
pub struct ReadyPolicy {
    /// What it is.
    pub policy: EvalPolicy,
    planner: Planner,
    params: PlanParams,
}

impl ReadyPolicy {
    /// Loads `policy`'s shipped network.
    ///
    /// # Errors
    /// Shipped weights that cannot be loaded, or options `plan` would refuse.
    pub fn new(policy: EvalPolicy) -> Result<Self> {
        let model = policy.options.default_model();
        let net = mvgrasp_planner::models::shipped(model)
            .ok_or_else(|| Error::Evaluate {
                problem: format!("no shipped network {model:?}"),
            })?
            .load()?;
        let (planner, params) = policy.options.on_mesh(net)?;
        Ok(Self {
            policy,
            planner,
            params,
        })
    }

    /// Plans on `object` in offered pose `pose` with `seed` and tries the grasp.
    ///
    /// # Errors
    /// A renderer, network or trial error.
    pub fn run(
        &self,
        renderer: &Renderer,
        object: &GraspObject,
        (name, pose, seed): (&str, usize, u64),
    ) -> Result<GraspRecord> {
        let report = self.plan(renderer, object.mesh(), pose, seed)?;
        let best = report.best;
        let outcome = match (&best, report.physics) {
            (None, _) => "no grasp".to_string(),
            (Some(_), None) => "not tried".to_string(),
            (Some(_), Some(p)) => match p.failed_at {
                None => "held".into(),
                Some(FailureStage::Settle) => "toppled".into(),
                Some(stage) => format!("{stage:?}").to_lowercase(),
            },
        };
        Ok(GraspRecord {
            object: name.to_string(),
            pose,
            policy: self.policy.name.clone(),
            seed,
            outcome,
            quality: best.map(|b| b.quality),
            probability: match (best, self.chance_source()) {
                (Some(b), Some(source)) => source.of(&b)?,
                _ => None,
            },
            robust: report.analytic.map(|a| a.robust),
            tilt_deg: best.map(|b| tilt_rad(&b.grasp).to_degrees()),
            grasp: best.map(|b| b.grasp),
        })
    }

    /// Plans on `mesh` in offered pose `pose` with `seed` (and tries the grasp), as `plan`
    /// would.
    ///
    /// # Errors
    /// A renderer, network or trial error.
    pub fn plan(
        &self,
        renderer: &Renderer,
        mesh: &TriangleMesh,
        pose: usize,
        seed: u64,
    ) -> Result<PlanReport> {
        let params = PlanParams {
            stable_pose: pose,
            seed,
            ..self.params.clone()
        };
        Ok(plan_grasp(renderer, mesh, &self.planner, &params)?)
    }

    /// Where the chance to hold of this policy's grasps comes from, if anywhere.
    fn chance_source(&self) -> Option<ChanceSource> {
        let options = &self.policy.options;
        options.chance_source(options.default_model(), false)
    }

    /// The gripper the policy plans for.
    pub fn gripper(&self) -> &Gripper {
        &self.params.labels.gripper
    }

    /// The policy's plan settings.
    pub fn params(&self) -> &PlanParams {
        &self.params
    }
}

/// Approaches the exhaustive search keeps: within this angle of straight down, degrees (an
/// arm over a table reaches these).
pub const REACH_TILT_DEG: f32 = 75.0;

/// Grasps the exhaustive search tries in physics, best robust quality first.
pub const SEARCH_TRIALS: usize = 20;

/// Whether some grasp in reach holds `object` resting at `table_from_object`: antipodal grasps
/// sampled on the true mesh (the grasp datasets' sampler: collision-free against the object
/// and the table), those approaching within [`REACH_TILT_DEG`] of straight down, the [`SEARCH_TRIALS`] of highest robust quality tried in the planner's
/// trial. An object toppling in every trial counts as not holdable.
///
/// # Errors
/// An object the sampler or the trial cannot prepare.
pub fn any_grasp_holds(
    object: &GraspObject,
    table_from_object: &Pose3,
    params: &PlanParams,
    seed: u64,
) -> Result<bool> {
    let gripper = &params.labels.gripper;
    let config = AnalysisConfig {
        sampling: params.labels.sampling,
        quality: params.labels.quality.clone(),
        physics: None,
        ..AnalysisConfig::default()
    };
    let analysis = analyse(object, table_from_object, gripper, &config, seed)?;
    let reachable: Vec<_> = analysis
        .grasps
        .iter()
        .filter(|g| tilt_rad(&g.grasp).to_degrees() <= REACH_TILT_DEG)
        .take(SEARCH_TRIALS)
        .map(|g| g.grasp)
        .collect();
    if reachable.is_empty() {
        return Ok(false);
    }
    let body = PhysicsObject::from_grasp_object(object, &params.labels.physics_shape)?;
    let labels = label_grasps(
        object,
        table_from_object,
        &reachable,
        gripper,
        &params.labels.label_params(Some(&body)),
        seed,
    )?;
    Ok(labels.iter().any(|l| l.physics.is_some_and(|p| p.success)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use mvgrasp_geometry::objects::{Category, generate};

    #[test]
    fn policies_parse_as_plan_options_and_a_wrong_name_lists_the_known_ones() {
        let rgb: EvalPolicy = "rgb".parse().unwrap();
        assert_eq!(rgb.options.depth_from, Some(DepthFrom::DEFAULT));
        assert!(!rgb.options.fuse);
        let fused: EvalPolicy = "depth-fused".parse().unwrap();
        assert_eq!(fused.options.depth_from, None);
        assert!(fused.options.fuse);
        for (name, ..) in POLICIES {
            assert!(name.parse::<EvalPolicy>().is_ok(), "{name}");
        }
        let wrong = "sweep".parse::<EvalPolicy>().unwrap_err();
        assert!(wrong.contains("rgb, depth, rgb-fused"), "{wrong}");
    }

    #[test]
    fn a_bowl_rests_open_at_the_top_and_a_mug_both_open_and_lying() {
        let kinds = |category| {
            let mesh = generate(category, 0, 0).unwrap().mesh;
            let object = GraspObject::new(mesh).unwrap();
            let rest = RestingPoses::of(object.mesh()).unwrap();
            rest.iter()
                .map(|(_, pose)| PoseKind::of(&object, &pose.table_from_object, 0.085))
                .collect::<Vec<_>>()
        };
        assert_eq!(kinds(Category::Bowl)[0], PoseKind::Rim);
        let mug = kinds(Category::Mug);
        assert!(mug.contains(&PoseKind::Rim), "{mug:?}");
        assert!(mug.contains(&PoseKind::Lying), "{mug:?}");
    }
}
