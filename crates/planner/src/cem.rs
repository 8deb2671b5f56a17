//! Dex-Net 2.0's cross-entropy method over a view's grasps: antipodal candidates from the
//! depth-image sampler scored by the network, a Gaussian mixture fitted to the best of them
//! (the elite), new candidates drawn from it and scored, and again.
//!
//! A grasp is the feature vector gqcnn uses, its two jaw points in the image and its depth,
//! (u1, v1, u2, v2, depth): the jaws are the grasp's width apart at its depth. The mixture has
//! diagonal covariances (a handful of elite grasps per component cannot fill a full one).

use mvgrasp_grasp::ImageGrasp;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

const DIM: usize = 5;
type Feature = [f64; DIM];

/// The cross-entropy method's settings; the defaults are Dex-Net 2.0's.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CemParams {
    /// Candidates from the antipodal sampler before the first refit.
    pub initial_samples: usize,
    /// Candidates drawn from the mixture in each iteration.
    pub samples_per_iteration: usize,
    /// Refits.
    pub iterations: usize,
    /// The best share of the scored candidates that the mixture is fitted to.
    pub elite_fraction: f32,
    /// Mixture components as a share of the elite.
    pub components_fraction: f32,
    /// Added to each variance, as a share of the elite's variance in that feature.
    pub variance_floor: f64,
    /// Expectation-maximisation steps per fit.
    pub em_steps: usize,
}

impl Default for CemParams {
    fn default() -> Self {
        Self {
            initial_samples: 250,
            samples_per_iteration: 50,
            iterations: 3,
            elite_fraction: 0.25,
            components_fraction: 0.4,
            variance_floor: 0.01,
            em_steps: 30,
        }
    }
}

/// A grasp's features with the camera's focal length `focal_px`.
pub fn features(g: &ImageGrasp, focal_px: f32) -> Feature {
    let half = f64::from(g.width_m / 2.0 * focal_px / g.depth_m.max(1e-6));
    let (sin, cos) = f64::from(g.angle_rad).sin_cos();
    let [u, v] = g.center_px.map(f64::from);
    [
        u - half * cos,
        v - half * sin,
        u + half * cos,
        v + half * sin,
        f64::from(g.depth_m),
    ]
}

/// The grasp of features `f` (the inverse of [`features`]).
pub fn grasp_of(f: &Feature, focal_px: f32) -> ImageGrasp {
    let (du, dv) = (f[2] - f[0], f[3] - f[1]);
    ImageGrasp {
        center_px: [((f[0] + f[2]) / 2.0) as f32, ((f[1] + f[3]) / 2.0) as f32],
        angle_rad: dv.atan2(du) as f32,
        depth_m: f[4] as f32,
        width_m: (du.hypot(dv) * f[4] / f64::from(focal_px)) as f32,
    }
}

/// A Gaussian mixture with diagonal covariances.
#[derive(Clone, Debug, PartialEq)]
pub struct Mixture {
    weights: Vec<f64>,
    means: Vec<Feature>,
    variances: Vec<Feature>,
}

impl Mixture {
    /// Fits `components` Gaussians to `points` by expectation-maximisation from a k-means++
    /// start, each variance floored at `floor` times the points' variance in that feature;
    /// deterministic from `rng`. `None` for no points.
    pub fn fit(
        points: &[Feature],
        components: usize,
        floor: f64,
        steps: usize,
        rng: &mut ChaCha8Rng,
    ) -> Option<Self> {
        let n = points.len();
        if n == 0 {
            return None;
        }
        let k = components.clamp(1, n);
        let mean = mean_of(points.iter(), n as f64);
        let mut spread = [0.0; DIM];
        for p in points {
            for d in 0..DIM {
                spread[d] += (p[d] - mean[d]).powi(2) / n as f64;
            }
        }
        let floor: Feature = spread.map(|s| (s * floor).max(1e-9));
        // k-means++: each next centre drawn with probability proportional to the squared
        // (variance-scaled) distance to the nearest centre so far.
        let scaled = |a: &Feature, b: &Feature| -> f64 {
            (0..DIM)
                .map(|d| (a[d] - b[d]).powi(2) / spread[d].max(1e-12))
                .sum()
        };
        let mut means = vec![points[rng.random_range(0..n)]];
        while means.len() < k {
            let distances: Vec<f64> = points
                .iter()
                .map(|p| {
                    means
                        .iter()
                        .map(|m| scaled(p, m))
                        .fold(f64::INFINITY, f64::min)
                })
                .collect();
            let total: f64 = distances.iter().sum();
            if total <= 0.0 {
                break;
            }
            let mut pick = rng.random_range(0.0..total);
            let index = distances
                .iter()
                .position(|&d| {
                    pick -= d;
                    pick < 0.0
                })
                .unwrap_or(n - 1);
            means.push(points[index]);
        }
        let k = means.len();
        let mut mixture = Self {
            weights: vec![1.0 / k as f64; k],
            variances: vec![spread.map(|s| s.max(1e-9)); k],
            means,
        };
        let mut responsibility = vec![vec![0.0; k]; n];
        for _ in 0..steps {
            // E: each point's share in each component (in log space against underflow).
            for (p, r) in points.iter().zip(&mut responsibility) {
                let logs: Vec<f64> = (0..k).map(|j| mixture.log_weighted(j, p)).collect();
                let top = logs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                let sum: f64 = logs.iter().map(|l| (l - top).exp()).sum();
                for j in 0..k {
                    r[j] = (logs[j] - top).exp() / sum;
                }
            }
            // M: weights, means and floored variances from the shares.
            for j in 0..k {
                let mass: f64 = responsibility.iter().map(|r| r[j]).sum();
                if mass < 1e-9 {
                    continue;
                }
                let mut m = [0.0; DIM];
                for (p, r) in points.iter().zip(&responsibility) {
                    for d in 0..DIM {
                        m[d] += r[j] * p[d] / mass;
                    }
                }
                let mut var = floor;
                for (p, r) in points.iter().zip(&responsibility) {
                    for d in 0..DIM {
                        var[d] += r[j] * (p[d] - m[d]).powi(2) / mass;
                    }
                }
                mixture.weights[j] = mass / n as f64;
                mixture.means[j] = m;
                mixture.variances[j] = var;
            }
        }
        Some(mixture)
    }

    /// log(weight_j N(p; mean_j, var_j)).
    fn log_weighted(&self, j: usize, p: &Feature) -> f64 {
        let (m, var) = (&self.means[j], &self.variances[j]);
        let mut log = self.weights[j].max(1e-300).ln();
        for d in 0..DIM {
            log -= 0.5 * ((p[d] - m[d]).powi(2) / var[d] + (std::f64::consts::TAU * var[d]).ln());
        }
        log
    }

    /// A draw.
    pub fn sample(&self, rng: &mut ChaCha8Rng) -> Feature {
        let mut pick = rng.random_range(0.0..1.0);
        let j = self
            .weights
            .iter()
            .position(|&w| {
                pick -= w;
                pick < 0.0
            })
            .unwrap_or(self.weights.len() - 1);
        let (m, var) = (&self.means[j], &self.variances[j]);
        std::array::from_fn(|d| {
            let z: f64 = StandardNormal.sample(rng);
            m[d] + z * var[d].sqrt()
        })
    }

    /// Components.
    pub fn len(&self) -> usize {
        self.weights.len()
    }

    /// Whether it has no component (never: a fit has at least one).
    pub fn is_empty(&self) -> bool {
        self.weights.is_empty()
    }
}

fn mean_of<'a>(points: impl Iterator<Item = &'a Feature>, n: f64) -> Feature {
    let mut mean = [0.0; DIM];
    for p in points {
        for d in 0..DIM {
            mean[d] += p[d] / n;
        }
    }
    mean
}

/// A seeded generator for the method.
pub fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn features_round_trip() {
        let g = ImageGrasp {
            center_px: [320.0, 240.0],
            angle_rad: 0.7,
            depth_m: 0.68,
            width_m: 0.045,
        };
        let back = grasp_of(&features(&g, 525.0), 525.0);
        assert!(
            (back.center_px[0] - 320.0).abs() < 1e-4 && (back.center_px[1] - 240.0).abs() < 1e-4
        );
        assert!((back.angle_rad - 0.7).abs() < 1e-5);
        assert!((back.depth_m - 0.68).abs() < 1e-6 && (back.width_m - 0.045).abs() < 1e-6);
    }

    #[test]
    fn a_mixture_finds_two_clusters_and_samples_near_them() {
        let mut r = rng(3);
        let mut points = Vec::new();
        for i in 0..40 {
            let jitter = |k: usize| ((i * 7 + k * 13) % 11) as f64 / 11.0 - 0.5;
            let c = if i % 2 == 0 { 100.0 } else { 300.0 };
            points.push([
                c + jitter(0),
                c + jitter(1),
                c + 20.0 + jitter(2),
                c + jitter(3),
                0.7,
            ]);
        }
        let mixture = Mixture::fit(&points, 2, 1e-4, 30, &mut r).unwrap();
        assert_eq!(mixture.len(), 2);
        let mut means: Vec<f64> = mixture.means.iter().map(|m| m[0]).collect();
        means.sort_by(f64::total_cmp);
        assert!(
            (means[0] - 100.0).abs() < 1.0 && (means[1] - 300.0).abs() < 1.0,
            "{means:?}"
        );
        for _ in 0..100 {
            let s = mixture.sample(&mut r);
            assert!(
                (s[0] - 100.0).abs() < 10.0 || (s[0] - 300.0).abs() < 10.0,
                "{s:?}"
            );
        }
        // The same seed, the same fit.
        assert_eq!(
            Mixture::fit(&points, 2, 0.01, 30, &mut rng(3)),
            Mixture::fit(&points, 2, 0.01, 30, &mut rng(3))
        );
        assert!(Mixture::fit(&[], 2, 0.01, 30, &mut r).is_none());
    }
}
