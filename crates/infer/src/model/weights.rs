//! Named tensors from a safetensors file, checked against the shapes a model expects.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use safetensors::{Dtype, SafeTensors};

use crate::error::{InferError, Result};
use crate::tensor::Tensor;

/// A JSON parser's message with its line breaks and control characters escaped (an unknown
/// key quotes the file's bytes): errors are printed one per line.
fn one_line(error: &serde_json::Error) -> String {
    let text = error.to_string();
    text.chars()
        .map(|c| {
            if c.is_control() {
                c.escape_default().to_string()
            } else {
                c.to_string()
            }
        })
        .collect()
}

/// The tensors of one safetensors file, as f32.
#[derive(Debug)]
pub struct Weights {
    tensors: HashMap<String, Tensor>,
    path: PathBuf,
}

impl Weights {
    /// Reads every tensor of the file (F32, or F64/F16... refused by name).
    ///
    /// # Errors
    /// [`InferError::Model`] naming the file when it cannot be read or is not safetensors
    /// (truncated, corrupt header); [`InferError::Weight`] for a tensor that is not float32.
    pub fn load(path: &Path) -> Result<Self> {
        let bytes = std::fs::read(path).map_err(|e| InferError::Model {
            detail: format!("cannot read: {e}"),
            path: path.to_path_buf(),
        })?;
        Self::from_bytes(&bytes, path)
    }

    /// Reads every tensor of a safetensors file held in memory; `path` names it in errors.
    ///
    /// # Errors
    /// As [`Weights::load`].
    pub fn from_bytes(bytes: &[u8], path: &Path) -> Result<Self> {
        let model_error = |detail: String| InferError::Model {
            detail,
            path: path.to_path_buf(),
        };
        let file = SafeTensors::deserialize(bytes)
            .map_err(|e| model_error(format!("not a safetensors file: {e}")))?;
        let mut tensors = HashMap::new();
        for (name, view) in file.tensors() {
            if view.dtype() != Dtype::F32 {
                return Err(InferError::Weight {
                    name,
                    detail: format!("dtype {:?}, expected F32", view.dtype()),
                    path: path.to_path_buf(),
                });
            }
            let data: Vec<f32> = view
                .data()
                .chunks_exact(4)
                .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                .collect();
            let tensor = Tensor::new(view.shape(), data).map_err(|e| InferError::Weight {
                name: name.clone(),
                detail: e.to_string(),
                path: path.to_path_buf(),
            })?;
            tensors.insert(name, tensor);
        }
        Ok(Self {
            tensors,
            path: path.to_path_buf(),
        })
    }

    /// Replaces every subnormal value (magnitude below `f32::MIN_POSITIVE`, about 1.2e-38) by
    /// a zero of its sign. Training with weight decay leaves many such weights (a third of a
    /// trained GQ-CNN's first fully connected layer), and on x86 each product with one that
    /// gives a subnormal result takes a microcode assist, some hundred times a plain multiply:
    /// a trained network ran three times slower than the same one with random weights. The
    /// products they would add are below 1.2e-38 times an activation, invisible in any sum
    /// that is not itself that small.
    pub(crate) fn flush_subnormals(&mut self) {
        for tensor in self.tensors.values_mut() {
            for v in tensor.data_mut() {
                if v.is_subnormal() {
                    *v = 0.0f32.copysign(*v);
                }
            }
        }
    }

    /// The file they came from.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Takes the tensor `name`, whatever its shape (inputs and outputs stored beside weights,
    /// as the parity fixtures do).
    ///
    /// # Errors
    /// [`InferError::Weight`] naming the tensor when it is missing.
    pub fn take_any(&mut self, name: &str) -> Result<Tensor> {
        self.tensors.remove(name).ok_or_else(|| InferError::Weight {
            name: name.to_string(),
            detail: "missing".into(),
            path: self.path.clone(),
        })
    }

    /// Takes the tensor `name`, which must have `shape`.
    ///
    /// # Errors
    /// [`InferError::Weight`] naming the tensor when it is missing or its shape differs.
    pub fn take(&mut self, name: &str, shape: &[usize]) -> Result<Tensor> {
        let weight_error = |detail: String| InferError::Weight {
            name: name.to_string(),
            detail,
            path: self.path.clone(),
        };
        let tensor = self
            .tensors
            .remove(name)
            .ok_or_else(|| weight_error("missing".into()))?;
        if tensor.shape() != shape {
            return Err(weight_error(format!(
                "shape {:?}, expected {shape:?}",
                tensor.shape()
            )));
        }
        Ok(tensor)
    }

    /// Names of tensors not taken yet, sorted (a model checks there are none left over).
    pub fn remaining(&self) -> Vec<&str> {
        let mut names: Vec<&str> = self.tensors.keys().map(String::as_str).collect();
        names.sort_unstable();
        names
    }
}

/// The text of a model's description `json`.
pub(crate) fn read_description(json: &Path) -> Result<String> {
    std::fs::read_to_string(json).map_err(|e| InferError::Model {
        detail: e.to_string(),
        path: json.to_path_buf(),
    })
}

/// The path of a file a description names, beside the description.
pub(crate) fn beside(json: &Path, name: &str) -> PathBuf {
    json.parent().unwrap_or(Path::new(".")).join(name)
}

/// A description of `kind` ("GQ-CNN") parsed from `text`, its `format` field checked against
/// `format`; errors name `json`.
pub(crate) fn parse_description<T: serde::de::DeserializeOwned>(
    text: &str,
    json: &Path,
    kind: &str,
    format: &str,
    format_of: impl Fn(&T) -> &str,
) -> Result<T> {
    let model_error = |detail: String| InferError::Model {
        detail,
        path: json.to_path_buf(),
    };
    let description: T = serde_json::from_str(text)
        .map_err(|e| model_error(format!("not {kind} description: {}", one_line(&e))))?;
    if format_of(&description) != format {
        return Err(model_error(format!(
            "format {:?}, expected {format:?}",
            format_of(&description)
        )));
    }
    Ok(description)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    #[test]
    fn subnormal_weights_are_flushed_to_signed_zeros() {
        let values = [1e-41f32, -1e-41, f32::MIN_POSITIVE, -0.5, 0.0, 3.0e-39];
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        let view = safetensors::tensor::TensorView::new(Dtype::F32, vec![6], &bytes).unwrap();
        let file = safetensors::serialize([("w", view)], None).unwrap();
        let mut weights = Weights::from_bytes(&file, Path::new("w.safetensors")).unwrap();
        weights.flush_subnormals();
        let w = weights.take("w", &[6]).unwrap();
        let bits: Vec<u32> = w.data().iter().map(|v| v.to_bits()).collect();
        let want = [0.0f32, -0.0, f32::MIN_POSITIVE, -0.5, 0.0, 0.0];
        assert_eq!(bits, want.map(f32::to_bits));
    }
}
