//! Parameters of robust grasp quality, with Dex-Net 2.0's values as defaults.

use serde::{Deserialize, Serialize};

use crate::error::{GraspError, Result};
use crate::quality::closure::validate_friction_coef;
use crate::quality::wrench::WrenchParams;

/// Uncertainty and contact model of [`crate::quality::robust_quality`].
///
/// Defaults are Dex-Net 2.0's robust Ferrari-Canny metric (`metrics.robust_ferrari_canny` in
/// BerkeleyAutomation/dex-net `test/config.yaml`; the sampling is `random_variables.py`):
/// friction 0.5 with sigma 0.1, gripper translation sigma 5 mm and rotation sigma 0.001 rad,
/// object translation sigma 1 cm and rotation sigma 0.01 rad, 25 samples, 8 cone facets,
/// soft fingers, and the 0.002 threshold of the Dex-Net 2.0 paper for a positive label.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RobustQualityParams {
    /// Mean Coulomb friction coefficient (Dex-Net: `friction_coef: 0.5`); also the one the
    /// nominal (unperturbed) evaluation uses.
    pub friction_coef_mean: f32,
    /// Standard deviation of the sampled friction coefficient (Dex-Net:
    /// `sigma_friction_coef: 0.1`).
    pub friction_coef_sigma: f32,
    /// Floor of the sampled friction coefficient: a draw below it is raised to it, so every
    /// sample has a valid (> 0) coefficient. Dex-Net clamps at 0, which means no force
    /// closure; a floor of 0.01 gives the same verdict for any real grasp. At sigma 0.1 around
    /// 0.5 a draw below it has probability about 5e-7.
    pub friction_coef_min: f32,
    /// Standard deviation of the gripper's translation along each axis, metres (Dex-Net:
    /// `sigma_grasp_trans_{x,y,z}: 0.005`).
    pub gripper_translation_sigma_m: f32,
    /// Standard deviation of the gripper's rotation about each axis, radians (Dex-Net:
    /// `sigma_grasp_rot_{x,y,z}: 0.001`).
    pub gripper_rotation_sigma_rad: f32,
    /// Standard deviation of the object's translation along each axis, metres (Dex-Net:
    /// `sigma_obj_trans_{x,y,z}: 0.01`).
    pub object_translation_sigma_m: f32,
    /// Standard deviation of the object's rotation about each axis (about its centre of
    /// mass), radians (Dex-Net: `sigma_obj_rot_{x,y,z}: 0.01`).
    pub object_rotation_sigma_rad: f32,
    /// Perturbed evaluations averaged (Dex-Net: `num_quality_samples: 25`).
    pub num_samples: usize,
    /// Robust epsilon above which a collision-free grasp is labelled positive (Dex-Net 2.0:
    /// 0.002).
    pub positive_threshold: f64,
    /// Friction cones and soft fingers.
    pub wrench: WrenchParams,
}

impl Default for RobustQualityParams {
    fn default() -> Self {
        Self {
            friction_coef_mean: 0.5,
            friction_coef_sigma: 0.1,
            friction_coef_min: 0.01,
            gripper_translation_sigma_m: 0.005,
            gripper_rotation_sigma_rad: 0.001,
            object_translation_sigma_m: 0.01,
            object_rotation_sigma_rad: 0.01,
            num_samples: 25,
            positive_threshold: 0.002,
            wrench: WrenchParams::default(),
        }
    }
}

impl RobustQualityParams {
    /// Every parameter at its value but no uncertainty: each sample is the nominal grasp.
    pub fn deterministic(&self) -> Self {
        Self {
            friction_coef_sigma: 0.0,
            gripper_translation_sigma_m: 0.0,
            gripper_rotation_sigma_rad: 0.0,
            object_translation_sigma_m: 0.0,
            object_rotation_sigma_rad: 0.0,
            ..self.clone()
        }
    }

    /// Checks every field: friction mean and floor finite and > 0, sigmas finite and >= 0, at
    /// least one sample, a finite threshold >= 0, and the wrench parameters.
    ///
    /// # Errors
    /// [`GraspError::InvalidParameter`] naming the first bad field.
    pub fn validate(&self) -> Result<()> {
        validate_friction_coef("robust quality", self.friction_coef_mean)?;
        let bad = |name, value: String, expected| {
            Err(GraspError::InvalidParameter {
                op: "robust quality",
                name,
                value,
                expected,
            })
        };
        if !(self.friction_coef_min.is_finite() && self.friction_coef_min > 0.0) {
            return bad(
                "friction_coef_min",
                self.friction_coef_min.to_string(),
                "a finite number > 0",
            );
        }
        for (name, value) in [
            ("friction_coef_sigma", self.friction_coef_sigma),
            (
                "gripper_translation_sigma_m",
                self.gripper_translation_sigma_m,
            ),
            (
                "gripper_rotation_sigma_rad",
                self.gripper_rotation_sigma_rad,
            ),
            (
                "object_translation_sigma_m",
                self.object_translation_sigma_m,
            ),
            ("object_rotation_sigma_rad", self.object_rotation_sigma_rad),
        ] {
            if !(value.is_finite() && value >= 0.0) {
                return bad(name, value.to_string(), "a finite number >= 0");
            }
        }
        if self.num_samples == 0 {
            return bad("num_samples", "0".into(), "at least 1");
        }
        if !(self.positive_threshold.is_finite() && self.positive_threshold >= 0.0) {
            return bad(
                "positive_threshold",
                self.positive_threshold.to_string(),
                "a finite number >= 0",
            );
        }
        self.wrench.validate()
    }

    /// Dex-Net 2.0's training label: positive when the robust epsilon exceeds
    /// [`RobustQualityParams::positive_threshold`] and the gripper is collision free.
    pub fn dexnet_label(&self, robust_epsilon: f64, collision_free: bool) -> bool {
        collision_free && robust_epsilon > self.positive_threshold
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_validate_and_round_trip_through_json() {
        let params = RobustQualityParams::default();
        params.validate().unwrap();
        let json = serde_json::to_string(&params).unwrap();
        let back: RobustQualityParams = serde_json::from_str(&json).unwrap();
        assert_eq!(back, params);
        // Partial configs fill in the defaults; unknown keys are refused.
        let partial: RobustQualityParams =
            serde_json::from_str(r#"{"num_samples": 5, "wrench": {"num_cone_faces": 4}}"#).unwrap();
        assert_eq!(partial.num_samples, 5);
        assert_eq!(partial.wrench.num_cone_faces, 4);
        assert_eq!(partial.friction_coef_mean, 0.5);
        assert!(serde_json::from_str::<RobustQualityParams>(r#"{"samples": 5}"#).is_err());
    }

    #[test]
    fn bad_fields_are_named() {
        let cases: [(RobustQualityParams, &str); 4] = [
            (
                RobustQualityParams {
                    friction_coef_mean: 0.0,
                    ..Default::default()
                },
                "friction_coef",
            ),
            (
                RobustQualityParams {
                    object_rotation_sigma_rad: f32::NAN,
                    ..Default::default()
                },
                "object_rotation_sigma_rad",
            ),
            (
                RobustQualityParams {
                    num_samples: 0,
                    ..Default::default()
                },
                "num_samples",
            ),
            (
                RobustQualityParams {
                    positive_threshold: -1.0,
                    ..Default::default()
                },
                "positive_threshold",
            ),
        ];
        for (params, name) in cases {
            let err = params.validate().unwrap_err().to_string();
            assert!(err.contains(name), "{err}");
        }
    }

    #[test]
    fn labels_need_both_quality_and_no_collision() {
        let params = RobustQualityParams::default();
        assert!(params.dexnet_label(0.0021, true));
        assert!(!params.dexnet_label(0.0021, false));
        assert!(!params.dexnet_label(0.002, true));
    }
}
