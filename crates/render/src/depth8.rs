//! The 8-bit depth export the seed paper feeds its networks: depth normalised between the near
//! and far planes. A helper for display and for the paper's inputs; float metres stay the main
//! format.

use crate::error::{RenderError, Result};

/// Maps depth in metres (0 = missing) to 0..=255 linearly from `z_near_m` (1) to `z_far_m`
/// (255), clamping outside; missing and non-finite pixels become 0.
///
/// # Errors
/// [`RenderError::InvalidParameter`] unless `0 <= z_near_m < z_far_m`, both finite.
pub fn depth_to_u8(depth_m: &[f32], z_near_m: f32, z_far_m: f32) -> Result<Vec<u8>> {
    if !(z_near_m.is_finite() && z_far_m.is_finite() && 0.0 <= z_near_m && z_near_m < z_far_m) {
        return Err(RenderError::InvalidParameter {
            op: "depth to 8 bit",
            name: "z_near_m, z_far_m",
            value: format!("{z_near_m}, {z_far_m}"),
            expected: "0 <= z_near_m < z_far_m, finite",
        });
    }
    let scale = 254.0 / (z_far_m - z_near_m);
    Ok(depth_m
        .iter()
        .map(|&z| {
            if z > 0.0 && z.is_finite() {
                (1.0 + (z.clamp(z_near_m, z_far_m) - z_near_m) * scale).round() as u8
            } else {
                0
            }
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn near_far_and_missing_map_to_the_ends() {
        let out = depth_to_u8(&[0.5, 1.0, 1.5, 0.0, f32::NAN, 0.2, 9.0], 0.5, 1.5).unwrap();
        assert_eq!(out, vec![1, 128, 255, 0, 0, 1, 255]);
    }

    #[test]
    fn a_bad_range_is_an_error() {
        assert!(depth_to_u8(&[1.0], 1.5, 0.5).is_err());
        assert!(depth_to_u8(&[1.0], f32::NAN, 0.5).is_err());
    }
}
