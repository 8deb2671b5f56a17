//! The multi-view stereo network and its geometry against torch: fixtures written by
//! `training/scripts/make_parity_fixtures.py` (a tiny network with random weights on three views
//! of random colours; its depth range, hypotheses and one correlation volume), computed by torch
//! in float64.

use std::path::{Path, PathBuf};

use mvgrasp_infer::model::Weights;
use mvgrasp_infer::ops::CameraMatrices;
use mvgrasp_infer::ops::plane_sweep::{
    Workspace, correlation_volume, depth_range, inverse_depth_planes,
};
use mvgrasp_infer::{Mvs, Parallelism, Tensor};

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures")
}

/// Every value within `tol * max(1, |want|)`; the largest difference.
fn assert_near(got: &[f32], want: &[f32], tol: f32, what: &str) -> f32 {
    assert_eq!(got.len(), want.len(), "{what}: lengths differ");
    let mut worst = 0.0f32;
    for (i, (&g, &w)) in got.iter().zip(want).enumerate() {
        let diff = (g - w).abs();
        worst = worst.max(diff);
        assert!(
            diff <= tol * w.abs().max(1.0),
            "{what}: value {i}: {g} vs torch {w}"
        );
    }
    worst
}

fn camera(k: &Tensor, pose: &Tensor, v: usize) -> CameraMatrices {
    let (k, p) = (&k.data()[v * 9..], &pose.data()[v * 16..]);
    CameraMatrices {
        k: std::array::from_fn(|r| std::array::from_fn(|c| k[r * 3 + c])),
        camera_from_world: std::array::from_fn(|r| std::array::from_fn(|c| p[r * 4 + c])),
    }
}

struct Io(Weights);

impl Io {
    fn load() -> Self {
        Self(Weights::load(&fixtures().join("mvs_tiny.io.safetensors")).unwrap())
    }

    fn take(&mut self, name: &str) -> Tensor {
        self.0.take_any(name).unwrap()
    }
}

#[test]
fn the_tiny_multi_view_stereo_network_matches_torch() {
    let mut io = Io::load();
    let (images, k, pose) = (
        io.take("images"),
        io.take("k"),
        io.take("camera_from_world"),
    );
    let (want_depth, want_confidence) = (io.take("depth"), io.take("confidence"));
    let cameras: Vec<_> = (0..3).map(|v| camera(&k, &pose, v)).collect();
    let mut first = None;
    for par in [Parallelism::Sequential, Parallelism::Rayon { threads: 2 }] {
        let net = Mvs::load(&fixtures().join("mvs_tiny.json"))
            .unwrap()
            .with_parallelism(par);
        let out = net.predict(&images, &cameras).unwrap();
        // Metres: within 20 micrometres of torch's float64 depth.
        let worst = assert_near(out.depth.data(), want_depth.data(), 2e-5, "depth");
        assert!(
            worst > 0.0,
            "float32 against float64 agreeing to the bit is suspicious"
        );
        assert_near(
            out.confidence.data(),
            want_confidence.data(),
            1e-3,
            "confidence",
        );
        // Whatever the thread count, the same bits.
        match &first {
            None => first = Some(out.depth),
            Some(depth) => assert_eq!(depth, &out.depth),
        }
    }
}

#[test]
fn the_geometry_matches_torch() {
    let mut io = Io::load();
    let (k, pose) = (io.take("k"), io.take("camera_from_world"));
    let cameras: Vec<_> = (0..3).map(|v| camera(&k, &pose, v)).collect();
    let centre = io.take("range.centre");
    let workspace = Workspace {
        centre: std::array::from_fn(|i| centre.data()[i]),
        half_side_m: 0.2,
        height_m: 0.3,
    };
    let (near, far) = depth_range(&cameras[1], &workspace, 24, 32);
    assert_near(&near, io.take("range.near").data(), 1e-5, "near");
    assert_near(&far, io.take("range.far").data(), 1e-5, "far");
    let want_planes = io.take("planes");
    let planes = inverse_depth_planes(&near, &far, 6);
    assert_near(&planes, want_planes.data(), 1e-5, "planes");
    let features = io.take("volume.features");
    let volume = correlation_volume(
        &features,
        &cameras,
        1,
        &want_planes,
        2,
        Parallelism::Sequential,
    )
    .unwrap();
    assert_near(
        volume.data(),
        io.take("volume.y").data(),
        1e-4,
        "correlation volume",
    );
}

#[test]
fn the_network_refuses_one_view_and_misshapen_images() {
    let mut io = Io::load();
    let (images, k, pose) = (
        io.take("images"),
        io.take("k"),
        io.take("camera_from_world"),
    );
    let cameras: Vec<_> = (0..3).map(|v| camera(&k, &pose, v)).collect();
    let net = Mvs::load(&fixtures().join("mvs_tiny.json")).unwrap();
    let one = Tensor::new(&[1, 3, 24, 32], images.data()[..3 * 24 * 32].to_vec()).unwrap();
    let error = net.predict(&one, &cameras[..1]).unwrap_err().to_string();
    assert!(error.contains("at least two views"), "{error}");
    assert!(net.predict(&images, &cameras[..2]).is_err());
}
