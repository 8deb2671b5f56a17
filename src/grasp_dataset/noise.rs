//! Dex-Net's depth-image noise: `depth * gamma + correlated Gaussian`, on the pixels that see
//! something (0 stays 0).

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Gamma, StandardNormal};

use mvgrasp_planner::DepthImage;

use super::config::NoiseParams;

/// Adds the noise of `params` to `depth` in place, from `seed`.
pub fn add_depth_noise(depth: &mut DepthImage, params: &NoiseParams, seed: u64) {
    let (width, height) = (depth.width(), depth.height());
    let depth_m = depth.as_mut_slice();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let k = params.gamma_shape;
    // Shape k, scale 1/k: mean 1, variance 1/k. `validate` guarantees k > 0.
    let gamma = Gamma::new(k, 1.0 / k).map_or(1.0, |g| g.sample(&mut rng));
    let step = params.correlation_px.max(1) as usize;
    let (w, h) = (width as usize, height as usize);
    let (gw, gh) = (w.div_ceil(step) + 1, h.div_ceil(step) + 1);
    let grid: Vec<f32> = (0..gw * gh)
        .map(|_| {
            let n: f32 = StandardNormal.sample(&mut rng);
            n * params.sigma_m
        })
        .collect();
    for y in 0..h {
        let gy = y as f32 / step as f32;
        let (y0, fy) = (gy.floor() as usize, gy.fract());
        for x in 0..w {
            let d = &mut depth_m[y * w + x];
            if *d <= 0.0 {
                continue;
            }
            let gx = x as f32 / step as f32;
            let (x0, fx) = (gx.floor() as usize, gx.fract());
            let g = |i: usize, j: usize| grid[j * gw + i];
            let top = g(x0, y0) * (1.0 - fx) + g(x0 + 1, y0) * fx;
            let bottom = g(x0, y0 + 1) * (1.0 - fx) + g(x0 + 1, y0 + 1) * fx;
            *d = (*d * gamma + top * (1.0 - fy) + bottom * fy).max(f32::MIN_POSITIVE);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mvgrasp_geometry::Intrinsics;

    #[test]
    fn noise_is_seeded_keeps_holes_and_has_dexnet_scale() {
        let params = NoiseParams {
            enabled: true,
            ..NoiseParams::default()
        };
        let k = Intrinsics::new(100.0, 100.0, 50.0, 40.0, 100, 80, 0.1, 2.0).unwrap();
        let mut values = vec![0.7f32; 100 * 80];
        values[5] = 0.0;
        let mut a = DepthImage::new(k, values).unwrap();
        let mut b = a.clone();
        add_depth_noise(&mut a, &params, 9);
        add_depth_noise(&mut b, &params, 9);
        assert_eq!(a, b);
        let a = a.as_slice();
        assert_eq!(a[5], 0.0);
        let mean = a.iter().sum::<f32>() / a.len() as f32;
        let std = (a.iter().map(|d| (d - mean).powi(2)).sum::<f32>() / a.len() as f32).sqrt();
        assert!((mean - 0.7).abs() < 0.05, "{mean}");
        assert!((0.001..0.01).contains(&std), "{std}");
        // Neighbours move together.
        assert!(
            (a[1000] - a[1001]).abs() < 0.5 * std,
            "{} {}",
            a[1000],
            a[1001]
        );
    }
}
