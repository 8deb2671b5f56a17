//! Softmax over the last axis.

use crate::error::Result;
use crate::ops::check::shape_error;
use crate::tensor::Tensor;

/// Softmax over the last axis, in place (torch's `softmax(x, dim=-1)`), stable for large
/// inputs: each row's maximum is subtracted before `exp`.
///
/// # Errors
/// [`InferError::ShapeMismatch`](crate::InferError::ShapeMismatch) for a tensor of rank 0 or
/// with an empty last axis.
pub fn softmax(x: &mut Tensor) -> Result<()> {
    let classes = match x.shape().last() {
        Some(&classes) if classes > 0 => classes,
        _ => return Err(shape_error("softmax", "[..., classes >= 1]", x.shape())),
    };
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
    #![allow(clippy::unwrap_used)]

    use super::*;
    use crate::testing::Rng;

    #[test]
    fn softmax_is_stable_and_sums_to_one() {
        let mut x = Tensor::new(&[2, 2], vec![1000.0, 1000.0, 0.0, 2f32.ln()]).unwrap();
        softmax(&mut x).unwrap();
        assert_eq!(x.data()[..2], [0.5, 0.5]);
        assert!((x.data()[3] - 2.0 / 3.0).abs() < 1e-6);
    }

    #[test]
    fn softmax_matches_its_definition_over_the_last_axis() {
        let mut rng = Rng::new(7);
        let x = rng.tensor_in(&[2, 3, 5], -4.0, 4.0);
        let mut y = x.clone();
        softmax(&mut y).unwrap();
        for (row, got) in x.data().chunks(5).zip(y.data().chunks(5)) {
            let total: f64 = row.iter().map(|&v| f64::from(v).exp()).sum();
            for (&v, &g) in row.iter().zip(got) {
                let want = f64::from(v).exp() / total;
                assert!((f64::from(g) - want).abs() < 1e-6, "{g} vs {want}");
            }
        }
    }

    #[test]
    fn softmax_rejects_an_empty_axis() {
        assert!(softmax(&mut Tensor::zeros(&[4, 0])).is_err());
        assert!(softmax(&mut Tensor::zeros(&[])).is_err());
        let mut v = Tensor::zeros(&[4]);
        softmax(&mut v).unwrap();
        assert_eq!(v.data(), [0.25; 4]);
    }
}
