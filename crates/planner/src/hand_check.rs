//! The open hand against what the cameras saw: a candidate is rejected when the gripper, open
//! and coming in straight along its approach from `approach_distance_m` back, would pass
//! through a point that some view observed (the object or the table), or when its contacts do
//! not lie on observed surface. Depth alone: no mesh is needed. With the views fused
//! ([`Fusion`]), the hand must also stay out of space that no view has seen, and above the
//! table.

use mvgrasp_geometry::{Mat3, Pose3, Vec3};
use mvgrasp_grasp::{Gripper, HandShapes};

use crate::depth_image::{MASK_MARGIN_PX, View};
use crate::fusion::Fusion;
use crate::scored::{Rejection, ScoredGrasp};

/// The hand's boxes are grown by this before observed points are tested against them, metres:
/// a candidate whose open hand comes within it of an observed point is rejected. The depth image
/// samples a surface about every 0.6 mm at the networks' 0.7 m (a PhoXi S pixel), so a surface
/// can reach that far into a box between the points that are tested; and the physics trial
/// counts an approach that comes within 0.1 mm of the object as touching it.
const HAND_CLEARANCE_M: f32 = 0.001;

/// Checks `candidate` against every view and, where given, the views fused: `None` when it
/// survives, else why not. The hand is `gripper`'s boxes, open for the candidate's width
/// ([`Gripper::opening_for`]), swept back along -z by its approach distance.
pub fn check_hand(
    candidate: &ScoredGrasp,
    views: &[View],
    fusion: Option<&Fusion>,
    gripper: &Gripper,
) -> Option<Rejection> {
    if !candidate.from_cloud
        && let Some(view) = views.get(candidate.view)
    {
        // The contacts' pixels; a grasp at no depth has none on the surface.
        let Some(jaws) = candidate.image.jaws_px(view.depth.intrinsics().fx) else {
            return Some(Rejection::ContactOffSurface);
        };
        let contacts = jaws.map(|[u, v]| [u.round() as i64, v.round() as i64]);
        if !contacts.iter().all(|&[u, v]| view.depth.at(u, v) > 0.0) {
            return Some(Rejection::ContactOffSurface);
        }
        if let Some(mask) = &view.mask
            && !contacts
                .iter()
                .all(|&[u, v]| mask.near(u, v, MASK_MARGIN_PX))
        {
            return Some(Rejection::ContactOffObject);
        }
    }
    let hand = HandShapes::new(
        gripper,
        gripper.opening_for(candidate.grasp.width_m),
        gripper.approach_distance_m,
    );
    let world_from_gripper = candidate.grasp.world_from_gripper;
    if let Some(fusion) = fusion
        && hand.lowest_z(&world_from_gripper) < fusion.table_z_m() + HAND_CLEARANCE_M
    {
        return Some(Rejection::HandBelowTable);
    }
    if meets_any_view(&hand, &world_from_gripper, views, fusion) {
        return Some(Rejection::HandMeetsObservedDepth);
    }
    // Observed points were tested exactly above; the cells say what no view has seen.
    let grown = Vec3::splat(HAND_CLEARANCE_M);
    fusion
        .filter(|fusion| !fusion.allows_unknown())
        .is_some_and(|fusion| {
            hand.boxes().iter().any(|(cuboid, box_pose)| {
                let [_, unknown, _] = fusion.count_in_box(
                    &(world_from_gripper * *box_pose),
                    cuboid.half_extents + grown,
                );
                unknown > 0
            })
        })
        .then_some(Rejection::HandEntersUnknownSpace)
}

/// Whether an observed point of some view lies in one of the hand's boxes grown by
/// [`HAND_CLEARANCE_M`]. With the views fused, a box that the fused model says holds no
/// observed point is not searched pixel by pixel.
fn meets_any_view(
    hand: &HandShapes,
    world_from_gripper: &Pose3,
    views: &[View],
    fusion: Option<&Fusion>,
) -> bool {
    let gripper_from_world = world_from_gripper.inverse();
    hand.boxes().iter().any(|(cuboid, box_pose)| {
        let half = cuboid.half_extents + Vec3::splat(HAND_CLEARANCE_M);
        if fusion.is_some_and(|f| !f.may_hold_observed(&(*world_from_gripper * *box_pose), half)) {
            return false;
        }
        views
            .iter()
            .any(|view| box_meets_view(half, box_pose, &gripper_from_world, view))
    })
}

/// Whether a point `view` observed lies inside the box of half extents `half` at
/// `gripper_from_box`.
fn box_meets_view(
    half: Vec3,
    gripper_from_box: &Pose3,
    gripper_from_world: &Pose3,
    view: &View,
) -> bool {
    let gripper_from_camera = *gripper_from_world * view.camera.world_from_camera;
    let camera_from_gripper = gripper_from_camera.inverse();
    let k = view.depth.intrinsics();
    // The pixels the box can cover: its corners projected (the whole image when a corner is
    // behind the camera).
    let (mut lo, mut hi) = ([f32::INFINITY; 2], [f32::NEG_INFINITY; 2]);
    for corner in 0..8 {
        let sign = |bit: u32| if corner >> bit & 1 == 1 { 1.0 } else { -1.0 };
        let local = Vec3::new(sign(0) * half.x, sign(1) * half.y, sign(2) * half.z);
        let in_camera =
            camera_from_gripper.transform_point(gripper_from_box.transform_point(local));
        match k.project(in_camera) {
            Some([u, v]) => {
                lo = [lo[0].min(u), lo[1].min(v)];
                hi = [hi[0].max(u), hi[1].max(v)];
            }
            None => {
                lo = [0.0, 0.0];
                hi = [k.width as f32, k.height as f32];
                break;
            }
        }
    }
    let clamp_u = |x: f32| x.clamp(0.0, k.width.saturating_sub(1) as f32) as i64;
    let clamp_v = |y: f32| y.clamp(0.0, k.height.saturating_sub(1) as f32) as i64;
    let (u0, u1) = (clamp_u(lo[0].floor()), clamp_u(hi[0].ceil()));
    let (v0, v1) = (clamp_v(lo[1].floor()), clamp_v(hi[1].ceil()));
    let box_from_camera = gripper_from_box.inverse() * gripper_from_camera;
    // Pixel (u, v) at depth d is the camera point d * (a_u, b_v, 1): in the box's frame,
    // d * (a_u * R_x + b_v * R_y + R_z) + t, with the rotation's columns formed once.
    let r = Mat3::from_quat(box_from_camera.rotation);
    let t = box_from_camera.translation;
    let columns: Vec<Vec3> = (u0..=u1)
        .map(|u| r.x_axis * ((u as f32 - k.cx) / k.fx))
        .collect();
    let width = k.width as usize;
    let data = view.depth.as_slice();
    (v0..=v1).any(|v| {
        let row_direction = r.y_axis * ((v as f32 - k.cy) / k.fy) + r.z_axis;
        let start = v as usize * width;
        // In the image whenever its intrinsics are valid; a row past it holds nothing.
        let Some(row) = data.get(start + u0 as usize..=start + u1 as usize) else {
            return false;
        };
        row.iter().zip(&columns).any(|(&d, &column)| {
            let p = (column + row_direction) * d + t;
            d > 0.0 && p.x.abs() < half.x && p.y.abs() < half.y && p.z.abs() < half.z
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::depth_image::Mask;
    use crate::test_scenes::{box_view, centred_candidate as candidate};
    use mvgrasp_grasp::ImageGrasp;

    #[test]
    fn the_open_hand_must_clear_what_the_camera_saw() {
        let view = box_view(false);
        let views = [view.clone()];
        let panda = Gripper::default();
        // Across the 4 cm side, 2 cm below the top: the open fingers (8 cm) come down on the
        // table beside the box, clear of it, and stop 3 cm above the table.
        let across = candidate(&view, 0.0, 0.67, 0.04);
        assert_eq!(check_hand(&across, &views, None, &panda), None);
        // Along the 12 cm side the open fingers land on the box's top.
        let along = candidate(&view, std::f32::consts::FRAC_PI_2, 0.67, 0.12);
        assert_eq!(
            check_hand(&along, &views, None, &panda),
            Some(Rejection::HandMeetsObservedDepth)
        );
        // Across, the hand opened for a 2 cm grasp (4 cm): the fingers come down brushing the
        // box's sides (the camera sees only the top's edge there); for a 2.5 cm grasp, 2.5 mm
        // beside them.
        let grazing = candidate(&view, 0.0, 0.67, 0.02);
        assert_eq!(
            check_hand(&grazing, &views, None, &panda),
            Some(Rejection::HandMeetsObservedDepth)
        );
        let clear = candidate(&view, 0.0, 0.67, 0.025);
        assert_eq!(check_hand(&clear, &views, None, &panda), None);
        // Across, but so deep that the fingertips go through the table.
        let deep = candidate(&view, 0.0, 0.73, 0.04);
        assert_eq!(
            check_hand(&deep, &views, None, &panda),
            Some(Rejection::HandMeetsObservedDepth)
        );
    }

    #[test]
    fn contacts_must_lie_on_the_objects_mask() {
        let view = box_view(false);
        let k = view.depth.intrinsics();
        let across = candidate(&view, 0.0, 0.67, 0.04);
        // A mask of the box's left half: the right contact is off it.
        let half: Vec<bool> = (0..k.width * k.height)
            .map(|i| {
                let (u, v) = ((i % k.width) as f32, (i / k.width) as f32);
                let (x, y) = ((u - k.cx) * 0.65 / k.fx, (v - k.cy) * 0.65 / k.fy);
                (-0.021..0.0).contains(&x) && y.abs() < 0.06
            })
            .collect();
        let masked = view
            .clone()
            .with_mask(Mask::new(k.width, k.height, half).unwrap())
            .unwrap();
        assert_eq!(
            check_hand(&across, &[masked], None, &Gripper::default()),
            Some(Rejection::ContactOffObject)
        );
        // The whole box: both on it.
        let whole: Vec<bool> = (0..k.width * k.height)
            .map(|i| view.depth.as_slice()[i as usize] < 0.68)
            .collect();
        let masked = view
            .clone()
            .with_mask(Mask::new(k.width, k.height, whole).unwrap())
            .unwrap();
        assert_eq!(
            check_hand(&across, &[masked], None, &Gripper::default()),
            None
        );
    }

    #[test]
    fn with_the_views_fused_the_hand_must_stay_out_of_unseen_space() {
        use crate::fusion::FusionParams;
        use crate::test_scenes::seen_box;
        use mvgrasp_geometry::{Pose3, Rot3};
        // Straight down across the 4 cm cube, 2.5 cm below its top, the hand open 6 cm: the +x
        // finger comes down beside the cube, into the shadow of a camera on -x.
        let image = ImageGrasp {
            center_px: [0.0, 0.0],
            angle_rad: 0.0,
            depth_m: 0.0,
            width_m: 0.04,
        };
        let down = Pose3::from_parts(
            Vec3::new(0.0, 0.0, 0.015),
            Rot3::from_rotation_x(std::f32::consts::PI),
        );
        // Planned in no view: the contacts' pixels are not tested.
        let grasp = |world_from_gripper| ScoredGrasp {
            view: usize::MAX,
            image,
            grasp: mvgrasp_grasp::Grasp {
                world_from_gripper,
                width_m: 0.04,
            },
            theta_rad: 0.0,
            quality: 0.9,
            view_quality: None,
            virtual_quality: None,
            by_scorer: false,
            from_cloud: false,
        };
        let across = grasp(down);
        let panda = Gripper::default();
        let params = FusionParams::default();
        let left = [seen_box(-1.0)];
        let fused = Fusion::build(&left, &params).unwrap();
        assert_eq!(check_hand(&across, &left, None, &panda), None);
        assert_eq!(
            check_hand(&across, &left, Some(&fused), &panda),
            Some(Rejection::HandEntersUnknownSpace)
        );
        // Seen from +x as well, the shadow is free space.
        let both = [seen_box(-1.0), seen_box(1.0)];
        let fused = Fusion::build(&both, &params).unwrap();
        assert_eq!(check_hand(&across, &both, Some(&fused), &panda), None);
        // 2 cm lower, the fingertips reach below the table.
        let low = grasp(Pose3::from_parts(
            Vec3::new(0.0, 0.0, -0.005),
            down.rotation,
        ));
        assert_eq!(
            check_hand(&low, &both, Some(&fused), &panda),
            Some(Rejection::HandBelowTable)
        );
    }

    #[test]
    fn contacts_must_lie_on_observed_surface() {
        let view = box_view(true);
        // The jaws 6 cm apart: the contact pixels fall in the unobserved ring around the box.
        let off = candidate(&view, 0.0, 0.67, 0.06);
        assert_eq!(
            check_hand(&off, &[view], None, &Gripper::default()),
            Some(Rejection::ContactOffSurface)
        );
    }
}
