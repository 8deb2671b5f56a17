//! The multi-view planner's ranker data (`training/scripts/fit_ranker.py` fits
//! `models/ranker_fused.json` to it): the planner plans on an object at rest from rendered
//! depth, and every candidate it re-scored on virtual views is tried in the physics trial.
//!
//! The planner is the default run's multi-view planner (`plan --depth-from rendered`: 5
//! views 0.65 m away, the first top-down, the top-down GQ-CNN re-scoring the best 10 of each
//! view) without the ranker it is fitted for, so the candidates come in the re-score's order;
//! with `ranked` the shipped ranker orders them (its re-score is then `virtual_quality`).

use mvgrasp_geometry::TriangleMesh;
use mvgrasp_grasp::GraspObject;
use mvgrasp_planner::tilt_rad;
use mvgrasp_render::Renderer;
use serde::{Deserialize, Serialize};

use crate::error::Result;
use crate::planner::{PlanOptions, PlanParams, Planner, check_grasps, models, plan_grasp};

/// One re-scored candidate and its trial: a line of the data `fit_ranker.py` reads.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RankerSample {
    /// The object's name.
    pub object: String,
    /// The planner that made it (`fused-5`: the multi-view planner over 5 views).
    pub policy: String,
    /// Its place in the planner's order (0: the grasp the planner returns).
    pub rank: usize,
    /// Its quality: the re-score, or with a ranker the ranker's chance.
    pub quality: f32,
    /// The proposing network's score in its view.
    pub view_quality: Option<f32>,
    /// The re-score on virtual views, where a ranker ordered the candidates.
    pub virtual_quality: Option<f32>,
    /// The view it was proposed in.
    pub view: usize,
    /// Its angle in that view's image, radians.
    pub theta_rad: f32,
    /// Proposed by the re-scoring network in the top-down view.
    pub by_scorer: bool,
    /// Proposed from the fused point cloud.
    pub from_cloud: bool,
    /// The approach's angle from straight down, degrees.
    pub tilt_deg: f32,
    /// The jaws' width, metres.
    pub width_m: f32,
    /// The grasp centre's height in the world (the table at 0), metres.
    pub z_m: f32,
    /// Dex-Net 2.0's robust label.
    pub robust: bool,
    /// Whether it held in the trial (`None`: not tried).
    pub held: Option<bool>,
    /// Where the trial failed (`Settle`: the object left its resting pose before the hand
    /// came; the fit leaves those out).
    pub failed_at: Option<String>,
}

/// The planner and settings that make the data.
pub struct RankerData {
    planner: Planner,
    params: PlanParams,
}

impl RankerData {
    /// The default run's multi-view planner on rendered depth, without the shipped ranker
    /// unless `ranked`.
    ///
    /// # Errors
    /// Shipped weights that cannot be loaded.
    pub fn new(ranked: bool) -> Result<Self> {
        let options = PlanOptions {
            fuse: true,
            ..PlanOptions::default()
        };
        let net = models::shipped(options.default_model())
            .ok_or_else(|| crate::Error::Evaluate {
                problem: format!("no shipped network {:?}", options.default_model()),
            })?
            .load()?;
        let (mut planner, params) = options.on_mesh(net)?;
        if let (Planner::MultiView(planner), false) = (&mut planner, ranked) {
            planner.scorer.ranker = None;
        }
        Ok(Self { planner, params })
    }

    /// Plans on `mesh` (named `object`) in its most probable resting pose and tries every
    /// re-scored candidate in the trial; none when nothing was re-scored.
    ///
    /// # Errors
    /// A mesh with no stable pose, or a renderer, network or trial error.
    pub fn samples(
        &self,
        renderer: &Renderer,
        object: &str,
        mesh: &TriangleMesh,
    ) -> Result<Vec<RankerSample>> {
        let report = plan_grasp(renderer, mesh, &self.planner, &self.params)?;
        let rescored: Vec<_> = report
            .candidates
            .iter()
            .take_while(|c| c.view_quality.is_some())
            .copied()
            .collect();
        if rescored.is_empty() {
            return Ok(Vec::new());
        }
        let labels = check_grasps(
            &GraspObject::new(mesh.clone())?,
            &report.table_from_object,
            &rescored,
            &self.params.labels.gripper,
            &self.params,
        )?;
        Ok(rescored
            .iter()
            .zip(&labels)
            .enumerate()
            .map(|(rank, (c, l))| RankerSample {
                object: object.to_string(),
                policy: format!("fused-{}", self.params.max_views),
                rank,
                quality: c.quality,
                view_quality: c.view_quality,
                virtual_quality: c.virtual_quality,
                view: c.view,
                theta_rad: c.theta_rad,
                by_scorer: c.by_scorer,
                from_cloud: c.from_cloud,
                tilt_deg: tilt_rad(&c.grasp).to_degrees(),
                width_m: c.grasp.width_m,
                z_m: c.grasp.world_from_gripper.translation.z,
                robust: l.robust,
                held: l.physics.map(|p| p.success),
                failed_at: l
                    .physics
                    .and_then(|p| p.failed_at)
                    .map(|f| format!("{f:?}")),
            })
            .collect())
    }
}
