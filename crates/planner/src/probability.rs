//! The chance that a planner's grasp holds in the physics trial. The top-down GQ-CNN's quality
//! is the chance that a grasp is robust under the analytic label, which the trial does not
//! follow closely (on the development set, raw qualities are 15 to 21 points off the share of
//! grasps that held); the multi-view planner's ranker models the trial's outcome of every
//! candidate it re-scores, and the best of them is the one it overrates (its best grasps sit
//! between 0.8 and 0.9 and hold 71% to 81% of the time on held-out objects, the rare ones below
//! 0.7 far less). Per planner and depth source, a logistic map of the quality's logit to the
//! trial's outcome (Platt scaling), fitted on the development set's grasps
//! (`training/scripts/fit_probability.py` on `evaluate --set dev` records;
//! `models/probability_topdown.json` and `models/probability_fused.json`).

use serde::Deserialize;

use crate::error::{PlannerError, Result, parse_tagged};

/// The probability file's format tag.
pub const PROBABILITY_FORMAT: &str = "mvgrasp-probability/1";

/// Which depth the grasp was planned on: the calibration differs (predicted depth misleads the
/// network in ways a depth camera's does not).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DepthSource {
    /// A depth camera's image, or rendered depth (`evaluate`'s `depth` policy).
    Camera,
    /// The plane sweep's depth from RGB views (`evaluate`'s `rgb` policy, the default run).
    Sweep,
}

/// Which planner chose the grasp: each has its own map ([`HoldProbability::shipped`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PlannerKind {
    /// The top-down GQ-CNN on one view (`evaluate`'s `rgb` and `depth` policies).
    TopDown,
    /// The multi-view planner, its quality the ranker's (`rgb-fused` and `depth-fused`).
    MultiView,
}

/// A logistic map of a quality's logit: `P = sigmoid(bias + slope * logit(quality))`.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Calibration {
    /// See the struct.
    pub bias: f32,
    /// See the struct.
    pub slope: f32,
}

/// The fitted maps, one per depth source.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HoldProbability {
    camera: Calibration,
    sweep: Calibration,
    score_floor: f32,
}

#[derive(Deserialize)]
struct ProbabilityFile {
    format: String,
    score_floor: f32,
    policies: Policies,
}

#[derive(Deserialize)]
struct Policies {
    rgb: Calibration,
    depth: Calibration,
}

impl HoldProbability {
    /// Parses a probability file's text; `path` names it in errors.
    ///
    /// # Errors
    /// [`PlannerError::File`] naming `path` for malformed JSON, another format, or a number
    /// that is not finite (or a floor outside (0, 0.5)).
    pub fn from_json(text: &str, path: &std::path::Path) -> Result<Self> {
        let error = |detail: String| PlannerError::file(path, detail);
        let file: ProbabilityFile = parse_tagged(
            text,
            path,
            "probability",
            PROBABILITY_FORMAT,
            |f: &ProbabilityFile| &f.format,
        )?;
        let [rgb, depth] = [file.policies.rgb, file.policies.depth];
        if ![rgb.bias, rgb.slope, depth.bias, depth.slope]
            .iter()
            .all(|v| v.is_finite())
        {
            return Err(error("a bias or slope is not finite".into()));
        }
        if !(file.score_floor > 0.0 && file.score_floor < 0.5) {
            return Err(error(format!(
                "score_floor {}: expected a number in (0, 0.5)",
                file.score_floor
            )));
        }
        Ok(Self {
            camera: depth,
            sweep: rgb,
            score_floor: file.score_floor,
        })
    }

    /// The shipped maps of `planner`'s grasps (`models/probability_topdown.json` and
    /// `models/probability_fused.json`, compiled in).
    ///
    /// # Errors
    /// Only if a shipped file is broken (a test loads them).
    pub fn shipped(planner: PlannerKind) -> Result<Self> {
        let (text, name) = match planner {
            PlannerKind::TopDown => (
                include_str!("../../../models/probability_topdown.json"),
                "models/probability_topdown.json",
            ),
            PlannerKind::MultiView => (
                include_str!("../../../models/probability_fused.json"),
                "models/probability_fused.json",
            ),
        };
        Self::from_json(text, std::path::Path::new(name))
    }

    /// The chance that a grasp of quality `quality` (the network's, or the multi-view
    /// planner's ranker's), planned on `source`, holds in the trial.
    pub fn of(&self, quality: f32, source: DepthSource) -> f32 {
        let map = match source {
            DepthSource::Camera => self.camera,
            DepthSource::Sweep => self.sweep,
        };
        let q = quality.clamp(self.score_floor, 1.0 - self.score_floor);
        let z = map.bias + map.slope * (q / (1.0 - q)).ln();
        1.0 / (1.0 + (-z).exp())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    #[test]
    fn the_shipped_maps_rise_with_quality_and_stay_probabilities() {
        for (planner, source) in [PlannerKind::TopDown, PlannerKind::MultiView]
            .into_iter()
            .flat_map(|k| [(k, DepthSource::Camera), (k, DepthSource::Sweep)])
        {
            let p = HoldProbability::shipped(planner).unwrap();
            let chances: Vec<f32> = [0.0, 0.1, 0.5, 0.9, 0.99, 1.0]
                .iter()
                .map(|&q| p.of(q, source))
                .collect();
            assert!(chances.windows(2).all(|w| w[0] <= w[1]), "{chances:?}");
            assert!(
                chances.iter().all(|c| (0.0..=1.0).contains(c)),
                "{chances:?}"
            );
            assert!(chances[5] - chances[0] > 0.1, "{chances:?}: no spread");
        }
    }

    #[test]
    fn the_map_is_the_logistic_of_the_fitted_line() {
        let text = r#"{"format": "mvgrasp-probability/1", "score_floor": 0.0001,
            "policies": {"rgb": {"bias": 0.0, "slope": 1.0}, "depth": {"bias": -1.0, "slope": 2.0}}}"#;
        let p = HoldProbability::from_json(text, Path::new("p.json")).unwrap();
        // slope 1, bias 0: the quality itself.
        assert!((p.of(0.8, DepthSource::Sweep) - 0.8).abs() < 1e-5);
        // logit(0.5) = 0: sigmoid(-1).
        let expected = 1.0 / (1.0 + 1f32.exp());
        assert!((p.of(0.5, DepthSource::Camera) - expected).abs() < 1e-5);
    }

    #[test]
    fn a_bad_file_is_refused_by_name() {
        let path = Path::new("models/p.json");
        for (text, says) in [
            ("[", "not a probability file"),
            (
                r#"{"format": "x", "score_floor": 0.0001, "policies": {"rgb": {"bias": 0, "slope": 1}, "depth": {"bias": 0, "slope": 1}}}"#,
                "format \"x\"",
            ),
            (
                r#"{"format": "mvgrasp-probability/1", "score_floor": 0.7, "policies": {"rgb": {"bias": 0, "slope": 1}, "depth": {"bias": 0, "slope": 1}}}"#,
                "score_floor 0.7",
            ),
            (
                r#"{"format": "mvgrasp-probability/1", "score_floor": 0.0001, "policies": {"rgb": {"bias": 0}, "depth": {"bias": 0, "slope": 1}}}"#,
                "missing field `slope`",
            ),
        ] {
            let message = HoldProbability::from_json(text, path)
                .unwrap_err()
                .to_string();
            assert!(message.starts_with("models/p.json: "), "{message}");
            assert!(message.contains(says), "{message}");
            assert!(!message.contains('\n'), "{message}");
        }
    }
}
