//! Pooling as its definition reads: pad the input explicitly, then reduce every full window.

use super::params::{AvgPoolDivisor, Geometry, Pool2dParams};
use crate::error::Result;
use crate::tensor::Tensor;

/// Max pooling by its definition: each plane is copied into a `-inf`-padded one and every
/// window of that is reduced whole. Slow; the reference [`max_pool2d`](super::max_pool2d) is
/// tested against.
///
/// # Errors
/// As [`max_pool2d_into`](super::max_pool2d_into).
pub fn max_pool2d_reference(input: &Tensor, params: Pool2dParams) -> Result<Tensor> {
    let g = Geometry::new("max_pool2d", input, params)?;
    pool(&g, input, f32::NEG_INFINITY, |window| {
        window
            .iter()
            .map(|&(v, _)| v)
            .fold(
                f32::NEG_INFINITY,
                |m, v| if v > m || v.is_nan() { v } else { m },
            )
    })
}

/// Average pooling by its definition: each plane is copied into a zero-padded one and every
/// window of that is summed and divided. Slow; the reference
/// [`avg_pool2d`](super::avg_pool2d) is tested against.
///
/// # Errors
/// As [`avg_pool2d_into`](super::avg_pool2d_into).
pub fn avg_pool2d_reference(
    input: &Tensor,
    params: Pool2dParams,
    divisor: AvgPoolDivisor,
) -> Result<Tensor> {
    let g = Geometry::new("avg_pool2d", input, params)?;
    pool(&g, input, 0.0, |window| {
        let sum: f32 = window.iter().map(|&(v, _)| v).sum();
        let count = match divisor {
            AvgPoolDivisor::Window => window.len(),
            AvgPoolDivisor::InputOnly => window.iter().filter(|&&(_, on_input)| on_input).count(),
        };
        sum / count as f32
    })
}

/// Pads each plane with `fill`, then applies `reduce` to each window's `(value, on_input)`
/// pairs, row by row.
fn pool(
    g: &Geometry,
    input: &Tensor,
    fill: f32,
    reduce: impl Fn(&[(f32, bool)]) -> f32,
) -> Result<Tensor> {
    let [kh, kw] = g.params.kernel;
    let [sh, sw] = g.params.stride;
    let [ph, pw] = g.params.padding;
    let (hp, wp) = (g.h + 2 * ph, g.w + 2 * pw);
    let mut values = Vec::with_capacity(g.n * g.c * g.oh * g.ow);
    let mut padded = vec![(fill, false); hp * wp];
    let mut window = Vec::with_capacity(kh * kw);
    for plane in input.data().chunks_exact(g.h * g.w) {
        padded.fill((fill, false));
        for y in 0..g.h {
            for x in 0..g.w {
                padded[(y + ph) * wp + x + pw] = (plane[y * g.w + x], true);
            }
        }
        for oy in 0..g.oh {
            for ox in 0..g.ow {
                window.clear();
                for ky in 0..kh {
                    for kx in 0..kw {
                        window.push(padded[(oy * sh + ky) * wp + ox * sw + kx]);
                    }
                }
                values.push(reduce(&window));
            }
        }
    }
    Tensor::new(&g.output_shape(), values)
}
