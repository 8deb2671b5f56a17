//! The fuzz targets: one per reader of outside bytes. Each writes its input to a file of the
//! format's name in a work folder (beside the companion files a format refers to) and calls
//! the reader a user's file reaches, so that the path, the extension and the error messages
//! are the ones a user meets. Seeds are valid files of each format, made here from the
//! project's own writers or spelled out, so that a run needs nothing outside the repository.

use std::path::Path;

use mvgrasp::grasp_dataset::{self, GraspDatasetConfig};
use mvgrasp::sensor_files;
use mvgrasp_geometry::{Camera, Intrinsics, load_mesh, pose_as_matrix, read_camera_pose};
use mvgrasp_grasp::Gripper;
use mvgrasp_infer::model::Weights;
use mvgrasp_infer::{Gqcnn, Lsm, Mvs};
use safetensors::Dtype;

/// A reader to fuzz.
#[derive(Clone, Copy, Debug)]
pub struct Target {
    /// Its name (`fuzz run --target NAME`, `regressions/NAME/`).
    pub name: &'static str,
    /// What it reads, for `fuzz list`.
    pub about: &'static str,
    /// The input's file name in the work folder (its extension picks the format).
    pub file_name: &'static str,
    /// Writes the files the input refers to into the work folder.
    pub setup: fn(&Path) -> std::io::Result<()>,
    /// Valid inputs to start from.
    pub seeds: fn() -> Vec<Vec<u8>>,
    /// Tokens of the format, for the mutator.
    pub dictionary: &'static [&'static [u8]],
    /// The longest input the mutator makes, bytes.
    pub max_len: usize,
    /// Reads the input at the path: `Err` with the reader's message when it refuses it.
    pub run: fn(&Path) -> Result<(), String>,
}

fn no_setup(_: &Path) -> std::io::Result<()> {
    Ok(())
}

fn message(error: impl std::fmt::Display) -> String {
    error.to_string()
}

// --- Images ---------------------------------------------------------------------------------

const WIDTH: u32 = 32;
const HEIGHT: u32 = 24;

/// A `.npy` file: `descr` like `<f4`, C or Fortran order, `shape`, then `data`.
fn npy(descr: &str, fortran: bool, shape: &[usize], data: &[u8]) -> Vec<u8> {
    let shape_text = match shape {
        [n] => format!("({n},)"),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(ToString::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        ),
    };
    let mut header = format!(
        "{{'descr': '{descr}', 'fortran_order': {}, 'shape': {shape_text}, }}",
        if fortran { "True" } else { "False" }
    );
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    bytes.extend_from_slice(&u16::try_from(header.len()).unwrap_or(0).to_le_bytes());
    bytes.extend_from_slice(header.as_bytes());
    bytes.extend_from_slice(data);
    bytes
}

/// A tabletop depth image, metres: the table at 0.6 m, a box 5 cm high, a few missing pixels.
fn depth_m() -> Vec<f32> {
    (0..WIDTH * HEIGHT)
        .map(|i| {
            let (u, v) = (i % WIDTH, i / WIDTH);
            if (u + v) % 17 == 0 {
                0.0
            } else if (10..22).contains(&u) && (8..16).contains(&v) {
                0.55
            } else {
                0.6
            }
        })
        .collect()
}

fn png(color: png::ColorType, depth: png::BitDepth, data: &[u8]) -> Vec<u8> {
    let mut bytes = Vec::new();
    let mut encoder = png::Encoder::new(&mut bytes, WIDTH, HEIGHT);
    encoder.set_color(color);
    encoder.set_depth(depth);
    let written = encoder
        .write_header()
        .and_then(|mut writer| writer.write_image_data(data));
    if written.is_err() {
        return Vec::new();
    }
    bytes
}

fn npy_seeds() -> Vec<Vec<u8>> {
    let depth = depth_m();
    let f4: Vec<u8> = depth.iter().flat_map(|d| d.to_le_bytes()).collect();
    let f8: Vec<u8> = depth
        .iter()
        .flat_map(|&d| f64::from(d).to_le_bytes())
        .collect();
    let (w, h) = (WIDTH as usize, HEIGHT as usize);
    vec![
        npy("<f4", false, &[h, w], &f4),
        npy("<f8", false, &[h, w], &f8),
        npy("<f4", true, &[w, h], &f4),
        npy("<f4", false, &[h, w, 1], &f4),
        npy("<u2", false, &[h, w], &f4[..f4.len() / 2]),
    ]
}

fn depth_png_seeds() -> Vec<Vec<u8>> {
    let millimetres: Vec<u8> = depth_m()
        .iter()
        .flat_map(|d| ((d * 1000.0) as u16).to_be_bytes())
        .collect();
    let grey8: Vec<u8> = depth_m().iter().map(|d| (d * 255.0) as u8).collect();
    vec![
        png(
            png::ColorType::Grayscale,
            png::BitDepth::Sixteen,
            &millimetres,
        ),
        png(png::ColorType::Grayscale, png::BitDepth::Eight, &grey8),
    ]
}

fn mask_png_seeds() -> Vec<Vec<u8>> {
    let mask: Vec<u8> = depth_m().iter().map(|&d| u8::from(d == 0.55)).collect();
    let rgb: Vec<u8> = mask.iter().flat_map(|&m| [m * 255; 3]).collect();
    vec![
        png(png::ColorType::Grayscale, png::BitDepth::Eight, &mask),
        png(png::ColorType::Rgb, png::BitDepth::Eight, &rgb),
    ]
}

fn rgb_png_seeds() -> Vec<Vec<u8>> {
    let rgb: Vec<u8> = (0..WIDTH * HEIGHT * 3)
        .map(|i| (i * 37 % 251) as u8)
        .collect();
    let rgba: Vec<u8> = (0..WIDTH * HEIGHT * 4)
        .map(|i| (i * 13 % 253) as u8)
        .collect();
    vec![
        png(png::ColorType::Rgb, png::BitDepth::Eight, &rgb),
        png(png::ColorType::Rgba, png::BitDepth::Eight, &rgba),
    ]
}

const PNG_TOKENS: &[&[u8]] = &[
    b"\x89PNG\r\n\x1a\n",
    b"IHDR",
    b"IDAT",
    b"IEND",
    b"PLTE",
    b"tRNS",
    b"\x00\x00\x00\x0d",
    b"\xff\xff\xff\xff",
];
const NPY_TOKENS: &[&[u8]] = &[
    b"\x93NUMPY",
    b"'descr': '<f4'",
    b"'descr': '>f8'",
    b"'descr': '|O'",
    b"'descr': '<c16'",
    b"'fortran_order': True",
    b"'shape': (100000, 100000)",
    b"'shape': ()",
    b"'shape': (0, 0)",
    b"'shape': (-1, 32)",
    b"(24, 32, 3)",
];

fn read_depth_file(path: &Path) -> Result<(), String> {
    sensor_files::read_depth(path).map(drop).map_err(message)
}

fn read_mask_file(path: &Path) -> Result<(), String> {
    sensor_files::read_mask(path, WIDTH, HEIGHT)
        .map(drop)
        .map_err(message)
}

fn read_rgb_file(path: &Path) -> Result<(), String> {
    sensor_files::read_rgb(path).map(drop).map_err(message)
}

// --- Cameras and poses -----------------------------------------------------------------------

const INTR: &str = r#"{"_cy": 239.5, "_cx": 319.5, "_fy": 525.0, "_height": 480, "_fx": 525.0, "_width": 640, "_skew": 0.0, "_K": 0, "_frame": "primesense_overhead"}"#;
const K_JSON: &str =
    r#"{"K": [[552.5, 0, 255.5], [0, 552.5, 191.75], [0, 0, 1]], "width": 516, "height": 386}"#;
const TF: &str = "primesense_overhead\nworld\n0.214280 0.004186 0.872913\n0.021188 -0.975273 0.219984\n-0.999765 -0.021698 0.000098\n0.004678 -0.219934 -0.975504\n";
const POSE_JSON: &str =
    r#"{"world_from_camera": [[1, 0, 0, 0.1], [0, -1, 0, 0], [0, 0, -1, 0.7], [0, 0, 0, 1]]}"#;
const JSON_TOKENS: &[&[u8]] = &[
    b"null",
    b"true",
    b"[]",
    b"{}",
    b"[[",
    b"\"\"",
    b",",
    b":",
    b"1e999",
    b"-",
    b"\"_fx\"",
    b"\"K\"",
    b"\"width\"",
    b"\"world_from_camera\"",
    b"\"intrinsics\"",
];

fn text_seeds(texts: &[&str]) -> Vec<Vec<u8>> {
    texts.iter().map(|t| t.as_bytes().to_vec()).collect()
}

fn read_intrinsics(path: &Path) -> Result<(), String> {
    Intrinsics::from_file(path).map(drop).map_err(message)
}

fn read_pose(path: &Path) -> Result<(), String> {
    read_camera_pose(path).map(drop).map_err(message)
}

/// The camera of the view folders: 32 x 24 pixels, 0.6 m above the table, looking down.
fn small_camera() -> Option<Camera> {
    let intrinsics = Intrinsics {
        fx: 30.0,
        fy: 30.0,
        cx: 15.5,
        cy: 11.5,
        width: WIDTH,
        height: HEIGHT,
        ..Intrinsics::phoxi_s()
    };
    let rows = [
        [1.0, 0.0, 0.0, 0.0],
        [0.0, -1.0, 0.0, 0.0],
        [0.0, 0.0, -1.0, 0.6],
        [0.0, 0.0, 0.0, 1.0],
    ];
    let world_from_camera = pose_as_matrix::from_rows(rows).ok()?;
    Some(Camera {
        intrinsics,
        world_from_camera,
    })
}

fn cameras_seeds() -> Vec<Vec<u8>> {
    let Some(camera) = small_camera() else {
        return Vec::new();
    };
    [vec![camera], vec![camera, camera]]
        .iter()
        .filter_map(|cameras| serde_json::to_vec_pretty(cameras).ok())
        .collect()
}

/// A view folder's other files: two cameras' depth, mask and RGB images and a `dataset.json`.
fn view_folder(dir: &Path) -> std::io::Result<()> {
    let npy = npy_seeds().swap_remove(0);
    let mask = mask_png_seeds().swap_remove(0);
    let rgb = rgb_png_seeds().swap_remove(0);
    for i in 0..2 {
        std::fs::write(dir.join(format!("{i:03}_depth.npy")), &npy)?;
        std::fs::write(dir.join(format!("{i:03}_mask.png")), &mask)?;
        std::fs::write(dir.join(format!("{i:03}_rgb.png")), &rgb)?;
    }
    if !dir.join("cameras.json").exists() {
        let cameras = cameras_seeds().pop().unwrap_or_default();
        std::fs::write(dir.join("cameras.json"), cameras)?;
    }
    Ok(())
}

fn dataset_json_seeds() -> Vec<Vec<u8>> {
    text_seeds(&[
        r#"{"depth_png_units_per_m": 10000.0, "mask_ids": {"background": 0, "object": 1, "table": 2}}"#,
        r#"{"depth_png_units_per_m": 1000}"#,
    ])
}

fn read_views(path: &Path) -> Result<(), String> {
    let dir = path.parent().unwrap_or(Path::new("."));
    mvgrasp::planner::read_views_dir(dir)
        .map(drop)
        .map_err(message)
}

fn read_rgb_views(path: &Path) -> Result<(), String> {
    let dir = path.parent().unwrap_or(Path::new("."));
    mvgrasp::planner::read_rgb_dir(dir)
        .map(drop)
        .map_err(message)
}

fn read_dataset_cameras(path: &Path) -> Result<(), String> {
    let cameras = mvgrasp::dataset::read_cameras(path).map_err(message)?;
    // Accepted cameras must be cameras: a reader may not pass on garbage.
    for camera in &cameras {
        camera
            .intrinsics
            .validate()
            .map_err(|e| format!("{}: accepted an invalid camera: {e}", path.display()))?;
    }
    Ok(())
}

// --- Meshes and grippers -----------------------------------------------------------------------

const CUBE_OBJ: &str = "# a 4 cm cube\no cube\nv -0.02 -0.02 -0.02\nv 0.02 -0.02 -0.02\nv 0.02 0.02 -0.02\nv -0.02 0.02 -0.02\nv -0.02 -0.02 0.02\nv 0.02 -0.02 0.02\nv 0.02 0.02 0.02\nv -0.02 0.02 0.02\nvt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\nf 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";
const TETRA_OBJ: &str = "v 0 0 0\nv 0.05 0 0\nv 0 0.05 0\nv 0 0 0.05\nvt 0 0\nf 1/1 3/1 2/1\nf 1/1 2/1 4/1\nf 1/1 4/1 3/1\nf 2//1 3//1 4//1\nvn 1 1 1\n";
const OBJ_TOKENS: &[&[u8]] = &[
    b"v ",
    b"vt ",
    b"vn ",
    b"f ",
    b"o ",
    b"g ",
    b"s 1",
    b"mtllib x.mtl",
    b"usemtl m",
    b"/",
    b"//",
    b"-1",
    b"\n",
    b"\\\n",
    b"l 1 2",
];

fn stl_binary() -> Vec<u8> {
    let corners = [
        [0.0f32, 0.0, 0.0],
        [0.05, 0.0, 0.0],
        [0.0, 0.05, 0.0],
        [0.0, 0.0, 0.05],
    ];
    let faces = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
    let mut bytes = vec![0u8; 80];
    bytes.extend_from_slice(&4u32.to_le_bytes());
    for face in faces {
        bytes.extend_from_slice(&[0u8; 12]);
        for corner in face {
            for c in corners[corner] {
                bytes.extend_from_slice(&c.to_le_bytes());
            }
        }
        bytes.extend_from_slice(&[0, 0]);
    }
    bytes
}

const STL_ASCII: &str = "solid t\nfacet normal 0 0 -1\nouter loop\nvertex 0 0 0\nvertex 0 0.05 0\nvertex 0.05 0 0\nendloop\nendfacet\nfacet normal 0 -1 0\nouter loop\nvertex 0 0 0\nvertex 0.05 0 0\nvertex 0 0 0.05\nendloop\nendfacet\nfacet normal -1 0 0\nouter loop\nvertex 0 0 0\nvertex 0 0 0.05\nvertex 0 0.05 0\nendloop\nendfacet\nfacet normal 1 1 1\nouter loop\nvertex 0.05 0 0\nvertex 0 0.05 0\nvertex 0 0 0.05\nendloop\nendfacet\nendsolid t\n";
const STL_TOKENS: &[&[u8]] = &[
    b"solid ",
    b"facet normal ",
    b"outer loop",
    b"vertex ",
    b"endloop",
    b"endfacet",
    b"endsolid",
    b"\xff\xff\xff\x7f",
];

fn stl_seeds() -> Vec<Vec<u8>> {
    vec![stl_binary(), STL_ASCII.as_bytes().to_vec()]
}

fn read_mesh(path: &Path) -> Result<(), String> {
    load_mesh(path).map(drop).map_err(message)
}

const URDF_MESH: &str = r#"<?xml version="1.0"?>
<robot name="cube">
  <link name="base">
    <visual><origin xyz="0 0 0.01" rpy="0 0 0.5"/><geometry><mesh filename="cube.obj" scale="1 1 1"/></geometry></visual>
    <collision><geometry><mesh filename="package://cube.obj"/></geometry></collision>
    <inertial><mass value="0.1"/><inertia ixx="1e-4" ixy="0" ixz="0" iyy="1e-4" iyz="0" izz="1e-4"/></inertial>
  </link>
</robot>
"#;
const URDF_TWO_LINKS: &str = r#"<robot name="two">
  <link name="a"><visual><geometry><box size="0.04 0.04 0.02"/></geometry></visual></link>
  <link name="b"><visual><origin xyz="0 0 0.03"/><geometry><mesh filename="tetra.stl" scale="2 2 2"/></geometry></visual></link>
  <joint name="j" type="fixed"><parent link="a"/><child link="b"/><origin xyz="0 0 0.01" rpy="0 0 0"/></joint>
</robot>
"#;
/// A two-finger slide gripper: a palm and two pads on prismatic joints, the second mimicking
/// the first (as `crates/grasp/tests/gripper_urdf.rs` measures it).
const URDF_GRIPPER: &str = r#"<robot name="slide">
  <link name="palm"><collision><geometry><box size="0.1 0.04 0.02"/></geometry></collision></link>
  <link name="left_pad"><collision><geometry><box size="0.01 0.02 0.05"/></geometry></collision></link>
  <link name="right_pad"><collision><geometry><mesh filename="cube.obj" scale="0.01 0.02 0.05"/></geometry></collision></link>
  <joint name="left_slide" type="prismatic"><parent link="palm"/><child link="left_pad"/>
    <origin xyz="-0.005 0 0.035"/><axis xyz="-1 0 0"/>
    <limit lower="0" upper="0.03" effort="30" velocity="1"/></joint>
  <joint name="right_slide" type="prismatic"><parent link="palm"/><child link="right_pad"/>
    <origin xyz="0.005 0 0.035"/><axis xyz="1 0 0"/>
    <limit lower="0" upper="0.03" effort="30" velocity="1"/>
    <mimic joint="left_slide" multiplier="1" offset="0"/></joint>
</robot>
"#;
const URDF_TOKENS: &[&[u8]] = &[
    b"<mimic joint=\"",
    b"type=\"prismatic\"",
    b"<axis xyz=\"",
    b"<limit lower=\"",
    b"upper=\"",
    b"_pad",
    b"multiplier=\"",
    b"<link name=\"x\">",
    b"</link>",
    b"<visual>",
    b"<collision>",
    b"<geometry>",
    b"<mesh filename=\"",
    b"cube.obj",
    b"tetra.stl",
    b"../../../../etc/passwd",
    b"scale=\"",
    b"<box size=\"",
    b"<cylinder radius=\"0.01\" length=\"0.1\"/>",
    b"<sphere radius=\"",
    b"<joint name=\"k\" type=\"revolute\">",
    b"<parent link=\"",
    b"<child link=\"",
    b"xyz=\"",
    b"rpy=\"",
    b"<!--",
    b"&amp;",
    b"<![CDATA[",
];

fn mesh_folder(dir: &Path) -> std::io::Result<()> {
    std::fs::write(dir.join("cube.obj"), CUBE_OBJ)?;
    std::fs::write(dir.join("tetra.stl"), stl_binary())
}

const GRIPPER_JSON: &str = r#"{"name": "panda", "max_opening_m": 0.08, "min_opening_m": 0.0}"#;
const DEXNET_PARAMS: &str =
    r#"{"min_width": 0.0, "max_width": 0.05, "force_limit": 50.0, "finger_radius": 0.01}"#;

fn gripper_json_seeds() -> Vec<Vec<u8>> {
    let mut seeds = text_seeds(&[GRIPPER_JSON, DEXNET_PARAMS, "{}"]);
    seeds.extend(serde_json::to_vec_pretty(&Gripper::default()).ok());
    seeds
}

fn gripper_toml_seeds() -> Vec<Vec<u8>> {
    let mut seeds = text_seeds(&["max_opening_m = 0.08\n", ""]);
    seeds.extend(
        toml::to_string(&Gripper::default())
            .ok()
            .map(String::into_bytes),
    );
    seeds
}

const TOML_TOKENS: &[&[u8]] = &[
    b" = ",
    b"\n",
    b"[",
    b"]",
    b"[[x]]",
    b"\"",
    b"'''",
    b"inf",
    b"nan",
    b"true",
    b"#",
    b"1979-05-27",
    b"0x7fffffff",
];

fn read_gripper(path: &Path) -> Result<(), String> {
    Gripper::from_file(path).map(drop).map_err(message)
}

// --- Grasp datasets, models, evaluation journals ----------------------------------------------

fn shard_seeds() -> Vec<Vec<u8>> {
    let (n, side) = (2usize, 8usize);
    let columns: Vec<(String, Dtype, Vec<usize>, Vec<u8>)> = grasp_dataset::shard::COLUMNS
        .iter()
        .map(|&(name, dtype, entry)| {
            let shape: Vec<usize> = std::iter::once(n)
                .chain(entry.iter().map(|&d| if d == 0 { side } else { d }))
                .collect();
            let count: usize = shape.iter().product();
            (
                name.to_string(),
                dtype,
                shape,
                vec![0u8; count * dtype.bitsize() / 8],
            )
        })
        .collect();
    let views: Vec<(String, safetensors::tensor::TensorView<'_>)> = columns
        .iter()
        .filter_map(|(name, dtype, shape, data)| {
            safetensors::tensor::TensorView::new(*dtype, shape.clone(), data)
                .ok()
                .map(|v| (name.clone(), v))
        })
        .collect();
    safetensors::serialize(views, None).into_iter().collect()
}

const SAFETENSORS_TOKENS: &[&[u8]] = &[
    b"\"dtype\":\"F32\"",
    b"\"dtype\":\"F64\"",
    b"\"dtype\":\"U8\"",
    b"\"shape\":[",
    b"\"data_offsets\":[",
    b"18446744073709551615",
    b"\"__metadata__\":{",
    b"\xff\xff\xff\xff\xff\xff\xff\x7f",
];

fn read_shard(path: &Path) -> Result<(), String> {
    grasp_dataset::shard::read_shard(path)
        .map(drop)
        .map_err(message)
}

fn manifest_seeds() -> Vec<Vec<u8>> {
    let config = GraspDatasetConfig::default();
    let manifest = serde_json::json!({
        "format": grasp_dataset::FORMAT,
        "config": config,
        "gripper": Gripper::default(),
        "intrinsics": Intrinsics::phoxi_s(),
        "objects": [{"id": 0, "name": "mug", "source": "built-in"}],
        "num_shards": 1,
        "shards": [],
        "totals": grasp_dataset::shard::Counts::default(),
    });
    serde_json::to_vec_pretty(&manifest).into_iter().collect()
}

fn read_manifest(path: &Path) -> Result<(), String> {
    let dir = path.parent().unwrap_or(Path::new("."));
    grasp_dataset::read_manifest(dir).map(drop).map_err(message)
}

fn config_seeds() -> Vec<Vec<u8>> {
    let mut seeds = text_seeds(&["objects = 4\n", ""]);
    seeds.extend(
        toml::to_string(&GraspDatasetConfig::default())
            .ok()
            .map(String::into_bytes),
    );
    seeds
}

fn read_config(path: &Path) -> Result<(), String> {
    GraspDatasetConfig::from_file(path)
        .map(drop)
        .map_err(message)
}

const GQCNN_JSON: &str = include_str!("../../../models/gqcnn_small_topdown.json");
const GQCNN_WEIGHTS: &[u8] = include_bytes!("../../../models/gqcnn_small_topdown.safetensors");
const LSM_JSON: &str = include_str!("../../../models/lsm_small.json");
const LSM_WEIGHTS: &[u8] = include_bytes!("../../../models/lsm_small.safetensors");
const MVS_JSON: &str = include_str!("../../../models/mvs_small.json");
const MVS_WEIGHTS: &[u8] = include_bytes!("../../../models/mvs_small.safetensors");

fn model_json_seeds() -> Vec<Vec<u8>> {
    text_seeds(&[GQCNN_JSON, LSM_JSON, MVS_JSON])
}

/// A model description: read as each kind of network with its shipped weights (a description
/// of one kind is refused by the others with a message).
fn read_model_json(path: &Path) -> Result<(), String> {
    let text = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let text =
        String::from_utf8(text).map_err(|e| format!("{}: not UTF-8: {e}", path.display()))?;
    let gqcnn = Gqcnn::from_bytes(&text, GQCNN_WEIGHTS, path).map(drop);
    let lsm = Lsm::from_bytes(&text, LSM_WEIGHTS, path).map(drop);
    let mvs = Mvs::from_bytes(&text, MVS_WEIGHTS, path).map(drop);
    gqcnn.or(lsm).or(mvs).map_err(message)
}

fn weights_seeds() -> Vec<Vec<u8>> {
    let mut seeds = shard_seeds();
    seeds.push(GQCNN_WEIGHTS.to_vec());
    seeds
}

/// A safetensors file: read as weights, then as the shipped GQ-CNN's.
fn read_weights(path: &Path) -> Result<(), String> {
    let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
    Weights::from_bytes(&bytes, path).map_err(message)?;
    let json = path.with_file_name("gqcnn_small_topdown.json");
    let description = GQCNN_JSON.replace("gqcnn_small_topdown.safetensors", "weights.safetensors");
    Gqcnn::from_bytes(&description, &bytes, &json)
        .map(drop)
        .map_err(message)
}

fn journal_seeds() -> Vec<Vec<u8>> {
    text_seeds(&[
        "{\"key\": \"grasp/mug/0/rgb/0\", \"value\": {\"held\": true, \"quality\": 0.9}}\n{\"key\": \"b\", \"value\": null}\n",
        "{\"key\": \"a\", \"value\": 1}\n{\"key\": \"half",
    ])
}

fn read_journal(path: &Path) -> Result<(), String> {
    mvgrasp::evaluate::journal::Journal::open(path)
        .map(drop)
        .map_err(message)
}

/// Every target.
pub const TARGETS: &[Target] = &[
    Target {
        name: "depth_npy",
        about: "depth .npy (float metres, C or Fortran order): sensor_files::read_depth",
        file_name: "depth.npy",
        setup: no_setup,
        seeds: npy_seeds,
        dictionary: NPY_TOKENS,
        max_len: 64 << 10,
        run: read_depth_file,
    },
    Target {
        name: "depth_png",
        about: "depth 16-bit PNG (millimetres): sensor_files::read_depth",
        file_name: "depth.png",
        setup: no_setup,
        seeds: depth_png_seeds,
        dictionary: PNG_TOKENS,
        max_len: 64 << 10,
        run: read_depth_file,
    },
    Target {
        name: "mask_png",
        about: "object mask PNG: sensor_files::read_mask",
        file_name: "mask.png",
        setup: no_setup,
        seeds: mask_png_seeds,
        dictionary: PNG_TOKENS,
        max_len: 64 << 10,
        run: read_mask_file,
    },
    Target {
        name: "rgb_png",
        about: "8-bit RGB(A) PNG photograph: sensor_files::read_rgb",
        file_name: "rgb.png",
        setup: no_setup,
        seeds: rgb_png_seeds,
        dictionary: PNG_TOKENS,
        max_len: 64 << 10,
        run: read_rgb_file,
    },
    Target {
        name: "intrinsics_intr",
        about: "Berkeley .intr intrinsics: Intrinsics::from_file",
        file_name: "camera.intr",
        setup: no_setup,
        seeds: || text_seeds(&[INTR, K_JSON]),
        dictionary: JSON_TOKENS,
        max_len: 4 << 10,
        run: read_intrinsics,
    },
    Target {
        name: "intrinsics_json",
        about: "intrinsics JSON (K, width, height): Intrinsics::from_file",
        file_name: "camera.json",
        setup: no_setup,
        seeds: || text_seeds(&[K_JSON, INTR]),
        dictionary: JSON_TOKENS,
        max_len: 4 << 10,
        run: read_intrinsics,
    },
    Target {
        name: "pose_tf",
        about: "Berkeley .tf camera pose: read_camera_pose",
        file_name: "camera.tf",
        setup: no_setup,
        seeds: || text_seeds(&[TF]),
        dictionary: &[b"\n", b" ", b"world"],
        max_len: 4 << 10,
        run: read_pose,
    },
    Target {
        name: "pose_json",
        about: "camera pose JSON (world_from_camera): read_camera_pose",
        file_name: "pose.json",
        setup: no_setup,
        seeds: || text_seeds(&[POSE_JSON]),
        dictionary: JSON_TOKENS,
        max_len: 4 << 10,
        run: read_pose,
    },
    Target {
        name: "mesh_obj",
        about: "Wavefront OBJ mesh: load_mesh",
        file_name: "mesh.obj",
        setup: no_setup,
        seeds: || text_seeds(&[CUBE_OBJ, TETRA_OBJ]),
        dictionary: OBJ_TOKENS,
        max_len: 16 << 10,
        run: read_mesh,
    },
    Target {
        name: "mesh_stl",
        about: "STL mesh, binary and ASCII: load_mesh",
        file_name: "mesh.stl",
        setup: no_setup,
        seeds: stl_seeds,
        dictionary: STL_TOKENS,
        max_len: 16 << 10,
        run: read_mesh,
    },
    Target {
        name: "mesh_urdf",
        about: "URDF object (meshes and primitives, joints): load_mesh",
        file_name: "object.urdf",
        setup: mesh_folder,
        seeds: || text_seeds(&[URDF_MESH, URDF_TWO_LINKS]),
        dictionary: URDF_TOKENS,
        max_len: 16 << 10,
        run: read_mesh,
    },
    Target {
        name: "gripper_json",
        about: "gripper JSON, or Dex-Net params.json: Gripper::from_file",
        file_name: "gripper.json",
        setup: no_setup,
        seeds: gripper_json_seeds,
        dictionary: JSON_TOKENS,
        max_len: 4 << 10,
        run: read_gripper,
    },
    Target {
        name: "gripper_toml",
        about: "gripper TOML: Gripper::from_file",
        file_name: "gripper.toml",
        setup: no_setup,
        seeds: gripper_toml_seeds,
        dictionary: TOML_TOKENS,
        max_len: 4 << 10,
        run: read_gripper,
    },
    Target {
        name: "gripper_urdf",
        about: "gripper URDF (measured from its finger links): Gripper::from_file",
        file_name: "gripper.urdf",
        setup: mesh_folder,
        seeds: || text_seeds(&[URDF_GRIPPER]),
        dictionary: URDF_TOKENS,
        max_len: 16 << 10,
        run: read_gripper,
    },
    Target {
        name: "views_cameras",
        about: "cameras.json of a depth view folder (with its images): read_views_dir",
        file_name: "cameras.json",
        setup: view_folder,
        seeds: cameras_seeds,
        dictionary: JSON_TOKENS,
        max_len: 8 << 10,
        run: read_views,
    },
    Target {
        name: "views_dataset_json",
        about: "dataset.json of a view folder (PNG depth units, mask ids): read_views_dir",
        file_name: "dataset.json",
        setup: view_folder,
        seeds: dataset_json_seeds,
        dictionary: JSON_TOKENS,
        max_len: 4 << 10,
        run: read_views,
    },
    Target {
        name: "rgb_views_cameras",
        about: "cameras.json of an RGB view folder (with its photographs): read_rgb_dir",
        file_name: "cameras.json",
        setup: view_folder,
        seeds: cameras_seeds,
        dictionary: JSON_TOKENS,
        max_len: 8 << 10,
        run: read_rgb_views,
    },
    Target {
        name: "dataset_cameras",
        about: "an RGB-D dataset split's cameras.json: dataset::read_cameras",
        file_name: "cameras.json",
        setup: no_setup,
        seeds: cameras_seeds,
        dictionary: JSON_TOKENS,
        max_len: 8 << 10,
        run: read_dataset_cameras,
    },
    Target {
        name: "grasp_shard",
        about: "grasp-dataset shard (safetensors columns): grasp_dataset::shard::read_shard",
        file_name: "shard-00000.safetensors",
        setup: no_setup,
        seeds: shard_seeds,
        dictionary: SAFETENSORS_TOKENS,
        max_len: 64 << 10,
        run: read_shard,
    },
    Target {
        name: "grasp_manifest",
        about: "grasp-dataset manifest (dataset.json): grasp_dataset::read_manifest",
        file_name: "dataset.json",
        setup: no_setup,
        seeds: manifest_seeds,
        dictionary: JSON_TOKENS,
        max_len: 16 << 10,
        run: read_manifest,
    },
    Target {
        name: "grasp_config",
        about: "grasp-dataset config TOML: GraspDatasetConfig::from_file",
        file_name: "config.toml",
        setup: no_setup,
        seeds: config_seeds,
        dictionary: TOML_TOKENS,
        max_len: 8 << 10,
        run: read_config,
    },
    Target {
        name: "model_json",
        about: "network description JSON (GQ-CNN, LSM, MVS) with shipped weights: *::from_bytes",
        file_name: "model.json",
        setup: no_setup,
        seeds: model_json_seeds,
        dictionary: JSON_TOKENS,
        max_len: 32 << 10,
        run: read_model_json,
    },
    Target {
        name: "model_weights",
        about: "network weights (safetensors) for the shipped GQ-CNN: Weights/Gqcnn::from_bytes",
        file_name: "weights.safetensors",
        setup: no_setup,
        seeds: weights_seeds,
        dictionary: SAFETENSORS_TOKENS,
        max_len: 2 << 20,
        run: read_weights,
    },
    Target {
        name: "evaluate_journal",
        about: "evaluate's records.jsonl journal (resume): evaluate::journal::Journal::open",
        file_name: "records.jsonl",
        setup: no_setup,
        seeds: journal_seeds,
        dictionary: JSON_TOKENS,
        max_len: 16 << 10,
        run: read_journal,
    },
];

/// The target called `name`.
pub fn target(name: &str) -> Option<&'static Target> {
    TARGETS.iter().find(|t| t.name == name)
}
