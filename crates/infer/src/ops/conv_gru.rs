//! The 3-D convolutional GRU cell the Learnt Stereo Machine fuses its views with.

use crate::error::{InferError, Result};
use crate::ops::check::shape_error;
use crate::ops::{
    Conv3dParams, concat_into, conv3d_into, conv3d_reference, sigmoid, sigmoid_reference, tanh,
    tanh_reference,
};
use crate::parallel::Parallelism;
use crate::tensor::Tensor;

/// The weights of a 3-D convolutional GRU cell with `hidden` channels and "same" 3x3x3 (odd)
/// kernels, as torch modules `gates = Conv3d(in + hidden, 2 * hidden)` and
/// `candidate = Conv3d(in + hidden, hidden)` hold them:
///
/// ```text
/// update, reset = split(sigmoid(gates([x, h])))       (update: the first hidden channels)
/// candidate     = tanh(candidate([x, reset * h]))
/// h'            = (1 - update) * h + update * candidate
/// ```
#[derive(Clone, Copy, Debug)]
pub struct ConvGru3d<'a> {
    /// `[2 * hidden, in + hidden, k, k, k]`.
    pub gates_weight: &'a Tensor,
    /// `[2 * hidden]`.
    pub gates_bias: Option<&'a Tensor>,
    /// `[hidden, in + hidden, k, k, k]`.
    pub candidate_weight: &'a Tensor,
    /// `[hidden]`.
    pub candidate_bias: Option<&'a Tensor>,
}

/// Buffers a [`ConvGru3d`] step reuses from call to call.
#[derive(Default)]
pub struct ConvGruScratch {
    joined: Tensor,
    gates: Tensor,
    candidate: Tensor,
    columns: Vec<f32>,
}

impl ConvGru3d<'_> {
    /// The hidden channels, the padding of a "same" convolution, checking that the two
    /// weights agree with each other and with `h` (`[N, hidden, D, H, W]`).
    fn check(&self, h: &Tensor) -> Result<(usize, Conv3dParams)> {
        const OP: &str = "conv_gru3d";
        let hidden = self.candidate_weight.shape().first().copied().unwrap_or(0);
        let [_, _, k, ..] = *self.gates_weight.shape() else {
            return Err(shape_error(
                OP,
                "gates weight of rank 5",
                self.gates_weight.shape(),
            ));
        };
        let gates = self.gates_weight.shape();
        let candidate = self.candidate_weight.shape();
        if gates.len() != 5
            || candidate.len() != 5
            || gates[0] != 2 * hidden
            || gates[1..] != candidate[1..]
            || gates[2..].iter().any(|&s| s != k)
            || k % 2 == 0
        {
            return Err(shape_error(
                OP,
                format!(
                    "gates weight [2 * hidden, in + hidden, k, k, k] (odd k) beside candidate weight {candidate:?}"
                ),
                gates,
            ));
        }
        if h.rank() != 5 || h.shape()[1] != hidden {
            return Err(shape_error(
                OP,
                format!("hidden state [batch, {hidden}, depth, height, width]"),
                h.shape(),
            ));
        }
        Ok((hidden, Conv3dParams::cubic(1, k / 2)))
    }

    /// One step: `h` becomes `h'` of input `x` (`[N, in, D, H, W]`).
    ///
    /// # Errors
    /// [`InferError::ShapeMismatch`] when the weights disagree with each other, with `h`, or
    /// `x` does not fit them.
    pub fn step(
        &self,
        x: &Tensor,
        h: &mut Tensor,
        scratch: &mut ConvGruScratch,
        par: Parallelism,
    ) -> Result<()> {
        let (hidden, params) = self.check(h)?;
        let s = scratch;
        concat_into(&[x, h], 1, &mut s.joined)?;
        conv3d_into(
            &s.joined,
            self.gates_weight,
            self.gates_bias,
            params,
            &mut s.gates,
            &mut s.columns,
            par,
        )?;
        sigmoid(&mut s.gates);
        let plane = h.len() / h.shape()[0].max(1) / hidden.max(1);
        let x_channels = x.shape()[1];
        // reset * h into the hidden channels of `joined`.
        let joined_image = (x_channels + hidden) * plane;
        let gates_image = 2 * hidden * plane;
        let hidden_image = hidden * plane;
        for (n, joined) in s
            .joined
            .data_mut()
            .chunks_exact_mut(joined_image)
            .enumerate()
        {
            let reset = &s.gates.data()[n * gates_image + hidden_image..(n + 1) * gates_image];
            let state = &h.data()[n * hidden_image..(n + 1) * hidden_image];
            for ((j, &r), &hv) in joined[x_channels * plane..]
                .iter_mut()
                .zip(reset)
                .zip(state)
            {
                *j = r * hv;
            }
        }
        conv3d_into(
            &s.joined,
            self.candidate_weight,
            self.candidate_bias,
            params,
            &mut s.candidate,
            &mut s.columns,
            par,
        )?;
        tanh(&mut s.candidate);
        for (n, state) in h.data_mut().chunks_exact_mut(hidden_image).enumerate() {
            let update = &s.gates.data()[n * gates_image..n * gates_image + hidden_image];
            let candidate = &s.candidate.data()[n * hidden_image..(n + 1) * hidden_image];
            for ((hv, &z), &c) in state.iter_mut().zip(update).zip(candidate) {
                *hv = (1.0 - z) * *hv + z * c;
            }
        }
        Ok(())
    }

    /// [`ConvGru3d::step`] by its formula, with the reference convolution, into a new tensor:
    /// what the fast step is tested against.
    ///
    /// # Errors
    /// As [`ConvGru3d::step`].
    pub fn step_reference(&self, x: &Tensor, h: &Tensor) -> Result<Tensor> {
        let (hidden, params) = self.check(h)?;
        let joined = crate::ops::concat(&[x, h], 1)?;
        let mut gates = conv3d_reference(&joined, self.gates_weight, self.gates_bias, params)?;
        sigmoid_reference(&mut gates);
        let [n, _, d, hh, w] = *h.shape() else {
            return Err(InferError::AxisOutOfRange {
                op: "conv_gru3d",
                axis: 4,
                rank: h.rank(),
            });
        };
        let at = |t: &Tensor, channels: usize, b: usize, c: usize, p: usize| {
            t.data()[(b * channels + c) * d * hh * w + p]
        };
        let mut reset_h = h.clone();
        let mut out = h.clone();
        for b in 0..n {
            for c in 0..hidden {
                for p in 0..d * hh * w {
                    let i = (b * hidden + c) * d * hh * w + p;
                    reset_h.data_mut()[i] = at(&gates, 2 * hidden, b, hidden + c, p) * h.data()[i];
                }
            }
        }
        let joined = crate::ops::concat(&[x, &reset_h], 1)?;
        let mut candidate =
            conv3d_reference(&joined, self.candidate_weight, self.candidate_bias, params)?;
        tanh_reference(&mut candidate);
        for b in 0..n {
            for c in 0..hidden {
                for p in 0..d * hh * w {
                    let i = (b * hidden + c) * d * hh * w + p;
                    let z = at(&gates, 2 * hidden, b, c, p);
                    out.data_mut()[i] = (1.0 - z) * h.data()[i] + z * candidate.data()[i];
                }
            }
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;
    use crate::testing::{Rng, assert_close};

    #[test]
    fn the_step_matches_its_formula() {
        let mut rng = Rng::new(51);
        let (cin, hidden) = (3, 4);
        let gates_weight = rng.tensor(&[2 * hidden, cin + hidden, 3, 3, 3]);
        let gates_bias = rng.tensor(&[2 * hidden]);
        let candidate_weight = rng.tensor(&[hidden, cin + hidden, 3, 3, 3]);
        let candidate_bias = rng.tensor(&[hidden]);
        let cell = ConvGru3d {
            gates_weight: &gates_weight,
            gates_bias: Some(&gates_bias),
            candidate_weight: &candidate_weight,
            candidate_bias: Some(&candidate_bias),
        };
        let mut scratch = ConvGruScratch::default();
        let mut h = rng.tensor(&[2, hidden, 4, 5, 3]);
        for _ in 0..3 {
            let x = rng.tensor(&[2, cin, 4, 5, 3]);
            let want = cell.step_reference(&x, &h).unwrap();
            cell.step(&x, &mut h, &mut scratch, Parallelism::Sequential)
                .unwrap();
            assert_close(&h, &want);
        }
        // The state stays inside the candidate's range (-1, 1) once it started there.
        assert!(h.data().iter().all(|v| v.abs() < 1.0));
    }

    #[test]
    fn mismatched_weights_and_states_are_errors() {
        let g = Tensor::zeros(&[8, 7, 3, 3, 3]);
        let c = Tensor::zeros(&[4, 7, 3, 3, 3]);
        let cell = ConvGru3d {
            gates_weight: &g,
            gates_bias: None,
            candidate_weight: &c,
            candidate_bias: None,
        };
        let x = Tensor::zeros(&[1, 3, 2, 2, 2]);
        let mut scratch = ConvGruScratch::default();
        let mut wrong_state = Tensor::zeros(&[1, 5, 2, 2, 2]);
        let err = cell.step(&x, &mut wrong_state, &mut scratch, Parallelism::Sequential);
        assert!(err.unwrap_err().to_string().contains("hidden state"));
        let short = Tensor::zeros(&[3, 7, 3, 3, 3]);
        let bad = ConvGru3d {
            candidate_weight: &short,
            ..cell
        };
        let mut h = Tensor::zeros(&[1, 4, 2, 2, 2]);
        assert!(
            bad.step(&x, &mut h, &mut scratch, Parallelism::Sequential)
                .is_err()
        );
        let wrong_input = Tensor::zeros(&[1, 2, 2, 2, 2]);
        assert!(
            cell.step(&wrong_input, &mut h, &mut scratch, Parallelism::Sequential)
                .is_err()
        );
    }
}
