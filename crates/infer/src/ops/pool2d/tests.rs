#![allow(clippy::unwrap_used)]

use super::*;
use crate::InferError;
use crate::tensor::Tensor;
use crate::testing::{Rng, assert_close};

fn grid() -> Tensor {
    Tensor::new(&[1, 1, 4, 4], (1..=16).map(|v| v as f32).collect()).unwrap()
}

#[test]
fn pools_by_hand() {
    let y = max_pool2d(&grid(), Pool2dParams::new([2, 2])).unwrap();
    assert_eq!(y.shape(), [1, 1, 2, 2]);
    assert_eq!(y.data(), [6.0, 8.0, 14.0, 16.0]);
    let y = avg_pool2d(&grid(), Pool2dParams::new([2, 2]), AvgPoolDivisor::Window).unwrap();
    assert_eq!(y.data(), [3.5, 5.5, 11.5, 13.5]);
    // Padding 1, stride 2, 3x3 window: the corner window holds 1, 2, 5, 6 and five padding cells.
    let p = Pool2dParams::new([3, 3])
        .with_stride([2, 2])
        .with_padding([1, 1]);
    let window = avg_pool2d(&grid(), p, AvgPoolDivisor::Window).unwrap();
    let input_only = avg_pool2d(&grid(), p, AvgPoolDivisor::InputOnly).unwrap();
    assert_eq!(window.data()[0], 14.0 / 9.0);
    assert_eq!(input_only.data()[0], 14.0 / 4.0);
    assert_eq!(
        max_pool2d(&grid(), p).unwrap().data(),
        [6.0, 8.0, 14.0, 16.0]
    );
}

#[test]
fn max_padding_is_minus_infinity() {
    // torch pads max pooling with -inf, so an all-negative input never pools to 0.
    let x = Tensor::full(&[1, 2, 3, 3], -5.0);
    let p = Pool2dParams::new([2, 2])
        .with_stride([1, 1])
        .with_padding([1, 1]);
    let y = max_pool2d(&x, p).unwrap();
    assert_eq!(y.shape(), [1, 2, 4, 4]);
    assert!(y.data().iter().all(|&v| v == -5.0), "{:?}", y.data());
}

#[test]
fn nan_wins_max_pooling_as_in_torch() {
    let mut x = grid();
    x.data_mut()[5] = f32::NAN;
    let y = max_pool2d(&x, Pool2dParams::new([2, 2])).unwrap();
    assert!(y.data()[0].is_nan());
    assert_eq!(y.data()[1..], [8.0, 14.0, 16.0]);
    let r = max_pool2d_reference(&x, Pool2dParams::new([2, 2])).unwrap();
    assert!(r.data()[0].is_nan());
}

#[test]
fn clipped_windows_match_the_padded_reference() {
    let mut rng = Rng::new(5);
    for _ in 0..60 {
        let kernel = [rng.range(1, 4), rng.range(1, 4)];
        let stride = [rng.range(1, 3), rng.range(1, 3)];
        let padding = [rng.range(0, kernel[0] / 2), rng.range(0, kernel[1] / 2)];
        let h = kernel[0] + rng.range(0, 6);
        let w = kernel[1] + rng.range(0, 6);
        let (n, c) = (rng.range(1, 2), rng.range(1, 3));
        let x = rng.tensor(&[n, c, h, w]);
        let p = Pool2dParams {
            kernel,
            stride,
            padding,
        };
        assert_close(
            &max_pool2d(&x, p).unwrap(),
            &max_pool2d_reference(&x, p).unwrap(),
        );
        for divisor in [AvgPoolDivisor::Window, AvgPoolDivisor::InputOnly] {
            assert_close(
                &avg_pool2d(&x, p, divisor).unwrap(),
                &avg_pool2d_reference(&x, p, divisor).unwrap(),
            );
        }
    }
}

#[test]
fn the_2x2_fast_path_is_the_reference_to_the_bit() {
    // Even and odd sides (floor mode drops the last row or column), NaNs and ties included.
    let mut rng = Rng::new(6);
    for [h, w] in [[4, 4], [5, 7], [2, 3], [16, 16]] {
        let mut x = rng.tensor(&[2, 3, h, w]);
        for (i, v) in x.data_mut().iter_mut().enumerate() {
            match i % 11 {
                3 => *v = f32::NAN,
                7 => *v = 0.0,
                8 => *v = -0.0,
                _ => {}
            }
        }
        let p = Pool2dParams::new([2, 2]);
        let (fast, slow) = (
            max_pool2d(&x, p).unwrap(),
            max_pool2d_reference(&x, p).unwrap(),
        );
        assert_eq!(fast.shape(), slow.shape());
        let bits = |t: &Tensor| t.data().iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&fast), bits(&slow), "{h}x{w}");
    }
}

#[test]
fn output_buffers_are_overwritten() {
    let mut out = Tensor::full(&[3, 3], f32::NAN);
    max_pool2d_into(&grid(), Pool2dParams::new([2, 2]), &mut out).unwrap();
    assert_eq!(out.data(), [6.0, 8.0, 14.0, 16.0]);
    avg_pool2d_into(
        &grid(),
        Pool2dParams::new([4, 4]),
        AvgPoolDivisor::Window,
        &mut out,
    )
    .unwrap();
    assert_eq!((out.shape(), out.data()), (&[1, 1, 1, 1][..], &[8.5][..]));
}

#[test]
fn bad_windows_are_errors() {
    let too_much_padding = Pool2dParams::new([2, 2]).with_padding([0, 2]);
    assert!(matches!(
        max_pool2d(&grid(), too_much_padding),
        Err(InferError::InvalidParameter {
            name: "padding[1]",
            ..
        })
    ));
    assert!(max_pool2d(&grid(), Pool2dParams::new([5, 1])).is_err());
    assert!(max_pool2d(&grid(), Pool2dParams::new([2, 2]).with_stride([1, 0])).is_err());
    assert!(
        avg_pool2d(
            &Tensor::zeros(&[4, 4]),
            Pool2dParams::new([2, 2]),
            AvgPoolDivisor::Window
        )
        .is_err()
    );
    assert!(max_pool2d(&Tensor::zeros(&[1, 1, 0, 4]), Pool2dParams::new([1, 1])).is_err());
}
