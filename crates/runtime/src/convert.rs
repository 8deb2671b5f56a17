//! The one place where geometry's types become the renderer's plain arrays.

use mvgrasp_geometry::pose_as_matrix::to_rows;
use mvgrasp_geometry::{Camera, Intrinsics, TriangleMesh};
use mvgrasp_render::{Frame, Intrinsics as RenderIntrinsics, Sides, View};

use crate::stereo::RgbView;

/// Which sides of `mesh` to draw: front faces only for a closed surface wound outwards (no
/// boundary edge, no neighbours wound against each other, positive signed volume), where back
/// faces never show from outside; both sides otherwise. A few non-manifold edges (three faces
/// on an edge, common in scans such as YCB's) leave a surface closed and are allowed.
pub fn sides_of(mesh: &TriangleMesh) -> Sides {
    let topology = mesh.topology();
    if topology.boundary_edges == 0
        && topology.misoriented_edges == 0
        && mesh.signed_volume_m3() > 0.0
    {
        Sides::Front
    } else {
        Sides::Both
    }
}

/// The renderer's copy of the intrinsics (same fields).
pub fn render_intrinsics(k: &Intrinsics) -> RenderIntrinsics {
    RenderIntrinsics {
        fx: k.fx,
        fy: k.fy,
        cx: k.cx,
        cy: k.cy,
        width: k.width,
        height: k.height,
        z_near_m: k.z_near_m,
        z_far_m: k.z_far_m,
    }
}

/// A posed camera as a render view.
pub fn render_view(camera: &Camera) -> View {
    View {
        intrinsics: render_intrinsics(&camera.intrinsics),
        camera_from_world: to_rows(&camera.camera_from_world()),
    }
}

/// A rendered frame as the colour view of `camera` (its mask: the pixels of `object_id`) and
/// its rendered depth, metres.
pub fn rgb_view_of(camera: &Camera, frame: Frame, object_id: u8) -> (RgbView, Vec<f32>) {
    let view = RgbView {
        camera: *camera,
        rgb: frame
            .rgb
            .chunks_exact(3)
            .map(|p| [p[0], p[1], p[2]])
            .collect(),
        mask: Some(frame.mask.iter().map(|&m| m == object_id).collect()),
    };
    (view, frame.depth_m)
}

#[cfg(test)]
mod tests {
    use super::*;
    use mvgrasp_geometry::Vec3;

    #[test]
    fn render_views_project_like_geometry_cameras() {
        let camera = Camera::look_at(
            Intrinsics::phoxi_s(),
            Vec3::new(0.3, -0.2, 0.4),
            Vec3::new(0.0, 0.0, 0.05),
            Vec3::Z,
        )
        .unwrap();
        let view = render_view(&camera);
        let p = Vec3::new(0.02, 0.03, 0.07);
        let expected = camera.project(p).unwrap();
        let m = view.camera_from_world;
        let in_camera: [f32; 3] =
            [0, 1, 2].map(|r| m[r][0] * p.x + m[r][1] * p.y + m[r][2] * p.z + m[r][3]);
        let got = mvgrasp_render::project(&view.intrinsics, in_camera);
        assert!((got[0] - expected[0]).abs() < 1e-3 && (got[1] - expected[1]).abs() < 1e-3);
    }
}
