//! A [`Gripper`] measured from a URDF: the finger pads posed at the opening joint's limits give
//! the stroke, the links that do not move with it give the palm.

use std::collections::HashMap;
use std::path::Path;

use mvgrasp_geometry::{Pose3, Rot3, TriangleMesh, UrdfGeometryKind, UrdfModel, Vec3};
use serde::{Deserialize, Serialize};

use crate::error::{GraspError, Result};
use crate::gripper::Gripper;

/// How to read a gripper from its URDF. Every field is optional.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct UrdfGripperSpec {
    /// The two finger-pad links, the -x finger first. Default: the two links whose names contain
    /// "pad" and that have geometry, ordered by name.
    pub finger_links: Option<[String; 2]>,
    /// The joint that opens and closes the fingers. Default: the last joint that drives both
    /// finger links (mimic joints count as their source).
    pub joint: Option<String>,
    /// Closing force, newtons. URDF effort limits are torques for linkage grippers and often
    /// placeholders (the pybullet Robotiq 2F-85 says 1000), so the force is not read from the
    /// file. Default: the Robotiq 2F-85's 235 N.
    pub force_limit_n: Option<f32>,
    /// See [`Gripper::approach_distance_m`]. Default: 0.08 m.
    pub approach_distance_m: Option<f32>,
}

/// A gripper read from a URDF, and where its gripper frame sits in the URDF's root frame.
#[derive(Clone, Debug, PartialEq)]
pub struct UrdfGripper {
    /// The gripper, named after the robot.
    pub gripper: Gripper,
    /// `urdf_root_from_gripper`: turns a grasp's `world_from_gripper` into the pose of the
    /// URDF's root link (`world_from_gripper * urdf_root_from_gripper.inverse()`).
    pub urdf_root_from_gripper: Pose3,
    /// The joint that opens the fingers, and its positions when they are widest and shut.
    pub joint: String,
    /// The joint position at the widest opening.
    pub open_position: f32,
}

/// The collision geometry of the links that matter, posed at one joint position (URDF root
/// frame).
struct Posed {
    pads: [Vec<Vec3>; 2],
    moving: Vec<Vec3>,
    fixed: Vec<Vec3>,
}

impl Gripper {
    /// Measures a gripper from the URDF at `path` (collision geometry, or visual where a link
    /// has none), as [`UrdfGripperSpec`] says.
    ///
    /// The opening joint is posed at both of its limits with every other joint at zero. The
    /// closing axis (x) runs from the first pad to the second when open; the approach (z) from
    /// the geometry that does not move with the joint (the palm) towards the pads; the origin is
    /// midway between the pads, level with the farthest fingertip. The stroke is the gap
    /// between the pads' inner faces at the two limits; finger thickness is the first pad's
    /// depth along x, finger width the widest moving link along y, finger length the reach of
    /// the moving links past the palm; the palm box bounds the fixed links. The URDF should
    /// describe the hand only: links of an arm would count as palm.
    ///
    /// # Errors
    /// [`GraspError::GripperFile`] naming the file: it cannot be read, the finger links or the
    /// joint cannot be found or do not move the pads apart, there is no palm geometry, or the
    /// measured gripper is invalid.
    pub fn from_urdf(path: impl AsRef<Path>, spec: &UrdfGripperSpec) -> Result<UrdfGripper> {
        let path = path.as_ref();
        let fail = |detail: String| GraspError::GripperFile {
            detail,
            path: path.to_path_buf(),
        };
        let model = UrdfModel::load(path).map_err(|e| fail(e.to_string()))?;
        let meshes = link_meshes(&model).map_err(|e| fail(e.to_string()))?;
        let pads = match &spec.finger_links {
            Some(links) => links.clone(),
            None => pad_links(&meshes).map_err(&fail)?,
        };
        for pad in &pads {
            if !meshes.contains_key(pad.as_str()) {
                return Err(fail(format!("finger link {pad:?} has no geometry")));
            }
        }
        let drivers = [
            model
                .driving_joints(&pads[0])
                .map_err(|e| fail(e.to_string()))?,
            model
                .driving_joints(&pads[1])
                .map_err(|e| fail(e.to_string()))?,
        ];
        let joint = match &spec.joint {
            Some(joint) => joint.clone(),
            None => drivers[0]
                .iter()
                .rev()
                .find(|j| drivers[1].contains(j))
                .cloned()
                .ok_or_else(|| {
                    fail(format!(
                        "no joint drives both finger links {pads:?}; name one in the spec"
                    ))
                })?,
        };
        let limits = model
            .joint_limits(&joint)
            .map_err(|e| fail(e.to_string()))?;
        let moving: Vec<&str> = meshes
            .keys()
            .copied()
            .filter(|link| {
                model
                    .driving_joints(link)
                    .is_ok_and(|joints| joints.contains(&joint))
            })
            .collect();
        let pose_at = |q: f32| -> Posed {
            let poses = model.link_poses(&HashMap::from([(joint.clone(), q)]));
            let place = |link: &str| -> Vec<Vec3> {
                let pose = poses.get(link).copied().unwrap_or(Pose3::IDENTITY);
                meshes[link]
                    .vertices()
                    .iter()
                    .map(|&v| pose.transform_point(v))
                    .collect()
            };
            Posed {
                pads: [place(&pads[0]), place(&pads[1])],
                moving: moving.iter().flat_map(|link| place(link)).collect(),
                fixed: meshes
                    .keys()
                    .filter(|link| !moving.contains(link))
                    .flat_map(|link| place(link))
                    .collect(),
            }
        };
        let states = limits.map(pose_at);
        let spread = |s: &Posed| centroid(&s.pads[0]).distance(centroid(&s.pads[1]));
        let open_index = usize::from(spread(&states[1]) > spread(&states[0]));
        let open = &states[open_index];
        if open.fixed.is_empty() {
            return Err(fail(
                "every link with geometry moves with the opening joint: no palm".into(),
            ));
        }
        let x = (centroid(&open.pads[1]) - centroid(&open.pads[0])).normalize_or_zero();
        let mid = (centroid(&open.pads[0]) + centroid(&open.pads[1])) / 2.0;
        let toward_pads = mid - centroid(&open.fixed);
        let z = (toward_pads - x * toward_pads.dot(x)).normalize_or_zero();
        if x == Vec3::ZERO || z == Vec3::ZERO {
            return Err(fail(format!(
                "the finger pads {pads:?} and the palm do not span a gripper frame"
            )));
        }
        let y = z.cross(x);
        let gap = |s: &Posed| span(&s.pads[1], x)[0] - span(&s.pads[0], x)[1];
        let gaps = states.each_ref().map(gap);
        let max_opening_m = gaps[0].max(gaps[1]);
        let min_opening_m = gaps[0].min(gaps[1]).max(0.0);
        let tip_z = span(&open.moving, z)[1];
        let palm_z = span(&open.fixed, z);
        let palm_x = span(&open.fixed, x);
        let palm_y = span(&open.fixed, y);
        let extent = |s: [f32; 2]| s[1] - s[0];
        let origin = mid + z * (tip_z - mid.dot(z));
        let finger_length_m = tip_z - palm_z[1];
        let finger_width_m = extent(span(&open.moving, y));
        let gripper = Gripper {
            name: model.name().to_string(),
            max_opening_m,
            min_opening_m,
            finger_length_m,
            finger_width_m,
            finger_thickness_m: extent(span(&open.pads[0], x)),
            force_limit_n: spec.force_limit_n.unwrap_or(235.0),
            palm_size_m: [extent(palm_x), extent(palm_y), extent(palm_z)],
            approach_distance_m: spec.approach_distance_m.unwrap_or(0.08),
            // The pad fills the finger's width (or half its length, if shorter).
            pad_radius_m: 0.5 * finger_width_m.min(finger_length_m),
            pad_friction: crate::gripper::DEFAULT_PAD_FRICTION,
            open_margin_m: crate::gripper::DEFAULT_OPEN_MARGIN_M,
        };
        gripper.validate().map_err(|e| fail(e.to_string()))?;
        let rotation = Rot3::from_mat3(&mvgrasp_geometry::Mat3::from_cols(x, y, z));
        let urdf_root_from_gripper = Pose3::from_parts(origin, rotation);
        Ok(UrdfGripper {
            gripper,
            urdf_root_from_gripper,
            joint,
            open_position: limits[open_index],
        })
    }
}

/// Every link's collision mesh (visual where it has none), in its own frame.
fn link_meshes(model: &UrdfModel) -> mvgrasp_geometry::Result<HashMap<&str, TriangleMesh>> {
    let mut meshes = HashMap::new();
    for link in model.link_names() {
        if let Some(mesh) = model.link_mesh(link, UrdfGeometryKind::Collision)? {
            meshes.insert(link, mesh);
        }
    }
    Ok(meshes)
}

/// The two links with geometry whose names contain "pad", in name order.
fn pad_links(meshes: &HashMap<&str, TriangleMesh>) -> std::result::Result<[String; 2], String> {
    let mut pads: Vec<&str> = meshes
        .keys()
        .copied()
        .filter(|l| l.to_ascii_lowercase().contains("pad"))
        .collect();
    pads.sort_unstable();
    match pads.as_slice() {
        [a, b] => Ok([a.to_string(), b.to_string()]),
        _ => Err(format!(
            "expected two finger-pad links (names containing \"pad\"), found {pads:?}; name \
             them in the spec's finger_links"
        )),
    }
}

fn centroid(points: &[Vec3]) -> Vec3 {
    points.iter().copied().sum::<Vec3>() / points.len().max(1) as f32
}

/// `[min, max]` of the points along `axis`.
fn span(points: &[Vec3], axis: Vec3) -> [f32; 2] {
    points
        .iter()
        .map(|p| p.dot(axis))
        .fold([f32::INFINITY, f32::NEG_INFINITY], |[lo, hi], d| {
            [lo.min(d), hi.max(d)]
        })
}
