//! The two convolutions as their definitions read: nested loops, nothing clever.

use super::geometry::{Conv3dParams, Geometry, Kind};
use crate::error::Result;
use crate::tensor::Tensor;

/// The input index along one axis that output `o` and kernel tap `k` meet in a convolution, if
/// it lies in `0..size`.
fn tap(o: usize, k: usize, stride: usize, padding: usize, size: usize) -> Option<usize> {
    (o * stride + k).checked_sub(padding).filter(|&i| i < size)
}

/// 3-D convolution (torch's cross-correlation) written as its definition: for every output
/// value, the bias plus the sum over input channels and kernel taps, taps outside the input
/// reading zero. Slow; the reference [`conv3d`](super::conv3d) is tested against.
///
/// `input` is `[N, C, D, H, W]`, `weight` `[out_C, C, k0, k1, k2]`, `bias` `[out_C]`.
///
/// # Errors
/// As [`conv3d`](super::conv3d).
pub fn conv3d_reference(
    input: &Tensor,
    weight: &Tensor,
    bias: Option<&Tensor>,
    params: Conv3dParams,
) -> Result<Tensor> {
    let (g, bias) = Geometry::new(Kind::Direct, input, weight, bias, params)?;
    let mut out = Tensor::zeros(&g.output_shape());
    let (x, k, y) = (input.data(), weight.data(), out.data_mut());
    let [d, h, w] = g.input;
    let [k0, k1, k2] = g.kernel;
    let [s0, s1, s2] = g.stride;
    let [p0, p1, p2] = g.padding;
    let mut i = 0;
    for n in 0..g.n {
        for o in 0..g.oc {
            for oz in 0..g.output[0] {
                for oy in 0..g.output[1] {
                    for ox in 0..g.output[2] {
                        let mut sum = bias.map_or(0.0, |b| b[o]);
                        for c in 0..g.c {
                            for kz in 0..k0 {
                                let Some(iz) = tap(oz, kz, s0, p0, d) else {
                                    continue;
                                };
                                for ky in 0..k1 {
                                    let Some(iy) = tap(oy, ky, s1, p1, h) else {
                                        continue;
                                    };
                                    for kx in 0..k2 {
                                        let Some(ix) = tap(ox, kx, s2, p2, w) else {
                                            continue;
                                        };
                                        let xv = x[(((n * g.c + c) * d + iz) * h + iy) * w + ix];
                                        let kv = k[(((o * g.c + c) * k0 + kz) * k1 + ky) * k2 + kx];
                                        sum += xv * kv;
                                    }
                                }
                            }
                        }
                        y[i] = sum;
                        i += 1;
                    }
                }
            }
        }
    }
    Ok(out)
}

/// The input index along one axis whose footprint puts kernel tap `k` on output `o` in a
/// transposed convolution (`o = i * stride + k - padding`), if there is one in `0..size`.
fn source(o: usize, k: usize, stride: usize, padding: usize, size: usize) -> Option<usize> {
    let at = (o + padding).checked_sub(k)?;
    (at % stride == 0 && at / stride < size).then_some(at / stride)
}

/// 3-D transposed convolution (torch's `nn.ConvTranspose3d`, the gradient of a convolution)
/// written as its definition: every output value is the bias plus, over input channels and
/// kernel taps, the input values whose footprint places that tap on it. Slow; the reference
/// [`conv_transpose3d`](super::conv_transpose3d) is tested against.
///
/// `input` is `[N, C, D, H, W]`, `weight` `[C, out_C, k0, k1, k2]`, `bias` `[out_C]`; the output
/// is `(D - 1) * stride - 2 * padding + k0` deep, and so on.
///
/// # Errors
/// As [`conv_transpose3d`](super::conv_transpose3d).
pub fn conv_transpose3d_reference(
    input: &Tensor,
    weight: &Tensor,
    bias: Option<&Tensor>,
    params: Conv3dParams,
) -> Result<Tensor> {
    let (g, bias) = Geometry::new(Kind::Transposed, input, weight, bias, params)?;
    let mut out = Tensor::zeros(&g.output_shape());
    let (x, k, y) = (input.data(), weight.data(), out.data_mut());
    let [d, h, w] = g.input;
    let [k0, k1, k2] = g.kernel;
    let [s0, s1, s2] = g.stride;
    let [p0, p1, p2] = g.padding;
    let mut i = 0;
    for n in 0..g.n {
        for o in 0..g.oc {
            for oz in 0..g.output[0] {
                for oy in 0..g.output[1] {
                    for ox in 0..g.output[2] {
                        let mut sum = bias.map_or(0.0, |b| b[o]);
                        for c in 0..g.c {
                            for kz in 0..k0 {
                                let Some(iz) = source(oz, kz, s0, p0, d) else {
                                    continue;
                                };
                                for ky in 0..k1 {
                                    let Some(iy) = source(oy, ky, s1, p1, h) else {
                                        continue;
                                    };
                                    for kx in 0..k2 {
                                        let Some(ix) = source(ox, kx, s2, p2, w) else {
                                            continue;
                                        };
                                        let xv = x[(((n * g.c + c) * d + iz) * h + iy) * w + ix];
                                        let kv =
                                            k[(((c * g.oc + o) * k0 + kz) * k1 + ky) * k2 + kx];
                                        sum += xv * kv;
                                    }
                                }
                            }
                        }
                        y[i] = sum;
                        i += 1;
                    }
                }
            }
        }
    }
    Ok(out)
}
