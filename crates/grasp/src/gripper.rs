//! Parallel-jaw gripper parameters, with presets.

use serde::{Deserialize, Serialize};

use crate::error::{GraspError, Result};

/// A parallel-jaw gripper, in the gripper frame of [`crate::Grasp`]: fingers close along x,
/// approach along z, the origin midway between the finger tips.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
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
}

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
        Self {
            name: preset.name().to_string(),
            max_opening_m,
            min_opening_m: 0.0,
            finger_length_m,
            finger_width_m,
            finger_thickness_m,
            force_limit_n,
        }
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
            ("finger_length_m", self.finger_length_m),
            ("finger_width_m", self.finger_width_m),
            ("finger_thickness_m", self.finger_thickness_m),
            ("force_limit_n", self.force_limit_n),
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
        Ok(())
    }

    /// Whether an object `width_m` wide fits between the open fingers and is not narrower than
    /// they close.
    pub fn fits(&self, width_m: f32) -> bool {
        (self.min_opening_m..=self.max_opening_m).contains(&width_m)
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
    }
}
