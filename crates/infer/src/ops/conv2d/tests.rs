#![allow(clippy::unwrap_used)]

use super::*;
use crate::InferError;
use crate::parallel::Parallelism;
use crate::tensor::Tensor;
use crate::testing::{Rng, assert_close, assert_same_bits};

const PARS: [Parallelism; 3] = [
    Parallelism::Sequential,
    Parallelism::Rayon { threads: 2 },
    Parallelism::Rayon { threads: 3 },
];

#[test]
fn a_small_convolution_by_hand() {
    // 3x3 input 1..9, a 2x2 kernel of ones: each output sums a 2x2 block, plus the bias.
    let x = Tensor::new(&[1, 1, 3, 3], (1..=9).map(|v| v as f32).collect()).unwrap();
    let w = Tensor::full(&[1, 1, 2, 2], 1.0);
    let b = Tensor::full(&[1], 0.5);
    let y = conv2d(
        &x,
        &w,
        Some(&b),
        Conv2dParams::default(),
        Parallelism::Sequential,
    )
    .unwrap();
    assert_eq!(y.shape(), [1, 1, 2, 2]);
    assert_eq!(y.data(), [12.5, 16.5, 24.5, 28.5]);
    // Padding 1, stride 2: the corners see one, two or four values.
    let params = Conv2dParams {
        stride: [2, 2],
        padding: [1, 1],
        ..Conv2dParams::default()
    };
    let y = conv2d(&x, &w, None, params, Parallelism::Sequential).unwrap();
    assert_eq!(y.data(), [1.0, 5.0, 11.0, 28.0]);
    assert_eq!(conv2d_reference(&x, &w, None, params).unwrap(), y);
}

/// Input `[n, c, h, w]`, weight `[oc, kh, kw]`, stride, padding, dilation.
type Case = ([usize; 4], [usize; 3], [usize; 2], [usize; 2], [usize; 2]);

#[test]
fn im2col_matches_the_reference() {
    let mut rng = Rng::new(1);
    // The last three run tap by tap (stride 1, no dilation, 4 or more input channels an
    // output channel): padded as the LSM's, unpadded, and wider padding than the kernel.
    let cases: [Case; 12] = [
        ([1, 1, 5, 5], [1, 3, 3], [1, 1], [0, 0], [1, 1]),
        ([2, 3, 8, 7], [4, 3, 3], [1, 1], [1, 1], [1, 1]),
        ([3, 2, 9, 11], [5, 3, 2], [2, 3], [1, 0], [1, 1]),
        ([1, 4, 10, 10], [3, 3, 3], [1, 2], [2, 1], [2, 3]),
        ([5, 3, 6, 6], [6, 1, 1], [1, 1], [0, 0], [1, 1]),
        ([2, 3, 6, 5], [2, 1, 1], [2, 1], [1, 0], [1, 1]),
        ([4, 1, 32, 32], [8, 7, 7], [1, 1], [3, 3], [1, 1]),
        ([2, 2, 4, 4], [3, 5, 5], [3, 3], [2, 2], [1, 1]),
        ([1, 2, 3, 9], [2, 1, 4], [1, 2], [0, 3], [1, 2]),
        ([2, 36, 7, 9], [4, 3, 3], [1, 1], [1, 1], [1, 1]),
        ([1, 8, 6, 5], [2, 3, 2], [1, 1], [0, 0], [1, 1]),
        ([3, 12, 4, 3], [3, 2, 3], [1, 1], [3, 2], [1, 1]),
    ];
    for (input, [oc, kh, kw], stride, padding, dilation) in cases {
        let x = rng.tensor(&input);
        let w = rng.tensor(&[oc, input[1], kh, kw]);
        let b = rng.tensor(&[oc]);
        let params = Conv2dParams {
            stride,
            padding,
            dilation,
        };
        for bias in [None, Some(&b)] {
            let want = conv2d_reference(&x, &w, bias, params).unwrap();
            for par in PARS {
                assert_close(&conv2d(&x, &w, bias, params, par).unwrap(), &want);
            }
        }
    }
}

#[test]
fn random_geometries_match_the_reference() {
    let mut rng = Rng::new(2);
    for _ in 0..40 {
        let (kh, kw) = (rng.range(1, 4), rng.range(1, 4));
        let stride = [rng.range(1, 3), rng.range(1, 3)];
        let dilation = [rng.range(1, 2), rng.range(1, 2)];
        let padding = [rng.range(0, 3), rng.range(0, 3)];
        let h = (dilation[0] * (kh - 1) + 1)
            .saturating_sub(2 * padding[0])
            .max(1)
            + rng.range(0, 6);
        let w = (dilation[1] * (kw - 1) + 1)
            .saturating_sub(2 * padding[1])
            .max(1)
            + rng.range(0, 6);
        let (n, c, oc) = (rng.range(1, 3), rng.range(1, 4), rng.range(1, 4));
        let x = rng.tensor(&[n, c, h, w]);
        let wt = rng.tensor(&[oc, c, kh, kw]);
        let b = rng.tensor(&[oc]);
        let params = Conv2dParams {
            stride,
            padding,
            dilation,
        };
        let want = conv2d_reference(&x, &wt, Some(&b), params).unwrap();
        let got = conv2d(&x, &wt, Some(&b), params, Parallelism::Rayon { threads: 2 }).unwrap();
        assert_close(&got, &want);
    }
}

#[test]
fn the_thread_count_does_not_change_a_bit() {
    let mut rng = Rng::new(3);
    // A lone image large enough for faer to split its product, one with a single output channel
    // (faer's matrix-vector path), a batch split by image, and one run tap by tap.
    for (input, oc) in [
        ([1, 16, 48, 48], 64),
        ([1, 16, 64, 64], 1),
        ([7, 4, 16, 16], 8),
        ([1, 128, 24, 32], 8),
    ] {
        let x = rng.tensor(&input);
        let w = rng.tensor(&[oc, input[1], 3, 3]);
        let b = rng.tensor(&[oc]);
        let params = Conv2dParams {
            padding: [1, 1],
            ..Conv2dParams::default()
        };
        let one = conv2d(&x, &w, Some(&b), params, Parallelism::Sequential).unwrap();
        for par in [
            Parallelism::Rayon { threads: 2 },
            Parallelism::Rayon { threads: 4 },
            Parallelism::all_threads(),
        ] {
            let got = conv2d(&x, &w, Some(&b), params, par).unwrap();
            assert_same_bits(&got, &one, &format!("{input:?} {par:?}"));
        }
        // An image's output does not depend on the batch it came in.
        let first = Tensor::new(
            &[1, input[1], input[2], input[3]],
            x.data()[..input[1] * input[2] * input[3]].to_vec(),
        )
        .unwrap();
        let alone = conv2d(
            &first,
            &w,
            Some(&b),
            params,
            Parallelism::Rayon { threads: 2 },
        )
        .unwrap();
        assert_eq!(alone.data(), &one.data()[..alone.len()]);
    }
}

#[test]
fn buffers_are_reused_and_overwritten() {
    let mut rng = Rng::new(4);
    let mut out = Tensor::full(&[100], f32::NAN);
    let mut scratch = vec![f32::NAN; 7];
    for (input, oc, par) in [
        ([2, 3, 9, 9], 4, Parallelism::Rayon { threads: 2 }),
        ([1, 2, 5, 5], 2, Parallelism::Sequential),
        ([3, 3, 9, 9], 4, Parallelism::Rayon { threads: 3 }),
        ([2, 16, 9, 9], 2, Parallelism::Rayon { threads: 2 }),
        ([1, 3, 5, 5], 2, Parallelism::Sequential),
    ] {
        let x = rng.tensor(&input);
        let w = rng.tensor(&[oc, input[1], 3, 3]);
        let params = Conv2dParams {
            padding: [1, 1],
            ..Conv2dParams::default()
        };
        conv2d_into(&x, &w, None, params, &mut out, &mut scratch, par).unwrap();
        assert_close(&out, &conv2d_reference(&x, &w, None, params).unwrap());
    }
}

#[test]
fn empty_batches_and_channels() {
    let w = Tensor::full(&[2, 0, 3, 3], 1.0);
    let b = Tensor::new(&[2], vec![1.0, -1.0]).unwrap();
    let params = Conv2dParams {
        padding: [1, 1],
        ..Conv2dParams::default()
    };
    let y = conv2d(
        &Tensor::zeros(&[1, 0, 2, 2]),
        &w,
        Some(&b),
        params,
        Parallelism::Sequential,
    )
    .unwrap();
    assert_eq!(y.shape(), [1, 2, 2, 2]);
    assert_eq!(y.data(), [1.0, 1.0, 1.0, 1.0, -1.0, -1.0, -1.0, -1.0]);
    let w = Tensor::zeros(&[2, 3, 3, 3]);
    let y = conv2d(
        &Tensor::zeros(&[0, 3, 4, 4]),
        &w,
        None,
        params,
        Parallelism::all_threads(),
    )
    .unwrap();
    assert_eq!(y.shape(), [0, 2, 4, 4]);
}

#[test]
fn bad_shapes_and_parameters_are_errors() {
    let x = Tensor::zeros(&[1, 3, 5, 5]);
    let seq = Parallelism::Sequential;
    let p = Conv2dParams::default();
    let wrong_channels = conv2d(&x, &Tensor::zeros(&[2, 4, 3, 3]), None, p, seq).unwrap_err();
    assert!(
        matches!(
            wrong_channels,
            InferError::ShapeMismatch { op: "conv2d", .. }
        ),
        "{wrong_channels}"
    );
    let too_big = conv2d(&x, &Tensor::zeros(&[2, 3, 6, 3]), None, p, seq).unwrap_err();
    assert!(too_big.to_string().contains("height >= 6"), "{too_big}");
    let stride = Conv2dParams {
        stride: [0, 1],
        ..p
    };
    assert!(matches!(
        conv2d(&x, &Tensor::zeros(&[2, 3, 3, 3]), None, stride, seq),
        Err(InferError::InvalidParameter {
            name: "stride[0]",
            ..
        })
    ));
    let bias = Tensor::zeros(&[3]);
    assert!(conv2d(&x, &Tensor::zeros(&[2, 3, 3, 3]), Some(&bias), p, seq).is_err());
    assert!(
        conv2d(
            &Tensor::zeros(&[3, 5, 5]),
            &Tensor::zeros(&[2, 3, 3, 3]),
            None,
            p,
            seq
        )
        .is_err()
    );
    assert!(conv2d(&x, &Tensor::zeros(&[2, 3, 0, 3]), None, p, seq).is_err());
    assert!(conv2d_reference(&x, &Tensor::zeros(&[2, 3, 6, 3]), None, p).is_err());
}

#[test]
fn large_images_go_in_bands_that_match_the_reference() {
    let mut rng = Rng::new(8);
    // Column matrices of 4.8 and 1.3 MB: two bands each, a "same" convolution and a strided one.
    for (input, oc, stride, padding) in [
        ([2, 40, 12, 40], 8, [1, 1], [2, 2]),
        ([1, 30, 40, 60], 3, [2, 2], [1, 1]),
    ] {
        let x = rng.tensor(&input);
        let w = rng.tensor(&[oc, input[1], 5, 5]);
        let b = rng.tensor(&[oc]);
        let params = Conv2dParams {
            stride,
            padding,
            ..Conv2dParams::default()
        };
        let want = conv2d_reference(&x, &w, Some(&b), params).unwrap();
        let one = conv2d(&x, &w, Some(&b), params, Parallelism::Sequential).unwrap();
        assert_close(&one, &want);
        for par in PARS {
            let got = conv2d(&x, &w, Some(&b), params, par).unwrap();
            assert_same_bits(&got, &one, &format!("{input:?} {par:?}"));
        }
    }
}
