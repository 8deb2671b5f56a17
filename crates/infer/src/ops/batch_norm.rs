//! Batch normalisation at inference: running statistics, then an optional affine map.

use crate::error::Result;
use crate::ops::check::{batch_channels_rest, non_negative, optional_vector, vector};
use crate::tensor::Tensor;

/// The state of a torch `nn.BatchNorm1d/2d/3d` in `eval()` mode, every tensor `[C]`.
#[derive(Clone, Copy, Debug)]
pub struct BatchNorm<'a> {
    /// `running_mean`.
    pub running_mean: &'a Tensor,
    /// `running_var`.
    pub running_var: &'a Tensor,
    /// `weight` (gamma); `None` for `affine=False`.
    pub weight: Option<&'a Tensor>,
    /// `bias` (beta); `None` for `affine=False`.
    pub bias: Option<&'a Tensor>,
    /// Added to the variance; torch's default is 1e-5.
    pub eps: f32,
}

/// The checked `[N, C, rest]` sizes, mean and variance, weight and bias.
type Checked<'a> = ([usize; 3], [&'a [f32]; 2], [Option<&'a [f32]>; 2]);

impl<'a> BatchNorm<'a> {
    fn check(&self, x: &Tensor) -> Result<Checked<'a>> {
        const OP: &str = "batch_norm";
        non_negative(OP, "eps", self.eps)?;
        let sizes = batch_channels_rest(OP, x, 2, "[batch, channels, ...] (rank >= 2)")?;
        let c = sizes[1];
        Ok((
            sizes,
            [
                vector(OP, "running_mean", self.running_mean, c)?,
                vector(OP, "running_var", self.running_var, c)?,
            ],
            [
                optional_vector(OP, "weight", self.weight, c)?,
                optional_vector(OP, "bias", self.bias, c)?,
            ],
        ))
    }
}

/// Batch normalisation of an `[N, C, ...]` tensor in place, as torch's in `eval()` mode:
/// `y = (x - mean) / sqrt(var + eps) * weight + bias`, folded into one multiply-add per value.
///
/// # Errors
/// [`InferError::ShapeMismatch`](crate::InferError::ShapeMismatch) for a tensor of rank below
/// 2 or a statistic not `[C]`; [`InferError::InvalidParameter`](crate::InferError::InvalidParameter)
/// for a negative or non-finite `eps`.
pub fn batch_norm(x: &mut Tensor, params: &BatchNorm<'_>) -> Result<()> {
    let ([_, channels, rest], [mean, var], [weight, bias]) = params.check(x)?;
    if channels == 0 || rest == 0 {
        return Ok(());
    }
    for image in x.data_mut().chunks_exact_mut(channels * rest) {
        for (c, plane) in image.chunks_exact_mut(rest).enumerate() {
            let scale = weight.map_or(1.0, |w| w[c]) / (var[c] + params.eps).sqrt();
            let shift = bias.map_or(0.0, |b| b[c]) - mean[c] * scale;
            for v in plane {
                *v = *v * scale + shift;
            }
        }
    }
    Ok(())
}

/// [`batch_norm`] by its formula, value by value into a new tensor. The reference
/// [`batch_norm`] is tested against.
///
/// # Errors
/// As [`batch_norm`].
pub fn batch_norm_reference(x: &Tensor, params: &BatchNorm<'_>) -> Result<Tensor> {
    let ([n, channels, rest], [mean, var], [weight, bias]) = params.check(x)?;
    let mut out = x.clone();
    let y = out.data_mut();
    for b in 0..n {
        for c in 0..channels {
            for p in 0..rest {
                let i = (b * channels + c) * rest + p;
                let normalised = (y[i] - mean[c]) / (var[c] + params.eps).sqrt();
                y[i] = normalised * weight.map_or(1.0, |w| w[c]) + bias.map_or(0.0, |b| b[c]);
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;
    use crate::testing::{Rng, assert_close};

    #[test]
    fn folded_matches_the_formula() {
        let mut rng = Rng::new(21);
        for shape in [vec![2, 3, 4, 5], vec![4, 6], vec![1, 2, 3, 2, 2]] {
            let c = shape[1];
            let x = rng.tensor_in(&shape, -5.0, 5.0);
            let (mean, var) = (rng.tensor(&[c]), rng.tensor_in(&[c], 0.0, 3.0));
            let (weight, bias) = (rng.tensor(&[c]), rng.tensor(&[c]));
            for affine in [false, true] {
                let params = BatchNorm {
                    running_mean: &mean,
                    running_var: &var,
                    weight: affine.then_some(&weight),
                    bias: affine.then_some(&bias),
                    eps: 1e-5,
                };
                let mut fast = x.clone();
                batch_norm(&mut fast, &params).unwrap();
                assert_close(&fast, &batch_norm_reference(&x, &params).unwrap());
            }
        }
    }

    #[test]
    fn one_value_by_hand() {
        let mean = Tensor::new(&[1], vec![1.0]).unwrap();
        let var = Tensor::new(&[1], vec![4.0]).unwrap();
        let (w, b) = (Tensor::full(&[1], 3.0), Tensor::full(&[1], 0.5));
        let params = BatchNorm {
            running_mean: &mean,
            running_var: &var,
            weight: Some(&w),
            bias: Some(&b),
            eps: 0.0,
        };
        let mut x = Tensor::new(&[1, 1, 1, 1], vec![5.0]).unwrap();
        batch_norm(&mut x, &params).unwrap();
        assert_eq!(x.data(), [(5.0 - 1.0) / 2.0 * 3.0 + 0.5]);
    }

    #[test]
    fn wrong_statistics_are_errors() {
        let (mean, var) = (Tensor::zeros(&[3]), Tensor::full(&[2], 1.0));
        let params = BatchNorm {
            running_mean: &mean,
            running_var: &var,
            weight: None,
            bias: None,
            eps: 1e-5,
        };
        let err = batch_norm(&mut Tensor::zeros(&[1, 3, 2, 2]), &params).unwrap_err();
        assert!(err.to_string().contains("running_var"), "{err}");
        let bad_eps = BatchNorm {
            eps: -1.0,
            running_var: &mean,
            ..params
        };
        assert!(batch_norm(&mut Tensor::zeros(&[1, 3, 2, 2]), &bad_eps).is_err());
        assert!(
            batch_norm(
                &mut Tensor::zeros(&[3]),
                &BatchNorm {
                    running_var: &mean,
                    ..params
                }
            )
            .is_err()
        );
    }
}
