//! The Learnt Stereo Machine and its ops against torch: fixtures written by
//! `training/scripts/make_parity_fixtures.py` (a tiny LSM with random weights on three views of
//! random colours; each op on random inputs), computed by torch in float64.

use std::path::{Path, PathBuf};

use mvgrasp_infer::model::Weights;
use mvgrasp_infer::ops::{
    self, CameraMatrices, Conv3dParams, ConvGru3d, ConvGruScratch, InstanceNorm, VoxelGrid,
};
use mvgrasp_infer::{Lsm, Parallelism, Tensor};

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures")
}

/// Every value within `tol * max(1, |want|)`; the largest difference.
fn assert_near(got: &Tensor, want: &Tensor, tol: f32, what: &str) -> f32 {
    assert_eq!(got.shape(), want.shape(), "{what}: shapes differ");
    let mut worst = 0.0f32;
    for (i, (&g, &w)) in got.data().iter().zip(want.data()).enumerate() {
        let diff = (g - w).abs();
        worst = worst.max(diff);
        assert!(
            diff <= tol * w.abs().max(1.0),
            "{what}: value {i}: {g} vs torch {w}"
        );
    }
    worst
}

fn camera(k: &Tensor, pose: &Tensor) -> CameraMatrices {
    let (k, p) = (k.data(), pose.data());
    CameraMatrices {
        k: std::array::from_fn(|r| std::array::from_fn(|c| k[r * 3 + c])),
        camera_from_world: std::array::from_fn(|r| std::array::from_fn(|c| p[r * 4 + c])),
    }
}

/// Row `i` of a stacked tensor (`[N, ...]` -> `[...]`).
fn row(t: &Tensor, i: usize) -> Tensor {
    let len = t.len() / t.shape()[0];
    Tensor::new(&t.shape()[1..], t.data()[i * len..(i + 1) * len].to_vec()).unwrap()
}

#[test]
fn the_tiny_lsm_matches_torch() {
    let mut io = Weights::load(&fixtures().join("lsm_tiny.io.safetensors")).unwrap();
    let mut take = |n: &str| io.take_any(n).unwrap();
    let (images, k, pose, want) = (
        take("images"),
        take("k"),
        take("camera_from_world"),
        take("depth"),
    );
    let cameras: Vec<_> = (0..3)
        .map(|v| camera(&row(&k, v), &row(&pose, v)))
        .collect();
    for par in [Parallelism::Sequential, Parallelism::Rayon { threads: 2 }] {
        let net = Lsm::load(&fixtures().join("lsm_tiny.json"))
            .unwrap()
            .with_parallelism(par);
        let depth = net.predict(&images, &cameras).unwrap();
        // Metres: within 10 micrometres of torch's float64 depth.
        let worst = assert_near(&depth, &want, 1e-5, "depth");
        assert!(worst > 0.0 || depth == want);
        // The grid centred by hand where the cameras place it: the same depth to the bit.
        let a = net.architecture();
        let grid = VoxelGrid::centred_on(&cameras, a.grid_side_m, a.grid_size).unwrap();
        let given = net.predict_in(&images, &cameras, grid.centre).unwrap();
        assert_eq!(given, depth);
    }
}

#[test]
fn the_lsm_refuses_what_it_cannot_use() {
    let net = Lsm::load(&fixtures().join("lsm_tiny.json")).unwrap();
    let mut io = Weights::load(&fixtures().join("lsm_tiny.io.safetensors")).unwrap();
    let (images, k, pose) = (
        io.take_any("images").unwrap(),
        io.take_any("k").unwrap(),
        io.take_any("camera_from_world").unwrap(),
    );
    let cameras: Vec<_> = (0..3)
        .map(|v| camera(&row(&k, v), &row(&pose, v)))
        .collect();
    let err = net.predict(&images, &cameras[..2]).unwrap_err().to_string();
    assert!(err.contains("images [2 views, 3, 24, 32]"), "{err}");
    let one = Tensor::new(&[1, 3, 24, 32], images.data()[..3 * 24 * 32].to_vec()).unwrap();
    let err = net.predict(&one, &cameras[..1]).unwrap_err().to_string();
    assert!(err.contains("at least two cameras"), "{err}");
    // One view places no grid; given a centre it predicts, given none or a bad one it refuses.
    let alone = net
        .predict_in(&one, &cameras[..1], [0.0, 0.0, 0.03])
        .unwrap();
    assert_eq!(alone.shape(), [1, 24, 32]);
    assert!(alone.data().iter().all(|d| d.is_finite() && *d > 0.0));
    let none = Tensor::new(&[0, 3, 24, 32], Vec::new()).unwrap();
    let err = net
        .predict_in(&none, &[], [0.0; 3])
        .unwrap_err()
        .to_string();
    assert!(err.contains("at least one view"), "{err}");
    let err = net
        .predict_in(&one, &cameras[..1], [f32::NAN, 0.0, 0.0])
        .unwrap_err()
        .to_string();
    assert!(err.contains("finite centre"), "{err}");

    let dir = tempfile::tempdir().unwrap();
    for ext in ["json", "safetensors"] {
        let name = format!("lsm_tiny.{ext}");
        std::fs::copy(fixtures().join(&name), dir.path().join(&name)).unwrap();
    }
    let json = dir.path().join("lsm_tiny.json");
    let text = std::fs::read_to_string(&json).unwrap();
    std::fs::write(
        &json,
        text.replace("\"gru_channels\": 6", "\"gru_channels\": 7"),
    )
    .unwrap();
    let err = Lsm::load(&json).unwrap_err().to_string();
    assert!(
        err.contains("gru.gates.weight") && err.contains("lsm_tiny.safetensors"),
        "{err}"
    );
    std::fs::write(&json, text.replace("mvgrasp-lsm/1", "mvgrasp-gqcnn/1")).unwrap();
    assert!(Lsm::load(&json).unwrap_err().to_string().contains("format"));
    std::fs::write(&json, text.replace("\"grid_size\": 8", "\"grid_size\": 7")).unwrap();
    assert!(Lsm::load(&json).unwrap_err().to_string().contains("even"));
}

#[test]
fn each_op_matches_torch() {
    let mut io = Weights::load(&fixtures().join("lsm_ops.io.safetensors")).unwrap();
    let mut t = |n: &str| io.take_any(n).unwrap();
    let par = Parallelism::Sequential;

    let (x, w, b, y) = (t("conv3d.x"), t("conv3d.w"), t("conv3d.b"), t("conv3d.y"));
    let params = Conv3dParams::cubic(2, 1);
    assert_near(
        &ops::conv3d(&x, &w, Some(&b), params, par).unwrap(),
        &y,
        1e-5,
        "conv3d",
    );
    let reference = ops::conv3d_reference(&x, &w, Some(&b), params).unwrap();
    assert_near(&reference, &y, 1e-5, "conv3d_reference");

    let (x, w, b, y) = (
        t("conv_transpose3d.x"),
        t("conv_transpose3d.w"),
        t("conv_transpose3d.b"),
        t("conv_transpose3d.y"),
    );
    let fast = ops::conv_transpose3d(&x, &w, Some(&b), params, par).unwrap();
    assert_near(&fast, &y, 1e-5, "conv_transpose3d");
    let reference = ops::conv_transpose3d_reference(&x, &w, Some(&b), params).unwrap();
    assert_near(&reference, &y, 1e-5, "conv_transpose3d_reference");

    let (mut x, w, b, y) = (
        t("instance_norm3d.x"),
        t("instance_norm3d.w"),
        t("instance_norm3d.b"),
        t("instance_norm3d.y"),
    );
    let norm = InstanceNorm {
        weight: Some(&w),
        bias: Some(&b),
        eps: 1e-5,
    };
    assert_near(
        &ops::instance_norm_reference(&x, &norm).unwrap(),
        &y,
        1e-5,
        "instance_norm3d_reference",
    );
    ops::instance_norm(&mut x, &norm).unwrap();
    assert_near(&x, &y, 1e-5, "instance_norm3d");

    let (gw, gb, cw, cb) = (
        t("gru.gates.weight"),
        t("gru.gates.bias"),
        t("gru.candidate.weight"),
        t("gru.candidate.bias"),
    );
    let cell = ConvGru3d {
        gates_weight: &gw,
        gates_bias: Some(&gb),
        candidate_weight: &cw,
        candidate_bias: Some(&cb),
    };
    let (x, mut h, y) = (t("gru.x"), t("gru.h"), t("gru.y"));
    assert_near(
        &cell.step_reference(&x, &h).unwrap(),
        &y,
        1e-5,
        "gru reference",
    );
    cell.step(&x, &mut h, &mut ConvGruScratch::default(), par)
        .unwrap();
    assert_near(&h, &y, 1e-5, "gru");

    let centre = t("unproject.centre");
    let grid = VoxelGrid {
        centre: [centre.data()[0], centre.data()[1], centre.data()[2]],
        side_m: 0.3,
        size: 8,
    };
    let first = camera(&t("unproject.k"), &t("unproject.camera_from_world"));
    let second = camera(&t("project.k"), &t("project.camera_from_world"));
    let placed = VoxelGrid::centred_on(&[first, second], 0.3, 8).unwrap();
    for (a, b) in placed.centre.iter().zip(grid.centre) {
        assert!(
            (a - b).abs() < 1e-6,
            "grid centre {:?} vs torch {:?}",
            placed.centre,
            grid.centre
        );
    }
    let features = row(&t("unproject.features"), 0);
    let got = ops::unproject(&features, &first, &grid, 0.15).unwrap();
    assert_near(&got, &row(&t("unproject.y"), 0), 1e-4, "unproject");
    let y = row(&t("project.y"), 0);
    let got = ops::project_rays(&row(&t("project.grid"), 0), &second, &grid, 5, 12, 16).unwrap();
    assert_near(&got, &y, 1e-4, "project_rays");

    let x = t("resize.x");
    assert_near(
        &ops::resize_bilinear(&x, 10, 14).unwrap(),
        &t("resize.bilinear"),
        1e-5,
        "bilinear",
    );
    let x = t("resize.area_x");
    assert_near(
        &ops::resize_area(&x, 12, 16).unwrap(),
        &t("resize.area"),
        1e-5,
        "area",
    );
}
