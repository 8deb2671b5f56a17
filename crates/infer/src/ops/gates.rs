//! The gates of recurrent cells: the logistic sigmoid and tanh.

use crate::tensor::Tensor;

/// Beyond this the logistic sigmoid is taken as exactly 0 (below `-SATURATED`) or 1 (above,
/// where f32 rounds it to 1 anyway): `exp(-40)` is 4.2e-18.
const SATURATED: f32 = 40.0;

/// `1 / (1 + exp(-x))` in place (torch's `sigmoid`), written so that neither a large positive
/// nor a large negative input overflows. Saturated inputs (|x| > 40) give exactly 0 or 1: an
/// `exp` that comes out subnormal, and the products a tiny gate then enters, cost x86 a
/// microcode assist each (a trained LSM's GRU gates saturate, and its fusion ran twice as slow
/// on them); the value differs from torch's by at most 4.2e-18.
pub fn sigmoid(x: &mut Tensor) {
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

/// `tanh(x)` in place (torch's `tanh`).
pub fn tanh(x: &mut Tensor) {
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
        let mut x = Tensor::new(&[5], vec![0.0, 2.0, -2.0, 100.0, -100.0]).unwrap();
        sigmoid(&mut x);
        let e2 = 1.0 / (1.0 + (-2.0f32).exp());
        assert_eq!(x.data()[0], 0.5);
        assert!((x.data()[1] - e2).abs() < 1e-7 && (x.data()[2] - (1.0 - e2)).abs() < 1e-7);
        assert_eq!((x.data()[3], x.data()[4]), (1.0, 0.0));
        // Saturated: exactly 0 or 1 past |x| = 40, the formula's value just inside.
        let mut edge = Tensor::new(&[3], vec![-39.9, -40.1, 40.1]).unwrap();
        sigmoid(&mut edge);
        assert!(
            edge.data()[0].is_normal() && edge.data()[0] < 5e-18,
            "{:?}",
            edge.data()
        );
        assert_eq!((edge.data()[1], edge.data()[2]), (0.0, 1.0));
        let mut t = Tensor::new(&[3], vec![0.0, 0.5, -30.0]).unwrap();
        tanh(&mut t);
        assert_eq!(t.data(), [0.0, 0.5f32.tanh(), -1.0]);
    }
}
