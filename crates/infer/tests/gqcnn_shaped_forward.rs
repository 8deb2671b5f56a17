//! A forward pass with Dex-Net 2.0's GQ-CNN layer sequence (shrunk): the fast ops with reused
//! buffers against the reference forms, and the same bits whatever the thread count.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // tests may fail loudly

use crate::common;

use common::{Rng, assert_close, assert_same_bits};
use mvgrasp_infer::ops::{self, Conv2dParams, LocalResponseNorm, Pool2dParams};
use mvgrasp_infer::{Parallelism, Result, Tensor};

/// Weights of a small GQ-CNN: an image stream, a pose stream, and merged fully connected layers.
struct Weights {
    conv: Vec<(Tensor, Tensor)>,
    fc3: (Tensor, Tensor),
    pc1: (Tensor, Tensor),
    fc4: (Tensor, Tensor),
    fc5: (Tensor, Tensor),
}

const FILTERS: usize = 8;
const SIZE: usize = 16;

impl Weights {
    fn new(rng: &mut Rng) -> Self {
        let mut layer = |shape: &[usize]| {
            let fan_in: usize = shape[1..].iter().product();
            let scale = (3.0 / fan_in as f32).sqrt();
            (rng.tensor(shape, scale), rng.tensor(&shape[..1], 0.1))
        };
        let conv = vec![
            layer(&[FILTERS, 1, 7, 7]),
            layer(&[FILTERS, FILTERS, 5, 5]),
            layer(&[FILTERS, FILTERS, 3, 3]),
            layer(&[FILTERS, FILTERS, 3, 3]),
        ];
        let flat = FILTERS * (SIZE / 4) * (SIZE / 4);
        Self {
            conv,
            fc3: layer(&[32, flat]),
            pc1: layer(&[8, 1]),
            fc4: layer(&[16, 40]),
            fc5: layer(&[2, 16]),
        }
    }
}

fn same(kernel: usize) -> Conv2dParams {
    Conv2dParams {
        padding: [kernel / 2, kernel / 2],
        ..Conv2dParams::default()
    }
}

/// The network with the fast ops, every intermediate in `buffers` (reused from call to call).
fn forward_fast(
    w: &Weights,
    image: &Tensor,
    depth: &Tensor,
    par: Parallelism,
    buffers: &mut [Tensor; 3],
    scratch: &mut Vec<f32>,
) -> Result<Tensor> {
    let [a, b, c] = buffers;
    let lrn = LocalResponseNorm::new(5);
    let pool = Pool2dParams::new([2, 2]);
    let mut x = image;
    for (i, (kernel, bias)) in w.conv.iter().enumerate() {
        ops::conv2d_into(
            x,
            kernel,
            Some(bias),
            same(kernel.shape()[2]),
            a,
            scratch,
            par,
        )?;
        ops::relu(a);
        if i % 2 == 1 {
            ops::max_pool2d_into(a, pool, b)?;
            ops::local_response_norm_into(b, lrn, c)?;
            std::mem::swap(a, c);
        }
        std::mem::swap(a, b);
        x = b;
    }
    let batch = image.shape()[0];
    b.reshape(&[batch, b.len() / batch])?;
    ops::linear_into(b, &w.fc3.0, Some(&w.fc3.1), a, par)?;
    ops::relu(a);
    ops::linear_into(depth, &w.pc1.0, Some(&w.pc1.1), c, par)?;
    ops::relu(c);
    let merged = ops::concat(&[a, c], 1)?;
    ops::linear_into(&merged, &w.fc4.0, Some(&w.fc4.1), a, par)?;
    ops::relu(a);
    let mut logits = ops::linear(a, &w.fc5.0, Some(&w.fc5.1), par)?;
    ops::softmax(&mut logits)?;
    Ok(logits)
}

/// The network with the reference forms, allocating as it goes.
fn forward_reference(w: &Weights, image: &Tensor, depth: &Tensor) -> Result<Tensor> {
    let lrn = LocalResponseNorm::new(5);
    let pool = Pool2dParams::new([2, 2]);
    let mut x = image.clone();
    for (i, (kernel, bias)) in w.conv.iter().enumerate() {
        x = ops::conv2d_reference(&x, kernel, Some(bias), same(kernel.shape()[2]))?;
        ops::relu(&mut x);
        if i % 2 == 1 {
            x = ops::max_pool2d_reference(&x, pool)?;
            x = ops::local_response_norm_reference(&x, lrn)?;
        }
    }
    let batch = image.shape()[0];
    x.reshape(&[batch, x.len() / batch])?;
    let mut image_features = ops::linear_reference(&x, &w.fc3.0, Some(&w.fc3.1))?;
    ops::relu(&mut image_features);
    let mut pose_features = ops::linear_reference(depth, &w.pc1.0, Some(&w.pc1.1))?;
    ops::relu(&mut pose_features);
    let merged = ops::concat(&[&image_features, &pose_features], 1)?;
    let mut hidden = ops::linear_reference(&merged, &w.fc4.0, Some(&w.fc4.1))?;
    ops::relu(&mut hidden);
    let mut logits = ops::linear_reference(&hidden, &w.fc5.0, Some(&w.fc5.1))?;
    ops::softmax(&mut logits)?;
    Ok(logits)
}

#[test]
fn fast_ops_with_reused_buffers_match_the_references() {
    let mut rng = Rng::new(2024);
    let weights = Weights::new(&mut rng);
    let mut buffers: [Tensor; 3] = Default::default();
    let mut scratch = Vec::new();
    for batch in [5, 1, 3] {
        let image = rng.tensor(&[batch, 1, SIZE, SIZE], 1.0);
        let depth = rng.tensor(&[batch, 1], 1.0);
        let want = forward_reference(&weights, &image, &depth).unwrap();
        let par = Parallelism::Rayon { threads: 2 };
        let got = forward_fast(&weights, &image, &depth, par, &mut buffers, &mut scratch).unwrap();
        assert_eq!(got.shape(), [batch, 2]);
        assert_close(&got, &want, 1e-4);
        for row in got.data().chunks(2) {
            assert!((row[0] + row[1] - 1.0).abs() < 1e-5, "{row:?}");
        }
    }
}

#[test]
fn the_thread_count_does_not_change_a_bit() {
    let mut rng = Rng::new(7);
    let weights = Weights::new(&mut rng);
    let image = rng.tensor(&[6, 1, SIZE, SIZE], 1.0);
    let depth = rng.tensor(&[6, 1], 1.0);
    let mut buffers: [Tensor; 3] = Default::default();
    let mut scratch = Vec::new();
    let mut run =
        |par| forward_fast(&weights, &image, &depth, par, &mut buffers, &mut scratch).unwrap();
    let one = run(Parallelism::Sequential);
    for threads in [2, 3, 4, 0] {
        assert_same_bits(&run(Parallelism::Rayon { threads }), &one);
    }
}
