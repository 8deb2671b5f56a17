//! A dense, row-major f32 tensor: the value every op takes and returns.

use crate::error::{InferError, Result};

/// A dense row-major f32 tensor (NCHW for images, as torch).
///
/// The default tensor is empty (shape `[0]`): a ready output buffer for the ops' `_into` forms,
/// which give it the shape they need and keep its allocation from call to call.
#[derive(Clone)]
pub struct Tensor {
    shape: Vec<usize>,
    /// The values in `data[..len]`; past them, values of an earlier, larger shape, kept so that
    /// a buffer that shrinks and grows again (as a model's intermediates do, layer by layer and
    /// call by call) is not zero-filled each time it grows.
    data: Vec<f32>,
    len: usize,
}

impl Default for Tensor {
    fn default() -> Self {
        Self {
            shape: vec![0],
            data: Vec::new(),
            len: 0,
        }
    }
}

impl PartialEq for Tensor {
    /// Same shape and values.
    fn eq(&self, other: &Self) -> bool {
        self.shape == other.shape && self.data() == other.data()
    }
}

impl std::fmt::Debug for Tensor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Tensor")
            .field("shape", &self.shape)
            .field("data", &self.data())
            .finish()
    }
}

impl Tensor {
    /// A tensor of `shape` holding `data` in row-major order.
    ///
    /// # Errors
    /// [`InferError::DataLength`] when `data` does not fill `shape` exactly.
    pub fn new(shape: &[usize], data: Vec<f32>) -> Result<Self> {
        let expected = shape.iter().product::<usize>();
        if data.len() != expected {
            return Err(InferError::DataLength {
                op: "tensor",
                shape: shape.to_vec(),
                expected,
                got: data.len(),
            });
        }
        Ok(Self {
            shape: shape.to_vec(),
            len: data.len(),
            data,
        })
    }

    /// A tensor of zeros.
    pub fn zeros(shape: &[usize]) -> Self {
        Self::full(shape, 0.0)
    }

    /// A tensor with every value `value`.
    pub fn full(shape: &[usize], value: f32) -> Self {
        let len = shape.iter().product();
        Self {
            shape: shape.to_vec(),
            data: vec![value; len],
            len,
        }
    }

    /// The shape.
    pub fn shape(&self) -> &[usize] {
        &self.shape
    }

    /// The number of axes.
    pub fn rank(&self) -> usize {
        self.shape.len()
    }

    /// The number of values (the product of the shape).
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether the tensor holds no values.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The values, row-major.
    pub fn data(&self) -> &[f32] {
        &self.data[..self.len]
    }

    /// The values, row-major, mutable.
    pub fn data_mut(&mut self) -> &mut [f32] {
        &mut self.data[..self.len]
    }

    /// The values, row-major, by value.
    pub fn into_data(mut self) -> Vec<f32> {
        self.data.truncate(self.len);
        self.data
    }

    /// Gives the tensor a new shape with the same number of values, in place (torch's
    /// `reshape` of a contiguous tensor; `[N, C, H, W]` to `[N, C * H * W]` flattens as torch
    /// does).
    ///
    /// # Errors
    /// [`InferError::DataLength`] when `shape` needs another number of values.
    pub fn reshape(&mut self, shape: &[usize]) -> Result<()> {
        let expected = shape.iter().product::<usize>();
        if expected != self.len {
            return Err(InferError::DataLength {
                op: "reshape",
                shape: shape.to_vec(),
                expected,
                got: self.len,
            });
        }
        self.shape.clear();
        self.shape.extend_from_slice(shape);
        Ok(())
    }

    /// Gives the tensor `shape`, keeping its allocation when that is big enough: how the ops'
    /// `_into` forms size their output. The values afterwards are unspecified (old values, of
    /// this shape or an earlier one, or zeros); the ops overwrite every one.
    pub fn resize(&mut self, shape: &[usize]) {
        self.shape.clear();
        self.shape.extend_from_slice(shape);
        self.len = shape.iter().product();
        if self.data.len() < self.len {
            self.data.resize(self.len, 0.0);
        }
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    #[test]
    fn tensors_check_their_length() {
        let err = Tensor::new(&[2, 3], vec![0.0; 5]).unwrap_err();
        assert!(err.to_string().contains("[2, 3]"), "{err}");
    }

    #[test]
    fn reshape_keeps_the_values_and_checks_the_count() {
        let mut t = Tensor::new(&[1, 2, 2, 1], vec![1.0, 2.0, 3.0, 4.0]).unwrap();
        t.reshape(&[1, 4]).unwrap();
        assert_eq!(t.shape(), [1, 4]);
        assert_eq!(t.data(), [1.0, 2.0, 3.0, 4.0]);
        assert!(t.reshape(&[3]).is_err());
        assert_eq!(
            t.shape(),
            [1, 4],
            "a failed reshape leaves the tensor alone"
        );
    }

    #[test]
    fn resize_reuses_the_allocation() {
        let mut t = Tensor::zeros(&[4, 4]);
        let before = t.data().as_ptr();
        t.resize(&[2, 3]);
        assert_eq!((t.shape(), t.len()), (&[2, 3][..], 6));
        assert_eq!(t.data().as_ptr(), before);
        assert!(Tensor::default().is_empty());
    }

    #[test]
    fn a_shrunk_tensor_shows_only_its_values() {
        let mut t = Tensor::new(&[4], vec![1.0, 2.0, 3.0, 4.0]).unwrap();
        t.resize(&[2]);
        assert_eq!((t.len(), t.data()), (2, &[1.0, 2.0][..]));
        assert_eq!(t, Tensor::new(&[2], vec![1.0, 2.0]).unwrap());
        assert!(format!("{t:?}").ends_with("data: [1.0, 2.0] }"), "{t:?}");
        assert!(
            t.reshape(&[4]).is_err(),
            "the old values are not the tensor's"
        );
        assert_eq!(t.clone().into_data(), [1.0, 2.0]);
        t.resize(&[3]);
        assert_eq!(t.len(), 3);
    }
}
