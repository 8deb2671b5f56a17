//! The multi-view planner's final ranking: the probability that a re-scored candidate holds in
//! physics, from what the planner knows of it, by a logistic model fitted to the physics trials
//! of the planner's own candidates on objects no network and no evaluation set uses
//! (`training/scripts/fit_ranker.py`, `models/ranker_fused.json`).
//!
//! The re-scoring network was trained on top-down crops with the analytic label: its score is
//! calibrated there, and over-confident for tilted approaches (on the development set the
//! candidates it scored 0.95 or more held 87% of the time within 15 degrees of straight down
//! and 66% between 15 and 45). The model weighs its score with the approach's tilt, the
//! proposing network's own score, who proposed it, the grasp's width and its height above the
//! table.

use serde::Deserialize;

use crate::error::{PlannerError, Result, parse_tagged};
use crate::scored::{ScoredGrasp, tilt_rad};

/// The ranker file's format tag.
pub const RANKER_FORMAT: &str = "mvgrasp-ranker/2";

/// The model's inputs, in the order of its weights (see [`Ranker::features`]).
pub const FEATURES: [&str; 9] = [
    "bias",
    "logit_quality",
    "logit_view_quality",
    "tilt",
    "tilt_squared",
    "by_scorer",
    "width",
    "height",
    "from_cloud",
];

/// Scores are clamped to this distance from 0 and 1 before their logit.
const SCORE_FLOOR: f32 = 1e-4;

/// A fitted ranking model.
#[derive(Clone, Debug, PartialEq)]
pub struct Ranker {
    weights: [f32; FEATURES.len()],
}

#[derive(Deserialize)]
struct RankerFile {
    format: String,
    features: Vec<String>,
    weights: Vec<f32>,
}

/// `ln(p / (1 - p))` of a score kept inside (0, 1).
fn logit(p: f32) -> f32 {
    let p = p.clamp(SCORE_FLOOR, 1.0 - SCORE_FLOOR);
    (p / (1.0 - p)).ln()
}

impl Ranker {
    /// Parses a ranker file's text; `path` names it in errors.
    ///
    /// # Errors
    /// [`PlannerError::File`] naming `path` for malformed JSON, another format, features
    /// other than [`FEATURES`] or weights that are not finite.
    pub fn from_json(text: &str, path: &std::path::Path) -> Result<Self> {
        let error = |detail: String| PlannerError::file(path, detail);
        let file: RankerFile =
            parse_tagged(text, path, "ranker", RANKER_FORMAT, |f: &RankerFile| {
                &f.format
            })?;
        if file.features != FEATURES {
            return Err(error(format!(
                "features {:?}, expected {FEATURES:?}",
                file.features
            )));
        }
        let weights: [f32; FEATURES.len()] = file.weights.try_into().map_err(|w: Vec<f32>| {
            error(format!(
                "{} weights for {} features",
                w.len(),
                FEATURES.len()
            ))
        })?;
        if !weights.iter().all(|w| w.is_finite()) {
            return Err(error("a weight is not finite".into()));
        }
        Ok(Self { weights })
    }

    /// The shipped model (`models/ranker_fused.json`, compiled in).
    ///
    /// # Errors
    /// Only if the shipped file is broken (a test loads it).
    pub fn shipped() -> Result<Self> {
        Self::from_json(
            include_str!("../../../models/ranker_fused.json"),
            std::path::Path::new("models/ranker_fused.json"),
        )
    }

    /// The model's inputs for `candidate` on a table at `table_z_m`, in the order of
    /// [`FEATURES`]: the re-score (`virtual_quality`, else `quality`) and the proposing
    /// network's score (`view_quality`, else the same) as logits, the tilt in units of 45
    /// degrees, width and height in units of 5 cm.
    pub fn features(candidate: &ScoredGrasp, table_z_m: f32) -> [f32; FEATURES.len()] {
        let tilt = tilt_rad(&candidate.grasp) / 45f32.to_radians();
        let height = candidate.grasp.world_from_gripper.translation.z - table_z_m;
        let rescore = candidate.virtual_quality.unwrap_or(candidate.quality);
        [
            1.0,
            logit(rescore),
            logit(candidate.view_quality.unwrap_or(rescore)),
            tilt,
            tilt * tilt,
            f32::from(u8::from(candidate.by_scorer)),
            candidate.grasp.width_m / 0.05,
            height / 0.05,
            f32::from(u8::from(candidate.from_cloud)),
        ]
    }

    /// The probability that `candidate` holds (see the module docs).
    pub fn probability(&self, candidate: &ScoredGrasp, table_z_m: f32) -> f32 {
        let x = Self::features(candidate, table_z_m);
        let z: f32 = x.iter().zip(&self.weights).map(|(x, w)| x * w).sum();
        1.0 / (1.0 + (-z).exp())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_scenes::{box_view, centred_candidate};
    use std::path::Path;

    /// A top-down grasp 4 cm wide across the box 3 cm above the table, with these scores.
    fn candidate(quality: f32, view_quality: f32) -> ScoredGrasp {
        ScoredGrasp {
            quality,
            view_quality: Some(view_quality),
            ..centred_candidate(&box_view(false), 0.0, 0.67, 0.04)
        }
    }

    #[test]
    fn the_shipped_ranker_loads_and_prefers_the_better_scored_candidate() {
        let ranker = Ranker::shipped().unwrap();
        let (good, poor) = (candidate(0.99, 0.9), candidate(0.6, 0.9));
        let p = ranker.probability(&good, 0.0);
        assert!((0.0..=1.0).contains(&p));
        assert!(p > ranker.probability(&poor, 0.0));
        // A top-down grasp 3 cm above the table, 4 cm wide.
        let x = Ranker::features(&good, 0.0);
        assert!(x[3].abs() < 0.01, "{x:?}");
        assert!(
            (x[6] - 0.8).abs() < 1e-6 && (x[7] - 0.6).abs() < 1e-3,
            "{x:?}"
        );
    }

    #[test]
    fn bad_ranker_files_name_the_file_and_the_problem() {
        let path = Path::new("r.json");
        let features = serde_json::to_string(&FEATURES).unwrap();
        let cases = [
            ("{", "not a ranker file"),
            (
                r#"{"format": "x", "features": [], "weights": []}"#,
                "format",
            ),
            (
                r#"{"format": "mvgrasp-ranker/2", "features": ["bias"], "weights": [0]}"#,
                "features",
            ),
        ];
        for (text, want) in cases {
            let err = Ranker::from_json(text, path).unwrap_err().to_string();
            assert!(err.contains("r.json") && err.contains(want), "{err}");
        }
        let short =
            format!(r#"{{"format": "{RANKER_FORMAT}", "features": {features}, "weights": [1]}}"#);
        let err = Ranker::from_json(&short, path).unwrap_err().to_string();
        assert!(err.contains("1 weights for 9 features"), "{err}");
        let weights = format!("[{}]", ["1"; 9].join(","));
        let fine = format!(
            r#"{{"format": "{RANKER_FORMAT}", "features": {features}, "weights": {weights}}}"#
        );
        Ranker::from_json(&fine, path).unwrap();
    }
}
