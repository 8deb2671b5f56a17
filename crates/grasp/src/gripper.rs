//! Parallel-jaw gripper parameters: presets, files (TOML, JSON, Dex-Net's `params.json`).

use std::path::Path;

use mvgrasp_geometry::Vec3;
use serde::{Deserialize, Serialize};

use crate::error::{GraspError, Result};

/// A parallel-jaw gripper, in the gripper frame of [`crate::Grasp`]: fingers close along x,
/// approach along z, the origin midway between the finger tips.
///
/// Collision geometry: two finger boxes (`finger_thickness_m` x `finger_width_m` x
/// `finger_length_m`) spanning z in `[-finger_length_m, 0]` at x = +-(opening / 2 +
/// thickness / 2), and a palm box of `palm_size_m` centred on the z axis behind them
/// ([`Gripper::finger_center`], [`Gripper::palm_center`]). Each finger's inner face carries a
/// round pad of `pad_radius_m` at its tip end, where it grips with `pad_friction`. The hand
/// opens to the grasp's width plus `open_margin_m` ([`Gripper::opening_for`]), as a controller
/// does, and every check uses that one geometry: the dataset's collision check, the planner's
/// hand check and the physics trial bring the open hand in from `approach_distance_m` back along
/// its approach.
///
/// In a file (TOML or JSON) every field is optional and defaults to the Panda preset's, so
/// `max_opening_m = 0.06` alone is a Panda with a narrower stroke.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Gripper {
    /// A short name ("panda", "yumi", "robotiq_2f_85").
    pub name: String,
    /// Widest opening between the finger pads, metres.
    pub max_opening_m: f32,
    /// Narrowest opening, metres.
    pub min_opening_m: f32,
    /// Finger length along the approach axis: how deep the fingers reach past the palm, metres.
    pub finger_length_m: f32,
    /// Finger width across the closing axis (along gripper y), metres.
    pub finger_width_m: f32,
    /// Finger thickness along the closing axis, metres.
    pub finger_thickness_m: f32,
    /// Largest closing force, newtons.
    pub force_limit_n: f32,
    /// Palm box behind the fingers: extent along the closing axis (x), across it (y) and
    /// along the approach (z), metres.
    pub palm_size_m: [f32; 3],
    /// The pre-grasp pose stands this far back along -z from the grasp; the open hand comes in
    /// straight from there, metres.
    pub approach_distance_m: f32,
    /// Radius of the round contact pad on each finger's inner face, centred across the finger
    /// and `pad_radius_m` back from its tip, metres (Dex-Net's `finger_radius`, the soft-finger
    /// contact radius). At most half the finger's width and length.
    pub pad_radius_m: f32,
    /// Coulomb friction between a pad (or any part of the hand) and an object.
    pub pad_friction: f32,
    /// The open hand stands this much wider than the grasp's width (at most `max_opening_m`),
    /// metres.
    pub open_margin_m: f32,
}

/// Pad friction unless a gripper file says otherwise (the usual value for rubber pads on household
/// objects, and Dex-Net's friction coefficient).
pub const DEFAULT_PAD_FRICTION: f32 = 0.5;

/// How much wider than the grasp the hand opens unless a gripper file says otherwise, metres.
pub const DEFAULT_OPEN_MARGIN_M: f32 = 0.02;

/// The grippers mvgrasp knows by name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GripperPreset {
    /// Franka Emika Panda hand: 8 cm opening, 5 cm fingers, 70 N continuous. The default.
    Panda,
    /// ABB YuMi with Dex-Net 2.0's metal spline fingers: 5 cm opening, 20 N.
    Yumi,
    /// Robotiq 2F-85: 8.5 cm opening, 235 N.
    Robotiq2f85,
}

impl GripperPreset {
    /// Every preset.
    pub const ALL: [GripperPreset; 3] = [Self::Panda, Self::Yumi, Self::Robotiq2f85];

    /// The preset's name in configs and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Self::Panda => "panda",
            Self::Yumi => "yumi",
            Self::Robotiq2f85 => "robotiq_2f_85",
        }
    }
}

impl std::str::FromStr for GripperPreset {
    type Err = GraspError;

    fn from_str(name: &str) -> Result<Self> {
        Self::ALL
            .into_iter()
            .find(|p| p.name() == name)
            .ok_or_else(|| GraspError::InvalidParameter {
                op: "gripper preset",
                name: "preset",
                value: name.to_string(),
                expected: "one of panda, yumi, robotiq_2f_85",
            })
    }
}

impl Default for Gripper {
    fn default() -> Self {
        Self::preset(GripperPreset::Panda)
    }
}

impl Gripper {
    /// A named preset (opening and force from the makers' sheets and Dex-Net's `params.json`).
    pub fn preset(preset: GripperPreset) -> Self {
        let (max_opening_m, finger_length_m, finger_width_m, finger_thickness_m, force_limit_n) =
            match preset {
                GripperPreset::Panda => (0.08, 0.05, 0.02, 0.012, 70.0),
                GripperPreset::Yumi => (0.05, 0.03, 0.02, 0.01, 20.0),
                GripperPreset::Robotiq2f85 => (0.085, 0.04, 0.022, 0.01, 235.0),
            };
        // Hand bodies, from the makers' drawings, rounded to a box.
        let palm_size_m = match preset {
            GripperPreset::Panda => [0.20, 0.06, 0.06],
            GripperPreset::Yumi => [0.08, 0.04, 0.04],
            GripperPreset::Robotiq2f85 => [0.15, 0.06, 0.09],
        };
        Self {
            name: preset.name().to_string(),
            max_opening_m,
            min_opening_m: 0.0,
            finger_length_m,
            finger_width_m,
            finger_thickness_m,
            force_limit_n,
            palm_size_m,
            approach_distance_m: 0.08,
            pad_radius_m: finger_width_m / 2.0,
            pad_friction: DEFAULT_PAD_FRICTION,
            open_margin_m: DEFAULT_OPEN_MARGIN_M,
        }
    }

    /// Half extents of a finger box: thickness along x, width along y, length along z.
    pub fn finger_half_extents(&self) -> Vec3 {
        Vec3::new(
            self.finger_thickness_m,
            self.finger_width_m,
            self.finger_length_m,
        ) / 2.0
    }

    /// Gripper-frame centre of the finger on the `side` of +x (`1.0`) or -x (`-1.0`) when the
    /// fingers stand `opening_m` apart.
    pub fn finger_center(&self, opening_m: f32, side: f32) -> Vec3 {
        Vec3::new(
            side * (opening_m + self.finger_thickness_m) / 2.0,
            0.0,
            -self.finger_length_m / 2.0,
        )
    }

    /// Half extents of the palm box.
    pub fn palm_half_extents(&self) -> Vec3 {
        Vec3::from_array(self.palm_size_m) / 2.0
    }

    /// Gripper-frame centre of the palm box, right behind the fingers.
    pub fn palm_center(&self) -> Vec3 {
        Vec3::new(0.0, 0.0, -self.finger_length_m - self.palm_size_m[2] / 2.0)
    }

    /// The gripper `spec` names: a preset (`panda`, `yumi`, `robotiq_2f_85`), or else a gripper
    /// file of that path ([`Gripper::from_file`]).
    ///
    /// # Errors
    /// [`GraspError::InvalidParameter`] when `spec` is neither a preset nor a file that exists;
    /// [`Gripper::from_file`]'s for a file it cannot use.
    pub fn from_name_or_file(spec: &str) -> Result<Self> {
        if let Ok(preset) = spec.parse::<GripperPreset>() {
            return Ok(Self::preset(preset));
        }
        if Path::new(spec).exists() {
            return Self::from_file(spec);
        }
        Err(GraspError::InvalidParameter {
            op: "gripper",
            name: "gripper",
            value: format!("{spec:?}"),
            expected: "a preset (panda, yumi, robotiq_2f_85) or a gripper file that exists",
        })
    }

    /// Reads a gripper from a file: `.toml` or `.json` with [`Gripper`]'s fields (missing ones
    /// are the Panda's), Dex-Net's `params.json` (`min_width`, `max_width`, `force_limit`,
    /// `finger_radius`; the other dimensions are the Panda's), or a `.urdf` measured with the
    /// default [`crate::UrdfGripperSpec`] ([`Gripper::from_urdf`]), then validates it.
    ///
    /// # Errors
    /// [`GraspError::GripperFile`] naming the file when it cannot be read or parsed, has an
    /// unknown field, or describes an invalid gripper.
    pub fn from_file(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let fail = |detail: String| GraspError::GripperFile {
            detail,
            path: path.to_path_buf(),
        };
        let extension = path
            .extension()
            .and_then(|e| e.to_str())
            .unwrap_or_default();
        if extension == "urdf" {
            return Self::from_urdf(path, &crate::UrdfGripperSpec::default()).map(|u| u.gripper);
        }
        let text = std::fs::read_to_string(path).map_err(|e| fail(e.to_string()))?;
        // One parse into a JSON value, whatever the format; its keys say what kind of file it is.
        let value: serde_json::Value = match extension {
            "toml" => toml::from_str::<toml::Table>(&text)
                .map_err(|e| mvgrasp_geometry::one_line(&e.to_string()))
                .and_then(|table| serde_json::to_value(table).map_err(|e| e.to_string())),
            "json" => {
                serde_json::from_str(&text).map_err(|e| mvgrasp_geometry::one_line(&e.to_string()))
            }
            other => Err(format!(
                "unknown extension {other:?}: expected .toml, .json or .urdf"
            )),
        }
        .map_err(fail)?;
        let names_itself = value.get("name").is_some();
        let mut gripper = if value.get("max_width").is_some() {
            serde_json::from_value::<DexNetParams>(value).map(DexNetParams::into_gripper)
        } else {
            serde_json::from_value::<Gripper>(value)
        }
        .map_err(|e| fail(mvgrasp_geometry::one_line(&e.to_string())))?;
        if !names_itself {
            gripper.name = path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default();
        }
        gripper.validate().map_err(|e| fail(e.to_string()))?;
        Ok(gripper)
    }

    /// Checks that every dimension is finite and positive and the openings are ordered.
    ///
    /// # Errors
    /// [`GraspError::InvalidParameter`] naming the first bad field.
    pub fn validate(&self) -> Result<()> {
        let bad = |name, value: f32, expected| {
            Err(GraspError::InvalidParameter {
                op: "gripper",
                name,
                value: value.to_string(),
                expected,
            })
        };
        for (name, value) in [
            ("max_opening_m", self.max_opening_m),
            ("palm_size_m[0]", self.palm_size_m[0]),
            ("palm_size_m[1]", self.palm_size_m[1]),
            ("palm_size_m[2]", self.palm_size_m[2]),
            ("approach_distance_m", self.approach_distance_m),
            ("finger_length_m", self.finger_length_m),
            ("finger_width_m", self.finger_width_m),
            ("finger_thickness_m", self.finger_thickness_m),
            ("force_limit_n", self.force_limit_n),
            ("pad_radius_m", self.pad_radius_m),
            ("pad_friction", self.pad_friction),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return bad(name, value, "a finite number > 0");
            }
        }
        if !(self.min_opening_m.is_finite()
            && (0.0..self.max_opening_m).contains(&self.min_opening_m))
        {
            return bad(
                "min_opening_m",
                self.min_opening_m,
                "0 <= min_opening_m < max_opening_m",
            );
        }
        if self.pad_radius_m > 0.5 * self.finger_width_m.min(self.finger_length_m) {
            return bad(
                "pad_radius_m",
                self.pad_radius_m,
                "at most half the finger's width and length",
            );
        }
        if !(self.open_margin_m.is_finite() && self.open_margin_m >= 0.0) {
            return bad("open_margin_m", self.open_margin_m, "a finite number >= 0");
        }
        Ok(())
    }

    /// How far the hand opens for a grasp `width_m` wide: the width plus `open_margin_m`,
    /// within the gripper's range, metres.
    pub fn opening_for(&self, width_m: f32) -> f32 {
        let open = width_m + self.open_margin_m;
        if open.is_nan() {
            return self.max_opening_m;
        }
        open.clamp(self.min_opening_m, self.max_opening_m)
    }

    /// Gripper-frame centre of the pad on the `side` of +x (`1.0`) or -x (`-1.0`) when the
    /// fingers stand `opening_m` apart: on the finger's inner face, `pad_radius_m` back from
    /// its tip.
    pub fn pad_center(&self, opening_m: f32, side: f32) -> Vec3 {
        Vec3::new(side * opening_m / 2.0, 0.0, -self.pad_radius_m)
    }

    /// Opening plus both fingers: the hand's reach along the closing axis when fully open.
    pub fn open_span_m(&self) -> f32 {
        self.max_opening_m + 2.0 * self.finger_thickness_m
    }

    /// Whether an object `width_m` wide fits between the open fingers and is not narrower than
    /// they close.
    pub fn fits(&self, width_m: f32) -> bool {
        (self.min_opening_m..=self.max_opening_m).contains(&width_m)
    }
}

/// Dex-Net's gripper `params.json`.
#[derive(Deserialize)]
struct DexNetParams {
    min_width: f32,
    max_width: f32,
    force_limit: f32,
    /// Dex-Net's soft-finger contact radius; the finger width here is its diameter.
    finger_radius: Option<f32>,
}

impl DexNetParams {
    fn into_gripper(self) -> Gripper {
        let panda = Gripper::default();
        Gripper {
            name: String::new(),
            min_opening_m: self.min_width,
            max_opening_m: self.max_width,
            force_limit_n: self.force_limit,
            finger_width_m: self.finger_radius.map_or(panda.finger_width_m, |r| 2.0 * r),
            pad_radius_m: self.finger_radius.unwrap_or(panda.pad_radius_m),
            ..panda
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_validate_and_parse() {
        for preset in GripperPreset::ALL {
            Gripper::preset(preset).validate().unwrap();
            assert_eq!(preset.name().parse::<GripperPreset>().unwrap(), preset);
        }
        assert_eq!(Gripper::default().max_opening_m, 0.08);
        assert_eq!(Gripper::preset(GripperPreset::Yumi).max_opening_m, 0.05);
        assert_eq!(
            Gripper::preset(GripperPreset::Robotiq2f85).max_opening_m,
            0.085
        );
        assert!("barrett".parse::<GripperPreset>().is_err());
    }

    #[test]
    fn bad_grippers_are_rejected_by_field() {
        let wide = Gripper {
            min_opening_m: 0.1,
            ..Gripper::default()
        };
        let err = wide.validate().unwrap_err().to_string();
        assert!(err.contains("min_opening_m"), "{err}");
        let weak = Gripper {
            force_limit_n: f32::NAN,
            ..Gripper::default()
        };
        assert!(
            weak.validate()
                .unwrap_err()
                .to_string()
                .contains("force_limit_n")
        );
        assert!(Gripper::default().fits(0.05) && !Gripper::default().fits(0.09));
        let big_pad = Gripper {
            pad_radius_m: 0.011,
            ..Gripper::default()
        };
        let err = big_pad.validate().unwrap_err().to_string();
        assert!(err.contains("pad_radius_m"), "{err}");
        let negative_margin = Gripper {
            open_margin_m: -0.01,
            ..Gripper::default()
        };
        assert!(negative_margin.validate().is_err());
    }

    #[test]
    fn the_hand_opens_to_the_grasp_width_plus_the_margin_within_its_stroke() {
        let panda = Gripper::default();
        assert!((panda.opening_for(0.03) - 0.05).abs() < 1e-6);
        assert_eq!(panda.opening_for(0.07), 0.08);
        assert_eq!(panda.opening_for(-0.05), 0.0);
        assert_eq!(panda.opening_for(f32::NAN), 0.08);
    }
}

#[cfg(test)]
mod file_tests {
    use super::*;

    fn write(name: &str, text: &str) -> (tempfile::TempDir, std::path::PathBuf) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join(name);
        std::fs::write(&path, text).unwrap();
        (dir, path)
    }

    #[test]
    fn toml_overrides_the_panda() {
        let (_d, path) = write(
            "narrow.toml",
            "max_opening_m = 0.06\nforce_limit_n = 30.0\n",
        );
        let g = Gripper::from_file(&path).unwrap();
        assert_eq!((g.max_opening_m, g.force_limit_n), (0.06, 30.0));
        assert_eq!(g.finger_length_m, Gripper::default().finger_length_m);
        assert_eq!(g.name, "narrow");
    }

    #[test]
    fn dexnet_params_json_is_read() {
        let (_d, path) = write(
            "params.json",
            r#"{"min_width": 0.0, "force_limit": 20.0, "max_width": 0.05, "finger_radius": 0.01}"#,
        );
        let g = Gripper::from_file(&path).unwrap();
        assert_eq!(
            (g.max_opening_m, g.force_limit_n, g.finger_width_m),
            (0.05, 20.0, 0.02)
        );
    }

    #[test]
    fn bad_files_name_the_file_and_the_problem() {
        let (_d, path) = write("typo.toml", "max_openin_m = 0.06\n");
        let err = Gripper::from_file(&path).unwrap_err().to_string();
        assert!(
            err.contains("typo.toml") && err.contains("max_openin_m"),
            "{err}"
        );
        let (_d, path) = write("wide.json", r#"{"min_opening_m": 0.2}"#);
        let err = Gripper::from_file(&path).unwrap_err().to_string();
        assert!(
            err.contains("wide.json") && err.contains("min_opening_m"),
            "{err}"
        );
        let err = Gripper::from_file("/nonexistent/g.toml")
            .unwrap_err()
            .to_string();
        assert!(err.contains("/nonexistent/g.toml"), "{err}");
    }
}
