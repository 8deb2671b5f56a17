//! Cameras: OpenCV pinhole intrinsics, views, and the projection from the OpenCV camera frame
//! (x right, y down, z forward) to wgpu's clip space (y up, depth 0..1). Pure CPU math, tested
//! here without a GPU.
//!
//! Pixel convention: pixel (u, v) covers `[u - 0.5, u + 0.5] x [v - 0.5, v + 0.5]` in the
//! pinhole's image coordinates `u = fx * x / z + cx`, `v = fy * y / z + cy`; its centre is at
//! integer coordinates, so `cx = (width - 1) / 2` centres the optical axis. The rasteriser samples
//! at framebuffer coordinates `u + 0.5`, so the projection shifts by half a pixel.

use crate::error::{RenderError, Result};

/// Pinhole camera intrinsics in pixels, plus the depth range that is rendered. The same fields
/// as `mvgrasp_geometry::Intrinsics` (the root crate converts).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Intrinsics {
    /// Focal length along u, pixels.
    pub fx: f32,
    /// Focal length along v, pixels.
    pub fy: f32,
    /// Principal point u, pixels (pixel centres at integers).
    pub cx: f32,
    /// Principal point v, pixels (pixel centres at integers).
    pub cy: f32,
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Nearest rendered depth, metres (> 0).
    pub z_near_m: f32,
    /// Farthest rendered depth, metres (> `z_near_m`).
    pub z_far_m: f32,
}

impl Intrinsics {
    /// PhoXi S, the seed paper's camera: fx = fy = 552.5, cx = 255.5, cy = 191.75, 516 x 386,
    /// depth 0.1 .. 2 m.
    pub const PHOXI_S: Self = Self {
        fx: 552.5,
        fy: 552.5,
        cx: 255.5,
        cy: 191.75,
        width: 516,
        height: 386,
        z_near_m: 0.1,
        z_far_m: 2.0,
    };
}

/// One camera to render from: intrinsics and the rigid `camera_from_world` transform (row-major
/// 4x4, OpenCV camera frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct View {
    /// The camera's intrinsics.
    pub intrinsics: Intrinsics,
    /// Row-major rigid transform taking world points into the OpenCV camera frame.
    pub camera_from_world: [[f32; 4]; 4],
}

/// The 4x4 identity, row-major.
pub const IDENTITY: [[f32; 4]; 4] = [
    [1.0, 0.0, 0.0, 0.0],
    [0.0, 1.0, 0.0, 0.0],
    [0.0, 0.0, 1.0, 0.0],
    [0.0, 0.0, 0.0, 1.0],
];

/// Largest deviation from orthonormality accepted in a rigid rotation (f32 pose chains drift).
const RIGID_TOLERANCE: f32 = 1e-3;

/// Checks a view's intrinsics and transform; `max_size_px` is the device's largest texture side.
pub(crate) fn validate_view(view: &View, view_index: usize, max_size_px: u32) -> Result<()> {
    let k = &view.intrinsics;
    let bad = |name: &'static str, value: String, expected: String| RenderError::InvalidView {
        view_index,
        name,
        value,
        expected,
    };
    for (name, f) in [("fx", k.fx), ("fy", k.fy)] {
        if !(f.is_finite() && f > 0.0) {
            return Err(bad(name, f.to_string(), "finite and > 0".into()));
        }
    }
    for (name, c) in [("cx", k.cx), ("cy", k.cy)] {
        if !c.is_finite() {
            return Err(bad(name, c.to_string(), "finite".into()));
        }
    }
    for (name, s) in [("width", k.width), ("height", k.height)] {
        if s == 0 || s > max_size_px {
            return Err(bad(
                name,
                s.to_string(),
                format!("1..={max_size_px} pixels (the device's largest texture)"),
            ));
        }
    }
    if !(k.z_near_m.is_finite() && k.z_far_m.is_finite() && 0.0 < k.z_near_m)
        || k.z_near_m >= k.z_far_m
    {
        return Err(bad(
            "z_near_m, z_far_m",
            format!("{}, {}", k.z_near_m, k.z_far_m),
            "0 < z_near_m < z_far_m, finite".into(),
        ));
    }
    if let Some(reason) = rigid_error(&view.camera_from_world) {
        return Err(bad(
            "camera_from_world",
            format!("{:?}", view.camera_from_world),
            format!("a rigid transform: {reason}"),
        ));
    }
    Ok(())
}

/// Why `m` is not a rigid transform (finite, rotation orthonormal with det +1, last row
/// 0 0 0 1), or `None` when it is.
pub(crate) fn rigid_error(m: &[[f32; 4]; 4]) -> Option<String> {
    if let Some(reason) = affine_error(m) {
        return Some(reason);
    }
    for i in 0..3 {
        for j in 0..3 {
            let dot: f32 = (0..3).map(|k| m[i][k] * m[j][k]).sum();
            let want = if i == j { 1.0 } else { 0.0 };
            if (dot - want).abs() > RIGID_TOLERANCE {
                return Some(format!(
                    "rotation rows {i}, {j} have dot product {dot}, not {want}"
                ));
            }
        }
    }
    let det = det3(m);
    if det < 0.0 {
        return Some(format!("rotation determinant is {det}, not +1 (a mirror)"));
    }
    None
}

/// Why `m` is not an invertible affine transform (finite, last row 0 0 0 1, non-singular), or
/// `None` when it is.
pub(crate) fn affine_error(m: &[[f32; 4]; 4]) -> Option<String> {
    if m.iter().flatten().any(|x| !x.is_finite()) {
        return Some("it holds a non-finite entry".into());
    }
    if m[3] != [0.0, 0.0, 0.0, 1.0] {
        return Some(format!("its last row is {:?}, not [0, 0, 0, 1]", m[3]));
    }
    let det = det3(m);
    if det.abs() < 1e-12 {
        return Some(format!("its 3x3 part is singular (determinant {det})"));
    }
    None
}

/// Determinant of the upper-left 3x3 block.
fn det3(m: &[[f32; 4]; 4]) -> f32 {
    m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
}

/// Row-major `clip_from_camera`: OpenCV camera frame to wgpu clip space, with `w = z`, depth 0 at
/// `z_near_m` and 1 at `z_far_m`, and y flipped (image v grows down, NDC y grows up). A point
/// that projects to pixel coordinates (u, v) lands at framebuffer coordinates (u + 0.5, v + 0.5),
/// the centre of pixel (u, v).
pub fn clip_from_camera(k: &Intrinsics) -> [[f32; 4]; 4] {
    let (w, h) = (f64::from(k.width), f64::from(k.height));
    let (n, f) = (f64::from(k.z_near_m), f64::from(k.z_far_m));
    // ndc_x = 2 (u + 0.5) / W - 1, ndc_y = 1 - 2 (v + 0.5) / H, times w = z.
    let a = 2.0 * f64::from(k.fx) / w;
    let b = 2.0 * (f64::from(k.cx) + 0.5) / w - 1.0;
    let c = -2.0 * f64::from(k.fy) / h;
    let d = 1.0 - 2.0 * (f64::from(k.cy) + 0.5) / h;
    let e = f / (f - n);
    let g = -f * n / (f - n);
    [
        [a as f32, 0.0, b as f32, 0.0],
        [0.0, c as f32, d as f32, 0.0],
        [0.0, 0.0, e as f32, g as f32],
        [0.0, 0.0, 1.0, 0.0],
    ]
}

/// Applies the affine `m` to a point.
pub(crate) fn transform_point(m: &[[f32; 4]; 4], p: [f32; 3]) -> [f32; 3] {
    let mut out = [0.0f32; 3];
    for (i, x) in out.iter_mut().enumerate() {
        *x = m[i][0] * p[0] + m[i][1] * p[1] + m[i][2] * p[2] + m[i][3];
    }
    out
}

/// Column-major copy of a row-major matrix, as WGSL's `mat4x4<f32>` lays it out.
pub(crate) fn column_major(m: &[[f32; 4]; 4]) -> [f32; 16] {
    let mut out = [0.0f32; 16];
    for (col, chunk) in out.chunks_exact_mut(4).enumerate() {
        for (row, x) in chunk.iter_mut().enumerate() {
            *x = m[row][col];
        }
    }
    out
}

/// Pinhole projection of a camera-frame point to pixel coordinates (u, v) (CPU reference).
pub fn project(k: &Intrinsics, p_camera: [f32; 3]) -> [f32; 2] {
    [
        k.fx * p_camera[0] / p_camera[2] + k.cx,
        k.fy * p_camera[1] / p_camera[2] + k.cy,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn apply(m: &[[f32; 4]; 4], p: [f32; 3]) -> [f32; 4] {
        let v = [p[0], p[1], p[2], 1.0];
        let mut out = [0.0; 4];
        for i in 0..4 {
            out[i] = (0..4).map(|k| m[i][k] * v[k]).sum();
        }
        out
    }

    /// Framebuffer coordinates (origin top-left, pixel centres at +0.5) of a camera point.
    fn framebuffer(k: &Intrinsics, p: [f32; 3]) -> [f32; 3] {
        let c = apply(&clip_from_camera(k), p);
        let ndc = [c[0] / c[3], c[1] / c[3], c[2] / c[3]];
        [
            (ndc[0] + 1.0) * 0.5 * k.width as f32,
            (1.0 - ndc[1]) * 0.5 * k.height as f32,
            ndc[2],
        ]
    }

    #[test]
    fn a_point_lands_on_its_pixel_centre() {
        let k = Intrinsics::PHOXI_S;
        for p in [[0.0, 0.0, 0.5], [0.03, -0.02, 0.7], [-0.1, 0.08, 1.3]] {
            let [u, v] = project(&k, p);
            let fb = framebuffer(&k, p);
            assert!((fb[0] - (u + 0.5)).abs() < 1e-3, "{fb:?} vs {u}");
            assert!((fb[1] - (v + 0.5)).abs() < 1e-3, "{fb:?} vs {v}");
        }
    }

    #[test]
    fn the_principal_point_at_the_middle_hits_the_middle() {
        let k = Intrinsics {
            cx: 9.5,
            cy: 4.5,
            width: 20,
            height: 10,
            ..Intrinsics::PHOXI_S
        };
        let fb = framebuffer(&k, [0.0, 0.0, 1.0]);
        assert!(
            (fb[0] - 10.0).abs() < 1e-5 && (fb[1] - 5.0).abs() < 1e-5,
            "{fb:?}"
        );
    }

    #[test]
    fn depth_maps_near_to_zero_and_far_to_one() {
        let k = Intrinsics::PHOXI_S;
        assert!(framebuffer(&k, [0.0, 0.0, k.z_near_m])[2].abs() < 1e-6);
        assert!((framebuffer(&k, [0.0, 0.0, k.z_far_m])[2] - 1.0).abs() < 1e-6);
        assert!(framebuffer(&k, [0.0, 0.0, 0.5])[2] < framebuffer(&k, [0.0, 0.0, 0.6])[2]);
    }

    #[test]
    fn y_down_in_the_camera_is_down_in_the_image() {
        let k = Intrinsics::PHOXI_S;
        assert!(framebuffer(&k, [0.0, 0.05, 0.5])[1] > framebuffer(&k, [0.0, 0.0, 0.5])[1]);
        assert!(framebuffer(&k, [0.05, 0.0, 0.5])[0] > framebuffer(&k, [0.0, 0.0, 0.5])[0]);
    }

    #[test]
    fn rigid_checks() {
        assert!(rigid_error(&IDENTITY).is_none());
        let (s, c) = (0.3f32.sin(), 0.3f32.cos());
        let rot = [
            [c, -s, 0.0, 0.1],
            [s, c, 0.0, 0.2],
            [0.0, 0.0, 1.0, 0.3],
            [0.0, 0.0, 0.0, 1.0],
        ];
        assert!(rigid_error(&rot).is_none());
        let mut scaled = IDENTITY;
        scaled[0][0] = 2.0;
        assert!(rigid_error(&scaled).is_some());
        assert!(affine_error(&scaled).is_none());
        let mut mirror = IDENTITY;
        mirror[2][2] = -1.0;
        assert!(rigid_error(&mirror).is_some());
        let mut projective = IDENTITY;
        projective[3][2] = 1.0;
        assert!(affine_error(&projective).is_some());
        let mut nan = IDENTITY;
        nan[1][3] = f32::NAN;
        assert!(affine_error(&nan).is_some());
        let mut singular = IDENTITY;
        singular[1] = [0.0, 0.0, 0.0, 0.0];
        assert!(affine_error(&singular).is_some());
    }

    #[test]
    fn bad_intrinsics_are_rejected() {
        let good = View {
            intrinsics: Intrinsics::PHOXI_S,
            camera_from_world: IDENTITY,
        };
        assert!(validate_view(&good, 0, 8192).is_ok());
        let with = |f: &dyn Fn(&mut Intrinsics)| {
            let mut v = good;
            f(&mut v.intrinsics);
            validate_view(&v, 3, 8192)
        };
        assert!(with(&|k| k.fx = 0.0).is_err());
        assert!(with(&|k| k.fy = f32::NAN).is_err());
        assert!(with(&|k| k.cx = f32::INFINITY).is_err());
        assert!(with(&|k| k.width = 0).is_err());
        assert!(with(&|k| k.height = 9000).is_err());
        assert!(with(&|k| k.z_near_m = 0.0).is_err());
        assert!(with(&|k| k.z_far_m = 0.05).is_err());
        let err = with(&|k| k.fx = -1.0).unwrap_err().to_string();
        assert!(err.contains("view 3") && err.contains("fx"), "{err}");
    }

    #[test]
    fn column_major_transposes() {
        let mut m = IDENTITY;
        m[0][3] = 5.0;
        assert_eq!(column_major(&m)[12], 5.0);
        assert_eq!(transform_point(&m, [1.0, 2.0, 3.0]), [6.0, 2.0, 3.0]);
    }
}
