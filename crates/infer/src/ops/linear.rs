//! A fully connected layer, `y = x · weightᵀ + bias`, with torch's weight layout.

use crate::error::Result;
use crate::gemm::{Rhs, matmul};
use crate::ops::check::{optional_vector, shape_error};
use crate::parallel::Parallelism;
use crate::tensor::Tensor;

/// The checked `(rows, in, out, bias)` of a linear layer.
fn check<'a>(
    x: &Tensor,
    weight: &Tensor,
    bias: Option<&'a Tensor>,
) -> Result<(usize, usize, usize, Option<&'a [f32]>)> {
    const OP: &str = "linear";
    let &[outputs, inputs] = weight.shape() else {
        return Err(shape_error(
            OP,
            "weight [out_features, in_features]",
            weight.shape(),
        ));
    };
    match x.shape().last() {
        Some(&features) if features == inputs => {}
        _ => {
            return Err(shape_error(
                OP,
                format!("[..., {inputs}] for a weight of shape [{outputs}, {inputs}]"),
                x.shape(),
            ));
        }
    }
    let bias = optional_vector(OP, "bias", bias, outputs)?;
    let rows = x.shape()[..x.rank() - 1].iter().product();
    Ok((rows, inputs, outputs, bias))
}

/// The output shape: `x`'s with the last axis `outputs` long.
fn output_shape(x: &Tensor, outputs: usize) -> Vec<usize> {
    let mut shape = x.shape().to_vec();
    if let Some(last) = shape.last_mut() {
        *last = outputs;
    }
    shape
}

/// torch's `nn.Linear`: `x [..., in]` times `weight [out, in]` transposed, plus `bias [out]`,
/// into a new `[..., out]` tensor.
///
/// # Errors
/// As [`linear_into`].
pub fn linear(
    x: &Tensor,
    weight: &Tensor,
    bias: Option<&Tensor>,
    par: Parallelism,
) -> Result<Tensor> {
    let mut out = Tensor::default();
    linear_into(x, weight, bias, &mut out, par)?;
    Ok(out)
}

/// [`linear`] into `out`, which is resized to `[..., out]` and keeps its allocation; one faer
/// matrix product, split over `par`'s threads.
///
/// # Errors
/// [`InferError::ShapeMismatch`](crate::InferError::ShapeMismatch) when `weight` is not
/// `[out, in]`, `x`'s last axis is not `in` long, or `bias` is not `[out]`.
pub fn linear_into(
    x: &Tensor,
    weight: &Tensor,
    bias: Option<&Tensor>,
    out: &mut Tensor,
    par: Parallelism,
) -> Result<()> {
    let (rows, inputs, outputs, bias) = check(x, weight, bias)?;
    out.resize(&output_shape(x, outputs));
    if let Some(bias) = bias {
        for row in out.data_mut().chunks_exact_mut(outputs) {
            row.copy_from_slice(bias);
        }
    }
    matmul(
        "linear",
        out.data_mut(),
        x.data(),
        weight.data(),
        [rows, inputs, outputs],
        Rhs::Transposed,
        bias.is_some(),
        par,
    )
}

/// [`linear`] by its definition: each output the bias plus a dot product, in order. Slow; the
/// reference [`linear`] is tested against.
///
/// # Errors
/// As [`linear_into`].
pub fn linear_reference(x: &Tensor, weight: &Tensor, bias: Option<&Tensor>) -> Result<Tensor> {
    let (rows, inputs, outputs, bias) = check(x, weight, bias)?;
    let mut out = Tensor::zeros(&output_shape(x, outputs));
    let (xs, w, y) = (x.data(), weight.data(), out.data_mut());
    for r in 0..rows {
        for o in 0..outputs {
            let mut sum = bias.map_or(0.0, |b| b[o]);
            for i in 0..inputs {
                sum += xs[r * inputs + i] * w[o * inputs + i];
            }
            y[r * outputs + o] = sum;
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;
    use crate::testing::{Rng, assert_close, assert_same_bits};

    #[test]
    fn a_small_product_by_hand() {
        let x = Tensor::new(&[1, 2], vec![1.0, 2.0]).unwrap();
        let w = Tensor::new(&[3, 2], vec![1.0, 0.0, 0.0, 1.0, 1.0, 1.0]).unwrap();
        let b = Tensor::new(&[3], vec![0.5, 0.0, -3.0]).unwrap();
        let y = linear(&x, &w, Some(&b), Parallelism::Sequential).unwrap();
        assert_eq!(y.shape(), [1, 3]);
        assert_eq!(y.data(), [1.5, 2.0, 0.0]);
    }

    #[test]
    fn faer_matches_the_reference() {
        let mut rng = Rng::new(11);
        for shape in [
            [1, 1, 1],
            [3, 17, 5],
            [64, 300, 33],
            [2, 1024, 2],
            [1, 4096, 1100],
        ] {
            let [rows, inputs, outputs] = shape;
            let x = rng.tensor(&[rows, inputs]);
            let w = rng.tensor(&[outputs, inputs]);
            let b = rng.tensor(&[outputs]);
            for bias in [None, Some(&b)] {
                let want = linear_reference(&x, &w, bias).unwrap();
                for par in [Parallelism::Sequential, Parallelism::Rayon { threads: 2 }] {
                    assert_close(&linear(&x, &w, bias, par).unwrap(), &want);
                }
            }
        }
    }

    #[test]
    fn the_thread_count_does_not_change_a_bit() {
        let mut rng = Rng::new(14);
        // One row (faer's matrix-vector path, in blocks of outputs; large enough for threads
        // in the second, with a last block cut short), one output, and a batch.
        for [rows, inputs, outputs] in [
            [1, 1024, 512],
            [1, 4096, 1100],
            [300, 700, 1],
            [96, 512, 256],
        ] {
            let x = rng.tensor(&[rows, inputs]);
            let w = rng.tensor(&[outputs, inputs]);
            let b = rng.tensor(&[outputs]);
            let one = linear(&x, &w, Some(&b), Parallelism::Sequential).unwrap();
            for threads in [2, 3, 4] {
                let par = Parallelism::Rayon { threads };
                let got = linear(&x, &w, Some(&b), par).unwrap();
                assert_same_bits(&got, &one, &format!("{rows}x{inputs}x{outputs} {par:?}"));
            }
        }
    }

    #[test]
    fn leading_axes_are_batch_axes() {
        let mut rng = Rng::new(12);
        let x = rng.tensor(&[2, 3, 4]);
        let w = rng.tensor(&[5, 4]);
        let y = linear(&x, &w, None, Parallelism::Sequential).unwrap();
        assert_eq!(y.shape(), [2, 3, 5]);
        assert_close(&y, &linear_reference(&x, &w, None).unwrap());
    }

    #[test]
    fn output_buffers_are_overwritten_not_added_to() {
        let mut rng = Rng::new(13);
        let (x, w) = (rng.tensor(&[4, 6]), rng.tensor(&[3, 6]));
        let mut out = Tensor::full(&[4, 3], f32::NAN);
        linear_into(&x, &w, None, &mut out, Parallelism::Sequential).unwrap();
        assert_close(&out, &linear_reference(&x, &w, None).unwrap());
    }

    #[test]
    fn wrong_shapes_are_errors() {
        let w = Tensor::zeros(&[3, 4]);
        let err = linear(&Tensor::zeros(&[2, 5]), &w, None, Parallelism::Sequential).unwrap_err();
        assert!(err.to_string().contains("[..., 4]"), "{err}");
        let bias = Tensor::zeros(&[4]);
        assert!(
            linear(
                &Tensor::zeros(&[2, 4]),
                &w,
                Some(&bias),
                Parallelism::Sequential
            )
            .is_err()
        );
        assert!(
            linear(
                &Tensor::zeros(&[2, 4]),
                &Tensor::zeros(&[12]),
                None,
                Parallelism::Sequential
            )
            .is_err()
        );
        assert!(linear(&Tensor::zeros(&[]), &w, None, Parallelism::Sequential).is_err());
    }
}
