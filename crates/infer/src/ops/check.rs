//! Shape and parameter checks the ops share, each returning the error that names the op.

use crate::error::{InferError, Result};
use crate::tensor::Tensor;

/// A [`InferError::ShapeMismatch`] for `got`.
pub(crate) fn shape_error(
    op: &'static str,
    expected: impl Into<String>,
    got: &[usize],
) -> InferError {
    InferError::ShapeMismatch {
        op,
        expected: expected.into(),
        got: got.to_vec(),
    }
}

/// The four sizes of an `[N, C, H, W]` tensor.
pub(crate) fn nchw(op: &'static str, x: &Tensor) -> Result<[usize; 4]> {
    match *x.shape() {
        [n, c, h, w] => Ok([n, c, h, w]),
        _ => Err(shape_error(
            op,
            "[batch, channels, height, width]",
            x.shape(),
        )),
    }
}

/// `[N, C, rest]` of a tensor of rank at least `min_rank` (>= 2), `rest` the product of the
/// axes after the channels.
pub(crate) fn batch_channels_rest(
    op: &'static str,
    x: &Tensor,
    min_rank: usize,
    expected: &'static str,
) -> Result<[usize; 3]> {
    match *x.shape() {
        [n, c, ref rest @ ..] if x.rank() >= min_rank => Ok([n, c, rest.iter().product()]),
        _ => Err(shape_error(op, expected, x.shape())),
    }
}

/// The values of a per-channel tensor, which must have shape `[len]`.
pub(crate) fn vector<'a>(
    op: &'static str,
    name: &'static str,
    x: &'a Tensor,
    len: usize,
) -> Result<&'a [f32]> {
    if x.shape() != [len] {
        return Err(shape_error(
            op,
            format!("{name} of shape [{len}]"),
            x.shape(),
        ));
    }
    Ok(x.data())
}

/// [`vector`] for an optional tensor.
pub(crate) fn optional_vector<'a>(
    op: &'static str,
    name: &'static str,
    x: Option<&'a Tensor>,
    len: usize,
) -> Result<Option<&'a [f32]>> {
    x.map(|x| vector(op, name, x, len)).transpose()
}

/// `value` must be at least 1.
pub(crate) fn positive(op: &'static str, name: &'static str, value: usize) -> Result<()> {
    if value == 0 {
        return Err(InferError::InvalidParameter {
            op,
            name,
            value: "0".into(),
            expected: "at least 1",
        });
    }
    Ok(())
}

/// `value` must be finite and not negative.
pub(crate) fn non_negative(op: &'static str, name: &'static str, value: f32) -> Result<()> {
    if !(value.is_finite() && value >= 0.0) {
        return Err(InferError::InvalidParameter {
            op,
            name,
            value: value.to_string(),
            expected: "a finite value >= 0",
        });
    }
    Ok(())
}

/// The output length of a sliding window along one axis (torch's floor formula), or `None` when
/// the dilated window does not fit the padded input.
pub(crate) fn window_output(
    input: usize,
    kernel: usize,
    stride: usize,
    padding: usize,
    dilation: usize,
) -> Option<usize> {
    let span = dilation * (kernel - 1) + 1;
    let padded = input + 2 * padding;
    (padded >= span).then(|| (padded - span) / stride + 1)
}

/// The outputs `lo..hi` along one axis whose input `o * stride + offset - padding` lies in
/// `0..width` (a sliding window's tap `offset`: the outputs that read the input, not padding).
pub(crate) fn valid_outputs(
    width: usize,
    out_width: usize,
    stride: usize,
    padding: usize,
    offset: usize,
) -> (usize, usize) {
    // ox * stride + offset >= padding
    let lo = padding
        .saturating_sub(offset)
        .div_ceil(stride)
        .min(out_width);
    // ox * stride + offset - padding <= width - 1
    let hi = if width + padding > offset {
        ((width + padding - offset - 1) / stride + 1).min(out_width)
    } else {
        0
    };
    (lo, hi.max(lo))
}
