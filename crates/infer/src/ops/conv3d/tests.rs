#![allow(clippy::unwrap_used)]

use super::*;
use crate::parallel::Parallelism;
use crate::tensor::Tensor;
use crate::testing::{Rng, assert_close, assert_same_bits};

/// Shapes the Learnt Stereo Machine uses (3x3x3 "same", stride-2 downsampling, 4x4x4 stride-2
/// upsampling) and odd ones: `[n, c, d, h, w]`, `oc`, kernel, params.
fn cases() -> Vec<([usize; 5], usize, [usize; 3], Conv3dParams)> {
    vec![
        ([1, 3, 6, 5, 4], 4, [3, 3, 3], Conv3dParams::cubic(1, 1)),
        // Too many channels for the row-by-row form: the column matrix's.
        ([1, 20, 4, 3, 5], 16, [3, 3, 3], Conv3dParams::cubic(1, 1)),
        ([2, 8, 5, 4, 7], 1, [3, 3, 3], Conv3dParams::cubic(1, 1)),
        ([2, 2, 7, 6, 6], 3, [3, 3, 3], Conv3dParams::cubic(2, 1)),
        ([1, 4, 4, 4, 4], 2, [4, 4, 4], Conv3dParams::cubic(2, 1)),
        (
            [1, 1, 5, 3, 6],
            2,
            [1, 2, 3],
            Conv3dParams {
                stride: [1, 2, 3],
                padding: [0, 1, 2],
            },
        ),
        ([2, 5, 3, 3, 3], 1, [1, 1, 1], Conv3dParams::default()),
    ]
}

#[test]
fn convolution_matches_its_definition_whatever_the_threads() {
    let mut rng = Rng::new(41);
    for (shape, oc, kernel, params) in cases() {
        let input = rng.tensor(&shape);
        let weight = rng.tensor(&[oc, shape[1], kernel[0], kernel[1], kernel[2]]);
        let bias = rng.tensor(&[oc]);
        let want = conv3d_reference(&input, &weight, Some(&bias), params).unwrap();
        let one = conv3d(
            &input,
            &weight,
            Some(&bias),
            params,
            Parallelism::Sequential,
        )
        .unwrap();
        assert_close(&one, &want);
        let two = Parallelism::Rayon { threads: 2 };
        let mut out = Tensor::default();
        let mut scratch = Vec::new();
        for _ in 0..2 {
            conv3d_into(
                &input,
                &weight,
                Some(&bias),
                params,
                &mut out,
                &mut scratch,
                two,
            )
            .unwrap();
            assert_same_bits(&out, &one, &format!("{shape:?} on two threads"));
        }
        let plain = conv3d(&input, &weight, None, params, Parallelism::Sequential).unwrap();
        assert_close(
            &plain,
            &conv3d_reference(&input, &weight, None, params).unwrap(),
        );
    }
}

#[test]
fn transposed_convolution_matches_its_definition_whatever_the_threads() {
    let mut rng = Rng::new(42);
    for (shape, oc, kernel, params) in cases() {
        let input = rng.tensor(&shape);
        let weight = rng.tensor(&[shape[1], oc, kernel[0], kernel[1], kernel[2]]);
        let bias = rng.tensor(&[oc]);
        let want = conv_transpose3d_reference(&input, &weight, Some(&bias), params).unwrap();
        let one = conv_transpose3d(
            &input,
            &weight,
            Some(&bias),
            params,
            Parallelism::Sequential,
        )
        .unwrap();
        assert_close(&one, &want);
        let two = conv_transpose3d(
            &input,
            &weight,
            Some(&bias),
            params,
            Parallelism::Rayon { threads: 2 },
        )
        .unwrap();
        assert_same_bits(&two, &one, &format!("{shape:?} on two threads"));
    }
}

#[test]
fn transposed_convolution_is_the_adjoint_of_convolution() {
    // <conv(x, W), y> = <x, conv_transpose(y, W)>: the transposed convolution is the
    // convolution's gradient, whatever the stride and padding; a check independent of both
    // definitions' index arithmetic.
    let mut rng = Rng::new(43);
    for (shape, oc, kernel, params) in cases() {
        let x = rng.tensor(&shape);
        let weight = rng.tensor(&[oc, shape[1], kernel[0], kernel[1], kernel[2]]);
        let forward = conv3d(&x, &weight, None, params, Parallelism::Sequential).unwrap();
        let y = rng.tensor(forward.shape());
        let back = conv_transpose3d(&y, &weight, None, params, Parallelism::Sequential).unwrap();
        if back.shape() != x.shape() {
            // A strided convolution that drops input rows has no exact inverse size.
            continue;
        }
        let dot = |a: &Tensor, b: &Tensor| -> f64 {
            a.data()
                .iter()
                .zip(b.data())
                .map(|(&a, &b)| f64::from(a) * f64::from(b))
                .sum()
        };
        let (lhs, rhs) = (dot(&forward, &y), dot(&x, &back));
        assert!(
            (lhs - rhs).abs() < 1e-3 * lhs.abs().max(1.0),
            "{shape:?}: {lhs} vs {rhs}"
        );
    }
}

#[test]
fn a_kernel_of_ones_sums_its_window() {
    let input = Tensor::full(&[1, 1, 3, 3, 3], 1.0);
    let weight = Tensor::full(&[1, 1, 3, 3, 3], 1.0);
    let out = conv3d(
        &input,
        &weight,
        None,
        Conv3dParams::cubic(1, 1),
        Parallelism::Sequential,
    )
    .unwrap();
    // A corner sees 2x2x2 inputs, an edge centre 2x2x3, a face centre 2x3x3, the centre 27.
    assert_eq!(out.data()[0], 8.0);
    assert_eq!(out.data()[1], 12.0);
    assert_eq!(out.data()[4], 18.0);
    assert_eq!(out.data()[13], 27.0);
    // Upsampling by 2 with a 4-tap kernel of ones: interior outputs get 2 taps per axis.
    let up = conv_transpose3d(
        &Tensor::full(&[1, 1, 2, 2, 2], 1.0),
        &Tensor::full(&[1, 1, 4, 4, 4], 1.0),
        None,
        Conv3dParams::cubic(2, 1),
        Parallelism::Sequential,
    )
    .unwrap();
    assert_eq!(up.shape(), [1, 1, 4, 4, 4]);
    assert_eq!(up.data()[(4 + 1) * 4 + 1], 8.0);
}

#[test]
fn wrong_shapes_are_errors_naming_the_op() {
    let x = Tensor::zeros(&[1, 2, 4, 4, 4]);
    let err = conv3d(
        &x,
        &Tensor::zeros(&[3, 1, 3, 3, 3]),
        None,
        Conv3dParams::default(),
        Parallelism::Sequential,
    )
    .unwrap_err();
    assert!(err.to_string().starts_with("conv3d:"), "{err}");
    let err = conv_transpose3d(
        &x,
        &Tensor::zeros(&[3, 2, 3, 3, 3]),
        None,
        Conv3dParams::default(),
        Parallelism::Sequential,
    )
    .unwrap_err();
    assert!(err.to_string().starts_with("conv_transpose3d:"), "{err}");
    let too_small = conv3d(
        &Tensor::zeros(&[1, 2, 2, 4, 4]),
        &Tensor::zeros(&[1, 2, 3, 3, 3]),
        None,
        Conv3dParams::default(),
        Parallelism::Sequential,
    );
    assert!(too_small.is_err());
    let zero_stride = Conv3dParams::cubic(0, 1);
    let w = Tensor::zeros(&[1, 2, 3, 3, 3]);
    assert!(conv3d(&x, &w, None, zero_stride, Parallelism::Sequential).is_err());
    assert!(
        conv3d(
            &Tensor::zeros(&[1, 2, 4, 4]),
            &w,
            None,
            Conv3dParams::default(),
            Parallelism::Sequential
        )
        .is_err()
    );
}
