//! `grasps.json`: the planner's ranked grasps for robots and scripts, and an overlay picture of
//! them on each view's depth image.
//!
//! The file (format `mvgrasp-grasps/1`):
//!
//! | field | meaning |
//! |---|---|
//! | `format` | `"mvgrasp-grasps/1"` |
//! | `frame` | `"given"` (the world of the camera poses given), `"estimated"` (a world on the table fitted in the image: z up, origin where the optical axis meets the table) or `"rendered"` (the table of a rendered scene) |
//! | `views[]` | per view: `intrinsics` (fx, fy, cx, cy, width, height) and `world_from_camera` (4x4, rows) |
//! | `grasps[]` | best first: `rank`, `view`, `quality` (the network's; with `plan --fuse` the ranker's probability that it holds, built on `virtual_quality`, the re-score on its virtual view, and `view_quality`, the planning network's), `width_m`, the image grasp (`u`, `v`, `angle_rad`, `depth_m`), `camera_from_gripper` and `world_from_gripper` (4x4, rows; the gripper frame of ARCHITECTURE.md: origin midway between the fingertips, +z the approach, +x the closing axis), and the paper's `p` (metres), `phi_rad`, `theta_rad` |
//! | `rejections` | candidates the hand check dropped before the best, by reason |
//! | `table` | the fitted table (camera frame: `normal`, `camera_height_m`, `inlier_share`, `rms_residual_m`, `points`), when one was fitted |

use std::path::Path;

use mvgrasp_geometry::Camera;
use mvgrasp_planner::{DepthImage, Rejections, ScoredGrasp, TableFit};
use serde::Serialize;

use crate::error::{Error, Result};
use crate::grasp_image::GRASP_COLORS;
use crate::images::write_png8;
use crate::planner::{PlanReport, SensorPlanReport, ViewsPlanReport};
use mvgrasp_geometry::pose_as_matrix::to_rows;

/// The `format` of `grasps.json`.
pub const GRASPS_FORMAT: &str = "mvgrasp-grasps/1";

/// Which world the `world_from_*` poses are in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum WorldFrame {
    /// The world of the camera poses given.
    Given,
    /// A world on the table fitted in the image.
    Estimated,
    /// The table of a rendered scene.
    Rendered,
}

/// A view's camera in `grasps.json`.
#[derive(Clone, Debug, Serialize)]
pub struct ViewEntry {
    /// fx, fy, cx, cy (pixels), width, height.
    pub intrinsics: [f32; 6],
    /// 4x4, rows.
    pub world_from_camera: [[f32; 4]; 4],
}

/// A grasp in `grasps.json`.
#[derive(Clone, Debug, Serialize)]
pub struct GraspEntry {
    /// 0 for the best.
    pub rank: usize,
    /// The view it was planned in.
    pub view: usize,
    /// The network's probability that it is robust; for the multi-view planner's, the
    /// ranker's probability that it holds (`models/ranker_fused.json`).
    pub quality: f32,
    /// With `plan --fuse`: the planning network's score on the view it was found in.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub view_quality: Option<f32>,
    /// With `plan --fuse`: the re-scoring network's score on its virtual view, which the
    /// ranker's `quality` is built on.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub virtual_quality: Option<f32>,
    /// Jaw opening at the contacts, metres.
    pub width_m: f32,
    /// The grasp centre's column, pixels.
    pub u: f32,
    /// Its row, pixels.
    pub v: f32,
    /// The closing axis in the image, from +u towards +v, radians.
    pub angle_rad: f32,
    /// The grasp centre's depth, metres.
    pub depth_m: f32,
    /// 4x4, rows: the gripper in the frame of the view's camera.
    pub camera_from_gripper: [[f32; 4]; 4],
    /// 4x4, rows: the gripper in the world.
    pub world_from_gripper: [[f32; 4]; 4],
    /// The paper's grasp centre p, metres (world).
    pub p: [f32; 3],
    /// The paper's phi, radians.
    pub phi_rad: f32,
    /// The paper's theta, radians.
    pub theta_rad: f32,
}

/// The content of `grasps.json`.
#[derive(Clone, Debug, Serialize)]
pub struct GraspsFile {
    /// [`GRASPS_FORMAT`].
    pub format: &'static str,
    /// Which world the poses are in.
    pub frame: WorldFrame,
    /// The cameras, in view order.
    pub views: Vec<ViewEntry>,
    /// Best first.
    pub grasps: Vec<GraspEntry>,
    /// Candidates the hand check dropped before the best, by reason.
    pub rejections: Rejections,
    /// The table fitted in the (first) view, if one was.
    pub table: Option<TableFit>,
}

impl GraspsFile {
    /// The file for `grasps` (best first) planned in the views of `cameras`.
    pub fn new(
        frame: WorldFrame,
        cameras: &[Camera],
        grasps: &[ScoredGrasp],
        rejections: Rejections,
        table: Option<TableFit>,
    ) -> Self {
        let views = cameras
            .iter()
            .map(|c| {
                let k = &c.intrinsics;
                ViewEntry {
                    intrinsics: [k.fx, k.fy, k.cx, k.cy, k.width as f32, k.height as f32],
                    world_from_camera: to_rows(&c.world_from_camera),
                }
            })
            .collect();
        let grasps = grasps
            .iter()
            .enumerate()
            .map(|(rank, g)| {
                let camera_from_gripper =
                    cameras.get(g.view).map_or(g.grasp.world_from_gripper, |c| {
                        c.camera_from_world() * g.grasp.world_from_gripper
                    });
                let paper = g.grasp.to_paper();
                GraspEntry {
                    rank,
                    view: g.view,
                    quality: g.quality,
                    view_quality: g.view_quality,
                    virtual_quality: g.virtual_quality,
                    width_m: g.grasp.width_m,
                    u: g.image.center_px[0],
                    v: g.image.center_px[1],
                    angle_rad: g.image.angle_rad,
                    depth_m: g.image.depth_m,
                    camera_from_gripper: to_rows(&camera_from_gripper),
                    world_from_gripper: to_rows(&g.grasp.world_from_gripper),
                    p: g.grasp.center().to_array(),
                    phi_rad: paper.phi_rad,
                    theta_rad: paper.theta_rad,
                }
            })
            .collect();
        Self {
            format: GRASPS_FORMAT,
            frame,
            views,
            grasps,
            rejections,
            table,
        }
    }

    /// The file of a plan on one sensor depth image (`plan --depth`): its frame the given
    /// camera pose's world, or the table fitted in the image when the pose was estimated.
    pub fn of_sensor(report: &SensorPlanReport) -> Self {
        let frame = if report.pose_estimated {
            WorldFrame::Estimated
        } else {
            WorldFrame::Given
        };
        Self::new(
            frame,
            &[report.view.camera],
            &report.top,
            report.rejections,
            Some(report.table),
        )
    }

    /// The file of a plan over posed views (`plan --views-dir`, `plan --rgb`).
    pub fn of_views(report: &ViewsPlanReport) -> Self {
        let cameras: Vec<Camera> = report.views.iter().map(|v| v.camera).collect();
        Self::new(
            WorldFrame::Given,
            &cameras,
            &report.top,
            report.rejections,
            report.tables.first().copied(),
        )
    }

    /// The file of a plan on a rendered scene (`plan` on a mesh).
    pub fn of_rendered(report: &PlanReport) -> Self {
        Self::new(
            WorldFrame::Rendered,
            &report.cameras,
            &report.top,
            report.rejections,
            None,
        )
    }

    /// The file as pretty JSON.
    ///
    /// # Errors
    /// [`Error::Json`] (never for these types in practice).
    pub fn to_json(&self) -> Result<String> {
        serde_json::to_string_pretty(self).map_err(|source| Error::Json {
            op: "write",
            what: "grasps",
            source,
            path: "grasps.json".into(),
        })
    }
}

/// Writes a picture of `grasps` (best first) planned in the view `view` over its depth image:
/// grey depth (near is bright, missing black), each grasp as its two jaws joined by a line, the
/// best five in [`GRASP_COLORS`] (the best green and drawn last), the rest grey.
///
/// # Errors
/// [`Error::Io`] when the PNG cannot be written.
pub fn write_overlay(
    path: &Path,
    depth: &DepthImage,
    view: usize,
    grasps: &[ScoredGrasp],
) -> Result<()> {
    let (w, h) = (depth.width() as usize, depth.height() as usize);
    let (near, far) = depth_span(depth.as_slice(), None);
    let span = far - near;
    let mut rgb: Vec<u8> = depth
        .as_slice()
        .iter()
        .flat_map(|&d| {
            let g = if d > 0.0 {
                (40.0 + 200.0 * (1.0 - ((d - near) / span).clamp(0.0, 1.0))) as u8
            } else {
                0
            };
            [g, g, g]
        })
        .collect();
    let k = depth.intrinsics();
    let mut plot = |x: f32, y: f32, color: [u8; 3], thick: bool| {
        let r = i64::from(thick);
        for dy in -r..=r {
            for dx in -r..=r {
                let (u, v) = (x.round() as i64 + dx, y.round() as i64 + dy);
                if (0..w as i64).contains(&u) && (0..h as i64).contains(&v) {
                    let i = 3 * (v as usize * w + u as usize);
                    rgb[i..i + 3].copy_from_slice(&color);
                }
            }
        }
    };
    let mut line = |a: [f32; 2], b: [f32; 2], color: [u8; 3], thick: bool| {
        let steps = (b[0] - a[0]).abs().max((b[1] - a[1]).abs()).ceil().max(1.0) as usize;
        for s in 0..=steps {
            let t = s as f32 / steps as f32;
            plot(
                a[0] + (b[0] - a[0]) * t,
                a[1] + (b[1] - a[1]) * t,
                color,
                thick,
            );
        }
    };
    let in_view: Vec<(usize, &ScoredGrasp)> = grasps
        .iter()
        .enumerate()
        .filter(|(_, g)| g.view == view)
        .collect();
    // Worst first, so that the best is drawn over the rest.
    for &(rank, g) in in_view.iter().rev() {
        let color = GRASP_COLORS.get(rank).copied().unwrap_or([150, 150, 150]);
        let image = &g.image;
        let Some([a, b]) = image.jaws_px(k.fx) else {
            continue;
        };
        // Each jaw drawn 2 cm long across the axis.
        let jaw = 0.01 * k.fx / image.depth_m;
        let (sin, cos) = image.angle_rad.sin_cos();
        let thick = rank == 0;
        line(a, b, color, false);
        for c in [a, b] {
            line(
                [c[0] - jaw * sin, c[1] + jaw * cos],
                [c[0] + jaw * sin, c[1] - jaw * cos],
                color,
                thick,
            );
        }
    }
    write_png8(path, depth.width(), depth.height(), 3, &rgb)
}

/// The picture of a plan from RGB views (`plan --out`: `views.png`): one column per view, its
/// colour image above its depth (grey, near bright, missing black; the predicted depth for RGB
/// input; with a mask the object on a bright scale of its own, the rest dim), both at half
/// resolution, and the best five grasps drawn in every view where they
/// project: the line between the contacts and each finger 3 cm back along the approach, in
/// [`GRASP_COLORS`] (the best green, drawn last and thicker).
///
/// # Errors
/// [`Error::Io`] when the PNG cannot be written; [`Error::Stereo`] for views of other sizes or
/// a colour image missing for a depth view.
pub fn write_contact_sheet(
    path: &Path,
    rgb: &[crate::stereo::RgbView],
    views: &[mvgrasp_planner::View],
    grasps: &[ScoredGrasp],
) -> Result<()> {
    let Some(first) = views.first() else {
        return Err(Error::Stereo {
            problem: format!("{}: no view to draw", path.display()),
        });
    };
    let k = first.camera.intrinsics;
    let (w, h) = (k.width as usize, k.height as usize);
    let same = |c: &Camera| (c.intrinsics.width, c.intrinsics.height) == (k.width, k.height);
    if rgb.len() != views.len()
        || !views.iter().all(|v| same(&v.camera))
        || !rgb.iter().all(|v| same(&v.camera))
    {
        return Err(Error::Stereo {
            problem: format!(
                "{}: {} colour images for {} views, all of one size expected",
                path.display(),
                rgb.len(),
                views.len()
            ),
        });
    }
    let (tw, th) = (w / 2, h / 2);
    let (sheet_w, sheet_h) = (tw * views.len(), 2 * th);
    let mut sheet = vec![0u8; 3 * sheet_w * sheet_h];
    for (col, (colour, view)) in rgb.iter().zip(views).enumerate() {
        let depth = view.depth.as_slice();
        // With a mask, the object on a grey scale of its own (bright) and the rest dim.
        let whole = depth_span(depth, None);
        let object = view.mask.as_ref().map(|m| (m, depth_span(depth, Some(m))));
        let grey = |d: f32, (near, far): (f32, f32), [dark, bright]: [f32; 2]| {
            (dark + (bright - dark) * (1.0 - ((d - near) / (far - near)).clamp(0.0, 1.0))) as u8
        };
        for y in 0..th {
            for x in 0..tw {
                let at = (2 * y) * w + 2 * x;
                let top = 3 * (y * sheet_w + col * tw + x);
                sheet[top..top + 3].copy_from_slice(&colour.rgb[at]);
                let d = depth[at];
                let g = match object {
                    _ if d <= 0.0 => 0,
                    Some((mask, span)) if mask.at((2 * x) as i64, (2 * y) as i64) => {
                        grey(d, span, [110.0, 250.0])
                    }
                    Some(_) => grey(d, whole, [30.0, 90.0]),
                    None => grey(d, whole, [40.0, 240.0]),
                };
                let bottom = 3 * ((th + y) * sheet_w + col * tw + x);
                sheet[bottom..bottom + 3].copy_from_slice(&[g, g, g]);
            }
        }
        for (rank, scored) in grasps.iter().enumerate().take(GRASP_COLORS.len()).rev() {
            let g = &scored.grasp;
            let half = g.closing_axis() * (g.width_m / 2.0);
            let back = g.approach() * -0.03;
            let tips = [g.center() - half, g.center() + half];
            let mut segments = vec![(tips[0], tips[1])];
            segments.extend(tips.iter().map(|&t| (t, t + back)));
            for row in 0..2 {
                for &(a, b) in &segments {
                    let (Some(a), Some(b)) = (view.camera.project(a), view.camera.project(b))
                    else {
                        continue;
                    };
                    let offset = [(col * tw) as f32, (row * th) as f32];
                    draw_line(
                        &mut sheet,
                        sheet_w,
                        [col * tw, row * th, tw, th],
                        [a[0] / 2.0 + offset[0], a[1] / 2.0 + offset[1]],
                        [b[0] / 2.0 + offset[0], b[1] / 2.0 + offset[1]],
                        GRASP_COLORS[rank],
                        rank == 0,
                    );
                }
            }
        }
    }
    write_png8(path, sheet_w as u32, sheet_h as u32, 3, &sheet)
}

/// The grey scale's ends of a depth picture: the 2nd and 98th percentiles of the positive
/// depths, over the object's pixels where a mask is given (all of them when it has none), else
/// over all; the far end at least 1 mm past the near one.
pub fn depth_span(depth: &[f32], mask: Option<&mvgrasp_planner::Mask>) -> (f32, f32) {
    let width = mask.map_or(1, |m| m.width() as usize);
    let on_object = |i: usize| mask.is_none_or(|m| m.at((i % width) as i64, (i / width) as i64));
    let mut valid: Vec<f32> = depth
        .iter()
        .enumerate()
        .filter(|&(i, &d)| d > 0.0 && on_object(i))
        .map(|(_, &d)| d)
        .collect();
    if valid.is_empty() {
        valid = depth.iter().copied().filter(|&d| d > 0.0).collect();
    }
    valid.sort_by(f32::total_cmp);
    let at = |q: f64| {
        valid
            .get(((valid.len().saturating_sub(1)) as f64 * q) as usize)
            .copied()
    };
    let (near, far) = (at(0.02).unwrap_or(0.0), at(0.98).unwrap_or(1.0));
    (near, far.max(near + 1e-3))
}

/// A line from `a` to `b` (sheet pixels) in `color`, clipped to the tile `[x, y, w, h]`.
fn draw_line(
    sheet: &mut [u8],
    sheet_w: usize,
    tile: [usize; 4],
    a: [f32; 2],
    b: [f32; 2],
    color: [u8; 3],
    thick: bool,
) {
    let [tx, ty, tw, th] = tile.map(|v| v as i64);
    let steps = (b[0] - a[0])
        .abs()
        .max((b[1] - a[1]).abs())
        .ceil()
        .clamp(1.0, 4096.0) as usize;
    let r = i64::from(thick);
    for s in 0..=steps {
        let t = s as f32 / steps as f32;
        let (x, y) = (
            (a[0] + (b[0] - a[0]) * t).round() as i64,
            (a[1] + (b[1] - a[1]) * t).round() as i64,
        );
        for dy in -r..=r {
            for dx in -r..=r {
                let (u, v) = (x + dx, y + dy);
                if (tx..tx + tw).contains(&u) && (ty..ty + th).contains(&v) {
                    let i = 3 * (v as usize * sheet_w + u as usize);
                    sheet[i..i + 3].copy_from_slice(&color);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sensor_files::read_rgb;
    use mvgrasp_geometry::{Intrinsics, Vec3};
    use mvgrasp_planner::{DepthImage, Mask, View};

    #[test]
    fn the_contact_sheet_draws_the_object_on_its_own_bright_scale() {
        // A 64 x 48 camera 0.7 m above the table; a 20 x 16 px object 5 to 6.5 cm tall (its
        // left columns nearest), and the table 0.70 m away.
        let k = Intrinsics {
            fx: 60.0,
            fy: 60.0,
            cx: 31.5,
            cy: 23.5,
            width: 64,
            height: 48,
            z_near_m: 0.1,
            z_far_m: 2.0,
        };
        let camera = Camera::look_at(
            k,
            Vec3::new(0.0, 0.0, 0.7),
            Vec3::ZERO,
            Vec3::new(0.0, -1.0, 0.0),
        )
        .unwrap();
        let on_object = |u: usize, v: usize| (22..42).contains(&u) && (16..32).contains(&v);
        let (mut depth, mut mask) = (Vec::new(), Vec::new());
        for v in 0..48 {
            for u in 0..64 {
                let object = on_object(u, v);
                depth.push(if object {
                    0.635 + 0.0008 * (u - 22) as f32
                } else {
                    0.7
                });
                mask.push(object);
            }
        }
        let view = View::new(0, camera, DepthImage::new(k, depth).unwrap())
            .unwrap()
            .with_mask(Mask::new(64, 48, mask.clone()).unwrap())
            .unwrap();
        let rgb = crate::stereo::RgbView {
            camera,
            rgb: vec![[90, 120, 150]; 64 * 48],
            mask: Some(mask),
        };
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("views.png");
        write_contact_sheet(&path, &[rgb], &[view], &[]).unwrap();
        let (w, h, sheet) = read_rgb(&path).unwrap();
        assert_eq!((w, h), (32, 48));
        // The depth row: the sheet's lower half, at half resolution.
        let grey = |x: usize, y: usize| sheet[(24 + y) * 32 + x][0];
        let (table, nearest, farthest) = (grey(2, 2), grey(11, 12), grey(20, 12));
        assert!(table <= 90, "the table dim: {table}");
        assert!(farthest >= 110, "the object's far side bright: {farthest}");
        assert!(
            nearest > farthest + 100,
            "the object's own span: {nearest} vs {farthest}"
        );
        // The colour row above, unchanged.
        assert_eq!(sheet[2 * 32 + 2], [90, 120, 150]);
    }
}
