//! A posed camera: intrinsics plus `world_from_camera`.

use std::path::Path;

use nalgebra::Matrix3;
use parry3d::math::{Pose3, Rot3, Vec3};
use serde::{Deserialize, Serialize};

use super::intrinsics::{Intrinsics, read_text};
use crate::error::{GeometryError, Result};

/// A pinhole camera placed in the world. The camera frame is OpenCV's: x right, y down, z along
/// the optical axis.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Camera {
    /// The pinhole model.
    pub intrinsics: Intrinsics,
    /// Maps camera-frame points to the world (serialised as a row-major 4x4 matrix).
    #[serde(with = "crate::pose_as_matrix")]
    pub world_from_camera: Pose3,
}

impl Camera {
    /// A camera at `eye` looking at `target`, with `up` (world) pointing up in the image
    /// (towards -y in the camera frame).
    ///
    /// # Errors
    /// [`GeometryError::InvalidParameter`] when `eye` equals `target`, `up` is parallel to the
    /// viewing direction, or any input is not finite.
    pub fn look_at(intrinsics: Intrinsics, eye: Vec3, target: Vec3, up: Vec3) -> Result<Self> {
        let invalid = |name, value: String, expected| GeometryError::InvalidParameter {
            op: "look at",
            name,
            value,
            expected,
        };
        if !(eye.is_finite() && target.is_finite() && up.is_finite()) {
            return Err(invalid(
                "eye, target, up",
                format!("{eye}, {target}, {up}"),
                "finite",
            ));
        }
        let z = (target - eye).normalize_or_zero();
        if z == Vec3::ZERO {
            return Err(invalid("target", target.to_string(), "distinct from eye"));
        }
        let x = z.cross(up).normalize_or_zero();
        if x.length_squared() < 0.5 {
            return Err(invalid(
                "up",
                up.to_string(),
                "not parallel to the viewing direction",
            ));
        }
        let y = z.cross(x);
        let rotation = Rot3::from_mat3(&parry3d::math::Mat3::from_cols(x, y, z));
        Ok(Self {
            intrinsics,
            world_from_camera: Pose3::from_parts(eye, rotation),
        })
    }

    /// Maps world points to the camera frame.
    #[inline]
    pub fn camera_from_world(&self) -> Pose3 {
        self.world_from_camera.inverse()
    }

    /// The camera's position in the world.
    pub fn position(&self) -> Vec3 {
        self.world_from_camera.translation
    }

    /// The optical axis (camera +z) in the world.
    pub fn optical_axis(&self) -> Vec3 {
        self.world_from_camera.transform_vector(Vec3::Z)
    }

    /// The pixel where a world point projects, or `None` behind the camera.
    #[inline]
    pub fn project(&self, world_point: Vec3) -> Option<[f32; 2]> {
        self.intrinsics
            .project(self.world_from_camera.inverse_transform_point(world_point))
    }

    /// The world point at pixel (u, v) and depth (z along the optical axis) `depth_m`.
    #[inline]
    pub fn unproject(&self, u: f32, v: f32, depth_m: f32) -> Vec3 {
        self.world_from_camera
            .transform_point(self.intrinsics.unproject(u, v, depth_m))
    }

    /// Back-projects a depth image to world points (see [`Intrinsics::depth_to_points`]).
    ///
    /// # Errors
    /// As [`Intrinsics::depth_to_points`].
    pub fn depth_to_world_points(&self, depth_m: &[f32]) -> Result<Vec<Vec3>> {
        let mut points = self.intrinsics.depth_to_points(depth_m)?;
        for p in &mut points {
            *p = self.world_from_camera.transform_point(*p);
        }
        Ok(points)
    }
}

/// Reads a Berkeley `.tf` file (autolab_core RigidTransform): the from-frame, the to-frame, a
/// translation line and three rotation rows. Returns `(from, to, to_from_from)`, e.g.
/// `("primesense_overhead", "world", world_from_camera)`.
///
/// # Errors
/// [`GeometryError::NotFound`], or [`GeometryError::Parse`] naming the file when a line is
/// missing, a number does not parse, or the rotation is not orthonormal with determinant 1.
pub fn read_tf(path: impl AsRef<Path>) -> Result<(String, String, Pose3)> {
    let path = path.as_ref();
    let text = read_text(path)?;
    let parse_error = |detail: String| GeometryError::Parse {
        format: "rigid transform (.tf)",
        detail,
        path: path.to_path_buf(),
    };
    let lines: Vec<&str> = text
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect();
    if lines.len() != 6 {
        return Err(parse_error(format!(
            "expected 6 non-empty lines, found {}",
            lines.len()
        )));
    }
    let row = |i: usize| -> Result<[f64; 3]> {
        let values: Vec<f64> = lines[i]
            .split_whitespace()
            .map(str::parse)
            .collect::<std::result::Result<_, _>>()
            .map_err(|e| parse_error(format!("line {}: {e}", i + 1)))?;
        <[f64; 3]>::try_from(values).map_err(|v| {
            parse_error(format!(
                "line {}: expected 3 numbers, found {}",
                i + 1,
                v.len()
            ))
        })
    };
    let t = row(2)?;
    let rows = [row(3)?, row(4)?, row(5)?];
    let pose = rigid_pose(rows, t).map_err(parse_error)?;
    Ok((lines[0].to_string(), lines[1].to_string(), pose))
}

/// A camera's pose in the world from a file: a Berkeley `.tf` file from the camera's frame to
/// the world ([`read_tf`]), or a JSON `{"world_from_camera": [[...], [...], [...], [...]]}`,
/// a 4x4 rigid transform in rows (last row 0, 0, 0, 1), metres.
///
/// # Errors
/// [`GeometryError::NotFound`], or [`GeometryError::Parse`] naming the file when it does not
/// parse or the matrix is not a rigid transform.
pub fn read_camera_pose(path: impl AsRef<Path>) -> Result<Pose3> {
    #[derive(Deserialize)]
    #[serde(deny_unknown_fields)]
    struct PoseJson {
        world_from_camera: [[f64; 4]; 4],
    }
    let path = path.as_ref();
    if path.extension().is_some_and(|e| e == "tf") {
        return read_tf(path).map(|(_, _, pose)| pose);
    }
    let text = read_text(path)?;
    let parse_error = |detail: String| GeometryError::Parse {
        format: "camera pose JSON (world_from_camera)",
        detail,
        path: path.to_path_buf(),
    };
    let m = serde_json::from_str::<PoseJson>(&text)
        .map_err(|e| parse_error(crate::one_line(&e.to_string())))?
        .world_from_camera;
    pose_from_rows(m).map_err(parse_error)
}

/// The rigid transform of a 4x4 matrix given in rows (last row 0, 0, 0, 1; a proper rotation
/// within 1e-3; finite), or why it is not one.
///
/// # Errors
/// A message saying why the matrix is not a rigid transform.
pub fn pose_from_rows(m: [[f64; 4]; 4]) -> std::result::Result<Pose3, String> {
    if m[3] != [0.0, 0.0, 0.0, 1.0] {
        return Err(format!(
            "the last row is {:?}, not [0, 0, 0, 1]: not a rigid transform",
            m[3]
        ));
    }
    let rows = [0, 1, 2].map(|i| [m[i][0], m[i][1], m[i][2]]);
    rigid_pose(rows, [m[0][3], m[1][3], m[2][3]])
}

/// The pose with rotation `rows` and translation `t`, if the rotation is a proper one (within
/// 1e-3) and everything is finite.
fn rigid_pose(rows: [[f64; 3]; 3], t: [f64; 3]) -> std::result::Result<Pose3, String> {
    if !rows.iter().flatten().chain(&t).all(|v| v.is_finite()) {
        return Err("a value is not finite".into());
    }
    let r = Matrix3::from_fn(|i, j| rows[i][j]);
    let orthonormality = (r.transpose() * r - Matrix3::identity()).abs().max();
    if !(orthonormality < 1e-3 && (r.determinant() - 1.0).abs() < 1e-3) {
        return Err(format!(
            "the rotation is not a proper rotation (|R^T R - I| = {orthonormality:.2e}, det = {:.4}): \
             not a rigid transform",
            r.determinant()
        ));
    }
    let cols = [0, 1, 2].map(|j| Vec3::new(r[(0, j)] as f32, r[(1, j)] as f32, r[(2, j)] as f32));
    let rotation =
        Rot3::from_mat3(&parry3d::math::Mat3::from_cols(cols[0], cols[1], cols[2])).normalize();
    let translation = Vec3::new(t[0] as f32, t[1] as f32, t[2] as f32);
    Ok(Pose3::from_parts(translation, rotation))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn look_at_follows_opencv_axes() {
        let k = Intrinsics::phoxi_s();
        // On the +x axis looking back at the origin, world up = +z.
        let cam = Camera::look_at(k, Vec3::new(1.0, 0.0, 0.0), Vec3::ZERO, Vec3::Z).unwrap();
        assert!((cam.optical_axis() - -Vec3::X).length() < 1e-6);
        // Image y (down) is world -z; image x (right) is world -y... seen from +x, +y is left.
        let y = cam.world_from_camera.transform_vector(Vec3::Y);
        assert!((y - -Vec3::Z).length() < 1e-6, "{y}");
        let [u, v] = cam.project(Vec3::ZERO).unwrap();
        assert!((u - k.cx).abs() < 1e-3 && (v - k.cy).abs() < 1e-3);
        // A point above the target appears above the image centre.
        assert!(cam.project(Vec3::new(0.0, 0.0, 0.1)).unwrap()[1] < k.cy);
        let back = cam.unproject(u, v, 1.0);
        assert!(back.length() < 1e-5);
    }

    #[test]
    fn cameras_round_trip_through_json_as_row_major_matrices() {
        let cam = Camera::look_at(
            Intrinsics::phoxi_s(),
            Vec3::new(0.3, 0.2, 0.5),
            Vec3::ZERO,
            Vec3::Z,
        )
        .unwrap();
        let json = serde_json::to_value(cam).unwrap();
        let rows = &json["world_from_camera"];
        assert_eq!(rows[0][3].as_f64().unwrap() as f32, 0.3);
        assert_eq!(rows[3], serde_json::json!([0.0, 0.0, 0.0, 1.0]));
        let back: Camera = serde_json::from_value(json).unwrap();
        assert!((back.position() - cam.position()).length() < 1e-6);
        let mut skewed = serde_json::to_value(cam).unwrap();
        skewed["world_from_camera"][0][0] = serde_json::json!(3.0);
        assert!(serde_json::from_value::<Camera>(skewed).is_err());
    }

    #[test]
    fn look_at_rejects_degenerate_input() {
        let k = Intrinsics::phoxi_s();
        assert!(Camera::look_at(k, Vec3::Z, Vec3::ZERO, Vec3::Z).is_err());
        assert!(Camera::look_at(k, Vec3::ZERO, Vec3::ZERO, Vec3::Y).is_err());
    }

    #[test]
    fn tf_files_parse_and_bad_rotations_are_rejected() {
        let dir = tempfile::tempdir().unwrap();
        let good = dir.path().join("cam.tf");
        std::fs::write(&good, "cam\nworld\n0.1 0.2 0.3\n1 0 0\n0 -1 0\n0 0 -1\n").unwrap();
        let (from, to, world_from_cam) = read_tf(&good).unwrap();
        assert_eq!((from.as_str(), to.as_str()), ("cam", "world"));
        assert!((world_from_cam.transform_vector(Vec3::Z) - -Vec3::Z).length() < 1e-6);
        let bad = dir.path().join("bad.tf");
        std::fs::write(&bad, "cam\nworld\n0 0 0\n1 0 0\n0 1 0\n0 0 2\n").unwrap();
        let err = read_tf(&bad).unwrap_err().to_string();
        assert!(err.contains("bad.tf") && err.contains("rotation"), "{err}");
    }
}
