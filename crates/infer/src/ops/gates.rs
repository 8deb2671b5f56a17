//! The gates of recurrent cells: the logistic sigmoid and tanh.

use crate::tensor::Tensor;

/// `1 / (1 + exp(-x))` in place (torch's `sigmoid`), written so that neither a large positive
/// nor a large negative input overflows.
pub fn sigmoid(x: &mut Tensor) {
    for v in x.data_mut() {
        *v = if *v >= 0.0 {
            1.0 / (1.0 + (-*v).exp())
        } else {
            let e = v.exp();
            e / (1.0 + e)
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
        assert_eq!(x.data()[3], 1.0);
        assert!((0.0..1e-40).contains(&x.data()[4]), "{}", x.data()[4]);
        let mut t = Tensor::new(&[3], vec![0.0, 0.5, -30.0]).unwrap();
        tanh(&mut t);
        assert_eq!(t.data(), [0.0, 0.5f32.tanh(), -1.0]);
    }
}
