//! URDF: every link's visual or collision geometry, placed by the joint tree at zero joint
//! positions, with each element's `origin` and mesh `scale` applied, merged into one mesh.

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
    let robot = urdf_rs::read_file(path).map_err(|e| GeometryError::Parse {
        format: "URDF",
        detail: e.to_string(),
        path: path.to_path_buf(),
    })?;
    let base_dir = path.parent().unwrap_or(Path::new("."));
    let world_from_link = link_poses(&robot, path)?;
    let mut parts = Vec::new();
    for link in &robot.links {
        let geometries: Vec<(&urdf_rs::Pose, &urdf_rs::Geometry)> = {
            let visual = link.visual.iter().map(|v| (&v.origin, &v.geometry));
            let collision = link.collision.iter().map(|c| (&c.origin, &c.geometry));
            match (kind, link.visual.is_empty(), link.collision.is_empty()) {
                (UrdfGeometryKind::Visual, false, _) | (UrdfGeometryKind::Collision, _, true) => {
                    visual.collect()
                }
                _ => collision.collect(),
            }
        };
        let link_pose = world_from_link
            .get(link.name.as_str())
            .copied()
            .unwrap_or(Pose3::IDENTITY);
        for (origin, geometry) in geometries {
            let in_link = geometry_mesh(geometry, base_dir).map_err(|e| match e {
                GeometryError::NotFound { path: mesh } => GeometryError::UrdfMeshMissing {
                    link: link.name.clone(),
                    mesh,
                    path: path.to_path_buf(),
                },
                other => GeometryError::UrdfLink {
                    link: link.name.clone(),
                    source: Box::new(other),
                    path: path.to_path_buf(),
                },
            })?;
            parts.push(in_link.transformed(&(link_pose * pose_from_urdf(origin))));
        }
    }
    if parts.is_empty() {
        let kind = match kind {
            UrdfGeometryKind::Visual => "visual",
            UrdfGeometryKind::Collision => "collision",
        };
        return Err(GeometryError::UrdfNoGeometry {
            kind,
            path: path.to_path_buf(),
        });
    }
    TriangleMesh::concatenate(&parts, path)
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

/// `world_from_link` for every link, with all joints at zero.
fn link_poses<'a>(robot: &'a urdf_rs::Robot, path: &Path) -> Result<HashMap<&'a str, Pose3>> {
    let children: Vec<&str> = robot.joints.iter().map(|j| j.child.link.as_str()).collect();
    let roots: Vec<&str> = robot
        .links
        .iter()
        .map(|l| l.name.as_str())
        .filter(|n| !children.contains(n))
        .collect();
    if roots.len() != 1 {
        return Err(GeometryError::UrdfStructure {
            detail: format!("expected one root link, found {} ({roots:?})", roots.len()),
            path: path.to_path_buf(),
        });
    }
    let mut poses = HashMap::from([(roots[0], Pose3::IDENTITY)]);
    // Joints may be listed in any order: sweep until every reachable link is placed.
    for _ in 0..=robot.joints.len() {
        let mut placed_any = false;
        for joint in &robot.joints {
            let child = joint.child.link.as_str();
            if poses.contains_key(child) {
                continue;
            }
            if let Some(parent) = poses.get(joint.parent.link.as_str()).copied() {
                poses.insert(child, parent * pose_from_urdf(&joint.origin));
                placed_any = true;
            }
        }
        if !placed_any {
            break;
        }
    }
    Ok(poses)
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
}
