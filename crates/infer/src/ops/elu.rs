//! ELU: `x` where positive, `alpha * (exp(x) - 1)` elsewhere.

use crate::tensor::Tensor;

/// ELU in place (torch's `nn.ELU(alpha)`): `x` for `x > 0`, else `alpha * (exp(x) - 1)`,
/// computed with `exp_m1` so small negative inputs keep their precision.
pub fn elu(x: &mut Tensor, alpha: f32) {
    for v in x.data_mut() {
        if *v <= 0.0 {
            *v = alpha * v.exp_m1();
        }
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    #[test]
    fn elu_matches_its_definition() {
        let mut x = Tensor::new(&[4], vec![-2.0, -1e-8, 0.0, 3.0]).unwrap();
        elu(&mut x, 1.5);
        let want = [1.5 * ((-2f64).exp() - 1.0), 1.5 * -1e-8, 0.0, 3.0];
        for (&got, want) in x.data().iter().zip(want) {
            assert!(
                (f64::from(got) - want).abs() <= 1e-7 * want.abs().max(1e-8),
                "{got} vs {want}"
            );
        }
    }

    #[test]
    fn elu_tends_to_minus_alpha() {
        let mut x = Tensor::new(&[1], vec![-100.0]).unwrap();
        elu(&mut x, 0.5);
        assert_eq!(x.data(), [-0.5]);
    }
}
