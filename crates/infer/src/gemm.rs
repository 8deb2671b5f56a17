//! The one door to faer's matrix product: slices in, slices out, lengths checked before faer
//! sees them (faer asserts on them, and library code must not panic).
//!
//! Determinism: faer's general product splits its output among threads and sums every value
//! over the inner dimension in the same order whatever the thread count. Its matrix-vector
//! product does not (it splits the inner dimension among threads and adds the partial sums),
//! so products with one output row or column run on one thread here.

use faer::{Accum, MatMut, MatRef};

use crate::error::{InferError, Result};
use crate::parallel::Parallelism;

/// How the right-hand operand of [`matmul`] lies in its slice.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Rhs {
    /// Row-major `[k, n]`.
    RowMajor,
    /// Row-major `[n, k]`, used transposed (torch's linear weight `[out, in]`).
    Transposed,
}

/// `dst[m, n] = lhs[m, k] · rhs[k, n]`, or `dst += ...` when `accumulate`; `dst` and `lhs` are
/// row-major.
#[allow(clippy::too_many_arguments)] // private: three operands, their sizes, and how to run
pub(crate) fn matmul(
    op: &'static str,
    dst: &mut [f32],
    lhs: &[f32],
    rhs: &[f32],
    [m, k, n]: [usize; 3],
    rhs_layout: Rhs,
    accumulate: bool,
    par: Parallelism,
) -> Result<()> {
    for (shape, len) in [
        ([m, n], dst.len()),
        ([m, k], lhs.len()),
        ([k, n], rhs.len()),
    ] {
        if shape[0] * shape[1] != len {
            return Err(InferError::DataLength {
                op,
                shape: shape.to_vec(),
                expected: shape[0] * shape[1],
                got: len,
            });
        }
    }
    if m == 0 || n == 0 {
        return Ok(());
    }
    if k == 0 {
        if !accumulate {
            dst.fill(0.0);
        }
        return Ok(());
    }
    let dst = MatMut::from_row_major_slice_mut(dst, m, n);
    let lhs = MatRef::from_row_major_slice(lhs, m, k);
    let rhs = match rhs_layout {
        Rhs::RowMajor => MatRef::from_row_major_slice(rhs, k, n),
        Rhs::Transposed => MatRef::from_row_major_slice(rhs, n, k).transpose(),
    };
    // A matrix-vector product: faer would split the sum itself, see the module doc.
    let par = if m == 1 || n == 1 {
        Parallelism::Sequential
    } else {
        par
    };
    let accum = if accumulate {
        Accum::Add
    } else {
        Accum::Replace
    };
    faer::linalg::matmul::matmul(dst, accum, lhs, rhs, 1.0, par.faer());
    Ok(())
}
