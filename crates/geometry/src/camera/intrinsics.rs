//! Camera intrinsics: focal lengths, principal point, image size and the rendering depth range.

use std::path::Path;

use parry3d::math::Vec3;
use serde::{Deserialize, Serialize};

use crate::error::{GeometryError, Result, in_memory};

/// Pinhole intrinsics in pixels, plus the near and far planes used when rendering.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Intrinsics {
    /// Focal length along x, pixels.
    pub fx: f32,
    /// Focal length along y, pixels.
    pub fy: f32,
    /// Principal point x, pixels (0 is the centre of the left column).
    pub cx: f32,
    /// Principal point y, pixels (0 is the centre of the top row).
    pub cy: f32,
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Nearest rendered depth, metres.
    pub z_near_m: f32,
    /// Farthest rendered depth, metres.
    pub z_far_m: f32,
}

/// The cameras mvgrasp knows by name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum IntrinsicsPreset {
    /// Photoneo PhoXi S as in Dex-Net: fx = fy = 552.5, (255.5, 191.75), 516 x 386.
    PhoxiS,
    /// Primesense Carmine 1.08: fx = fy = 525, (319.5, 239.5), 640 x 480.
    Primesense,
    /// A RealSense D435's depth stream at 640 x 480 with typical factory calibration:
    /// fx = fy = 385, (319.5, 239.5).
    RealsenseD435,
}

impl IntrinsicsPreset {
    /// Every preset.
    pub const ALL: [IntrinsicsPreset; 3] = [Self::PhoxiS, Self::Primesense, Self::RealsenseD435];

    /// The preset's name as written in configs and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Self::PhoxiS => "phoxi_s",
            Self::Primesense => "primesense",
            Self::RealsenseD435 => "realsense_d435",
        }
    }
}

impl std::str::FromStr for IntrinsicsPreset {
    type Err = GeometryError;

    fn from_str(name: &str) -> Result<Self> {
        Self::ALL
            .into_iter()
            .find(|p| p.name() == name)
            .ok_or_else(|| GeometryError::InvalidParameter {
                op: "intrinsics preset",
                name: "preset",
                value: name.to_string(),
                expected: "one of phoxi_s, primesense, realsense_d435",
            })
    }
}

/// Near and far planes of the presets, metres: covers tabletop cameras 0.3 to 1.5 m away.
const Z_NEAR_M: f32 = 0.1;
const Z_FAR_M: f32 = 2.0;

impl Intrinsics {
    /// Checked intrinsics (the eight numbers are the fields, in order).
    ///
    /// # Errors
    /// [`GeometryError::InvalidParameter`] naming the first bad field.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        fx: f32,
        fy: f32,
        cx: f32,
        cy: f32,
        width: u32,
        height: u32,
        z_near_m: f32,
        z_far_m: f32,
    ) -> Result<Self> {
        let intrinsics = Self {
            fx,
            fy,
            cx,
            cy,
            width,
            height,
            z_near_m,
            z_far_m,
        };
        intrinsics.validate()?;
        Ok(intrinsics)
    }

    /// A named preset.
    pub fn preset(preset: IntrinsicsPreset) -> Self {
        let (fx, cx, cy, width, height) = match preset {
            IntrinsicsPreset::PhoxiS => (552.5, 255.5, 191.75, 516, 386),
            IntrinsicsPreset::Primesense => (525.0, 319.5, 239.5, 640, 480),
            IntrinsicsPreset::RealsenseD435 => (385.0, 319.5, 239.5, 640, 480),
        };
        Self {
            fx,
            fy: fx,
            cx,
            cy,
            width,
            height,
            z_near_m: Z_NEAR_M,
            z_far_m: Z_FAR_M,
        }
    }

    /// Photoneo PhoXi S, the paper's camera.
    pub fn phoxi_s() -> Self {
        Self::preset(IntrinsicsPreset::PhoxiS)
    }

    /// Checks every field: focal lengths and the depth range positive and finite, a non-empty
    /// image, and a principal point inside it.
    ///
    /// # Errors
    /// [`GeometryError::InvalidParameter`] naming the first bad field.
    pub fn validate(&self) -> Result<()> {
        let bad = |name, value: String, expected| {
            Err(GeometryError::InvalidParameter {
                op: "intrinsics",
                name,
                value,
                expected,
            })
        };
        for (name, f) in [("fx", self.fx), ("fy", self.fy)] {
            if !(f.is_finite() && f > 0.0) {
                return bad(name, f.to_string(), "a finite focal length > 0 pixels");
            }
        }
        if self.width == 0 || self.height == 0 || self.width > 16384 || self.height > 16384 {
            return bad(
                "width x height",
                format!("{}x{}", self.width, self.height),
                "between 1 and 16384 pixels each",
            );
        }
        if !(self.cx.is_finite() && (-0.5..=self.width as f32 - 0.5).contains(&self.cx)) {
            return bad(
                "cx",
                self.cx.to_string(),
                "inside the image: -0.5 to width - 0.5",
            );
        }
        if !(self.cy.is_finite() && (-0.5..=self.height as f32 - 0.5).contains(&self.cy)) {
            return bad(
                "cy",
                self.cy.to_string(),
                "inside the image: -0.5 to height - 0.5",
            );
        }
        if !(self.z_near_m.is_finite() && self.z_near_m > 0.0 && self.z_far_m.is_finite())
            || self.z_far_m <= self.z_near_m
        {
            return bad(
                "z_near_m, z_far_m",
                format!("{}, {}", self.z_near_m, self.z_far_m),
                "0 < z_near_m < z_far_m, finite",
            );
        }
        Ok(())
    }

    /// Reads the Berkeley `.intr` JSON (`_fx _fy _cx _cy _width _height`, as written by
    /// perception/autolab_core), with the presets' depth range.
    ///
    /// # Errors
    /// [`GeometryError::NotFound`], [`GeometryError::Parse`] or
    /// [`GeometryError::InvalidParameter`], each naming the file.
    pub fn from_intr_file(path: impl AsRef<Path>) -> Result<Self> {
        #[derive(Deserialize)]
        struct Intr {
            _fx: f32,
            _fy: f32,
            _cx: f32,
            _cy: f32,
            _width: u32,
            _height: u32,
        }
        let path = path.as_ref();
        let text = read_text(path)?;
        let parse_error = |detail: String| GeometryError::Parse {
            format: "intrinsics JSON (.intr)",
            detail,
            path: path.to_path_buf(),
        };
        let intr: Intr = serde_json::from_str(&text)
            .map_err(|e| parse_error(crate::one_line(&e.to_string())))?;
        let intrinsics = Self {
            fx: intr._fx,
            fy: intr._fy,
            cx: intr._cx,
            cy: intr._cy,
            width: intr._width,
            height: intr._height,
            z_near_m: Z_NEAR_M,
            z_far_m: Z_FAR_M,
        };
        intrinsics
            .validate()
            .map_err(|e| parse_error(e.to_string()))?;
        Ok(intrinsics)
    }

    /// Reads intrinsics from a file: the Berkeley `.intr` JSON ([`Intrinsics::from_intr_file`]),
    /// or a plain JSON with the 3x3 camera matrix and the image size,
    /// `{"K": [[fx, 0, cx], [0, fy, cy], [0, 0, 1]], "width": W, "height": H}` (a `.json` with
    /// the `.intr` keys reads as one), with the presets' depth range.
    ///
    /// # Errors
    /// [`GeometryError::NotFound`], or [`GeometryError::Parse`] naming the file: a missing key,
    /// a matrix with skew or a last row other than (0, 0, 1), or a bad value.
    pub fn from_file(path: impl AsRef<Path>) -> Result<Self> {
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct PlainJson {
            #[serde(rename = "K")]
            k: [[f64; 3]; 3],
            width: u32,
            height: u32,
        }
        let path = path.as_ref();
        let text = read_text(path)?;
        let parse_error = |detail: String| GeometryError::Parse {
            format: "intrinsics JSON (K, width, height)",
            detail,
            path: path.to_path_buf(),
        };
        let is_intr = path.extension().is_some_and(|e| e == "intr")
            || serde_json::from_str::<serde_json::Value>(&text)
                .is_ok_and(|v| v.get("_fx").is_some());
        if is_intr {
            return Self::from_intr_file(path);
        }
        let plain: PlainJson = serde_json::from_str(&text)
            .map_err(|e| parse_error(crate::one_line(&e.to_string())))?;
        let k = plain.k;
        if k[0][1] != 0.0 || k[1][0] != 0.0 || k[2] != [0.0, 0.0, 1.0] {
            return Err(parse_error(format!(
                "K = {k:?}: expected [[fx, 0, cx], [0, fy, cy], [0, 0, 1]] (no skew)"
            )));
        }
        let intrinsics = Self {
            fx: k[0][0] as f32,
            fy: k[1][1] as f32,
            cx: k[0][2] as f32,
            cy: k[1][2] as f32,
            width: plain.width,
            height: plain.height,
            z_near_m: Z_NEAR_M,
            z_far_m: Z_FAR_M,
        };
        intrinsics
            .validate()
            .map_err(|e| parse_error(e.to_string()))?;
        Ok(intrinsics)
    }

    /// The pixel (u, v) where a point in the camera frame projects, or `None` behind the camera.
    #[inline]
    pub fn project(&self, camera_point: Vec3) -> Option<[f32; 2]> {
        (camera_point.z > 0.0).then(|| {
            [
                self.fx * camera_point.x / camera_point.z + self.cx,
                self.fy * camera_point.y / camera_point.z + self.cy,
            ]
        })
    }

    /// The camera-frame point at pixel (u, v) whose depth (z) is `depth_m`.
    #[inline]
    pub fn unproject(&self, u: f32, v: f32, depth_m: f32) -> Vec3 {
        Vec3::new(
            (u - self.cx) * depth_m / self.fx,
            (v - self.cy) * depth_m / self.fy,
            depth_m,
        )
    }

    /// Back-projects a row-major depth image (z in metres; 0, negative or NaN = missing) to
    /// camera-frame points, one per valid pixel, in row-major order.
    ///
    /// # Errors
    /// [`GeometryError::InvalidParameter`] when the image is not width x height.
    pub fn depth_to_points(&self, depth_m: &[f32]) -> Result<Vec<Vec3>> {
        let expected = self.width as usize * self.height as usize;
        if depth_m.len() != expected {
            return Err(GeometryError::InvalidParameter {
                op: "depth to points",
                name: "depth image length",
                value: format!(
                    "{} (intrinsics say {}x{} = {expected})",
                    depth_m.len(),
                    self.width,
                    self.height
                ),
                expected: "width * height values",
            });
        }
        let width = self.width as usize;
        Ok(depth_m
            .iter()
            .enumerate()
            .filter(|(_, z)| **z > 0.0 && z.is_finite())
            .map(|(i, &z)| self.unproject((i % width) as f32, (i / width) as f32, z))
            .collect())
    }
}

/// Reads a small text file, naming it in errors.
pub(super) fn read_text(path: &Path) -> Result<String> {
    if !path.is_file() {
        return Err(GeometryError::NotFound {
            path: path.to_path_buf(),
        });
    }
    std::fs::read_to_string(path).map_err(|source| GeometryError::Io {
        op: "read",
        source,
        path: if path.as_os_str().is_empty() {
            in_memory()
        } else {
            path.to_path_buf()
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_match_the_guide_and_validate() {
        let p = Intrinsics::phoxi_s();
        assert_eq!(
            (p.fx, p.fy, p.cx, p.cy, p.width, p.height),
            (552.5, 552.5, 255.5, 191.75, 516, 386)
        );
        for preset in IntrinsicsPreset::ALL {
            Intrinsics::preset(preset).validate().unwrap();
            assert_eq!(preset.name().parse::<IntrinsicsPreset>().unwrap(), preset);
        }
        assert!("kinect".parse::<IntrinsicsPreset>().is_err());
    }

    #[test]
    fn project_inverts_unproject() {
        let k = Intrinsics::preset(IntrinsicsPreset::Primesense);
        let p = k.unproject(100.25, 300.5, 0.7);
        let [u, v] = k.project(p).unwrap();
        assert!((u - 100.25).abs() < 1e-3 && (v - 300.5).abs() < 1e-3);
        assert!(k.project(Vec3::new(0.0, 0.0, -1.0)).is_none());
    }

    #[test]
    fn depth_to_points_skips_missing_pixels_and_checks_size() {
        let k = Intrinsics::new(10.0, 10.0, 1.0, 1.0, 3, 3, 0.1, 2.0).unwrap();
        let mut depth = vec![0.5; 9];
        depth[0] = 0.0;
        depth[4] = f32::NAN;
        let points = k.depth_to_points(&depth).unwrap();
        assert_eq!(points.len(), 7);
        assert_eq!(points[0], Vec3::new(0.0, -0.05, 0.5)); // pixel (1, 0)
        assert!(k.depth_to_points(&depth[..8]).is_err());
    }

    #[test]
    fn invalid_fields_are_named() {
        let err = Intrinsics::new(0.0, 1.0, 1.0, 1.0, 3, 3, 0.1, 2.0).unwrap_err();
        assert!(err.to_string().contains("fx"), "{err}");
        let err = Intrinsics::new(1.0, 1.0, 1.0, 1.0, 3, 3, 2.0, 1.0).unwrap_err();
        assert!(err.to_string().contains("z_near_m"), "{err}");
    }
}
