//! Helpers the integration tests share: a seeded generator and closeness checks.

#![allow(dead_code, clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use mvgrasp_infer::Tensor;
use mvgrasp_infer::bench::SplitMix64;

/// SplitMix64 (`mvgrasp_infer::bench::SplitMix64`): small, seeded, the same numbers on every
/// platform.
pub struct Rng(SplitMix64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Self(SplitMix64(seed))
    }

    fn next_u64(&mut self) -> u64 {
        self.0.next_u64()
    }

    /// A tensor of `shape` with values uniform in `[-scale, scale)`.
    pub fn tensor(&mut self, shape: &[usize], scale: f32) -> Tensor {
        let data = (0..shape.iter().product::<usize>())
            .map(|_| {
                let unit = (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32;
                scale * (2.0 * unit - 1.0)
            })
            .collect();
        Tensor::new(shape, data).unwrap()
    }
}

/// Panics unless both tensors have one shape and agree within `tol * max(1, |want|)`.
pub fn assert_close(got: &Tensor, want: &Tensor, tol: f32) {
    assert_eq!(got.shape(), want.shape(), "shapes differ");
    for (i, (&g, &w)) in got.data().iter().zip(want.data()).enumerate() {
        assert!(
            (g - w).abs() <= tol * w.abs().max(1.0),
            "value {i}: got {g}, want {w}"
        );
    }
}

/// Panics unless both tensors are the same to the bit.
pub fn assert_same_bits(got: &Tensor, want: &Tensor) {
    assert_eq!(got.shape(), want.shape(), "shapes differ");
    let bits = |t: &Tensor| t.data().iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    assert!(bits(got) == bits(want), "values differ");
}
