//! Every bad input the loaders know gets its own error kind, and a message that names the file.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // tests may fail loudly

use crate::common;

use std::path::{Path, PathBuf};

use mvgrasp_geometry::{GeometryError, LoadOptions, Vec3, load_mesh, load_mesh_with, write_obj};

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// A 5 cm tetrahedron.
const TETRA: &str =
    "v 0 0 0\nv 0.05 0 0\nv 0 0.05 0\nv 0 0 0.05\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";

fn assert_names_file(err: &GeometryError, path: &Path) {
    let message = err.to_string();
    assert!(
        message.contains(&path.display().to_string()),
        "message does not name the file: {message}"
    );
}

#[test]
fn missing_file() {
    let path = Path::new("/nonexistent/mug.obj");
    let err = load_mesh(path).unwrap_err();
    assert!(matches!(err, GeometryError::NotFound { .. }), "{err:?}");
    assert_names_file(&err, path);
}

#[test]
fn unsupported_extension() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "mug.ply", "ply");
    let err = load_mesh(&path).unwrap_err();
    assert!(
        matches!(err, GeometryError::UnsupportedFormat { ref extension, .. } if extension == "ply")
    );
    assert_names_file(&err, &path);
}

#[test]
fn unparsable_obj_stl_and_urdf() {
    let dir = tempfile::tempdir().unwrap();
    for (name, text, format) in [
        ("bad.obj", "v 0 zero 0\nf 1 2 3\n", "OBJ"),
        (
            "bad.stl",
            "solid x\n facet normal 0 0 1\n  outer loop\n   vertex 0 0\n",
            "STL",
        ),
        ("bad.urdf", "<robot name='r'><link name='a'>", "URDF"),
    ] {
        let path = write(dir.path(), name, text);
        let err = load_mesh(&path).unwrap_err();
        assert!(
            matches!(err, GeometryError::Parse { format: f, .. } if f == format),
            "{name}: {err:?}"
        );
        assert_names_file(&err, &path);
    }
}

#[test]
fn no_triangles() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "points.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n");
    let err = load_mesh(&path).unwrap_err();
    assert!(matches!(err, GeometryError::NoTriangles { .. }), "{err:?}");
    assert_names_file(&err, &path);
}

#[test]
fn nan_and_infinite_vertices() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(
        dir.path(),
        "nan.obj",
        &TETRA.replace("v 0 0 0.05", "v 0 inf nan"),
    );
    let err = load_mesh(&path).unwrap_err();
    assert!(
        matches!(
            err,
            GeometryError::NonFiniteVertices {
                count: 1,
                total: 4,
                first: 3,
                ..
            }
        ),
        "{err:?}"
    );
    assert_names_file(&err, &path);
}

#[test]
fn real_all_nan_mesh_from_pybullet() {
    let Some(root) = common::shared_meshes() else {
        return;
    };
    let obj = root.join("pybullet/random_urdfs/168/168.obj");
    let err = load_mesh(&obj).unwrap_err();
    assert!(matches!(err, GeometryError::NonFiniteVertices { count, total, .. } if count == total));
    assert_names_file(&err, &obj);
    // Through its URDF the error names both the URDF and the mesh.
    let urdf = root.join("pybullet/random_urdfs/168/168.urdf");
    let err = load_mesh(&urdf).unwrap_err();
    assert!(matches!(err, GeometryError::UrdfLink { ref source, .. }
        if matches!(**source, GeometryError::NonFiniteVertices { .. })));
    assert_names_file(&err, &urdf);
    assert_names_file(&err, &obj);
}

#[test]
fn out_of_range_indices() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "oob.obj", &format!("{TETRA}f 1 2 9\n"));
    let err = load_mesh(&path).unwrap_err();
    assert!(
        matches!(
            err,
            GeometryError::IndexOutOfRange {
                triangle: 4,
                index: 9,
                vertex_count: 4,
                ..
            }
        ),
        "{err:?}"
    );
    assert_names_file(&err, &path);
    // In-memory meshes are checked the same way.
    let err =
        mvgrasp_geometry::TriangleMesh::new(vec![Vec3::ZERO; 3], vec![[0, 1, 3]]).unwrap_err();
    assert!(matches!(
        err,
        GeometryError::IndexOutOfRange { index: 3, .. }
    ));
}

#[test]
fn degenerate_faces_only() {
    let dir = tempfile::tempdir().unwrap();
    // Collinear points and a repeated vertex: no triangle has area.
    let path = write(
        dir.path(),
        "flat.obj",
        "v 0 0 0\nv 0.05 0 0\nv 0.1 0 0\nf 1 2 3\nf 1 1 2\n",
    );
    let err = load_mesh(&path).unwrap_err();
    assert!(
        matches!(err, GeometryError::DegenerateOnly { triangles: 2, .. }),
        "{err:?}"
    );
    assert_names_file(&err, &path);
    // A degenerate face among good ones is dropped, not fatal.
    let path = write(dir.path(), "some.obj", &format!("{TETRA}f 1 1 2\n"));
    assert_eq!(load_mesh(&path).unwrap().triangles().len(), 4);
}

#[test]
fn absurd_sizes_get_a_units_hint() {
    let dir = tempfile::tempdir().unwrap();
    let scaled = |factor: f32| {
        TETRA
            .lines()
            .map(|l| match l.strip_prefix("v ") {
                Some(v) => {
                    let xyz: Vec<String> = v
                        .split(' ')
                        .map(|c| (c.parse::<f32>().unwrap() * factor).to_string())
                        .collect();
                    format!("v {}", xyz.join(" "))
                }
                None => l.to_string(),
            })
            .collect::<Vec<_>>()
            .join("\n")
    };
    for (factor, hint) in [
        (1000.0, "millimetres"),
        (100.0, "centimetres"),
        (0.01, "scale"),
    ] {
        let path = write(dir.path(), &format!("x{factor}.obj"), &scaled(factor));
        let err = load_mesh(&path).unwrap_err();
        assert!(matches!(err, GeometryError::AbsurdSize { .. }), "{err:?}");
        assert!(err.to_string().contains(hint), "{err}");
        assert_names_file(&err, &path);
    }
    // The hint works: load the millimetre file with scale 0.001.
    let path = dir.path().join("x1000.obj");
    let mesh = load_mesh_with(
        &path,
        &LoadOptions {
            scale: 0.001,
            ..Default::default()
        },
    )
    .unwrap();
    assert!((mesh.aabb().extents().max_element() - 0.05).abs() < 1e-6);
    let err = load_mesh_with(
        &path,
        &LoadOptions {
            scale: -1.0,
            ..Default::default()
        },
    )
    .unwrap_err();
    assert!(matches!(
        err,
        GeometryError::InvalidParameter { name: "scale", .. }
    ));
}

#[test]
fn urdf_missing_mesh_no_geometry_and_two_roots() {
    let dir = tempfile::tempdir().unwrap();
    let missing = write(
        dir.path(),
        "missing.urdf",
        r#"<robot name="r"><link name="body"><visual><geometry><mesh filename="meshes/gone.obj"/></geometry></visual></link></robot>"#,
    );
    let err = load_mesh(&missing).unwrap_err();
    assert!(
        matches!(err, GeometryError::UrdfMeshMissing { ref link, .. } if link == "body"),
        "{err:?}"
    );
    assert!(err.to_string().contains("gone.obj"), "{err}");
    assert_names_file(&err, &missing);

    let empty = write(
        dir.path(),
        "empty.urdf",
        r#"<robot name="r"><link name="body"/></robot>"#,
    );
    let err = load_mesh(&empty).unwrap_err();
    assert!(
        matches!(err, GeometryError::UrdfNoGeometry { .. }),
        "{err:?}"
    );

    let two_roots = write(
        dir.path(),
        "roots.urdf",
        r#"<robot name="r"><link name="a"><visual><geometry><box size="0.05 0.05 0.05"/></geometry></visual></link><link name="b"/></robot>"#,
    );
    let err = load_mesh(&two_roots).unwrap_err();
    assert!(
        matches!(err, GeometryError::UrdfStructure { .. }),
        "{err:?}"
    );
}

#[test]
fn real_urdf_with_an_unsupported_missing_collision_file() {
    let Some(root) = common::shared_meshes() else {
        return;
    };
    let urdf = root.join("pybullet/toys/concave_box.urdf");
    let err = load_mesh(&urdf).unwrap_err();
    // Its collision element is a <cdf> naming concave_box.cdf, which exists nowhere.
    assert!(
        matches!(err, GeometryError::Parse { format: "URDF", .. }),
        "{err:?}"
    );
    assert!(err.to_string().contains("cdf"), "{err}");
    assert_names_file(&err, &urdf);
}

#[test]
fn urdf_applies_joint_origin_and_mesh_scale() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "tetra.obj", TETRA);
    let urdf = write(
        dir.path(),
        "robot.urdf",
        r#"<robot name="r">
          <link name="base"><visual><origin xyz="0 0 0.01"/><geometry><box size="0.04 0.02 0.02"/></geometry></visual></link>
          <link name="tip"><collision><origin xyz="0.1 0 0" rpy="0 0 1.5707963"/>
            <geometry><mesh filename="tetra.obj" scale="2 2 2"/></geometry></collision></link>
          <joint name="j" type="revolute"><parent link="base"/><child link="tip"/><origin xyz="0 0 0.05"/></joint>
        </robot>"#,
    );
    let mesh = load_mesh(&urdf).unwrap();
    let aabb = mesh.aabb();
    // Box: x in [-0.02, 0.02], z in [0, 0.02]. Tetra (10 cm after scale), yawed 90 deg, at
    // (0.1, 0, 0.05): x in [0, 0.1] maps to y, y in [0, 0.1] maps to -x.
    assert!(
        (aabb.mins - Vec3::new(-0.02, -0.01, 0.0)).length() < 1e-5,
        "{:?}",
        aabb.mins
    );
    assert!(
        (aabb.maxs - Vec3::new(0.1, 0.1, 0.15)).length() < 1e-5,
        "{:?}",
        aabb.maxs
    );
    assert_eq!(mesh.triangles().len(), 12 + 4);
}

#[test]
fn obj_round_trips_through_write_obj() {
    let dir = tempfile::tempdir().unwrap();
    let original = load_mesh(write(dir.path(), "t.obj", TETRA)).unwrap();
    let out = dir.path().join("out.obj");
    write_obj(&original, &out).unwrap();
    let back = load_mesh(&out).unwrap();
    assert_eq!(back.vertices(), original.vertices());
    assert_eq!(back.triangles(), original.triangles());
    assert!(back.is_watertight());
    let err = write_obj(&original, "/nonexistent/dir/out.obj").unwrap_err();
    assert!(matches!(err, GeometryError::Io { .. }));
}

#[test]
fn garbage_and_mutated_files_never_panic() {
    use rand::{RngExt, SeedableRng};
    let dir = tempfile::tempdir().unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(0);
    let urdf = r#"<robot name="r"><link name="a"><visual><origin rpy="0 1 0"/><geometry><mesh filename="t.obj" scale="1 1 1"/></geometry></visual></link></robot>"#;
    for i in 0..300 {
        let (ext, base) = match i % 3 {
            0 => ("obj", TETRA.as_bytes()),
            1 => ("stl", &b"solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 0.05 0 0\nvertex 0 0.05 0\nendloop\nendfacet\nendsolid s\n"[..]),
            _ => ("urdf", urdf.as_bytes()),
        };
        let mut bytes = base.to_vec();
        for _ in 0..rng.random_range(1..8) {
            let at = rng.random_range(0..bytes.len());
            match rng.random_range(0..3) {
                0 => bytes[at] = rng.random(),
                1 => {
                    bytes.remove(at);
                }
                _ => bytes.insert(at, b"-0.9e39nan/ \n"[rng.random_range(0..13)]),
            }
        }
        std::fs::write(dir.path().join("t.obj"), TETRA).unwrap();
        let path = dir.path().join(format!("f{i}.{ext}"));
        std::fs::write(&path, &bytes).unwrap();
        if let Ok(mesh) = load_mesh(&path) {
            assert!(mesh.vertices().iter().all(|v| v.is_finite()));
        }
    }
}
