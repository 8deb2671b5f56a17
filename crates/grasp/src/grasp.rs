//! The grasp forms of the project and the one place that converts between them.
//!
//! - [`Grasp`]: 6-DoF, `world_from_gripper` (origin midway between the finger tips, +z the
//!   approach, +x the closing axis) and the opening width.
//! - [`ImageGrasp`]: Dex-Net 2.0's planar grasp in a depth image: centre pixel, in-image angle
//!   of the closing axis, depth of the centre along the optical axis, width; the gripper
//!   approaches along the camera's +z.
//! - [`PaperGrasp`]: the seed paper's g = (p, phi, theta), a report form (5 DoF, see its docs).

use mvgrasp_geometry::{Camera, Intrinsics, Pose3, Rot3, Vec3};
use serde::{Deserialize, Serialize};

/// A 6-DoF parallel-jaw grasp in the world.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Grasp {
    /// The gripper frame in the world: origin midway between the finger tips, +z approach,
    /// +x closing axis (a row-major 4x4 matrix in JSON).
    #[serde(with = "mvgrasp_geometry::pose_as_matrix")]
    pub world_from_gripper: Pose3,
    /// Opening between the fingers at the contacts, metres.
    pub width_m: f32,
}

/// A planar grasp in a depth image (Dex-Net 2.0).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ImageGrasp {
    /// The grasp centre, pixels (u right, v down).
    pub center_px: [f32; 2],
    /// Angle of the closing axis in the image, from +u towards +v, radians.
    pub angle_rad: f32,
    /// Depth of the grasp centre along the optical axis, metres.
    pub depth_m: f32,
    /// Opening width, metres.
    pub width_m: f32,
}

/// The seed paper's g = (p, phi, theta).
///
/// `theta` is the angle between the approach direction and the table plane (pi/2 approaching
/// straight down, 0 from the side); `phi` is the direction in the table plane (from world +x
/// towards +y) of the closing axis projected onto it. That is five of a grasp's six degrees of
/// freedom: [`PaperGrasp::to_world`] assumes the paper's case of a closing axis parallel to the
/// table, where the two forms map one to one.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PaperGrasp {
    /// Grasp centre in the world, metres.
    pub position_m: Vec3,
    /// Closing-axis direction in the table plane, radians.
    pub phi_rad: f32,
    /// Angle between the approach and the table plane, radians.
    pub theta_rad: f32,
}

impl ImageGrasp {
    /// The jaws' points in the image, pixels: the grasp's width apart along its axis, seen at
    /// its depth through a focal length of `focal_px` (the -x jaw first); `None` for a grasp at
    /// no depth.
    pub fn jaws_px(&self, focal_px: f32) -> Option<[[f32; 2]; 2]> {
        if self.depth_m <= 0.0 {
            return None;
        }
        let half = self.width_m / 2.0 * focal_px / self.depth_m;
        let (sin, cos) = self.angle_rad.sin_cos();
        let [u, v] = self.center_px;
        Some([-1.0f32, 1.0].map(|side| [u + side * half * cos, v + side * half * sin]))
    }

    /// The gripper frame in the camera frame.
    pub fn camera_from_gripper(&self, intrinsics: &Intrinsics) -> Pose3 {
        let [u, v] = self.center_px;
        let center = intrinsics.unproject(u, v, self.depth_m);
        Pose3::from_parts(center, Rot3::from_rotation_z(self.angle_rad))
    }

    /// The 6-DoF grasp in the world seen by `camera`.
    pub fn to_world(&self, camera: &Camera) -> Grasp {
        Grasp {
            world_from_gripper: camera.world_from_camera
                * self.camera_from_gripper(&camera.intrinsics),
            width_m: self.width_m,
        }
    }
}

impl Grasp {
    /// The grasp centre in the world.
    pub fn center(&self) -> Vec3 {
        self.world_from_gripper.translation
    }

    /// The approach direction (gripper +z) in the world.
    pub fn approach(&self) -> Vec3 {
        self.world_from_gripper.transform_vector(Vec3::Z)
    }

    /// The closing axis (gripper +x) in the world.
    pub fn closing_axis(&self) -> Vec3 {
        self.world_from_gripper.transform_vector(Vec3::X)
    }

    /// This grasp as seen by `camera`, if it approaches along the optical axis within
    /// `max_tilt_rad` and its centre is in front of the camera.
    pub fn to_image(&self, camera: &Camera, max_tilt_rad: f32) -> Option<ImageGrasp> {
        let camera_from_gripper = camera.camera_from_world() * self.world_from_gripper;
        let approach = camera_from_gripper.transform_vector(Vec3::Z);
        if approach.z < max_tilt_rad.cos() {
            return None;
        }
        let center = camera_from_gripper.translation;
        let center_px = camera.intrinsics.project(center)?;
        let axis = camera_from_gripper.transform_vector(Vec3::X);
        Some(ImageGrasp {
            center_px,
            angle_rad: axis.y.atan2(axis.x),
            depth_m: center.z,
            width_m: self.width_m,
        })
    }

    /// The paper's (p, phi, theta) for this grasp (world z is up, the table is z = 0's plane).
    pub fn to_paper(&self) -> PaperGrasp {
        let approach = self.approach();
        let axis = self.closing_axis();
        PaperGrasp {
            position_m: self.center(),
            phi_rad: axis.y.atan2(axis.x),
            theta_rad: (-approach.z).clamp(-1.0, 1.0).asin(),
        }
    }
}

impl PaperGrasp {
    /// The 6-DoF grasp whose closing axis is horizontal at `phi_rad` and whose approach dips
    /// `theta_rad` below the table plane, leaning towards the side of `+z x closing axis`.
    pub fn to_world(&self, width_m: f32) -> Grasp {
        let (sin_phi, cos_phi) = self.phi_rad.sin_cos();
        let (sin_theta, cos_theta) = self.theta_rad.sin_cos();
        let x = Vec3::new(cos_phi, sin_phi, 0.0);
        let z = Vec3::new(-sin_phi, cos_phi, 0.0) * cos_theta - Vec3::Z * sin_theta;
        let y = z.cross(x);
        let rotation = Rot3::from_mat3(&mvgrasp_geometry::Mat3::from_cols(x, y, z));
        Grasp {
            world_from_gripper: Pose3::from_parts(self.position_m, rotation),
            width_m,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_jaws_are_the_width_apart_along_the_axis_at_the_depth() {
        // 5 cm at 0.5 m through 500 px: 50 px apart, along the axis at 90 degrees (down v).
        let g = ImageGrasp {
            center_px: [100.0, 80.0],
            angle_rad: std::f32::consts::FRAC_PI_2,
            depth_m: 0.5,
            width_m: 0.05,
        };
        let [a, b] = g.jaws_px(500.0).unwrap();
        assert!(
            (a[0] - 100.0).abs() < 1e-4 && (a[1] - 55.0).abs() < 1e-4,
            "{a:?}"
        );
        assert!(
            (b[0] - 100.0).abs() < 1e-4 && (b[1] - 105.0).abs() < 1e-4,
            "{b:?}"
        );
        assert_eq!(ImageGrasp { depth_m: 0.0, ..g }.jaws_px(500.0), None);
    }

    fn top_down_camera() -> Camera {
        let k = Intrinsics::phoxi_s();
        Camera::look_at(k, Vec3::new(0.0, 0.0, 0.7), Vec3::ZERO, Vec3::Y).unwrap()
    }

    #[test]
    fn image_grasp_lifts_to_the_world_and_back() {
        let camera = top_down_camera();
        let image = ImageGrasp {
            center_px: [300.0, 150.0],
            angle_rad: 0.4,
            depth_m: 0.68,
            width_m: 0.05,
        };
        let grasp = image.to_world(&camera);
        assert!(
            (grasp.approach() - -Vec3::Z).length() < 1e-6,
            "approach along the optical axis"
        );
        assert!(
            (grasp.center().z - 0.02).abs() < 1e-5,
            "0.68 m below a camera 0.7 m up"
        );
        let back = grasp.to_image(&camera, 0.01).unwrap();
        assert!(
            (back.center_px[0] - 300.0).abs() < 1e-3 && (back.center_px[1] - 150.0).abs() < 1e-3
        );
        assert!((back.angle_rad - 0.4).abs() < 1e-5 && (back.depth_m - 0.68).abs() < 1e-6);
    }

    #[test]
    fn a_grasp_seen_from_the_side_has_no_image_form_in_a_top_down_camera() {
        let side = PaperGrasp {
            position_m: Vec3::ZERO,
            phi_rad: 0.0,
            theta_rad: 0.0,
        }
        .to_world(0.04);
        assert!(side.to_image(&top_down_camera(), 0.2).is_none());
    }

    #[test]
    fn paper_form_round_trips_for_horizontal_closing_axes() {
        for (phi, theta) in [
            (0.3f32, 1.2f32),
            (-2.0, 0.1),
            (3.0, std::f32::consts::FRAC_PI_2 - 1e-3),
        ] {
            let paper = PaperGrasp {
                position_m: Vec3::new(0.1, 0.2, 0.03),
                phi_rad: phi,
                theta_rad: theta,
            };
            let grasp = paper.to_world(0.05);
            assert!(grasp.closing_axis().z.abs() < 1e-6);
            assert!((grasp.approach().length() - 1.0).abs() < 1e-5);
            let back = grasp.to_paper();
            assert!(
                (back.phi_rad - phi).abs() < 1e-4 && (back.theta_rad - theta).abs() < 1e-3,
                "{back:?}"
            );
        }
        // Top-down: theta = 90 degrees.
        let top = ImageGrasp {
            center_px: [255.5, 191.75],
            angle_rad: 0.0,
            depth_m: 0.7,
            width_m: 0.05,
        };
        let theta = top.to_world(&top_down_camera()).to_paper().theta_rad;
        assert!((theta - std::f32::consts::FRAC_PI_2).abs() < 1e-3);
    }
}
