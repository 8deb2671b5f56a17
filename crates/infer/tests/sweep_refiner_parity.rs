//! The sweep refiner against torch: a tiny network (3 dilated layers, random weights) on
//! random features, written by `training/scripts/make_parity_fixtures.py` and computed by torch
//! in float64.

use std::path::{Path, PathBuf};

use mvgrasp_infer::model::Weights;
use mvgrasp_infer::{Parallelism, SweepRefiner};

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures")
}

#[test]
fn the_tiny_sweep_refiner_matches_torch() {
    let mut io = Weights::load(&fixtures().join("sweep_refiner_tiny.io.safetensors")).unwrap();
    let features = io.take_any("features").unwrap();
    let want_correction = io.take_any("correction_m").unwrap();
    let want_confidence = io.take_any("confidence").unwrap();
    for par in [Parallelism::Sequential, Parallelism::Rayon { threads: 2 }] {
        let net = SweepRefiner::load(&fixtures().join("sweep_refiner_tiny.json"))
            .unwrap()
            .with_parallelism(par);
        let out = net.predict(&features).unwrap();
        assert_eq!(out.correction_m.shape(), want_correction.shape());
        let mut worst = 0.0f32;
        for (i, (&got, &want)) in out
            .correction_m
            .data()
            .iter()
            .zip(want_correction.data())
            .enumerate()
        {
            worst = worst.max((got - want).abs());
            // Metres: within a micrometre of torch's float64 correction.
            assert!(
                (got - want).abs() <= 1e-6,
                "correction {i}: {got} vs torch {want}"
            );
        }
        assert!(
            worst > 0.0,
            "float32 against float64 agreeing to the bit is suspicious"
        );
        for (i, (&got, &want)) in out
            .confidence
            .data()
            .iter()
            .zip(want_confidence.data())
            .enumerate()
        {
            assert!(
                (got - want).abs() <= 1e-5,
                "confidence {i}: {got} vs torch {want}"
            );
        }
    }
}

#[test]
fn features_of_the_wrong_shape_are_refused_with_both_shapes() {
    let net = SweepRefiner::load(&fixtures().join("sweep_refiner_tiny.json")).unwrap();
    let wrong = mvgrasp_infer::Tensor::zeros(&[1, 3, 8, 8]);
    let error = net.predict(&wrong).unwrap_err().to_string();
    assert!(
        error.contains("[1, 3, 8, 8]") && error.contains("[1, 12, H, W]"),
        "{error}"
    );
}
