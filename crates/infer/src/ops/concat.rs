//! Concatenation of tensors along one axis.

use crate::error::{InferError, Result};
use crate::ops::check::shape_error;
use crate::tensor::Tensor;

/// The output shape of concatenating `inputs` along `axis`, checked.
fn output_shape(inputs: &[&Tensor], axis: usize) -> Result<Vec<usize>> {
    const OP: &str = "concat";
    let Some(first) = inputs.first() else {
        return Err(InferError::InvalidParameter {
            op: OP,
            name: "inputs",
            value: "[]".into(),
            expected: "at least one tensor",
        });
    };
    if axis >= first.rank() {
        return Err(InferError::AxisOutOfRange {
            op: OP,
            axis,
            rank: first.rank(),
        });
    }
    let mut shape = first.shape().to_vec();
    shape[axis] = 0;
    for x in inputs {
        let fits = x.rank() == shape.len()
            && x.shape()
                .iter()
                .zip(&shape)
                .enumerate()
                .all(|(i, (a, b))| i == axis || a == b);
        if !fits {
            let mut expected = format!("{:?}", first.shape());
            expected.push_str(&format!(" with any size along axis {axis}"));
            return Err(shape_error(OP, expected, x.shape()));
        }
        shape[axis] += x.shape()[axis];
    }
    Ok(shape)
}

/// Concatenation of `inputs` along `axis` (torch's `cat`) into a new tensor.
///
/// # Errors
/// As [`concat_into`].
pub fn concat(inputs: &[&Tensor], axis: usize) -> Result<Tensor> {
    let mut out = Tensor::default();
    concat_into(inputs, axis, &mut out)?;
    Ok(out)
}

/// [`concat()`] into `out`, which is resized and keeps its allocation. `out` must not be one of
/// the inputs (the borrow checker sees to it).
///
/// # Errors
/// [`InferError::InvalidParameter`] for no inputs, [`InferError::AxisOutOfRange`] for an axis
/// beyond the first input's rank, [`InferError::ShapeMismatch`] when an input's rank or size
/// off the axis differs from the first's.
pub fn concat_into(inputs: &[&Tensor], axis: usize, out: &mut Tensor) -> Result<()> {
    let shape = output_shape(inputs, axis)?;
    out.resize(&shape);
    // Row-major: the axes before `axis` count the blocks; each input adds one run a block.
    let blocks: usize = shape[..axis].iter().product();
    let inner: usize = shape[axis + 1..].iter().product();
    let y = out.data_mut();
    let mut at = 0;
    for block in 0..blocks {
        for x in inputs {
            let run = x.shape()[axis] * inner;
            y[at..at + run].copy_from_slice(&x.data()[block * run..(block + 1) * run]);
            at += run;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;
    use crate::testing::Rng;

    /// The row-major multi-index of flat position `i` in `shape`.
    fn unravel(mut i: usize, shape: &[usize]) -> Vec<usize> {
        let mut index = vec![0; shape.len()];
        for (d, &size) in shape.iter().enumerate().rev() {
            index[d] = i % size;
            i /= size;
        }
        index
    }

    fn ravel(index: &[usize], shape: &[usize]) -> usize {
        index
            .iter()
            .zip(shape)
            .fold(0, |flat, (&i, &size)| flat * size + i)
    }

    #[test]
    fn every_value_lands_where_its_index_says() {
        let mut rng = Rng::new(41);
        for axis in 0..3 {
            let mut shapes = vec![vec![2, 3, 4]; 3];
            for (k, shape) in shapes.iter_mut().enumerate() {
                shape[axis] = k + 1;
            }
            let inputs: Vec<Tensor> = shapes.iter().map(|s| rng.tensor(s)).collect();
            let refs: Vec<&Tensor> = inputs.iter().collect();
            let out = concat(&refs, axis).unwrap();
            for (i, &got) in out.data().iter().enumerate() {
                let mut index = unravel(i, out.shape());
                let mut k = 0;
                while index[axis] >= inputs[k].shape()[axis] {
                    index[axis] -= inputs[k].shape()[axis];
                    k += 1;
                }
                assert_eq!(got, inputs[k].data()[ravel(&index, inputs[k].shape())]);
            }
        }
    }

    #[test]
    fn channels_of_two_images() {
        let a = Tensor::new(&[1, 1, 1, 2], vec![1.0, 2.0]).unwrap();
        let b = Tensor::new(&[1, 2, 1, 2], vec![3.0, 4.0, 5.0, 6.0]).unwrap();
        let y = concat(&[&a, &b], 1).unwrap();
        assert_eq!(y.shape(), [1, 3, 1, 2]);
        assert_eq!(y.data(), [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
    }

    #[test]
    fn mismatches_are_errors() {
        let a = Tensor::zeros(&[2, 3]);
        assert!(matches!(
            concat(&[], 0),
            Err(InferError::InvalidParameter { .. })
        ));
        assert!(matches!(
            concat(&[&a], 2),
            Err(InferError::AxisOutOfRange {
                axis: 2,
                rank: 2,
                ..
            })
        ));
        let err = concat(&[&a, &Tensor::zeros(&[3, 3])], 1).unwrap_err();
        assert!(err.to_string().contains("[3, 3]"), "{err}");
        assert!(concat(&[&a, &Tensor::zeros(&[2, 3, 1])], 1).is_err());
        assert_eq!(
            concat(&[&a, &Tensor::zeros(&[2, 0])], 1).unwrap().shape(),
            [2, 3]
        );
    }
}
