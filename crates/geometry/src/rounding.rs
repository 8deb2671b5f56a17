//! Rounding without libm calls, to the bit of `f32::floor` and `f32::round`: the workspace is
//! built for baseline x86-64, where `floorf` and `roundf` are calls, and the planner's inner
//! loops (nine samples a crop pixel, two roundings a point of a virtual crop, two a cell and view
//! of the space carving) spent a sixth to a third of their time in them; the plane sweep's
//! consistency check rounds two coordinates a pixel and view. Each is tested against
//! the libm form over halves, their neighbours and sweeps.

/// `x.floor()` for a finite `x`, the same value to the bit. Values of 2^23 or more are integers
/// already.
#[inline]
pub fn floor(x: f32) -> f32 {
    if x.abs() >= 8_388_608.0 {
        return x;
    }
    let t = (x as i32 as f32).copysign(x);
    if t > x { t - 1.0 } else { t }
}

/// `x.round() as i64`: truncation, then away from zero where the (exactly computed) fraction is
/// a half or more. Values of 2^23 or more (and NaN, as `as` takes it: 0) go through `as` alone.
#[inline]
pub fn round(x: f32) -> i64 {
    if x.is_nan() || x.abs() >= 8_388_608.0 {
        return x as i64;
    }
    let t = x as i64;
    let fraction = x - t as f32;
    t + i64::from(fraction >= 0.5) - i64::from(fraction <= -0.5)
}

/// `x.round()` as an index below `size`, or `None` where it falls outside `0..size` or `x` is
/// not a number.
#[inline]
pub fn rounded_index(x: f32, size: usize) -> Option<usize> {
    let r = round(x);
    (!x.is_nan() && r >= 0 && (r as usize) < size).then_some(r as usize)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn floor_is_floorf_to_the_bit() {
        let mut values = vec![
            0.0f32,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            1.5,
            -1.5,
            2.999_999_8,
            -2.999_999_8,
            8_388_607.5,
            -8_388_607.5,
            8_388_608.0,
            -8_388_609.0,
            1e20,
            -1e20,
            f32::MAX,
            f32::MIN,
            f32::MIN_POSITIVE,
            -f32::MIN_POSITIVE,
            1e-45,
            -1e-45,
        ];
        // A sweep over the image range at odd steps, and every power-of-two neighbourhood.
        values.extend((0..200_000).map(|i| -1000.0 + i as f32 * 0.010_007));
        for e in -30..40 {
            let p = 2.0f32.powi(e);
            values.extend([
                p,
                -p,
                p.next_up(),
                p.next_down(),
                -p.next_up(),
                -p.next_down(),
            ]);
        }
        for x in values {
            assert_eq!(floor(x).to_bits(), x.floor().to_bits(), "floor({x})");
        }
    }

    #[test]
    fn round_is_roundf_to_the_bit() {
        let mut values = vec![
            0.0f32,
            -0.0,
            0.5,
            -0.5,
            1.5,
            -1.5,
            2.5,
            -2.5,
            0.499_999_97,
            -0.499_999_97,
            8_388_607.5,
            -8_388_607.5,
            8_388_608.0,
            1e12,
            -1e12,
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
        ];
        for k in -2000..2000 {
            let half = k as f32 * 0.5;
            values.extend([half, half.next_down(), half.next_up()]);
        }
        let mut x = 0.123_456_7f32;
        for _ in 0..100_000 {
            x = (x * 7919.0 + 0.618_034).rem_euclid(1500.0) - 750.0;
            values.push(x);
        }
        for x in values {
            assert_eq!(round(x), x.round() as i64, "{x}");
        }
    }

    #[test]
    fn rounded_index_is_round_to_the_bit() {
        let reference = |x: f32, size: usize| {
            let r = x.round();
            (r >= 0.0 && r < size as f32).then_some(r as usize)
        };
        let mut values = vec![
            -0.5f32,
            -0.499_999_97,
            -0.0,
            0.0,
            0.499_999_97,
            0.5,
            1.5,
            2.5,
            31.499_998,
            31.5,
            32.0,
            -1.0,
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            1e30,
            -1e30,
        ];
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        values.extend((0..200_000).map(|_| rng.random_range(-3.0f32..35.0)));
        // Exact halves and their neighbours.
        for k in -4..70 {
            let half = k as f32 * 0.5;
            values.extend([half, half.next_down(), half.next_up()]);
        }
        for x in values {
            assert_eq!(rounded_index(x, 32), reference(x, 32), "{x}");
        }
    }
}
