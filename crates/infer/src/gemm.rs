//! The one door to faer's matrix product: slices in, slices out, lengths checked before faer
//! sees them (faer asserts on them, and library code must not panic).
//!
//! Determinism: faer's general product splits its output among threads and sums every value
//! over the inner dimension in the same order whatever the thread count. Its matrix-vector
//! product does not (it splits the inner dimension among threads and adds the partial sums),
//! so products with one output row or column run on one thread here, except one input row
//! times a linear layer's weight: that one is cut into blocks of outputs of a fixed size,
//! whatever the thread count, and the blocks shared among threads. So the thread count changes
//! no bit, and the split can be chosen for speed alone: small products run on one thread.

use faer::{Accum, MatMut, MatRef};
use rayon::prelude::*;

use crate::error::{InferError, Result};
use crate::parallel::Parallelism;

/// The fewest multiply-adds (`m * n * k`) for which [`matmul`] splits a product among threads.
const PARALLEL_MIN_PRODUCTS: usize = 1 << 22;

/// The outputs of a block of one row times a transposed weight (see the module doc); a
/// block of Dex-Net's first fully connected layer is 4 MB of weights.
const MATVEC_BLOCK: usize = 256;

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
    if m * n != dst.len() {
        return Err(InferError::DataLength {
            op,
            shape: vec![m, n],
            expected: m * n,
            got: dst.len(),
        });
    }
    matmul_rows(op, dst, n, lhs, rhs, [m, k, n], rhs_layout, accumulate, par)
}

/// [`matmul`] into a block of columns of a wider row-major matrix: row `i` of the product is
/// `dst[i * row_stride..][..n]`, and the values between rows are left alone.
#[allow(clippy::too_many_arguments)] // private: three operands, their sizes, and how to run
pub(crate) fn matmul_rows(
    op: &'static str,
    dst: &mut [f32],
    row_stride: usize,
    lhs: &[f32],
    rhs: &[f32],
    [m, k, n]: [usize; 3],
    rhs_layout: Rhs,
    accumulate: bool,
    par: Parallelism,
) -> Result<()> {
    for (shape, len) in [([m, k], lhs.len()), ([k, n], rhs.len())] {
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
    let needed = (m - 1) * row_stride + n;
    if row_stride < n || dst.len() < needed {
        return Err(InferError::DataLength {
            op,
            shape: vec![m, n],
            expected: needed,
            got: dst.len(),
        });
    }
    let dst = &mut dst[..needed];
    if k == 0 {
        if !accumulate {
            for row in dst.chunks_mut(row_stride) {
                row[..n].fill(0.0);
            }
        }
        return Ok(());
    }
    if m == 1 && rhs_layout == Rhs::Transposed && n > MATVEC_BLOCK {
        // Memory-bound (each weight read once): worth the threads, in blocks fixed in advance.
        let tasks = if n * k < PARALLEL_MIN_PRODUCTS {
            1
        } else {
            par.threads().min(n.div_ceil(MATVEC_BLOCK))
        };
        let per_task = n.div_ceil(MATVEC_BLOCK).div_ceil(tasks) * MATVEC_BLOCK;
        let run = |(dst, rhs): (&mut [f32], &[f32])| {
            let blocks = dst
                .chunks_mut(MATVEC_BLOCK)
                .zip(rhs.chunks(MATVEC_BLOCK * k));
            for (dst, rhs) in blocks {
                let shape = [1, k, dst.len()];
                let seq = faer::Par::Seq;
                product(dst, dst.len(), lhs, rhs, shape, rhs_layout, accumulate, seq);
            }
        };
        if tasks <= 1 {
            run((dst, rhs));
        } else {
            let rhs_runs = rhs.par_chunks(per_task * k);
            dst.par_chunks_mut(per_task).zip(rhs_runs).for_each(run);
        }
        return Ok(());
    }
    // A matrix-vector product: faer would split the sum itself, see the module doc. A small
    // product runs on one thread too: it takes tens of microseconds, and splitting it costs
    // about as much as it saves (a small GQ-CNN scored one crop at a time ran 20% slower on
    // two threads than on one).
    let par = if m == 1 || n == 1 || m * n * k < PARALLEL_MIN_PRODUCTS {
        Parallelism::Sequential
    } else {
        par
    };
    let shape = [m, k, n];
    product(
        dst,
        row_stride,
        lhs,
        rhs,
        shape,
        rhs_layout,
        accumulate,
        par.faer(),
    );
    Ok(())
}

/// faer's product on slices whose lengths [`matmul_rows`] checked.
#[allow(clippy::too_many_arguments)] // private: three operands, their sizes, and how to run
fn product(
    dst: &mut [f32],
    row_stride: usize,
    lhs: &[f32],
    rhs: &[f32],
    [m, k, n]: [usize; 3],
    rhs_layout: Rhs,
    accumulate: bool,
    par: faer::Par,
) {
    // Not `from_row_major_slice_with_stride_mut`: in faer 0.24.4 it makes a column-major view
    // (the row stride used as the column stride), which writes out of place and past the
    // rows; the transposed column-major view is the row-major one asked for.
    let dst =
        MatMut::from_column_major_slice_with_stride_mut(dst, n, m, row_stride).transpose_mut();
    let lhs = MatRef::from_row_major_slice(lhs, m, k);
    let rhs = match rhs_layout {
        Rhs::RowMajor => MatRef::from_row_major_slice(rhs, k, n),
        Rhs::Transposed => MatRef::from_row_major_slice(rhs, n, k).transpose(),
    };
    let accum = if accumulate {
        Accum::Add
    } else {
        Accum::Replace
    };
    faer::linalg::matmul::matmul(dst, accum, lhs, rhs, 1.0, par);
    // faer's kernels leave the upper halves of the vector registers dirty on every thread that
    // ran them; the rest of the crate is compiled for baseline x86-64 (SSE), and each of its
    // vector instructions then pays for merging with the dirty upper halves. Clearing them
    // made the LSM three times faster (the GRU's gates and the ray projection ran in the
    // shadow of the convolutions' kernels).
    if matches!(par, faer::Par::Seq) {
        clear_upper_vector_state();
    } else {
        rayon::broadcast(|_| clear_upper_vector_state());
    }
}

/// `vzeroupper` where the CPU has AVX (see [`product`]); nothing elsewhere.
fn clear_upper_vector_state() {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx") {
        // SAFETY: the CPU has AVX (checked just above), the one requirement of the
        // instruction; it zeroes the upper halves of the vector registers, which hold no live
        // values across this call (the compiler saves nothing there: the calling convention
        // treats them as clobbered).
        #[allow(unsafe_code)]
        unsafe {
            zero_upper();
        }
    }
}

/// `vzeroupper`.
///
/// # Safety
/// The CPU must have AVX.
#[cfg(target_arch = "x86_64")]
#[allow(unsafe_code)]
#[target_feature(enable = "avx")]
unsafe fn zero_upper() {
    std::arch::x86_64::_mm256_zeroupper();
}
