//! The gates of recurrent cells: the logistic sigmoid and tanh.

use crate::tensor::Tensor;

/// Beyond this the logistic sigmoid is taken as exactly 0 (below `-SATURATED`) or 1 (above,
/// where f32 rounds it to 1 anyway): `exp(-40)` is 4.2e-18.
const SATURATED: f32 = 40.0;

/// `1 / (1 + exp(-x))` in place (torch's `sigmoid`), within 2e-7 of the exact value (relative
/// error under 1e-6; tested over the whole range). Saturated inputs (|x| > 40) give exactly 0
/// or 1: an `exp` that comes out subnormal, and the products a tiny gate then enters, cost x86
/// a microcode assist each (a trained LSM's GRU gates saturate, and its fusion ran twice as
/// slow on them); the value differs from torch's by at most 4.2e-18. The loop has no branch
/// and no call ([`exp`]), so that it runs four or eight values at a time: the libm calls of
/// [`sigmoid_reference`] were a tenth of the LSM's time.
pub fn sigmoid(x: &mut Tensor) {
    for v in x.data_mut() {
        let clamped = v.clamp(-SATURATED, SATURATED);
        let s = 1.0 / (1.0 + exp(-clamped));
        *v = if *v > SATURATED {
            1.0
        } else if *v < -SATURATED {
            0.0
        } else {
            s
        };
    }
}

/// `tanh(x)` in place (torch's `tanh`), within 2e-7 of the exact value (tested over the whole
/// range), branch- and call-free as [`sigmoid`]: an odd polynomial below |x| = 0.625 (Cephes'
/// `tanhf`), `1 - 2 / (exp(2 |x|) + 1)` with the sign above, exactly +-1 past |x| = 10.
#[allow(clippy::excessive_precision)] // Cephes' coefficients as published
pub fn tanh(x: &mut Tensor) {
    for v in x.data_mut() {
        let a = v.abs().min(10.0);
        let z = a * a;
        let small = ((((-5.704_988_7e-3 * z + 2.063_908_9e-2) * z - 5.373_971_6e-2) * z
            + 1.333_144_2e-1)
            * z
            - 3.333_328_2e-1)
            * z
            * a
            + a;
        let large = 1.0 - 2.0 / (exp(2.0 * a) + 1.0);
        let t = if a < 0.625 { small } else { large };
        *v = if v.is_nan() {
            *v
        } else if v.abs() >= 10.0 {
            1.0f32.copysign(*v)
        } else {
            t.copysign(*v)
        };
    }
}

/// `exp(x)` for |x| <= 88 (Cephes' `expf`: `x = n ln 2 + r`, a degree-6 polynomial in r, `2^n`
/// put into the exponent bits), written with no branch or call so that loops over it
/// vectorise.
#[inline(always)]
#[allow(clippy::excessive_precision)] // Cephes' coefficients as published
fn exp(x: f32) -> f32 {
    const LN2_HI: f32 = 0.693_359_4;
    const LN2_LO: f32 = -2.121_944_4e-4;
    // Round to nearest by the 1.5 * 2^23 trick (no SSE4 rounding instruction on the baseline).
    const ROUND: f32 = 12_582_912.0;
    let n = (x * std::f32::consts::LOG2_E + ROUND) - ROUND;
    let r = x - n * LN2_HI - n * LN2_LO;
    let p = (((((1.987_569_1e-4 * r + 1.398_199_9e-3) * r + 8.333_452e-3) * r + 4.166_579_6e-2)
        * r
        + 1.666_666_5e-1)
        * r
        + 5.000_000_1e-1)
        * r
        * r
        + r
        + 1.0;
    // |n| <= 127 for |x| <= 88: a normal power of two.
    let scale = f32::from_bits((((n as i32) + 127) as u32) << 23);
    p * scale
}

/// [`sigmoid`] by the formula on libm's `exp`: what the fast one is tested against, and the
/// reference GRU step's.
pub fn sigmoid_reference(x: &mut Tensor) {
    for v in x.data_mut() {
        *v = if *v > SATURATED {
            1.0
        } else if *v >= 0.0 {
            1.0 / (1.0 + (-*v).exp())
        } else if *v > -SATURATED {
            let e = v.exp();
            e / (1.0 + e)
        } else {
            0.0
        };
    }
}

/// [`tanh`] by libm's `tanhf`: what the fast one is tested against, and the reference GRU
/// step's.
pub fn tanh_reference(x: &mut Tensor) {
    for v in x.data_mut() {
        *v = v.tanh();
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    #[test]
    fn known_values_and_no_overflow() {
        for (gate, name) in [
            (sigmoid as fn(&mut Tensor), "fast"),
            (sigmoid_reference, "reference"),
        ] {
            let mut x = Tensor::new(&[5], vec![0.0, 2.0, -2.0, 100.0, -100.0]).unwrap();
            gate(&mut x);
            let e2 = 1.0 / (1.0 + (-2.0f32).exp());
            assert_eq!(x.data()[0], 0.5, "{name}");
            assert!((x.data()[1] - e2).abs() < 1e-7 && (x.data()[2] - (1.0 - e2)).abs() < 1e-7);
            assert_eq!((x.data()[3], x.data()[4]), (1.0, 0.0), "{name}");
            // Saturated: exactly 0 or 1 past |x| = 40, the formula's value just inside.
            let mut edge = Tensor::new(&[3], vec![-39.9, -40.1, 40.1]).unwrap();
            gate(&mut edge);
            assert!(
                edge.data()[0].is_normal() && edge.data()[0] < 5e-18,
                "{name}: {:?}",
                edge.data()
            );
            assert_eq!((edge.data()[1], edge.data()[2]), (0.0, 1.0), "{name}");
        }
        for (gate, name) in [
            (tanh as fn(&mut Tensor), "fast"),
            (tanh_reference, "reference"),
        ] {
            let mut t = Tensor::new(&[5], vec![0.0, -0.0, 30.0, -30.0, f32::NAN]).unwrap();
            gate(&mut t);
            assert_eq!(t.data()[..4], [0.0, -0.0, 1.0, -1.0], "{name}");
            assert!(
                t.data()[1].is_sign_negative() && t.data()[4].is_nan(),
                "{name}"
            );
        }
        let mut nan = Tensor::new(&[1], vec![f32::NAN]).unwrap();
        sigmoid(&mut nan);
        assert!(nan.data()[0].is_nan());
    }

    /// The fast gates against the exact value (f64) at a million points over the range that
    /// matters and past it, and against the libm forms: within 2e-7 absolute and 1e-6
    /// relative (a few units in the last place).
    #[test]
    fn fast_gates_are_within_a_few_ulp() {
        let xs: Vec<f32> = (0..=1_000_000)
            .map(|i| -50.0 + 100.0 * i as f32 / 1e6)
            .chain([
                1e-30, -1e-7, 1e-3, 0.624_999, 0.625, 9.999, 10.0, 40.0, -40.0,
            ])
            .collect();
        let exact: [fn(f64) -> f64; 2] = [|x| 1.0 / (1.0 + (-x).exp()), f64::tanh];
        let fast: [fn(&mut Tensor); 2] = [sigmoid, tanh];
        let reference: [fn(&mut Tensor); 2] = [sigmoid_reference, tanh_reference];
        for g in 0..2 {
            let mut got = Tensor::new(&[xs.len()], xs.clone()).unwrap();
            fast[g](&mut got);
            let mut libm = got.clone();
            libm.data_mut().copy_from_slice(&xs);
            reference[g](&mut libm);
            for ((&x, &y), &l) in xs.iter().zip(got.data()).zip(libm.data()) {
                let want = exact[g](f64::from(x));
                let err = (f64::from(y) - want).abs();
                // Past |x| = 40 the sigmoid is exactly 0 or 1 (documented): absolute error only.
                let relative = if g == 0 && x.abs() > 40.0 { 1.0 } else { 1e-6 };
                assert!(
                    err <= 2e-7 && err <= relative * want.abs() + 1e-30,
                    "gate {g} at {x}: {y} against {want}"
                );
                assert!(
                    (y - l).abs() <= 2e-7,
                    "gate {g} at {x}: {y} against libm's {l}"
                );
            }
        }
    }
}
