//! Test helpers: a small seeded generator and a closeness check (tests only).

#![allow(clippy::panic)]

use crate::tensor::Tensor;

/// SplitMix64 ([`crate::bench::SplitMix64`]): small, seeded, the same numbers on every
/// platform.
pub(crate) struct Rng(crate::bench::SplitMix64);

impl Rng {
    pub(crate) fn new(seed: u64) -> Self {
        Self(crate::bench::SplitMix64(seed))
    }

    pub(crate) fn next_u64(&mut self) -> u64 {
        self.0.next_u64()
    }

    /// Uniform in `[lo, hi)`.
    pub(crate) fn uniform(&mut self, lo: f32, hi: f32) -> f32 {
        let unit = (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32;
        lo + (hi - lo) * unit
    }

    /// Uniform in `lo..=hi`.
    pub(crate) fn range(&mut self, lo: usize, hi: usize) -> usize {
        lo + (self.next_u64() % (hi - lo + 1) as u64) as usize
    }

    /// A tensor of `shape` with values uniform in `[-1, 1)`.
    pub(crate) fn tensor(&mut self, shape: &[usize]) -> Tensor {
        self.tensor_in(shape, -1.0, 1.0)
    }

    /// A tensor of `shape` with values uniform in `[lo, hi)`.
    pub(crate) fn tensor_in(&mut self, shape: &[usize], lo: f32, hi: f32) -> Tensor {
        let data = (0..shape.iter().product::<usize>())
            .map(|_| self.uniform(lo, hi))
            .collect();
        match Tensor::new(shape, data) {
            Ok(t) => t,
            Err(e) => panic!("{e}"),
        }
    }
}

/// Panics unless `got` and `want` have one shape and every value agrees within
/// `1e-4 * max(1, |want|)`.
pub(crate) fn assert_close(got: &Tensor, want: &Tensor) {
    assert_eq!(got.shape(), want.shape(), "shapes differ");
    for (i, (&g, &w)) in got.data().iter().zip(want.data()).enumerate() {
        let ok = (g - w).abs() <= 1e-4 * w.abs().max(1.0) || (g.is_nan() && w.is_nan()) || g == w;
        assert!(ok, "value {i}: got {g}, want {w}");
    }
}

/// Panics unless `got` and `want` are the same to the bit (shape and every value).
pub(crate) fn assert_same_bits(got: &Tensor, want: &Tensor, context: &str) {
    assert_eq!(got.shape(), want.shape(), "{context}: shapes differ");
    let differ = got
        .data()
        .iter()
        .zip(want.data())
        .position(|(g, w)| g.to_bits() != w.to_bits());
    if let Some(i) = differ {
        panic!(
            "{context}: value {i} differs: {} vs {}",
            got.data()[i],
            want.data()[i]
        );
    }
}
