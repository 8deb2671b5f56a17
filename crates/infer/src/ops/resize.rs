//! Image resizing as torch's `F.interpolate`: bilinear (upsampling the decoder's features) and
//! area (averaging camera images down to a network's input size).

use crate::error::Result;
use crate::ops::check::{nchw, positive};
use crate::tensor::Tensor;

/// The two source pixels and the weight of the second for output pixel `o` of a bilinear
/// resize from `input` to `output` pixels along one axis (`align_corners=False`: pixel centres
/// map to pixel centres, `src = (o + 0.5) * input / output - 0.5`, clamped at 0).
fn bilinear_taps(o: usize, input: usize, output: usize) -> (usize, usize, f32) {
    let scale = input as f32 / output as f32;
    let src = ((o as f32 + 0.5) * scale - 0.5).max(0.0);
    let lo = (src as usize).min(input - 1);
    let hi = if lo + 1 < input { lo + 1 } else { lo };
    (lo, hi, src - lo as f32)
}

/// Bilinear resize of an `[N, C, H, W]` tensor to `[N, C, height, width]` (torch's
/// `F.interpolate(mode="bilinear", align_corners=False)` with `size` given).
///
/// # Errors
/// [`InferError::ShapeMismatch`](crate::InferError::ShapeMismatch) for a tensor not NCHW or
/// with an empty image; [`InferError::InvalidParameter`](crate::InferError::InvalidParameter)
/// for a zero output size.
pub fn resize_bilinear(x: &Tensor, height: usize, width: usize) -> Result<Tensor> {
    const OP: &str = "resize_bilinear";
    let [n, c, h, w] = nchw(OP, x)?;
    positive(OP, "height", height)?;
    positive(OP, "width", width)?;
    if h == 0 || w == 0 {
        return Err(crate::ops::check::shape_error(
            OP,
            "[batch, channels, height >= 1, width >= 1]",
            x.shape(),
        ));
    }
    let rows: Vec<_> = (0..height).map(|o| bilinear_taps(o, h, height)).collect();
    let cols: Vec<_> = (0..width).map(|o| bilinear_taps(o, w, width)).collect();
    let mut out = Tensor::zeros(&[n, c, height, width]);
    for (plane, out_plane) in x
        .data()
        .chunks_exact(h * w)
        .zip(out.data_mut().chunks_exact_mut(height * width))
    {
        for (&(y0, y1, ly), out_row) in rows.iter().zip(out_plane.chunks_exact_mut(width)) {
            let (top, bottom) = (&plane[y0 * w..(y0 + 1) * w], &plane[y1 * w..(y1 + 1) * w]);
            for (&(x0, x1, lx), v) in cols.iter().zip(out_row) {
                let upper = (1.0 - lx) * top[x0] + lx * top[x1];
                let lower = (1.0 - lx) * bottom[x0] + lx * bottom[x1];
                *v = (1.0 - ly) * upper + ly * lower;
            }
        }
    }
    Ok(out)
}

/// The source pixels `start..end` averaged into output pixel `o` along one axis (torch's
/// adaptive average pooling: `floor(o * input / output)..ceil((o + 1) * input / output)`).
fn area_bin(o: usize, input: usize, output: usize) -> (usize, usize) {
    (o * input / output, ((o + 1) * input).div_ceil(output))
}

/// Area resize of an `[N, C, H, W]` tensor to `[N, C, height, width]` (torch's
/// `F.interpolate(mode="area")`, which is `adaptive_avg_pool2d`): each output pixel is the
/// mean of its bin of input pixels. Summed in f64.
///
/// # Errors
/// As [`resize_bilinear`].
pub fn resize_area(x: &Tensor, height: usize, width: usize) -> Result<Tensor> {
    const OP: &str = "resize_area";
    let [n, c, h, w] = nchw(OP, x)?;
    positive(OP, "height", height)?;
    positive(OP, "width", width)?;
    if h == 0 || w == 0 {
        return Err(crate::ops::check::shape_error(
            OP,
            "[batch, channels, height >= 1, width >= 1]",
            x.shape(),
        ));
    }
    let mut out = Tensor::zeros(&[n, c, height, width]);
    for (plane, out_plane) in x
        .data()
        .chunks_exact(h * w)
        .zip(out.data_mut().chunks_exact_mut(height * width))
    {
        for (oy, out_row) in out_plane.chunks_exact_mut(width).enumerate() {
            let (y0, y1) = area_bin(oy, h, height);
            for (ox, v) in out_row.iter_mut().enumerate() {
                let (x0, x1) = area_bin(ox, w, width);
                let mut sum = 0.0f64;
                for row in plane[y0 * w..y1 * w].chunks_exact(w) {
                    sum += row[x0..x1].iter().map(|&v| f64::from(v)).sum::<f64>();
                }
                *v = (sum / ((y1 - y0) * (x1 - x0)) as f64) as f32;
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    #[test]
    fn bilinear_doubling_is_torchs() {
        // torch: F.interpolate(tensor([[[[0., 1.]]]]), size=(1, 4), mode="bilinear")
        // -> [0, 0.25, 0.75, 1]; a constant stays constant.
        let x = Tensor::new(&[1, 1, 1, 2], vec![0.0, 1.0]).unwrap();
        let y = resize_bilinear(&x, 1, 4).unwrap();
        assert_eq!(y.data(), [0.0, 0.25, 0.75, 1.0]);
        let flat = resize_bilinear(&Tensor::full(&[2, 3, 4, 5], 7.0), 9, 11).unwrap();
        assert!(flat.data().iter().all(|&v| (v - 7.0).abs() < 1e-6));
        // The same size is the identity.
        let x = Tensor::new(&[1, 1, 2, 2], vec![1.0, 2.0, 3.0, 4.0]).unwrap();
        assert_eq!(resize_bilinear(&x, 2, 2).unwrap(), x);
    }

    #[test]
    fn area_averages_blocks_and_uneven_bins() {
        let x = Tensor::new(&[1, 1, 2, 4], vec![1.0, 3.0, 5.0, 7.0, 1.0, 3.0, 5.0, 7.0]).unwrap();
        assert_eq!(resize_area(&x, 1, 2).unwrap().data(), [2.0, 6.0]);
        // 3 -> 2: bins 0..2 and 1..3 (torch's adaptive pooling overlaps them).
        let x = Tensor::new(&[1, 1, 1, 3], vec![0.0, 3.0, 6.0]).unwrap();
        assert_eq!(resize_area(&x, 1, 2).unwrap().data(), [1.5, 4.5]);
        assert!(resize_area(&x, 0, 2).is_err());
        assert!(resize_bilinear(&Tensor::zeros(&[1, 3]), 2, 2).is_err());
    }
}
