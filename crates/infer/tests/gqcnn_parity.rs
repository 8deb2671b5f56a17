//! The GQ-CNN against torch: fixtures written by `training/scripts/make_parity_fixtures.py`
//! (tiny networks of the same layer kinds as the shipped ones, random weights), and loading
//! errors that name the file and the tensor.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // tests may fail loudly

use std::path::{Path, PathBuf};

use mvgrasp_infer::model::Weights;
use mvgrasp_infer::{Gqcnn, GqcnnWorkspace, InferError, Parallelism, Tensor};

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures")
}

fn io(name: &str) -> (Tensor, Tensor, Vec<f32>) {
    let mut file = Weights::load(&fixtures().join(format!("{name}.io.safetensors"))).unwrap();
    let mut tensor = |n: &str| file.take_any(n).unwrap();
    (
        tensor("depth"),
        tensor("pose"),
        tensor("logits").into_data(),
    )
}

#[test]
fn both_networks_match_torch_within_1e_4() {
    for name in ["gqcnn_tiny_pose1", "gqcnn_tiny_pose2"] {
        let (depth, pose, expected) = io(name);
        for par in [Parallelism::Sequential, Parallelism::Rayon { threads: 2 }] {
            let net = Gqcnn::load(&fixtures().join(format!("{name}.json")))
                .unwrap()
                .with_parallelism(par);
            let mut workspace = GqcnnWorkspace::default();
            // Twice: the second call reuses the buffers of the first.
            for _ in 0..2 {
                let logits = net.logits(&depth, &pose, &mut workspace).unwrap();
                assert_eq!(logits.shape(), [7, 2]);
                for (got, want) in logits.data().iter().zip(&expected) {
                    assert!((got - want).abs() < 1e-4, "{name}: {got} vs torch {want}");
                }
            }
            let p = net.predict(&depth, &pose, &mut workspace).unwrap();
            assert!(p.iter().all(|p| (0.0..=1.0).contains(p)));
        }
    }
}

#[test]
fn wrong_inputs_are_shape_errors() {
    let net = Gqcnn::load(&fixtures().join("gqcnn_tiny_pose2.json")).unwrap();
    let mut workspace = GqcnnWorkspace::default();
    let depth = Tensor::zeros(&[3, 1, 32, 32]);
    let pose = Tensor::zeros(&[3, 2]);
    let err = net.logits(&depth, &pose, &mut workspace).unwrap_err();
    assert!(matches!(err, InferError::ShapeMismatch { .. }), "{err}");
    let depth = Tensor::zeros(&[3, 1, 16, 16]);
    let err = net
        .logits(&depth, &Tensor::zeros(&[3, 1]), &mut workspace)
        .unwrap_err();
    assert!(err.to_string().contains("pose"), "{err}");
}

#[test]
fn grasps_that_share_a_crop_score_as_if_each_had_its_own() {
    let (depth, pose, _) = io("gqcnn_tiny_pose2");
    let net = Gqcnn::load(&fixtures().join("gqcnn_tiny_pose2.json")).unwrap();
    let mut workspace = GqcnnWorkspace::default();
    // Crop i's grasps at three poses each, as the sampler tries an axis at three depths.
    let crops = depth.shape()[0];
    let side = depth.shape()[2];
    let pixels = side * side;
    let image_of: Vec<usize> = (0..crops).flat_map(|i| [i; 3]).collect();
    let pose_rows: Vec<f32> = image_of
        .iter()
        .enumerate()
        .flat_map(|(k, &i)| {
            let row = &pose.data()[2 * i..2 * i + 2];
            [row[0] + 0.01 * (k % 3) as f32, row[1]]
        })
        .collect();
    let shared_pose = Tensor::new(&[image_of.len(), 2], pose_rows).unwrap();
    let repeated: Vec<f32> = image_of
        .iter()
        .flat_map(|&i| depth.data()[i * pixels..(i + 1) * pixels].to_vec())
        .collect();
    let repeated = Tensor::new(&[image_of.len(), 1, side, side], repeated).unwrap();
    let each = net
        .predict(&repeated, &shared_pose, &mut workspace)
        .unwrap();
    let shared = net
        .predict_shared(&depth, &image_of, &shared_pose, &mut workspace)
        .unwrap();
    assert_eq!(
        shared.iter().map(|p| p.to_bits()).collect::<Vec<_>>(),
        each.iter().map(|p| p.to_bits()).collect::<Vec<_>>()
    );
    // A crop index past the crops, or one index too few, is refused.
    let mut bad = image_of.clone();
    bad[4] = crops;
    let err = net
        .predict_shared(&depth, &bad, &shared_pose, &mut workspace)
        .unwrap_err();
    assert!(err.to_string().contains("crop index"), "{err}");
    let err = net
        .predict_shared(&depth, &image_of[1..], &shared_pose, &mut workspace)
        .unwrap_err();
    assert!(err.to_string().contains("pose"), "{err}");
}

fn copy_fixture(dir: &Path, name: &str) -> PathBuf {
    for ext in ["json", "safetensors"] {
        std::fs::copy(
            fixtures().join(format!("{name}.{ext}")),
            dir.join(format!("{name}.{ext}")),
        )
        .unwrap();
    }
    dir.join(format!("{name}.json"))
}

#[test]
fn bad_model_files_name_the_file_and_the_tensor() {
    let dir = tempfile::tempdir().unwrap();
    let name = "gqcnn_tiny_pose1";
    let json = copy_fixture(dir.path(), name);
    let weights = dir.path().join(format!("{name}.safetensors"));

    // A truncated weights file.
    let bytes = std::fs::read(&weights).unwrap();
    std::fs::write(&weights, &bytes[..bytes.len() / 2]).unwrap();
    let err = Gqcnn::load(&json).unwrap_err().to_string();
    assert!(err.contains("gqcnn_tiny_pose1.safetensors"), "{err}");

    // An architecture that disagrees with the weights: the tensor is named.
    std::fs::write(&weights, &bytes).unwrap();
    let text = std::fs::read_to_string(&json).unwrap();
    std::fs::write(&json, text.replace("\"image_fc\": 24", "\"image_fc\": 25")).unwrap();
    let err = Gqcnn::load(&json).unwrap_err().to_string();
    assert!(
        err.contains("image_fc.weight") && err.contains("expected [25"),
        "{err}"
    );

    // A zero standard deviation would divide by zero: refused.
    std::fs::write(&json, &text).unwrap();
    let mut file = safetensors::SafeTensors::deserialize(&bytes)
        .unwrap()
        .tensors()
        .into_iter()
        .map(|(name, view)| {
            (
                name,
                (view.dtype(), view.shape().to_vec(), view.data().to_vec()),
            )
        })
        .collect::<std::collections::BTreeMap<_, _>>();
    if let Some(std) = file.get_mut("image_std") {
        std.2 = 0.0f32.to_le_bytes().to_vec();
    }
    let views: Vec<_> = file
        .iter()
        .map(|(n, (d, s, b))| {
            (
                n.clone(),
                safetensors::tensor::TensorView::new(*d, s.clone(), b).unwrap(),
            )
        })
        .collect();
    std::fs::write(&weights, safetensors::serialize(views, None).unwrap()).unwrap();
    let err = Gqcnn::load(&json).unwrap_err().to_string();
    assert!(err.contains("standard deviation"), "{err}");

    // Another format, and garbage.
    std::fs::write(&json, text.replace("mvgrasp-gqcnn/1", "something-else")).unwrap();
    assert!(
        Gqcnn::load(&json)
            .unwrap_err()
            .to_string()
            .contains("format")
    );
    std::fs::write(&json, "{").unwrap();
    let err = Gqcnn::load(&json).unwrap_err().to_string();
    assert!(err.contains(&json.display().to_string()), "{err}");
    assert!(Gqcnn::load(&dir.path().join("missing.json")).is_err());
}
