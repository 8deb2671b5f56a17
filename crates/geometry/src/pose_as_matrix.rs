//! Serde for poses as the row-major 4x4 homogeneous matrix robotics tools expect; use with
//! `#[serde(with = "mvgrasp_geometry::pose_as_matrix")]`.

use glam::Mat4;
use parry3d::math::Pose3;
use serde::{Deserialize, Deserializer, Serialize, Serializer, de::Error};

/// Writes `pose` as `[[r00, r01, r02, tx], ..., [0, 0, 0, 1]]`.
///
/// # Errors
/// Whatever the serializer reports.
pub fn serialize<S: Serializer>(pose: &Pose3, serializer: S) -> Result<S::Ok, S::Error> {
    let m = pose.to_mat4().transpose(); // glam is column-major: rows of m are columns here
    [0, 1, 2, 3]
        .map(|i| m.col(i).to_array())
        .serialize(serializer)
}

/// Reads a row-major 4x4 matrix, rejecting one that is not a rigid transform.
///
/// # Errors
/// A custom error for a matrix with scale, shear or a bad last row.
pub fn deserialize<'de, D: Deserializer<'de>>(deserializer: D) -> Result<Pose3, D::Error> {
    from_rows(<[[f32; 4]; 4]>::deserialize(deserializer)?).map_err(D::Error::custom)
}

/// The pose of a row-major 4x4 matrix, exactly as a file's is read (so that a pose given in
/// memory, from Python, gives the same bits as the same values read from JSON).
///
/// # Errors
/// A matrix with scale, shear, a bad last row or a value that is not finite.
pub fn from_rows(rows: [[f32; 4]; 4]) -> Result<Pose3, &'static str> {
    let m = Mat4::from_cols_array_2d(&rows).transpose();
    let pose = Pose3::from_mat4(m);
    let error = (pose.to_mat4() - m)
        .abs()
        .to_cols_array()
        .into_iter()
        .fold(0.0, f32::max);
    if error.is_nan() || error >= 1e-3 || rows[3] != [0.0, 0.0, 0.0, 1.0] {
        return Err("not a rigid transform (rotation + translation)");
    }
    Ok(pose)
}
