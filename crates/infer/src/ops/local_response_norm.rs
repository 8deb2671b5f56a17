//! Local response normalisation across channels, exactly as torch's `nn.LocalResponseNorm`.

use crate::error::Result;
use crate::ops::check::{batch_channels_rest, positive};
use crate::tensor::Tensor;

/// The parameters of torch's `nn.LocalResponseNorm(size, alpha, beta, k)`:
///
/// `y[n, c] = x[n, c] / (k + alpha / size * sum(x[n, c']^2))^beta`
///
/// the sum over the channels `c'` from `c - size / 2` to `c + (size - 1) / 2` (integer
/// division; channels beyond the ends count as zeros, and the division is always by `size`).
///
/// TensorFlow's `tf.nn.local_response_normalization(depth_radius, bias, alpha, beta)`, which
/// the original Dex-Net GQ-CNN used, is `size = 2 * depth_radius + 1`, `k = bias` and
/// `alpha = alpha_tf * size` here: it sums where torch averages.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LocalResponseNorm {
    /// Channels in the window; at least 1.
    pub size: usize,
    /// Scale of the mean square (torch's default 1e-4).
    pub alpha: f32,
    /// Exponent (torch's default 0.75).
    pub beta: f32,
    /// Additive constant (torch's default 1.0).
    pub k: f32,
}

impl LocalResponseNorm {
    /// A `size`-channel window with torch's defaults `alpha = 1e-4`, `beta = 0.75`, `k = 1`.
    pub fn new(size: usize) -> Self {
        Self {
            size,
            alpha: 1e-4,
            beta: 0.75,
            k: 1.0,
        }
    }

    /// The checked `[N, C, rest]` sizes of `input`.
    fn check(&self, input: &Tensor) -> Result<[usize; 3]> {
        const OP: &str = "local_response_norm";
        positive(OP, "size", self.size)?;
        batch_channels_rest(OP, input, 3, "[batch, channels, spatial...] (rank >= 3)")
    }

    /// The channel window of output channel `c` among `channels`: torch pads `size / 2`
    /// channels before and `(size - 1) / 2` after.
    fn window(&self, c: usize, channels: usize) -> std::ops::Range<usize> {
        c.saturating_sub(self.size / 2)..(c + (self.size - 1) / 2 + 1).min(channels)
    }

    /// `x / (k + alpha * mean_square)^beta`.
    fn normalise(&self, x: f32, sum_of_squares: f32) -> f32 {
        x / (self.k + self.alpha * (sum_of_squares / self.size as f32)).powf(self.beta)
    }

    /// [`Self::normalise`] over a plane: `sums` holds each value's sum of squares on entry and
    /// the output on return. The usual exponents (0.75: torch's default and Dex-Net's; 0.5; 1)
    /// are square roots and divisions, which vectorise; others call `powf` per value (a
    /// library call: it made LRN four fifths of a small GQ-CNN's time).
    fn normalise_plane(&self, x: &[f32], sums: &mut [f32]) {
        let (k, alpha, size) = (self.k, self.alpha, self.size as f32);
        let base = |s: f32| k + alpha * (s / size);
        let pairs = sums.iter_mut().zip(x);
        if self.beta == 0.75 {
            for (s, &v) in pairs {
                let root = base(*s).sqrt();
                *s = v / (root * root.sqrt());
            }
        } else if self.beta == 0.5 {
            for (s, &v) in pairs {
                *s = v / base(*s).sqrt();
            }
        } else if self.beta == 1.0 {
            for (s, &v) in pairs {
                *s = v / base(*s);
            }
        } else {
            for (s, &v) in pairs {
                *s = self.normalise(v, *s);
            }
        }
    }
}

/// Local response normalisation of an `[N, C, ...]` tensor into a new one of its shape.
///
/// # Errors
/// As [`local_response_norm_into`].
pub fn local_response_norm(input: &Tensor, params: LocalResponseNorm) -> Result<Tensor> {
    let mut out = Tensor::default();
    local_response_norm_into(input, params, &mut out)?;
    Ok(out)
}

/// [`local_response_norm`] into `out`, which is resized to the input's shape and keeps its
/// allocation. Works plane by plane: each output plane first gathers its window's squares, so
/// the inner loops run over contiguous memory.
///
/// # Errors
/// [`InferError::ShapeMismatch`](crate::InferError::ShapeMismatch) for a tensor of rank below
/// 3 (as torch); [`InferError::InvalidParameter`](crate::InferError::InvalidParameter) for a
/// zero `size`.
pub fn local_response_norm_into(
    input: &Tensor,
    params: LocalResponseNorm,
    out: &mut Tensor,
) -> Result<()> {
    let [_, channels, plane] = params.check(input)?;
    out.resize(input.shape());
    if plane == 0 || channels == 0 {
        return Ok(());
    }
    let images = input.data().chunks_exact(channels * plane);
    for (x, y) in images.zip(out.data_mut().chunks_exact_mut(channels * plane)) {
        for (c, y_plane) in y.chunks_exact_mut(plane).enumerate() {
            y_plane.fill(0.0);
            for c2 in params.window(c, channels) {
                for (s, &v) in y_plane.iter_mut().zip(&x[c2 * plane..(c2 + 1) * plane]) {
                    *s += v * v;
                }
            }
            params.normalise_plane(&x[c * plane..(c + 1) * plane], y_plane);
        }
    }
    Ok(())
}

/// Local response normalisation by its definition, one output value at a time. Slow; the
/// reference [`local_response_norm`] is tested against.
///
/// # Errors
/// As [`local_response_norm_into`].
pub fn local_response_norm_reference(input: &Tensor, params: LocalResponseNorm) -> Result<Tensor> {
    let [n, channels, plane] = params.check(input)?;
    let x = input.data();
    let mut out = Tensor::zeros(input.shape());
    let y = out.data_mut();
    for b in 0..n {
        for c in 0..channels {
            for p in 0..plane {
                let at = |c: usize| x[(b * channels + c) * plane + p];
                let mut sum = 0.0;
                for c2 in params.window(c, channels) {
                    sum += at(c2) * at(c2);
                }
                y[(b * channels + c) * plane + p] = params.normalise(at(c), sum);
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
    fn the_window_is_torchs() {
        // torch pads size / 2 channels before and (size - 1) / 2 after.
        let odd = LocalResponseNorm::new(5);
        assert_eq!(odd.window(0, 8), 0..3);
        assert_eq!(odd.window(4, 8), 2..7);
        assert_eq!(odd.window(7, 8), 5..8);
        let even = LocalResponseNorm::new(4);
        assert_eq!(even.window(4, 8), 2..6);
        assert_eq!(even.window(0, 8), 0..2);
    }

    #[test]
    fn one_value_by_hand() {
        // torch.nn.LocalResponseNorm(3, alpha=0.3, beta=0.75, k=2) on channels [1, 2, 3] of one
        // pixel: channel 1 sees 1 + 4 + 9 = 14, so y = 2 / (2 + 0.3 * 14 / 3)^0.75.
        let x = Tensor::new(&[1, 3, 1, 1], vec![1.0, 2.0, 3.0]).unwrap();
        let params = LocalResponseNorm {
            size: 3,
            alpha: 0.3,
            beta: 0.75,
            k: 2.0,
        };
        let y = local_response_norm(&x, params).unwrap();
        let want = [
            1.0 / (2.0 + 0.3 * 5.0 / 3.0f32).powf(0.75),
            2.0 / (2.0 + 0.3 * 14.0 / 3.0f32).powf(0.75),
            3.0 / (2.0 + 0.3 * 13.0 / 3.0f32).powf(0.75),
        ];
        for (g, w) in y.data().iter().zip(want) {
            assert!((g - w).abs() < 1e-6, "{g} vs {w}");
        }
    }

    #[test]
    fn planes_match_the_reference() {
        let mut rng = Rng::new(3);
        for (shape, size) in [
            (vec![2, 7, 5, 3], 5),
            (vec![1, 6, 4, 4], 4),
            (vec![3, 3, 9], 1),
            (vec![1, 2, 3, 3], 8),
        ] {
            let x = rng.tensor_in(&shape, -3.0, 3.0);
            // The exponents with a fast path, and one without.
            for beta in [0.75, 0.5, 1.0, 0.6] {
                let params = LocalResponseNorm {
                    size,
                    alpha: 0.5,
                    beta,
                    k: 1.5,
                };
                let fast = local_response_norm(&x, params).unwrap();
                assert_close(&fast, &local_response_norm_reference(&x, params).unwrap());
            }
        }
    }

    #[test]
    fn bad_input_is_an_error() {
        let params = LocalResponseNorm::new(5);
        assert!(local_response_norm(&Tensor::zeros(&[2, 3]), params).is_err());
        let zero = LocalResponseNorm::new(0);
        assert!(local_response_norm(&Tensor::zeros(&[1, 2, 2, 2]), zero).is_err());
    }
}
