//! The fast transposed 3-D convolution: for a band of input slices, one faer product
//! `[positions, C] · [C, out_C * taps]` gives every input position's contribution to every
//! output channel and kernel tap (torch's weight `[C, out_C, k0, k1, k2]` read as it lies), and
//! col2vol adds each to the output value that tap lands on.

use super::geometry::{Conv3dParams, Geometry, Kind};
use crate::error::Result;
use crate::gemm::{Rhs, matmul};
use crate::ops::stretch;
use crate::parallel::Parallelism;
use crate::tensor::Tensor;

/// Transposed 3-D convolution (torch's `nn.ConvTranspose3d`, no output padding, one group) of
/// an `[N, C, D, H, W]` batch with a `[C, out_C, k0, k1, k2]` weight and an optional `[out_C]`
/// bias, into a new `[N, out_C, (D - 1) * stride - 2 * padding + k0, ...]` tensor.
///
/// # Errors
/// As [`conv_transpose3d_into`].
pub fn conv_transpose3d(
    input: &Tensor,
    weight: &Tensor,
    bias: Option<&Tensor>,
    params: Conv3dParams,
    par: Parallelism,
) -> Result<Tensor> {
    let mut out = Tensor::default();
    conv_transpose3d_into(input, weight, bias, params, &mut out, &mut Vec::new(), par)?;
    Ok(out)
}

/// [`conv_transpose3d`] into `out` (resized), with `scratch` for the products; both keep their
/// allocations. Every value is the same whatever `par` says.
///
/// # Errors
/// [`InferError::ShapeMismatch`](crate::InferError::ShapeMismatch) when `input` is not
/// `[N, C, D, H, W]` with every axis non-empty, `weight` not `[C, out_C, k0, k1, k2]`, `bias`
/// not `[out_C]`, or the padding removes the whole output;
/// [`InferError::InvalidParameter`](crate::InferError::InvalidParameter) for a zero stride.
pub fn conv_transpose3d_into(
    input: &Tensor,
    weight: &Tensor,
    bias: Option<&Tensor>,
    params: Conv3dParams,
    out: &mut Tensor,
    scratch: &mut Vec<f32>,
    par: Parallelism,
) -> Result<()> {
    let (g, bias) = Geometry::new(Kind::Transposed, input, weight, bias, params)?;
    out.resize(&g.output_shape());
    let (in_len, out_len) = (g.input_len(), g.output_len());
    if g.n == 0 || out_len == 0 {
        return Ok(());
    }
    let [_, h, w] = g.input;
    let band = band_slices(&g);
    let width = g.oc * g.taps();
    let buffer = stretch(scratch, band * h * w * (g.c + width));
    let (transposed, contributions) = buffer.split_at_mut(band * h * w * g.c);
    let (x, k) = (input.data(), weight.data());
    for (i, y) in out.data_mut().chunks_exact_mut(out_len).enumerate() {
        let x = &x[i * in_len..(i + 1) * in_len];
        let plane = g.output.iter().product::<usize>();
        for (row, o) in y.chunks_exact_mut(plane).enumerate() {
            o.fill(bias.map_or(0.0, |b| b[row]));
        }
        for start in (0..g.input[0]).step_by(band) {
            let slices = (start + band).min(g.input[0]) - start;
            let positions = slices * h * w;
            let first = start * h * w;
            // The band's input as [positions, C].
            let xt = &mut transposed[..positions * g.c];
            for (c, channel) in x.chunks_exact(g.input.iter().product()).enumerate() {
                for (p, &v) in channel[first..first + positions].iter().enumerate() {
                    xt[p * g.c + c] = v;
                }
            }
            let col = &mut contributions[..positions * width];
            let shape = [positions, g.c, width];
            matmul(
                "conv_transpose3d",
                col,
                xt,
                k,
                shape,
                Rhs::RowMajor,
                false,
                par,
            )?;
            scatter(&g, col, first, positions, y);
        }
    }
    Ok(())
}

/// The most values of a band's contributions (4 MiB).
const BAND_VALUES: usize = 1 << 20;

/// The input slices (along depth) multiplied at a time, fixed by the geometry alone.
fn band_slices(g: &Geometry) -> usize {
    let per_slice = g.input[1] * g.input[2] * g.oc * g.taps();
    (BAND_VALUES / per_slice.max(1)).clamp(1, g.input[0].max(1))
}

/// col2vol: adds contribution `[p, (o, kz, ky, kx)]` of input position `first + p` to the
/// output value at `input * stride + tap - padding` of channel `o`, where that lies inside.
fn scatter(g: &Geometry, col: &[f32], first: usize, positions: usize, y: &mut [f32]) {
    let [_, h, w] = g.input;
    let [od, oh, ow] = g.output;
    let [k0, k1, k2] = g.kernel;
    let [s0, s1, s2] = g.stride;
    let [p0, p1, p2] = g.padding;
    let width = g.oc * g.taps();
    let at = |i: usize, k: usize, s: usize, p: usize, size: usize| {
        (i * s + k).checked_sub(p).filter(|&o| o < size)
    };
    for (p, row) in col.chunks_exact(width).take(positions).enumerate() {
        let index = first + p;
        let (iz, iy, ix) = (index / (h * w), (index / w) % h, index % w);
        for (o, taps) in row.chunks_exact(g.taps()).enumerate() {
            let out = &mut y[o * od * oh * ow..(o + 1) * od * oh * ow];
            for kz in 0..k0 {
                let Some(oz) = at(iz, kz, s0, p0, od) else {
                    continue;
                };
                for ky in 0..k1 {
                    let Some(oy) = at(iy, ky, s1, p1, oh) else {
                        continue;
                    };
                    for kx in 0..k2 {
                        let Some(ox) = at(ix, kx, s2, p2, ow) else {
                            continue;
                        };
                        out[(oz * oh + oy) * ow + ox] += taps[(kz * k1 + ky) * k2 + kx];
                    }
                }
            }
        }
    }
}
