//! ReLU: `max(x, 0)`.

use crate::tensor::Tensor;

/// `max(x, 0)` in place (torch's `nn.ReLU`; NaN stays NaN).
pub fn relu(x: &mut Tensor) {
    // A select, not a branch: it vectorises, and signs at random would mispredict half the time.
    for v in x.data_mut() {
        *v = if *v < 0.0 { 0.0 } else { *v };
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    #[test]
    fn relu_clamps_negatives() {
        let mut x = Tensor::new(&[4], vec![-1.0, 0.0, 2.0, f32::NAN]).unwrap();
        relu(&mut x);
        assert_eq!(x.data()[..3], [0.0, 0.0, 2.0]);
        assert!(x.data()[3].is_nan(), "torch propagates NaN");
    }
}
