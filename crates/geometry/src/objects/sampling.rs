//! The seeded random source of the object library, with rounding that keeps manifests readable.

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::category::Category;

/// The random source of one object, seeded from `(seed, category, index)` only, so an object
/// does not depend on how many others are generated.
pub(crate) struct Sampler {
    rng: ChaCha8Rng,
}

/// SplitMix64's finaliser: a bijective mix of 64 bits.
fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

impl Sampler {
    /// The sampler of object `index` of `category` under the library seed `seed`.
    pub(crate) fn for_object(seed: u64, category: Category, index: u32) -> Self {
        let h = mix(mix(mix(seed) ^ category.seed_salt()) ^ u64::from(index));
        Self {
            rng: ChaCha8Rng::seed_from_u64(h),
        }
    }

    /// Uniform in `[lo, hi)` (or `lo` when the range is empty), unrounded.
    pub(crate) fn uniform(&mut self, lo: f32, hi: f32) -> f32 {
        let u: f32 = self.rng.random();
        if hi > lo { lo + (hi - lo) * u } else { lo }
    }

    /// A length in metres, uniform in `[lo, hi]`, rounded to 0.1 mm.
    pub(crate) fn length_m(&mut self, lo: f32, hi: f32) -> f32 {
        round_to(self.uniform(lo, hi), 1e4).clamp(lo.min(hi), hi.max(lo))
    }

    /// A ratio or an angle, uniform in `[lo, hi]`, rounded to 0.001.
    pub(crate) fn ratio(&mut self, lo: f32, hi: f32) -> f32 {
        round_to(self.uniform(lo, hi), 1e3).clamp(lo.min(hi), hi.max(lo))
    }

    /// True with probability `p`.
    pub(crate) fn chance(&mut self, p: f32) -> bool {
        self.uniform(0.0, 1.0) < p
    }

    /// An index in `0..n` (0 when `n` is 0).
    pub(crate) fn pick(&mut self, n: usize) -> usize {
        let i = (self.uniform(0.0, n as f32)) as usize;
        i.min(n.saturating_sub(1))
    }

    /// An integer in `lo..=hi`.
    pub(crate) fn int(&mut self, lo: u32, hi: u32) -> u32 {
        lo + self.pick((hi.saturating_sub(lo) + 1) as usize) as u32
    }
}

/// `x` rounded to a multiple of `1 / per_unit`, computed so that the result is the float
/// nearest the decimal (it prints short).
fn round_to(x: f32, per_unit: f32) -> f32 {
    (x * per_unit).round() / per_unit
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samplers_depend_on_every_part_of_the_key() {
        let draw = |seed, c, i| Sampler::for_object(seed, c, i).uniform(0.0, 1.0);
        let base = draw(0, Category::Mug, 0);
        assert_eq!(base, draw(0, Category::Mug, 0));
        assert_ne!(base, draw(1, Category::Mug, 0));
        assert_ne!(base, draw(0, Category::Bowl, 0));
        assert_ne!(base, draw(0, Category::Mug, 1));
    }

    #[test]
    fn rounded_values_stay_in_range_and_print_short() {
        let mut s = Sampler::for_object(7, Category::Box, 3);
        for _ in 0..200 {
            let x = s.length_m(0.03, 0.07);
            assert!((0.03..=0.07).contains(&x));
            assert!(x.to_string().len() <= 6, "{x}");
            let k = s.int(2, 5);
            assert!((2..=5).contains(&k));
        }
    }
}
