//! Element-wise and row-wise ops. Each has the plain form that is obviously right; the faer
//! kernels that come with the networks are tested against these.

use crate::error::{InferError, Result};
use crate::tensor::Tensor;

/// `max(x, 0)` in place.
pub fn relu(x: &mut Tensor) {
    for v in x.data_mut() {
        *v = v.max(0.0);
    }
}

/// Softmax over the last axis of a `[batch, classes]` tensor, in place, stable for large inputs
/// (the row maximum is subtracted first).
///
/// # Errors
/// [`InferError::ShapeMismatch`] unless the tensor is two-dimensional with at least one class.
pub fn softmax_rows(x: &mut Tensor) -> Result<()> {
    let &[_, classes] = x.shape() else {
        return Err(InferError::ShapeMismatch {
            op: "softmax",
            expected: "[batch, classes]".into(),
            got: x.shape().to_vec(),
        });
    };
    if classes == 0 {
        return Err(InferError::ShapeMismatch {
            op: "softmax",
            expected: "[batch, classes >= 1]".into(),
            got: x.shape().to_vec(),
        });
    }
    for row in x.data_mut().chunks_exact_mut(classes) {
        let max = row.iter().copied().fold(f32::NEG_INFINITY, f32::max);
        let mut sum = 0.0;
        for v in row.iter_mut() {
            *v = (*v - max).exp();
            sum += *v;
        }
        for v in row.iter_mut() {
            *v /= sum;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn softmax_is_stable_and_sums_to_one() {
        let mut x = Tensor::new(&[2, 2], vec![1000.0, 1000.0, 0.0, 2f32.ln()]).unwrap();
        softmax_rows(&mut x).unwrap();
        assert_eq!(x.data()[..2], [0.5, 0.5]);
        assert!((x.data()[3] - 2.0 / 3.0).abs() < 1e-6);
        assert!(softmax_rows(&mut Tensor::zeros(&[4])).is_err());
    }

    #[test]
    fn relu_clamps_negatives() {
        let mut x = Tensor::new(&[3], vec![-1.0, 0.0, 2.0]).unwrap();
        relu(&mut x);
        assert_eq!(x.data(), [0.0, 0.0, 2.0]);
    }

    #[test]
    fn tensors_check_their_length() {
        let err = Tensor::new(&[2, 3], vec![0.0; 5]).unwrap_err();
        assert!(err.to_string().contains("[2, 3]"), "{err}");
    }
}
