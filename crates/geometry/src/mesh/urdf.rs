//! URDF: the kinematic tree ([`UrdfModel`]) and every link's visual or collision geometry,
//! placed by the joints (at zero when loaded as a mesh), with each element's `origin` and mesh
//! `scale` applied.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::EulerRot;
use parry3d::math::{Pose3, Rot3, Vec3};
use parry3d::shape::{Ball, Capsule, Cuboid, Cylinder};

use super::TriangleMesh;
use super::load::{UrdfGeometryKind, load_unscaled};
use crate::error::{GeometryError, Result};

/// Subdivisions used to tessellate URDF cylinders, spheres and capsules.
const PRIMITIVE_SUBDIVISIONS: u32 = 32;

pub(super) fn read_urdf(path: &Path, kind: UrdfGeometryKind) -> Result<TriangleMesh> {
    UrdfModel::load(path)?.mesh(kind, &HashMap::new())
}

/// A URDF's kinematic tree: its links, joints and geometry, posed at any joint positions.
///
/// Revolute and continuous joints turn about their axis, prismatic joints slide along it, and a
/// `<mimic>` joint follows its source (`multiplier * q + offset`); floating and planar joints
/// stay at their origin. Grippers are described this way, so [`UrdfModel::link_poses`] is what
/// turns a gripper's URDF into finger positions at its joint limits.
#[derive(Debug, Clone)]
pub struct UrdfModel {
    robot: urdf_rs::Robot,
    root: String,
    path: PathBuf,
}

impl UrdfModel {
    /// Parses the URDF at `path` and checks that its joints form one tree.
    ///
    /// # Errors
    /// [`GeometryError::Parse`] for malformed XML; [`GeometryError::UrdfStructure`] when there is
    /// not exactly one root link, a joint names a missing link or a link has two parents.
    pub fn load(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|e| match e.kind() {
            std::io::ErrorKind::NotFound => GeometryError::NotFound {
                path: path.to_path_buf(),
            },
            _ => GeometryError::Parse {
                format: "URDF",
                detail: crate::one_line(&e.to_string()),
                path: path.to_path_buf(),
            },
        })?;
        let robot = urdf_rs::read_from_string(&with_limit_velocities(&text)).map_err(|e| {
            GeometryError::Parse {
                format: "URDF",
                detail: crate::one_line(&e.to_string()),
                path: path.to_path_buf(),
            }
        })?;
        let structure = |detail: String| GeometryError::UrdfStructure {
            detail,
            path: path.to_path_buf(),
        };
        let has_link = |name: &str| robot.links.iter().any(|l| l.name == name);
        for joint in &robot.joints {
            for end in [&joint.parent.link, &joint.child.link] {
                if !has_link(end) {
                    return Err(structure(format!(
                        "joint {:?} names link {end:?}, which does not exist",
                        joint.name
                    )));
                }
            }
            if robot
                .joints
                .iter()
                .filter(|j| j.child.link == joint.child.link)
                .count()
                > 1
            {
                return Err(structure(format!(
                    "link {:?} is the child of more than one joint",
                    joint.child.link
                )));
            }
            if let Some(mimic) = &joint.mimic
                && !robot.joints.iter().any(|j| j.name == mimic.joint)
            {
                return Err(structure(format!(
                    "joint {:?} mimics {:?}, which does not exist",
                    joint.name, mimic.joint
                )));
            }
        }
        let roots: Vec<&str> = robot
            .links
            .iter()
            .map(|l| l.name.as_str())
            .filter(|n| !robot.joints.iter().any(|j| j.child.link == *n))
            .collect();
        if roots.len() != 1 {
            return Err(structure(format!(
                "expected one root link, found {} ({roots:?})",
                roots.len()
            )));
        }
        let root = roots[0].to_string();
        Ok(Self {
            robot,
            root,
            path: path.to_path_buf(),
        })
    }

    /// The robot's name.
    pub fn name(&self) -> &str {
        &self.robot.name
    }

    /// The file it came from.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Every link's name, in file order.
    pub fn link_names(&self) -> impl Iterator<Item = &str> {
        self.robot.links.iter().map(|l| l.name.as_str())
    }

    /// The joints that move `link` relative to the root, root first, each named by the joint
    /// that drives it (a mimic joint by its source); fixed joints are left out.
    ///
    /// # Errors
    /// [`GeometryError::UrdfStructure`] when `link` does not exist.
    pub fn driving_joints(&self, link: &str) -> Result<Vec<String>> {
        if !self.link_names().any(|l| l == link) {
            return Err(self.structure(format!("no link named {link:?}")));
        }
        let mut joints = Vec::new();
        let mut current = link;
        while let Some(joint) = self.robot.joints.iter().find(|j| j.child.link == current) {
            if !matches!(joint.joint_type, urdf_rs::JointType::Fixed) {
                let source = joint.mimic.as_ref().map_or(&joint.name, |m| &m.joint);
                joints.push(source.clone());
            }
            current = &joint.parent.link;
        }
        joints.reverse();
        Ok(joints)
    }

    /// A joint's `[lower, upper]` limits (radians or metres).
    ///
    /// # Errors
    /// [`GeometryError::UrdfStructure`] when the joint does not exist.
    pub fn joint_limits(&self, joint: &str) -> Result<[f32; 2]> {
        let joint = self.joint(joint)?;
        Ok([joint.limit.lower as f32, joint.limit.upper as f32])
    }

    /// A joint's effort limit (newtons for a prismatic joint, newton-metres for a revolute one).
    ///
    /// # Errors
    /// [`GeometryError::UrdfStructure`] when the joint does not exist.
    pub fn joint_effort(&self, joint: &str) -> Result<f32> {
        Ok(self.joint(joint)?.limit.effort as f32)
    }

    /// `root_from_link` for every link reachable from the root, with the joints at `positions`
    /// (by name; a joint not named is at 0, a mimic joint follows its source).
    pub fn link_poses(&self, positions: &HashMap<String, f32>) -> HashMap<&str, Pose3> {
        let position = |joint: &urdf_rs::Joint| match &joint.mimic {
            Some(m) => {
                let q = positions.get(&m.joint).copied().unwrap_or(0.0);
                q * m.multiplier.unwrap_or(1.0) as f32 + m.offset.unwrap_or(0.0) as f32
            }
            None => positions.get(&joint.name).copied().unwrap_or(0.0),
        };
        let mut poses = HashMap::from([(self.root.as_str(), Pose3::IDENTITY)]);
        // Joints may be listed in any order: sweep until every reachable link is placed.
        for _ in 0..=self.robot.joints.len() {
            let mut placed_any = false;
            for joint in &self.robot.joints {
                let child = joint.child.link.as_str();
                if poses.contains_key(child) {
                    continue;
                }
                if let Some(parent) = poses.get(joint.parent.link.as_str()).copied() {
                    let motion = joint_motion(joint, position(joint));
                    poses.insert(child, parent * pose_from_urdf(&joint.origin) * motion);
                    placed_any = true;
                }
            }
            if !placed_any {
                break;
            }
        }
        poses
    }

    /// One link's geometry of `kind` (falling back to the other kind when it has none), merged
    /// into one mesh in the link's frame; `None` for a link without geometry.
    ///
    /// # Errors
    /// [`GeometryError::UrdfStructure`] for an unknown link; [`GeometryError::UrdfMeshMissing`]
    /// or [`GeometryError::UrdfLink`] for geometry that cannot be read.
    pub fn link_mesh(&self, link: &str, kind: UrdfGeometryKind) -> Result<Option<TriangleMesh>> {
        let link = self
            .robot
            .links
            .iter()
            .find(|l| l.name == link)
            .ok_or_else(|| self.structure(format!("no link named {link:?}")))?;
        let visual = link.visual.iter().map(|v| (&v.origin, &v.geometry));
        let collision = link.collision.iter().map(|c| (&c.origin, &c.geometry));
        let geometries: Vec<(&urdf_rs::Pose, &urdf_rs::Geometry)> =
            match (kind, link.visual.is_empty(), link.collision.is_empty()) {
                (UrdfGeometryKind::Visual, false, _) | (UrdfGeometryKind::Collision, _, true) => {
                    visual.collect()
                }
                _ => collision.collect(),
            };
        let base_dir = self.path.parent().unwrap_or(Path::new("."));
        let mut parts = Vec::with_capacity(geometries.len());
        for (origin, geometry) in geometries {
            let in_element = geometry_mesh(geometry, base_dir).map_err(|e| match e {
                GeometryError::NotFound { path: mesh } => GeometryError::UrdfMeshMissing {
                    link: link.name.clone(),
                    mesh,
                    path: self.path.clone(),
                },
                other => GeometryError::UrdfLink {
                    link: link.name.clone(),
                    source: Box::new(other),
                    path: self.path.clone(),
                },
            })?;
            parts.push(in_element.transformed(&pose_from_urdf(origin)));
        }
        if parts.is_empty() {
            return Ok(None);
        }
        TriangleMesh::concatenate(&parts, &self.path).map(Some)
    }

    /// Every link's geometry of `kind`, posed by the joints at `positions` (see
    /// [`UrdfModel::link_poses`]), merged into one mesh in the root frame.
    ///
    /// # Errors
    /// [`GeometryError::UrdfNoGeometry`] when no link has geometry; the errors of
    /// [`UrdfModel::link_mesh`].
    pub fn mesh(
        &self,
        kind: UrdfGeometryKind,
        positions: &HashMap<String, f32>,
    ) -> Result<TriangleMesh> {
        let poses = self.link_poses(positions);
        let mut parts = Vec::new();
        for link in &self.robot.links {
            if let Some(mesh) = self.link_mesh(&link.name, kind)? {
                let pose = poses
                    .get(link.name.as_str())
                    .copied()
                    .unwrap_or(Pose3::IDENTITY);
                parts.push(mesh.transformed(&pose));
            }
        }
        if parts.is_empty() {
            let kind = match kind {
                UrdfGeometryKind::Visual => "visual",
                UrdfGeometryKind::Collision => "collision",
            };
            return Err(GeometryError::UrdfNoGeometry {
                kind,
                path: self.path.clone(),
            });
        }
        TriangleMesh::concatenate(&parts, &self.path)
    }

    fn joint(&self, name: &str) -> Result<&urdf_rs::Joint> {
        self.robot
            .joints
            .iter()
            .find(|j| j.name == name)
            .ok_or_else(|| self.structure(format!("no joint named {name:?}")))
    }

    fn structure(&self, detail: String) -> GeometryError {
        GeometryError::UrdfStructure {
            detail,
            path: self.path.clone(),
        }
    }
}

/// The URDF text with `velocity="0"` added to every `<limit>` element that lacks it: the URDF
/// spec requires the attribute and urdf-rs insists, but pybullet and many published files (the
/// pybullet Robotiq 2F-85 among them) leave it out of joints that are not driven.
fn with_limit_velocities(text: &str) -> std::borrow::Cow<'_, str> {
    let mut pieces = text.split("<limit");
    let Some(first) = pieces.next() else {
        return text.into();
    };
    let mut out = String::with_capacity(text.len());
    out.push_str(first);
    let mut changed = false;
    for piece in pieces {
        out.push_str("<limit");
        let tag_end = piece.find('>').unwrap_or(piece.len());
        let is_limit = piece.starts_with(|c: char| c.is_whitespace() || c == '/' || c == '>');
        if is_limit && !piece[..tag_end].contains("velocity") {
            out.push_str(" velocity=\"0\"");
            changed = true;
        }
        out.push_str(piece);
    }
    if changed { out.into() } else { text.into() }
}

/// `parent_from_child` of a URDF `<origin>`: fixed-axis roll, pitch, yaw then translation.
fn pose_from_urdf(origin: &urdf_rs::Pose) -> Pose3 {
    let [x, y, z] = origin.xyz.0.map(|v| v as f32);
    let [roll, pitch, yaw] = origin.rpy.0.map(|v| v as f32);
    Pose3::from_parts(
        Vec3::new(x, y, z),
        Rot3::from_euler(EulerRot::ZYX, yaw, pitch, roll),
    )
}

/// The motion of `joint` at position `q`, in the joint frame.
fn joint_motion(joint: &urdf_rs::Joint, q: f32) -> Pose3 {
    let axis = Vec3::from_array(joint.axis.xyz.0.map(|v| v as f32)).normalize_or_zero();
    match joint.joint_type {
        urdf_rs::JointType::Revolute | urdf_rs::JointType::Continuous if axis != Vec3::ZERO => {
            Pose3::from_parts(Vec3::ZERO, Rot3::from_axis_angle(axis, q))
        }
        urdf_rs::JointType::Prismatic => Pose3::from_translation(axis * q),
        _ => Pose3::IDENTITY,
    }
}

/// One geometry element in its own frame, in metres (mesh `scale` applied).
fn geometry_mesh(geometry: &urdf_rs::Geometry, base_dir: &Path) -> Result<TriangleMesh> {
    let f = |v: f64| v as f32;
    let (vertices, triangles) = match geometry {
        urdf_rs::Geometry::Mesh { filename, scale } => {
            let file = resolve_mesh_path(filename, base_dir);
            let mesh = load_unscaled(&file, UrdfGeometryKind::Visual)?;
            let scale = scale.map_or(Vec3::ONE, |s| Vec3::new(f(s[0]), f(s[1]), f(s[2])));
            return Ok(mesh.scaled(scale));
        }
        urdf_rs::Geometry::Box { size } => {
            Cuboid::new(Vec3::new(f(size[0]), f(size[1]), f(size[2])) * 0.5).to_trimesh()
        }
        urdf_rs::Geometry::Cylinder { radius, length } => {
            // parry's cylinder runs along y; URDF's along z.
            let (v, t) =
                Cylinder::new(f(*length) * 0.5, f(*radius)).to_trimesh(PRIMITIVE_SUBDIVISIONS);
            let y_to_z = Rot3::from_rotation_x(std::f32::consts::FRAC_PI_2);
            (v.into_iter().map(|p| y_to_z * p).collect(), t)
        }
        urdf_rs::Geometry::Capsule { radius, length } => {
            Capsule::new_z(f(*length) * 0.5, f(*radius))
                .to_trimesh(PRIMITIVE_SUBDIVISIONS, PRIMITIVE_SUBDIVISIONS / 2)
        }
        urdf_rs::Geometry::Sphere { radius } => {
            Ball::new(f(*radius)).to_trimesh(PRIMITIVE_SUBDIVISIONS, PRIMITIVE_SUBDIVISIONS / 2)
        }
    };
    TriangleMesh::new(vertices, triangles)
}

/// Resolves a URDF mesh reference: relative to the URDF's folder; `file://` stripped;
/// `package://pkg/rest` looked up as `rest` beside the URDF, then as `pkg/rest` in each
/// ancestor folder.
fn resolve_mesh_path(filename: &str, base_dir: &Path) -> PathBuf {
    if let Some(rest) = filename.strip_prefix("package://") {
        let (package, inner) = rest.split_once('/').unwrap_or((rest, ""));
        let beside = base_dir.join(inner);
        if beside.is_file() {
            return beside;
        }
        for ancestor in base_dir.ancestors() {
            let candidate = ancestor.join(package).join(inner);
            if candidate.is_file() {
                return candidate;
            }
        }
        return beside;
    }
    let plain = filename.strip_prefix("file://").unwrap_or(filename);
    base_dir.join(plain)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rpy_is_fixed_axis_roll_then_pitch_then_yaw() {
        let origin = urdf_rs::Pose {
            xyz: urdf_rs::Vec3([1.0, 2.0, 3.0]),
            rpy: urdf_rs::Vec3([0.0, 0.0, std::f64::consts::FRAC_PI_2]),
        };
        let pose = pose_from_urdf(&origin);
        let x = pose.transform_vector(Vec3::X);
        assert!(
            (x - Vec3::Y).length() < 1e-6,
            "yaw 90 deg maps x to y, got {x}"
        );
        assert_eq!(pose.translation, Vec3::new(1.0, 2.0, 3.0));
    }

    #[test]
    fn package_urls_resolve_beside_the_urdf() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir_all(dir.path().join("meshes")).unwrap();
        std::fs::write(dir.path().join("meshes/a.obj"), "").unwrap();
        let p = resolve_mesh_path("package://robot/meshes/a.obj", dir.path());
        assert_eq!(p, dir.path().join("meshes/a.obj"));
    }

    const TWO_FINGERS: &str = r#"<robot name="two_fingers">
  <link name="palm"><collision><geometry><box size="0.1 0.02 0.02"/></geometry></collision></link>
  <link name="left"><collision><geometry><box size="0.01 0.02 0.04"/></geometry></collision></link>
  <link name="right"><collision><geometry><box size="0.01 0.02 0.04"/></geometry></collision></link>
  <link name="arm"/>
  <joint name="mount" type="revolute"><parent link="arm"/><child link="palm"/>
    <axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <joint name="left_slide" type="prismatic"><parent link="palm"/><child link="left"/>
    <origin xyz="-0.01 0 0.03"/><axis xyz="-1 0 0"/>
    <limit lower="0" upper="0.04" effort="30" velocity="1"/></joint>
  <joint name="right_slide" type="prismatic"><parent link="palm"/><child link="right"/>
    <origin xyz="0.01 0 0.03"/><axis xyz="1 0 0"/>
    <limit lower="0" upper="0.04" effort="30" velocity="1"/>
    <mimic joint="left_slide" multiplier="1" offset="0"/></joint>
</robot>"#;

    #[test]
    fn joints_move_links_and_mimic_joints_follow_their_source() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("two_fingers.urdf");
        std::fs::write(&path, TWO_FINGERS).unwrap();
        let model = UrdfModel::load(&path).unwrap();
        assert_eq!(model.name(), "two_fingers");
        assert_eq!(
            model.driving_joints("right").unwrap(),
            ["mount", "left_slide"]
        );
        assert_eq!(model.joint_limits("left_slide").unwrap(), [0.0, 0.04]);
        assert_eq!(model.joint_effort("left_slide").unwrap(), 30.0);
        let open = HashMap::from([("left_slide".to_string(), 0.04)]);
        let poses = model.link_poses(&open);
        assert!((poses["left"].translation - Vec3::new(-0.05, 0.0, 0.03)).length() < 1e-6);
        assert!((poses["right"].translation - Vec3::new(0.05, 0.0, 0.03)).length() < 1e-6);
        let turned = HashMap::from([("mount".to_string(), std::f32::consts::FRAC_PI_2)]);
        let poses = model.link_poses(&turned);
        assert!((poses["right"].translation - Vec3::new(0.0, 0.01, 0.03)).length() < 1e-6);
        let mesh = model.mesh(UrdfGeometryKind::Collision, &open).unwrap();
        assert!((mesh.aabb().extents().x - 0.11).abs() < 1e-6);
        assert!(model.driving_joints("thumb").is_err());
        assert!(model.joint_limits("elbow").is_err());
    }

    #[test]
    fn limits_without_a_velocity_read_as_zero() {
        let text = r#"<limit effort="1" lower="0" upper="1"/><limit velocity="2"/><limits/>"#;
        assert_eq!(
            with_limit_velocities(text),
            r#"<limit velocity="0" effort="1" lower="0" upper="1"/><limit velocity="2"/><limits/>"#
        );
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("no_velocity.urdf");
        std::fs::write(&path, TWO_FINGERS.replace(r#" velocity="1""#, "")).unwrap();
        assert_eq!(
            UrdfModel::load(&path)
                .unwrap()
                .joint_limits("left_slide")
                .unwrap(),
            [0.0, 0.04]
        );
    }

    #[test]
    fn a_mimic_of_a_missing_joint_is_a_structure_error() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("bad.urdf");
        std::fs::write(
            &path,
            TWO_FINGERS.replace(r#"mimic joint="left_slide""#, r#"mimic joint="nope""#),
        )
        .unwrap();
        let err = UrdfModel::load(&path).unwrap_err().to_string();
        assert!(err.contains("mimics") && err.contains("bad.urdf"), "{err}");
    }
}
