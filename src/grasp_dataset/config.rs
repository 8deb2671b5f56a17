//! The typed config of a grasp dataset (one TOML file per dataset).

use std::path::Path;

use mvgrasp_geometry::{Intrinsics, IntrinsicsPreset};
use mvgrasp_grasp::physics::{PhysicsObject, PhysicsParams, ShapeParams};
use mvgrasp_grasp::quality::RobustQualityParams;
use mvgrasp_grasp::{GraspError, Gripper, LabelParams, LabelSettings, SamplingParams};
pub use mvgrasp_planner::CropParams;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result, RuntimeError};

/// Everything that decides a grasp dataset's bytes. Every field has a default; a TOML file
/// sets any of them (unknown keys are errors).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GraspDatasetConfig {
    /// Seeds everything (mixed with each object's name).
    pub seed: u64,
    /// A gripper preset name (`panda`, `yumi`, `robotiq_2f_85`) or a gripper file (TOML,
    /// JSON, Dex-Net `params.json`, URDF).
    pub gripper: String,
    /// An intrinsics preset name (`phoxi_s`, `primesense`, `realsense_d435`).
    pub intrinsics: String,
    /// Where the cameras are.
    pub cameras: CameraDistribution,
    /// The most probable stable poses used per object (marginal ones left out).
    pub stable_poses_per_object: usize,
    /// Antipodal axes sampled per stable pose (each scored once, then seen by every view).
    pub grasps_per_pose: usize,
    /// Cameras per stable pose.
    pub views_per_pose: usize,
    /// A grasp belongs to a view when its approach, turned to lie across its axis, is within
    /// this angle of the optical axis, degrees.
    pub max_tilt_deg: f32,
    /// The image crops.
    pub crop: CropParams,
    /// Depth noise (off by default).
    pub noise: NoiseParams,
    /// Fraction of the collision-free datapoints that also get a physics label, chosen by a
    /// hash of their ids (0 turns physics off; 1 labels every collision-free datapoint).
    pub physics_fraction: f32,
    /// Rapier trials per physics label (K), each with the object's placement, the gripper's
    /// pose and the pads' friction perturbed as robust quality perturbs them
    /// ([`mvgrasp_grasp::physics::PhysicsNoise::matching`] of `quality`); the label is the
    /// share that held.
    pub physics_trials: usize,
    /// Objects per shard (a shard holds whole objects).
    pub objects_per_shard: usize,
    /// Antipodal sampling (friction cone, tries, duplicates, collision margins).
    pub sampling: SamplingParams,
    /// Robust quality (Dex-Net 2.0's perturbations and label threshold).
    pub quality: RobustQualityParams,
    /// Physics trials.
    pub physics: PhysicsParams,
    /// How the physics trials shape each object (the hull or VHACD's parts by default; a shell
    /// of slabs along the surface with `shell = true`).
    pub physics_shape: ShapeParams,
    /// Neighbours packed around each object ([`super::clutter`]); none by default, the object
    /// alone on the table. Not with physics labels: the trial does not simulate neighbours.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub clutter: Option<super::clutter::ClutterParams>,
}

impl Default for GraspDatasetConfig {
    /// The label settings are [`LabelSettings`]'s defaults, the planner's.
    fn default() -> Self {
        let labels = LabelSettings::default();
        Self {
            seed: 0,
            gripper: labels.gripper.name.clone(),
            intrinsics: IntrinsicsPreset::PhoxiS.name().to_string(),
            cameras: CameraDistribution::TopDown(TopDownCameras::default()),
            stable_poses_per_object: 3,
            grasps_per_pose: 100,
            views_per_pose: 10,
            max_tilt_deg: 5.0,
            crop: CropParams::default(),
            noise: NoiseParams::default(),
            physics_fraction: 0.1,
            physics_trials: 1,
            objects_per_shard: 4,
            sampling: labels.sampling,
            quality: labels.quality,
            physics: labels.physics,
            physics_shape: labels.physics_shape,
            clutter: None,
        }
    }
}

/// The two camera distributions of issue 5.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum CameraDistribution {
    /// Dex-Net 2.0's: above the table, looking down.
    TopDown(TopDownCameras),
    /// The multi-view GQ-CNN's: anywhere on the hemisphere, looking at the object.
    MultiView(MultiViewCameras),
}

/// Cameras above the table as Dex-Net 2.0 sampled them.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TopDownCameras {
    /// Distance from the point looked at, metres, uniform in `[min, max]`.
    pub radius_m: [f32; 2],
    /// Largest angle between the optical axis and straight down, degrees (uniform from 0).
    pub max_polar_deg: f32,
    /// The point looked at is the object's centre of mass moved by up to this much in x and y
    /// (uniform), so the object sits off the image centre, metres.
    pub planar_offset_m: f32,
}

impl Default for TopDownCameras {
    fn default() -> Self {
        Self {
            radius_m: [0.65, 0.75],
            max_polar_deg: 18.0,
            planar_offset_m: 0.05,
        }
    }
}

/// Cameras on the hemisphere around the object, optical axis through its centre of mass.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MultiViewCameras {
    /// Distance from the object's centre of mass, metres, uniform in `[min, max]`.
    pub radius_m: [f32; 2],
    /// Elevation of the camera above the table plane, degrees, uniform in `[min, max]` (90 is
    /// straight down).
    pub elevation_deg: [f32; 2],
}

impl Default for MultiViewCameras {
    fn default() -> Self {
        Self {
            radius_m: [0.5, 0.75],
            elevation_deg: [10.0, 90.0],
        }
    }
}

/// Dex-Net's depth noise: a multiplicative Gamma factor per image, and Gaussian noise drawn on
/// a coarse grid and upsampled (so neighbouring pixels move together).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct NoiseParams {
    /// Apply the noise.
    pub enabled: bool,
    /// Shape k of the Gamma factor (mean 1, variance 1/k; Dex-Net: 1000).
    pub gamma_shape: f32,
    /// Standard deviation of the correlated Gaussian noise, metres (Dex-Net: 0.005).
    pub sigma_m: f32,
    /// The Gaussian noise is drawn every this many pixels and interpolated between (Dex-Net's
    /// `gp_rescale_factor`: 4).
    pub correlation_px: u32,
}

impl Default for NoiseParams {
    fn default() -> Self {
        Self {
            enabled: false,
            gamma_shape: 1000.0,
            sigma_m: 0.005,
            correlation_px: 4,
        }
    }
}

impl GraspDatasetConfig {
    /// Reads a TOML config; keys not given keep their defaults.
    ///
    /// # Errors
    /// [`Error::Io`] for an unreadable file; [`Error::ConfigFile`] naming the file for what is
    /// wrong in it: [`Error::Toml`] (malformed, an unknown key, a wrong type) or a value out of
    /// range ([`GraspDatasetConfig::validate`]).
    pub fn from_file(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).map_err(Error::io("read", path))?;
        let config: Self = toml::from_str(&text)
            .map_err(|source| Error::from(RuntimeError::Toml { source }).in_config(path))?;
        config.validate().map_err(|e| e.in_config(path))?;
        Ok(config)
    }

    /// Checks every value that the types do not.
    ///
    /// # Errors
    /// [`Error::ConfigValue`] naming the first bad key, or the gripper's or intrinsics' error.
    pub fn validate(&self) -> Result<()> {
        fn bad(
            key: &'static str,
            value: impl std::fmt::Debug,
            expected: &'static str,
        ) -> Result<()> {
            Err(Error::from(RuntimeError::ConfigValue {
                key,
                value: format!("{value:?}"),
                expected,
            }))
        }
        self.gripper()?;
        self.intrinsics()?;
        for (key, value) in [
            ("stable_poses_per_object", self.stable_poses_per_object),
            ("grasps_per_pose", self.grasps_per_pose),
            ("views_per_pose", self.views_per_pose),
            ("objects_per_shard", self.objects_per_shard),
            ("physics_trials", self.physics_trials),
        ] {
            if value == 0 {
                return bad(key, value, "must be at least 1");
            }
        }
        if !(self.max_tilt_deg.is_finite() && (0.0..90.0).contains(&self.max_tilt_deg)) {
            return bad("max_tilt_deg", self.max_tilt_deg, "must be in [0, 90)");
        }
        if !(0.0..=1.0).contains(&self.physics_fraction) {
            return bad(
                "physics_fraction",
                self.physics_fraction,
                "must be in [0, 1]",
            );
        }
        if let Some(clutter) = &self.clutter {
            clutter.validate()?;
        }
        let c = self.crop;
        if c.size_px == 0 || !c.size_px.is_multiple_of(2) || c.window_px < c.size_px {
            return bad(
                "crop",
                c,
                "size_px must be even and > 0, window_px >= size_px",
            );
        }
        let n = self.noise;
        let noise_ok = n.gamma_shape.is_finite()
            && n.gamma_shape > 0.0
            && n.sigma_m.is_finite()
            && n.sigma_m >= 0.0
            && n.correlation_px > 0;
        if !noise_ok {
            return bad(
                "noise",
                n,
                "gamma_shape > 0, sigma_m >= 0 and correlation_px >= 1",
            );
        }
        let ordered = |r: [f32; 2]| r[0].is_finite() && r[1].is_finite() && r[0] <= r[1];
        match self.cameras {
            CameraDistribution::TopDown(t) => {
                if !(ordered(t.radius_m) && t.radius_m[0] > 0.0) {
                    return bad(
                        "cameras.radius_m",
                        t.radius_m,
                        "must be [min, max] with 0 < min <= max",
                    );
                }
                if !((0.0..=90.0).contains(&t.max_polar_deg)
                    && t.planar_offset_m.is_finite()
                    && t.planar_offset_m >= 0.0)
                {
                    return bad(
                        "cameras",
                        t,
                        "max_polar_deg must be in [0, 90], planar_offset_m >= 0",
                    );
                }
            }
            CameraDistribution::MultiView(m) => {
                if !(ordered(m.radius_m) && m.radius_m[0] > 0.0) {
                    return bad(
                        "cameras.radius_m",
                        m.radius_m,
                        "must be [min, max] with 0 < min <= max",
                    );
                }
                if !(ordered(m.elevation_deg)
                    && m.elevation_deg[0] >= 0.0
                    && m.elevation_deg[1] <= 90.0)
                {
                    return bad(
                        "cameras.elevation_deg",
                        m.elevation_deg,
                        "must be [min, max] within [0, 90]",
                    );
                }
            }
        }
        self.sampling.validate()?;
        self.quality.validate()?;
        self.physics.validate()?;
        self.physics_shape.validate()?;
        Ok(())
    }

    /// The gripper the config names.
    ///
    /// # Errors
    /// [`Error::ConfigValue`] when it is neither a preset nor a readable gripper file.
    pub fn gripper(&self) -> Result<Gripper> {
        Gripper::from_name_or_file(&self.gripper).map_err(|e| match e {
            GraspError::InvalidParameter {
                value, expected, ..
            } => Error::from(RuntimeError::ConfigValue {
                key: "gripper",
                value,
                expected,
            }),
            other => other.into(),
        })
    }

    /// The gripper and the settings that label this dataset's grasps.
    ///
    /// # Errors
    /// See [`Self::gripper`].
    pub fn label_settings(&self) -> Result<LabelSettings> {
        Ok(LabelSettings {
            gripper: self.gripper()?,
            sampling: self.sampling,
            quality: self.quality.clone(),
            physics: self.physics.clone(),
            physics_shape: self.physics_shape,
        })
    }

    /// How this config labels grasps ([`mvgrasp_grasp::label_grasps`]), with a rapier trial on
    /// `body` when given.
    pub fn label_params<'a>(&'a self, body: Option<&'a PhysicsObject>) -> LabelParams<'a> {
        LabelParams {
            quality: &self.quality,
            collision: &self.sampling.collision,
            physics: body.map(|body| (&self.physics, body)),
        }
    }

    /// The intrinsics the config names.
    ///
    /// # Errors
    /// [`Error::ConfigValue`] for an unknown preset name.
    pub fn intrinsics(&self) -> Result<Intrinsics> {
        IntrinsicsPreset::ALL
            .into_iter()
            .find(|p| p.name() == self.intrinsics)
            .map(Intrinsics::preset)
            .ok_or_else(|| {
                Error::from(RuntimeError::ConfigValue {
                    key: "intrinsics",
                    value: format!("{:?}", self.intrinsics),
                    expected: "one of phoxi_s, primesense, realsense_d435",
                })
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The committed configs behind the shipped networks parse, and name the camera
    /// distributions their networks' input contracts assume.
    #[test]
    fn the_shipped_dataset_configs_parse() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("training/configs/datasets");
        let topdown = GraspDatasetConfig::from_file(&dir.join("topdown.toml")).unwrap();
        // Dex-Net 2.0's cameras (the default), and a physics label of 10 trials on every
        // collision-free datapoint.
        assert_eq!(
            topdown,
            GraspDatasetConfig {
                physics_fraction: 1.0,
                physics_trials: 10,
                ..GraspDatasetConfig::default()
            }
        );
        let multiview = GraspDatasetConfig::from_file(&dir.join("multiview.toml")).unwrap();
        assert_eq!(
            multiview.cameras,
            CameraDistribution::MultiView(MultiViewCameras::default())
        );
        assert_eq!(
            GraspDatasetConfig {
                cameras: topdown.cameras,
                ..multiview
            },
            topdown
        );
    }

    /// The planner checks its choice with the settings that labelled the shipped networks'
    /// datasets, and sees with their camera: its quality is the chance the check measures.
    #[test]
    fn the_planner_checks_and_sees_as_the_shipped_datasets_were_labelled() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("training/configs/datasets");
        let planner = crate::planner::PlanParams::default();
        for name in ["topdown.toml", "multiview.toml", "multiview_large.toml"] {
            let config = GraspDatasetConfig::from_file(&dir.join(name)).unwrap();
            assert_eq!(config.label_settings().unwrap(), planner.labels, "{name}");
            assert_eq!(config.intrinsics().unwrap(), planner.intrinsics, "{name}");
        }
    }

    #[test]
    fn a_bad_value_names_its_file_and_key() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("bad.toml");
        std::fs::write(&path, "physics_fraction = 2.0\n").unwrap();
        let err = GraspDatasetConfig::from_file(&path).unwrap_err();
        assert!(
            matches!(&err, Error::Runtime(RuntimeError::ConfigFile { source, .. })
                if matches!(**source, RuntimeError::ConfigValue { key: "physics_fraction", .. })),
            "{err:?}"
        );
        assert!(
            err.to_string()
                .contains("bad.toml: config key physics_fraction = 2.0")
        );
    }
}
