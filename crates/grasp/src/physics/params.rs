//! The knobs of a physics trial ([`PhysicsParams`]) and of the pose noise that
//! [`crate::physics::success_probability`] samples ([`PhysicsNoise`]).

use serde::{Deserialize, Serialize};

use crate::error::{GraspError, Result};
use crate::object::DEFAULT_DENSITY_KG_M3;
use crate::quality::RobustQualityParams;

/// How a grasp is simulated and judged (see [`crate::physics`] for the phases).
///
/// The defaults keep a trial near 400 rapier steps; the solver settings (8 iterations, 300 Hz
/// contacts, length unit 0.3) were picked on a can lying on its side and a 20 cm stick held by its
/// end: with rapier's defaults (4 iterations, 30 Hz contacts), 100 Hz contacts or a length unit
/// of 0.1 the fingers sink into the object, or it creeps in the hand, under a 70 N squeeze:
///
/// | field | default | |
/// |---|---|---|
/// | `timestep_s` | 1/240 s | rapier step |
/// | `solver_iterations` | 8 | rapier's `num_solver_iterations` (substeps) |
/// | `solver_length_unit_m` | 0.3 m | rapier's `length_unit`: slop 1.5 mm, contact prediction 6 mm |
/// | `contact_frequency_hz` | 300 Hz | contact softness (rapier: 30) |
/// | `contact_damping_ratio` | 1 | (rapier: 10) |
/// | `settle_time_s` | 0.1 s | the object alone on the table |
/// | `settle_tolerance_m` | 5 mm | the settling object may move this much |
/// | `settle_tolerance_rad` | 0.1 rad | and turn this much |
/// | `finger_mass_kg` | 0.1 kg | each finger (gravity-free; the palm carries them) |
/// | `closing_speed_m_s` | 0.15 m/s | each finger's speed while closing |
/// | `closing_force_n` | `None` | each finger's force limit; `None` is the gripper's `force_limit_n` |
/// | `close_hold_s` | 0.05 s | squeezing after the fingers stop |
/// | `table_friction` | 0.5 | object against table (the hand grips with the gripper's `pad_friction`) |
/// | `object_density_kg_m3` | 1000 | [`DEFAULT_DENSITY_KG_M3`] |
/// | `lift_height_m` | 0.15 m | straight up, minimum-jerk profile |
/// | `lift_duration_s` | 0.4 s | peak acceleration 5.4 m/s^2 |
/// | `lift_hold_s` | 0.1 s | held still before the shake |
/// | `shake_amplitude_m` | 0.02 m | vertical |
/// | `shake_angle_rad` | 0.25 rad | about the closing axis |
/// | `shake_frequency_hz` | 2.5 Hz | |
/// | `shake_duration_s` | 0.8 s | two oscillations, faded in and out |
/// | `final_hold_s` | 0.1 s | held still after the shake |
/// | `contact_tolerance_m` | 2 mm | a finger closer than this to the object touches it |
/// | `min_lift_fraction` | 0.5 | the object must rise this fraction of `lift_height_m` |
/// | `max_slip_m` | `None` | if set, the object may move at most this much relative to the gripper |
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct PhysicsParams {
    /// Simulation step, seconds.
    pub timestep_s: f32,
    /// Solver iterations (substeps) per step.
    pub solver_iterations: usize,
    /// rapier's length unit, metres: its tolerances (slop, contact prediction distance) scale
    /// with it. 0.3 suits objects a few centimetres across: at 0.1 the 2 mm prediction distance
    /// loses contacts between a finger pad and a finely faceted hull (a can on its side) and the
    /// fingers squeeze through it.
    pub solver_length_unit_m: f32,
    /// Natural frequency of the contacts' softness, hertz (rapier's default is 30, too soft for
    /// a light object squeezed by tens of newtons: the fingers would sink through it).
    pub contact_frequency_hz: f32,
    /// Damping ratio of the contacts' softness (rapier's default is 10).
    pub contact_damping_ratio: f32,
    /// Time the object rests on the table before the gripper comes, seconds.
    pub settle_time_s: f32,
    /// While settling, the object's centre of mass may move at most this far, metres, else the
    /// pose is not stable and the trial fails at [`crate::physics::FailureStage::Settle`].
    pub settle_tolerance_m: f32,
    /// While settling, the object may turn at most this much, radians.
    pub settle_tolerance_rad: f32,
    /// Distance from the pre-grasp pose to the grasp pose along the approach, metres.
    /// Mass of each finger, kilograms.
    pub finger_mass_kg: f32,
    /// Each finger's closing speed, metres per second.
    pub closing_speed_m_s: f32,
    /// Each finger's force limit, newtons; `None` takes the gripper's `force_limit_n`.
    pub closing_force_n: Option<f32>,
    /// Time the fingers keep squeezing after they stop, seconds.
    pub close_hold_s: f32,
    /// Coulomb friction between the object and the table (between the object and the hand it
    /// is the gripper's `pad_friction`).
    pub table_friction: f32,
    /// Object density, kilograms per cubic metre.
    pub object_density_kg_m3: f32,
    /// How far the palm is lifted, straight up, metres.
    pub lift_height_m: f32,
    /// Duration of the lift, seconds.
    pub lift_duration_s: f32,
    /// Time the gripper holds still after the lift, seconds.
    pub lift_hold_s: f32,
    /// Amplitude of the vertical shake, metres.
    pub shake_amplitude_m: f32,
    /// Amplitude of the shake's rotation about the closing axis, radians.
    pub shake_angle_rad: f32,
    /// Shake frequency, hertz.
    pub shake_frequency_hz: f32,
    /// Shake duration, seconds.
    pub shake_duration_s: f32,
    /// Time the gripper holds still after the shake, seconds.
    pub final_hold_s: f32,
    /// A finger touches the object when their distance is below this, metres.
    pub contact_tolerance_m: f32,
    /// A held object's centre of mass must have risen at least this fraction of
    /// `lift_height_m` above where it rested.
    pub min_lift_fraction: f32,
    /// If set, a held object's centre of mass may move at most this far relative to the gripper
    /// between the end of the closing and the end of the trial, metres. Off by default: the
    /// issue's criterion is "still held between the fingers", and an object held off its
    /// centre of mass swings about the grasp axis in rapier, whose rigid single-point contacts
    /// have no torsional friction (real pads do); the swing is reported as `slip_m` and
    /// `slip_rad`, not judged.
    pub max_slip_m: Option<f32>,
    /// The hand grips the mesh's own surface (a triangle-mesh collider that only the hand
    /// touches) instead of the collision shape, which still carries the object on the table.
    /// Exact where the shape bulges (a hull over a bottle's neck), but 10 to 15 times slower (a
    /// side grasp on a 16k-triangle can: 250 to 380 ms against 17 to 26 ms), so off by default.
    pub grip_true_surface: bool,
}

impl Default for PhysicsParams {
    fn default() -> Self {
        Self {
            timestep_s: 1.0 / 240.0,
            solver_iterations: 8,
            solver_length_unit_m: 0.3,
            contact_frequency_hz: 300.0,
            contact_damping_ratio: 1.0,
            settle_time_s: 0.1,
            settle_tolerance_m: 0.005,
            settle_tolerance_rad: 0.1,
            finger_mass_kg: 0.1,
            closing_speed_m_s: 0.15,
            closing_force_n: None,
            close_hold_s: 0.05,
            table_friction: 0.5,
            object_density_kg_m3: DEFAULT_DENSITY_KG_M3,
            lift_height_m: 0.15,
            lift_duration_s: 0.4,
            lift_hold_s: 0.1,
            shake_amplitude_m: 0.02,
            shake_angle_rad: 0.25,
            shake_frequency_hz: 2.5,
            shake_duration_s: 0.8,
            final_hold_s: 0.1,
            contact_tolerance_m: 0.002,
            min_lift_fraction: 0.5,
            max_slip_m: None,
            grip_true_surface: false,
        }
    }
}

impl PhysicsParams {
    /// Checks every field's range.
    ///
    /// # Errors
    /// [`GraspError::InvalidParameter`] naming the first bad field.
    pub fn validate(&self) -> Result<()> {
        let bad = |name, value: f32, expected| {
            Err(GraspError::InvalidParameter {
                op: "physics params",
                name,
                value: value.to_string(),
                expected,
            })
        };
        for (name, value) in [
            ("timestep_s", self.timestep_s),
            ("solver_length_unit_m", self.solver_length_unit_m),
            ("contact_frequency_hz", self.contact_frequency_hz),
            ("contact_damping_ratio", self.contact_damping_ratio),
            ("settle_tolerance_m", self.settle_tolerance_m),
            ("settle_tolerance_rad", self.settle_tolerance_rad),
            ("finger_mass_kg", self.finger_mass_kg),
            ("closing_speed_m_s", self.closing_speed_m_s),
            ("object_density_kg_m3", self.object_density_kg_m3),
            ("lift_height_m", self.lift_height_m),
            ("lift_duration_s", self.lift_duration_s),
            ("shake_frequency_hz", self.shake_frequency_hz),
            ("contact_tolerance_m", self.contact_tolerance_m),
        ]
        .into_iter()
        .chain(self.max_slip_m.map(|max| ("max_slip_m", max)))
        {
            if !(value.is_finite() && value > 0.0) {
                return bad(name, value, "a finite number > 0");
            }
        }
        for (name, value) in [
            ("settle_time_s", self.settle_time_s),
            ("close_hold_s", self.close_hold_s),
            ("table_friction", self.table_friction),
            ("lift_hold_s", self.lift_hold_s),
            ("shake_amplitude_m", self.shake_amplitude_m),
            ("shake_angle_rad", self.shake_angle_rad),
            ("shake_duration_s", self.shake_duration_s),
            ("final_hold_s", self.final_hold_s),
        ] {
            if !(value.is_finite() && value >= 0.0) {
                return bad(name, value, "a finite number >= 0");
            }
        }
        if self.timestep_s > 0.05 {
            return bad("timestep_s", self.timestep_s, "at most 0.05 s");
        }
        if !(1..=64).contains(&self.solver_iterations) {
            return bad(
                "solver_iterations",
                self.solver_iterations as f32,
                "1 to 64",
            );
        }
        if let Some(force) = self.closing_force_n
            && !(force.is_finite() && force > 0.0)
        {
            return bad("closing_force_n", force, "a finite number > 0 or null");
        }
        if !(self.min_lift_fraction.is_finite() && (0.0..=1.0).contains(&self.min_lift_fraction)) {
            return bad("min_lift_fraction", self.min_lift_fraction, "0 to 1");
        }
        let steps = self.total_time_s() / self.timestep_s;
        if steps > 100_000.0 {
            return bad(
                "timestep_s",
                self.timestep_s,
                "at most 100000 steps a trial",
            );
        }
        Ok(())
    }

    /// The longest simulated time of one trial, seconds (closing takes its longest: from
    /// fully open to fully shut at `closing_speed_m_s`, with a 0.2 m opening at most).
    pub(crate) fn total_time_s(&self) -> f32 {
        self.settle_time_s
            + 0.1 / self.closing_speed_m_s
            + self.close_hold_s
            + self.lift_duration_s
            + self.lift_hold_s
            + self.shake_duration_s
            + self.final_hold_s
    }
}

/// Pose noise for [`crate::physics::success_probability`]: each trial draws independent normal
/// perturbations of the gripper's pose (in its own frame, about the grasp centre), of the
/// object's placement on the table (in the table plane, about its centre of mass) and of the
/// pads' friction coefficient.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct PhysicsNoise {
    /// Standard deviation of each component of the gripper's translation, metres.
    pub gripper_translation_sigma_m: f32,
    /// Standard deviation of each component of the gripper's rotation vector, radians.
    pub gripper_rotation_sigma_rad: f32,
    /// Standard deviation of each of the object's x and y on the table, metres.
    pub object_translation_sigma_m: f32,
    /// Standard deviation of the object's turn about the vertical, radians.
    pub object_yaw_sigma_rad: f32,
    /// Standard deviation of the pads' friction coefficient about the gripper's `pad_friction`.
    pub friction_sigma: f32,
    /// Floor of the drawn friction coefficient.
    pub friction_min: f32,
}

impl Default for PhysicsNoise {
    /// 5 mm and 0.05 rad (about 3 degrees) for the gripper, 5 mm and 0.05 rad for the object,
    /// the friction unperturbed.
    fn default() -> Self {
        Self {
            gripper_translation_sigma_m: 0.005,
            gripper_rotation_sigma_rad: 0.05,
            object_translation_sigma_m: 0.005,
            object_yaw_sigma_rad: 0.05,
            friction_sigma: 0.0,
            friction_min: 0.01,
        }
    }
}

impl PhysicsNoise {
    /// No noise: every trial is the nominal one.
    pub const NONE: Self = Self {
        gripper_translation_sigma_m: 0.0,
        gripper_rotation_sigma_rad: 0.0,
        object_translation_sigma_m: 0.0,
        object_yaw_sigma_rad: 0.0,
        friction_sigma: 0.0,
        friction_min: 0.01,
    };

    /// The perturbations robust Ferrari-Canny quality samples (Dex-Net 2.0's), as far as a
    /// trial on a table can take them: the gripper's translation and rotation and the friction
    /// coefficient's deviation and floor as they are; the object's translation in the table
    /// plane only and its rotation about the vertical only (a tilt or a lift off the table
    /// would settle back).
    pub fn matching(robust: &RobustQualityParams) -> Self {
        Self {
            gripper_translation_sigma_m: robust.gripper_translation_sigma_m,
            gripper_rotation_sigma_rad: robust.gripper_rotation_sigma_rad,
            object_translation_sigma_m: robust.object_translation_sigma_m,
            object_yaw_sigma_rad: robust.object_rotation_sigma_rad,
            friction_sigma: robust.friction_coef_sigma,
            friction_min: robust.friction_coef_min,
        }
    }

    /// Checks that every deviation is finite and not negative.
    ///
    /// # Errors
    /// [`GraspError::InvalidParameter`] naming the first bad field.
    pub fn validate(&self) -> Result<()> {
        for (name, value) in [
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
            ("object_yaw_sigma_rad", self.object_yaw_sigma_rad),
            ("friction_sigma", self.friction_sigma),
            ("friction_min", self.friction_min),
        ] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(GraspError::InvalidParameter {
                    op: "physics noise",
                    name,
                    value: value.to_string(),
                    expected: "a finite number >= 0",
                });
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_validate_and_bad_fields_are_named() {
        PhysicsParams::default().validate().unwrap();
        PhysicsNoise::default().validate().unwrap();
        let bad = PhysicsParams {
            timestep_s: 0.0,
            ..PhysicsParams::default()
        };
        assert!(
            bad.validate()
                .unwrap_err()
                .to_string()
                .contains("timestep_s")
        );
        let bad = PhysicsParams {
            closing_force_n: Some(-1.0),
            ..PhysicsParams::default()
        };
        let err = bad.validate().unwrap_err().to_string();
        assert!(err.contains("closing_force_n"), "{err}");
        let bad = PhysicsNoise {
            object_yaw_sigma_rad: f32::NAN,
            ..PhysicsNoise::default()
        };
        assert!(bad.validate().is_err());
    }

    #[test]
    fn params_round_trip_through_json_and_missing_fields_take_defaults() {
        let params = PhysicsParams {
            closing_force_n: Some(20.0),
            ..PhysicsParams::default()
        };
        let json = serde_json::to_string(&params).unwrap();
        assert_eq!(
            serde_json::from_str::<PhysicsParams>(&json).unwrap(),
            params
        );
        let partial: PhysicsParams = serde_json::from_str(r#"{"lift_height_m": 0.1}"#).unwrap();
        assert_eq!(partial.lift_height_m, 0.1);
        assert_eq!(partial.timestep_s, PhysicsParams::default().timestep_s);
        let noise: PhysicsNoise = serde_json::from_str("{}").unwrap();
        assert_eq!(noise, PhysicsNoise::default());
    }

    #[test]
    fn the_matching_noise_is_robust_qualitys() {
        let robust = RobustQualityParams::default();
        let noise = PhysicsNoise::matching(&robust);
        noise.validate().unwrap();
        assert_eq!(noise.gripper_translation_sigma_m, 0.005);
        assert_eq!(noise.gripper_rotation_sigma_rad, 0.001);
        assert_eq!(noise.object_translation_sigma_m, 0.01);
        assert_eq!(noise.object_yaw_sigma_rad, 0.01);
        assert_eq!(noise.friction_sigma, 0.1);
        assert_eq!(noise.friction_min, 0.01);
    }
}
