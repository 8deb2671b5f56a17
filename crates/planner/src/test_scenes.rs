//! Depth images the planner's unit tests share.

use mvgrasp_geometry::{Camera, Intrinsics, IntrinsicsPreset, Vec3};

use mvgrasp_grasp::ImageGrasp;

use crate::depth_image::{DepthImage, View};
use crate::scored::ScoredGrasp;

/// A box `half_m` (x, y half extents, metres) and 5 cm tall on a table 0.7 m below a camera
/// with `k` looking straight down, as that camera sees it (exact per-pixel depth). Where
/// `unseen_m` is given, the table within those half extents around the box is missing (0).
pub(crate) fn box_on_table(
    k: Intrinsics,
    half_m: [f32; 2],
    unseen_m: Option<[f32; 2]>,
) -> DepthImage {
    let inside = |half: [f32; 2], x: f32, y: f32| x.abs() < half[0] && y.abs() < half[1];
    let mut depth = Vec::with_capacity((k.width * k.height) as usize);
    for v in 0..k.height {
        for u in 0..k.width {
            let (x, y) = (
                (u as f32 - k.cx) * 0.65 / k.fx,
                (v as f32 - k.cy) * 0.65 / k.fy,
            );
            depth.push(if inside(half_m, x, y) {
                0.65
            } else if unseen_m.is_some_and(|unseen| inside(unseen, x, y)) {
                0.0
            } else {
                0.7
            });
        }
    }
    DepthImage::new(k, depth).unwrap()
}

/// A 4 cm x 12 cm box 5 cm tall on a table, 0.7 m below a PhoXi S looking straight down
/// ([`box_on_table`]), with the table 2 cm around the box left unobserved where `hole` is set.
pub(crate) fn box_view(hole: bool) -> View {
    let k = Intrinsics::preset(IntrinsicsPreset::PhoxiS);
    let depth = box_on_table(k, [0.02, 0.06], hole.then_some([0.04, 0.08]));
    let camera = Camera::look_at(
        k,
        Vec3::new(0.0, 0.0, 0.7),
        Vec3::ZERO,
        Vec3::new(0.0, -1.0, 0.0),
    )
    .unwrap();
    View::new(0, camera, depth).unwrap()
}

/// A 4 cm cube on the table at the origin, seen by a PhoXi S 0.6 m away at 45 degrees above
/// the table from the side of `side` (-1: from -x, 1: from +x), exact per-pixel depth (ray
/// casts against the cube and the table).
pub(crate) fn seen_box(side: f32) -> View {
    let k = Intrinsics::preset(IntrinsicsPreset::PhoxiS);
    let target = Vec3::new(0.0, 0.0, 0.02);
    let r = 0.6 * std::f32::consts::FRAC_1_SQRT_2;
    let camera = Camera::look_at(
        k,
        target + Vec3::new(side * r, 0.0, r),
        target,
        Vec3::new(0.0, 0.0, 1.0),
    )
    .unwrap();
    let (lo, hi) = (Vec3::new(-0.02, -0.02, 0.0), Vec3::new(0.02, 0.02, 0.04));
    let origin = camera.position();
    let rotation = camera.world_from_camera.rotation;
    let mut depth = Vec::with_capacity((k.width * k.height) as usize);
    for v in 0..k.height {
        for u in 0..k.width {
            // Along this direction the parameter is the depth (camera z).
            let dir = rotation * Vec3::new((u as f32 - k.cx) / k.fx, (v as f32 - k.cy) / k.fy, 1.0);
            // The cube: slabs.
            let (mut t0, mut t1) = (0.0f32, f32::INFINITY);
            for a in 0..3 {
                let (ta, tb) = ((lo[a] - origin[a]) / dir[a], (hi[a] - origin[a]) / dir[a]);
                t0 = t0.max(ta.min(tb));
                t1 = t1.min(ta.max(tb));
            }
            let table = if dir.z < 0.0 { -origin.z / dir.z } else { 0.0 };
            depth.push(if t0 <= t1 { t0 } else { table });
        }
    }
    View::new(0, camera, DepthImage::new(k, depth).unwrap()).unwrap()
}

/// A candidate of quality 0.9 at the centre of `view`'s image, closing at `angle_rad`, at
/// `depth_m` and `width_m`, lifted to the world with the view's camera.
pub(crate) fn centred_candidate(
    view: &View,
    angle_rad: f32,
    depth_m: f32,
    width_m: f32,
) -> ScoredGrasp {
    let k = view.depth.intrinsics();
    let image = ImageGrasp {
        center_px: [k.cx, k.cy],
        angle_rad,
        depth_m,
        width_m,
    };
    ScoredGrasp {
        view: 0,
        image,
        grasp: image.to_world(&view.camera),
        theta_rad: view.theta_rad(),
        quality: 0.9,
        view_quality: None,
        virtual_quality: None,
        by_scorer: false,
        from_cloud: false,
    }
}
