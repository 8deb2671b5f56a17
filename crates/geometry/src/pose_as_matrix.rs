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
    to_rows(pose).serialize(serializer)
}

/// `pose` as the rows of its 4x4 homogeneous matrix (`[r00, r01, r02, tx]` first, `[0, 0, 0,
/// 1]` last): what files, the renderer and Python take.
pub fn to_rows(pose: &Pose3) -> [[f32; 4]; 4] {
    let m = pose.to_mat4().transpose(); // glam is column-major: rows of m are columns here
    [0, 1, 2, 3].map(|i| m.col(i).to_array())
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

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;
    use glam::{Quat, Vec3};

    /// The rows written are the ones read: a pose through `to_rows` and `from_rows` comes back
    /// within float rounding, and its translation exactly.
    #[test]
    fn rows_written_are_rows_read() {
        let pose = Pose3::from_parts(
            Vec3::new(0.1, -0.2, 0.65),
            Quat::from_euler(glam::EulerRot::ZYX, 0.3, -1.1, 2.0),
        );
        let rows = to_rows(&pose);
        assert_eq!(rows[3], [0.0, 0.0, 0.0, 1.0]);
        assert_eq!([rows[0][3], rows[1][3], rows[2][3]], [0.1, -0.2, 0.65]);
        let back = from_rows(rows).unwrap();
        let error = (back.to_mat4() - pose.to_mat4())
            .abs()
            .to_cols_array()
            .into_iter()
            .fold(0.0, f32::max);
        assert!(error < 1e-6, "{error}");
        // The rows are the matrix's rows: the rotation's first column is the image of x.
        let x = pose.rotation * Vec3::X;
        let column = Vec3::new(rows[0][0], rows[1][0], rows[2][0]);
        assert!(
            (column - x).abs().max_element() < 1e-6,
            "{column} against {x}"
        );
    }

    #[test]
    fn a_matrix_with_scale_is_refused() {
        let mut rows = to_rows(&Pose3::IDENTITY);
        rows[0][0] = 2.0;
        assert!(from_rows(rows).is_err());
    }
}
