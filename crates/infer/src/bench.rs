//! Timing a GQ-CNN the way its torch twin is timed (`benches/gqcnn/bench_torch.py`): the same
//! seeded inputs (SplitMix64, as the script draws them), a warm-up, then calls until a time
//! has passed and at least 5 calls were made; the median call and the mean probability (a
//! check that two runtimes scored the same inputs alike). `benches/gqcnn` and `evaluate
//! --suite speed` both time through here.

use std::time::Instant;

use crate::error::Result;
use crate::model::{Gqcnn, GqcnnWorkspace};
use crate::tensor::Tensor;

/// SplitMix64 (Steele, Lea, Flood 2014), as `bench_torch.py` has it: the same numbers in both;
/// the state is the seed.
pub struct SplitMix64(pub u64);

impl SplitMix64 {
    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `[lo, hi)`, computed in f64 and rounded once to f32.
    fn uniform(&mut self, lo: f64, hi: f64) -> f32 {
        let unit = (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
        (lo + (hi - lo) * unit) as f32
    }
}

/// `batch` depth crops `[batch, 1, size, size]` (0.6..0.75 m) and poses `[batch, P]` (grasp
/// depth 0.6..0.75 m, then theta 0..1.57 rad): crops first, then poses, row by row.
///
/// # Errors
/// Only for a zero size.
pub fn gqcnn_inputs(
    batch: usize,
    size: usize,
    pose_inputs: usize,
    seed: u64,
) -> Result<(Tensor, Tensor)> {
    let mut rng = SplitMix64(seed);
    let depth = (0..batch * size * size)
        .map(|_| rng.uniform(0.6, 0.75))
        .collect();
    let pose = (0..batch * pose_inputs)
        .map(|i| match i % pose_inputs {
            0 => rng.uniform(0.6, 0.75),
            _ => rng.uniform(0.0, 1.57),
        })
        .collect();
    Ok((
        Tensor::new(&[batch, 1, size, size], depth)?,
        Tensor::new(&[batch, pose_inputs], pose)?,
    ))
}

/// How fast a network scored one batch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Timing {
    /// Timed calls.
    pub calls: usize,
    /// The median call, seconds.
    pub median_s: f64,
    /// The mean probability of the last call.
    pub mean_p: f64,
}

impl Timing {
    /// Crops scored per second at the median call.
    pub fn crops_per_s(&self, batch: usize) -> f64 {
        batch as f64 / self.median_s
    }
}

/// Times `net.predict` on a seeded batch of `batch` crops: a warm-up of `warmup_s` (at least 2
/// calls), then calls until `seconds` have passed and at least 5 were made, on the threads of
/// the caller's rayon pool and the network's own parallelism.
///
/// # Errors
/// A failed prediction.
pub fn time_gqcnn(
    net: &Gqcnn,
    batch: usize,
    seed: u64,
    (warmup_s, seconds): (f64, f64),
) -> Result<Timing> {
    let arch = net.architecture();
    let (depth, pose) = gqcnn_inputs(batch, arch.image_size_px, arch.pose_inputs, seed)?;
    let mut workspace = GqcnnWorkspace::default();
    let mut p = Vec::new();
    let warm = Instant::now();
    for i in 0.. {
        if i >= 2 && warm.elapsed().as_secs_f64() >= warmup_s {
            break;
        }
        p = net.predict(&depth, &pose, &mut workspace)?;
    }
    let mut times = Vec::new();
    let started = Instant::now();
    while times.len() < 5 || started.elapsed().as_secs_f64() < seconds {
        let t = Instant::now();
        p = net.predict(&depth, &pose, &mut workspace)?;
        times.push(t.elapsed().as_secs_f64());
    }
    let mean_p = p.iter().map(|&v| f64::from(v)).sum::<f64>() / batch.max(1) as f64;
    Ok(Timing {
        calls: times.len(),
        median_s: median(times),
        mean_p,
    })
}

/// The median of `values` (NaN for none).
pub fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    let n = values.len();
    match n {
        0 => f64::NAN,
        _ if n % 2 == 1 => values[n / 2],
        _ => 0.5 * (values[n / 2 - 1] + values[n / 2]),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inputs_are_the_scripts_numbers_in_their_ranges() {
        let (depth, pose) = gqcnn_inputs(3, 4, 2, 0).unwrap();
        assert_eq!(depth.shape(), &[3, 1, 4, 4]);
        assert_eq!(pose.shape(), &[3, 2]);
        assert!(depth.data().iter().all(|d| (0.6..0.75).contains(d)));
        for row in pose.data().chunks(2) {
            assert!((0.6..0.75).contains(&row[0]) && (0.0..1.57).contains(&row[1]));
        }
        // SplitMix64 from 0: the first output is 0xE220A8397B1DCDAF (the reference values).
        let first = (0xE220_A839_7B1D_CDAF_u64 >> 11) as f64 / (1u64 << 53) as f64;
        assert_eq!(depth.data()[0], (0.6 + 0.15 * first) as f32);
        assert_eq!(gqcnn_inputs(3, 4, 2, 0).unwrap().0.data(), depth.data());
        assert_ne!(gqcnn_inputs(3, 4, 2, 1).unwrap().0.data(), depth.data());
    }

    #[test]
    fn the_median_of_even_and_odd_counts() {
        assert_eq!(median(vec![3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(vec![4.0, 1.0, 2.0, 3.0]), 2.5);
        assert!(median(Vec::new()).is_nan());
    }
}
