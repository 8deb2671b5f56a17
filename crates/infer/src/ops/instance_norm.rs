//! Instance normalisation: each image's channel normalised by its own mean and variance.

use crate::error::Result;
use crate::ops::check::{batch_channels_rest, non_negative, optional_vector};
use crate::tensor::Tensor;

/// The state of a torch `nn.InstanceNorm1d/2d/3d` without running statistics (its default),
/// `weight` and `bias` `[C]` when `affine=True`.
#[derive(Clone, Copy, Debug)]
pub struct InstanceNorm<'a> {
    /// `weight` (gamma); `None` for `affine=False`, torch's default.
    pub weight: Option<&'a Tensor>,
    /// `bias` (beta); `None` for `affine=False`.
    pub bias: Option<&'a Tensor>,
    /// Added to the variance; torch's default is 1e-5.
    pub eps: f32,
}

/// The checked `[N, C, rest]` sizes, weight and bias.
type Checked<'a> = ([usize; 3], [Option<&'a [f32]>; 2]);

impl<'a> InstanceNorm<'a> {
    fn check(&self, x: &Tensor) -> Result<Checked<'a>> {
        const OP: &str = "instance_norm";
        non_negative(OP, "eps", self.eps)?;
        let sizes = batch_channels_rest(OP, x, 3, "[batch, channels, spatial...] (rank >= 3)")?;
        let c = sizes[1];
        Ok((
            sizes,
            [
                optional_vector(OP, "weight", self.weight, c)?,
                optional_vector(OP, "bias", self.bias, c)?,
            ],
        ))
    }
}

/// Instance normalisation of an `[N, C, ...]` tensor in place, as torch's:
/// `y = (x - mean) / sqrt(var + eps) * weight + bias`, with the mean and the biased variance of
/// each `(n, c)` plane. The statistics are summed in f64 (two passes); each value then takes
/// one subtraction and one multiply-add in f32 (subtracting the mean first keeps a plane whose
/// variance is tiny next to its mean from cancelling).
///
/// # Errors
/// [`InferError::ShapeMismatch`](crate::InferError::ShapeMismatch) for a tensor of rank below
/// 3 or a `weight` / `bias` not `[C]`;
/// [`InferError::InvalidParameter`](crate::InferError::InvalidParameter) for a negative or
/// non-finite `eps`.
pub fn instance_norm(x: &mut Tensor, params: &InstanceNorm<'_>) -> Result<()> {
    let ([_, channels, rest], [weight, bias]) = params.check(x)?;
    if channels == 0 || rest == 0 {
        return Ok(());
    }
    for (i, plane) in x.data_mut().chunks_exact_mut(rest).enumerate() {
        let c = i % channels;
        let len = rest as f64;
        let mean = plane.iter().map(|&v| f64::from(v)).sum::<f64>() / len;
        let var = plane
            .iter()
            .map(|&v| (f64::from(v) - mean).powi(2))
            .sum::<f64>()
            / len;
        let scale = f64::from(weight.map_or(1.0, |w| w[c])) / (var + f64::from(params.eps)).sqrt();
        let (mean, scale, shift) = (mean as f32, scale as f32, bias.map_or(0.0, |b| b[c]));
        for v in plane {
            *v = (*v - mean) * scale + shift;
        }
    }
    Ok(())
}

/// [`instance_norm`] by its formula into a new tensor: the statistics by the textbook
/// one-pass-each loops in f64, then each value normalised on its own. The reference
/// [`instance_norm`] is tested against.
///
/// # Errors
/// As [`instance_norm`].
pub fn instance_norm_reference(x: &Tensor, params: &InstanceNorm<'_>) -> Result<Tensor> {
    let ([n, channels, rest], [weight, bias]) = params.check(x)?;
    let mut out = x.clone();
    let y = out.data_mut();
    for b in 0..n {
        for c in 0..channels {
            let start = (b * channels + c) * rest;
            let mut mean = 0.0f64;
            for p in 0..rest {
                mean += f64::from(y[start + p]);
            }
            mean /= rest as f64;
            let mut var = 0.0f64;
            for p in 0..rest {
                var += (f64::from(y[start + p]) - mean).powi(2);
            }
            var /= rest as f64;
            for p in 0..rest {
                let normalised =
                    (f64::from(y[start + p]) - mean) / (var + f64::from(params.eps)).sqrt();
                let affine = normalised * f64::from(weight.map_or(1.0, |w| w[c]))
                    + f64::from(bias.map_or(0.0, |b| b[c]));
                y[start + p] = affine as f32;
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
        let mut rng = Rng::new(31);
        for shape in [vec![2, 3, 8, 5], vec![1, 4, 17], vec![3, 2, 1, 1]] {
            let c = shape[1];
            let x = rng.tensor_in(&shape, -2.0, 6.0);
            let (weight, bias) = (rng.tensor(&[c]), rng.tensor(&[c]));
            for affine in [false, true] {
                let params = InstanceNorm {
                    weight: affine.then_some(&weight),
                    bias: affine.then_some(&bias),
                    eps: 1e-5,
                };
                let mut fast = x.clone();
                instance_norm(&mut fast, &params).unwrap();
                assert_close(&fast, &instance_norm_reference(&x, &params).unwrap());
            }
        }
    }

    #[test]
    fn planes_come_out_standardised() {
        let mut rng = Rng::new(32);
        let mut x = rng.tensor_in(&[2, 3, 6, 6], 10.0, 20.0);
        let params = InstanceNorm {
            weight: None,
            bias: None,
            eps: 0.0,
        };
        instance_norm(&mut x, &params).unwrap();
        for plane in x.data().chunks(36) {
            let mean = plane.iter().sum::<f32>() / 36.0;
            let var = plane.iter().map(|v| (v - mean).powi(2)).sum::<f32>() / 36.0;
            assert!(
                mean.abs() < 1e-5 && (var - 1.0).abs() < 1e-4,
                "{mean} {var}"
            );
        }
    }

    #[test]
    fn wrong_shapes_are_errors() {
        let w = Tensor::zeros(&[2]);
        let params = InstanceNorm {
            weight: Some(&w),
            bias: None,
            eps: 1e-5,
        };
        assert!(instance_norm(&mut Tensor::zeros(&[1, 3, 4, 4]), &params).is_err());
        let plain = InstanceNorm {
            weight: None,
            ..params
        };
        assert!(instance_norm(&mut Tensor::zeros(&[2, 3]), &plain).is_err());
    }
}
