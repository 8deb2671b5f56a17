//! Conversions of Rust values to Python objects.

use pyo3::IntoPyObjectExt;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use serde::Serialize;
use serde::de::DeserializeOwned;
use serde_json::Value;

/// A serialisable Rust value (a shard record, a manifest) as Python dicts, lists, strings and
/// numbers: the same structure as its JSON file, without JSON text crossing the binding.
pub(crate) fn to_python<'py, T: Serialize>(
    py: Python<'py>,
    value: &T,
) -> PyResult<Bound<'py, PyAny>> {
    let value = serde_json::to_value(value)
        .map_err(|e| pyo3::exceptions::PyValueError::new_err(e.to_string()))?;
    json_to_python(py, &value)
}

fn json_to_python<'py>(py: Python<'py>, value: &Value) -> PyResult<Bound<'py, PyAny>> {
    match value {
        Value::Null => Ok(py.None().into_bound(py)),
        Value::Bool(b) => b.into_bound_py_any(py),
        Value::Number(n) => match (n.as_i64(), n.as_u64(), n.as_f64()) {
            (Some(i), _, _) => i.into_bound_py_any(py),
            (None, Some(u), _) => u.into_bound_py_any(py),
            (None, None, f) => f.unwrap_or(f64::NAN).into_bound_py_any(py),
        },
        Value::String(s) => s.into_bound_py_any(py),
        Value::Array(items) => {
            let list = PyList::empty(py);
            for item in items {
                list.append(json_to_python(py, item)?)?;
            }
            Ok(list.into_any())
        }
        Value::Object(map) => {
            let dict = PyDict::new(py);
            for (key, item) in map {
                dict.set_item(key, json_to_python(py, item)?)?;
            }
            Ok(dict.into_any())
        }
    }
}

/// `defaults` with the fields of a Python dict put over them (nested dicts merged into nested
/// structs), for settings given as `params={...}`. Raises `ValueError` naming `name` and the
/// key for a key the settings do not have, a value of the wrong type, or a non-dict.
pub(crate) fn from_python<T: Serialize + DeserializeOwned>(
    name: &str,
    value: &Bound<'_, PyAny>,
    defaults: &T,
) -> PyResult<T> {
    let py = value.py();
    let text: String = py
        .import("json")?
        .call_method1("dumps", (value,))
        .map_err(|e| PyValueError::new_err(format!("{name}: not JSON-like: {e}")))?
        .extract()?;
    let given: Value =
        serde_json::from_str(&text).map_err(|e| PyValueError::new_err(format!("{name}: {e}")))?;
    let mut merged =
        serde_json::to_value(defaults).map_err(|e| PyValueError::new_err(e.to_string()))?;
    merge(name, &mut merged, given)?;
    serde_json::from_value(merged).map_err(|e| PyValueError::new_err(format!("{name}: {e}")))
}

/// Puts `given`'s keys over `base`'s, recursively; every key must be one `base` has.
fn merge(path: &str, base: &mut Value, given: Value) -> PyResult<()> {
    let (Value::Object(base), Value::Object(given)) = (&mut *base, &given) else {
        if given.is_object() {
            return Err(PyValueError::new_err(format!(
                "{path}: a dict where a value is expected"
            )));
        }
        if base.is_object() {
            return Err(PyValueError::new_err(format!(
                "{path}: expected a dict of settings"
            )));
        }
        *base = given;
        return Ok(());
    };
    for (key, value) in given.clone() {
        let Some(slot) = base.get_mut(&key) else {
            let mut known: Vec<&String> = base.keys().collect();
            known.sort();
            return Err(PyValueError::new_err(format!(
                "{path}: unknown key {key:?} (known: {})",
                known
                    .iter()
                    .map(|k| k.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            )));
        };
        if slot.is_null() {
            // An optional setting that is off by default: take the value as given.
            *slot = value;
        } else {
            merge(&format!("{path}.{key}"), slot, value)?;
        }
    }
    Ok(())
}
