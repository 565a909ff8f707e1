//! Values across the boundary: JSON values (metrics, summaries) to Python objects, Python objects
//! (keyword arguments, overrides) to TOML values, and the resolution a caller names.

use amorph::voxel::GridDims;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};

/// A JSON value as the Python object `json.loads` would give.
pub fn json_to_py<'py>(py: Python<'py>, value: &serde_json::Value) -> PyResult<Bound<'py, PyAny>> {
    use serde_json::Value;
    Ok(match value {
        Value::Null => py.None().into_bound(py),
        Value::Bool(b) => PyBool::new(py, *b).to_owned().into_any(),
        Value::Number(n) => match (n.as_i64(), n.as_u64()) {
            (Some(i), _) => i.into_pyobject(py)?.into_any(),
            (None, Some(u)) => u.into_pyobject(py)?.into_any(),
            _ => PyFloat::new(py, n.as_f64().unwrap_or(f64::NAN)).into_any(),
        },
        Value::String(s) => PyString::new(py, s).into_any(),
        Value::Array(items) => {
            let list = PyList::empty(py);
            for item in items {
                list.append(json_to_py(py, item)?)?;
            }
            list.into_any()
        }
        Value::Object(map) => {
            let dict = PyDict::new(py);
            for (k, v) in map {
                dict.set_item(k, json_to_py(py, v)?)?;
            }
            dict.into_any()
        }
    })
}

/// A Python value as TOML: bool, int, float, str, lists and dicts of them. `key` names it in the
/// error a value of another type raises.
pub fn py_to_toml(value: &Bound<'_, PyAny>, key: &str) -> PyResult<toml::Value> {
    if value.is_instance_of::<PyBool>() {
        return Ok(toml::Value::Boolean(value.extract()?));
    }
    if value.is_instance_of::<PyInt>() {
        let i: i64 = value
            .extract()
            .map_err(|_| PyValueError::new_err(format!("{key} = {value}: out of range")))?;
        return Ok(toml::Value::Integer(i));
    }
    if value.is_instance_of::<PyFloat>() {
        return Ok(toml::Value::Float(value.extract()?));
    }
    if let Ok(s) = value.cast::<PyString>() {
        return Ok(toml::Value::String(s.extract()?));
    }
    if let Ok(path) = value.extract::<std::path::PathBuf>() {
        return Ok(toml::Value::String(path.display().to_string()));
    }
    if let Ok(dict) = value.cast::<PyDict>() {
        let mut table = toml::Table::new();
        for (k, v) in dict.iter() {
            let k: String = k
                .extract()
                .map_err(|_| PyValueError::new_err(format!("{key}: every key must be a str")))?;
            let inner = py_to_toml(&v, &format!("{key}.{k}"))?;
            table.insert(k, inner);
        }
        return Ok(toml::Value::Table(table));
    }
    if value.is_instance_of::<PyList>() || value.is_instance_of::<PyTuple>() {
        let items = value
            .try_iter()?
            .enumerate()
            .map(|(i, item)| py_to_toml(&item?, &format!("{key}[{i}]")))
            .collect::<PyResult<Vec<_>>>()?;
        return Ok(toml::Value::Array(items));
    }
    // numpy scalars and anything else that is a number.
    if let Ok(f) = value
        .call_method0("__float__")
        .and_then(|f| f.extract::<f64>())
    {
        return Ok(toml::Value::Float(f));
    }
    Err(PyValueError::new_err(format!(
        "{key} = {value}: expected a bool, number, str, list or dict"
    )))
}

/// A resolution given as `"6x20x6"` or `(6, 20, 6)`, within the grid limits every task obeys.
pub fn resolution(value: &Bound<'_, PyAny>) -> PyResult<GridDims> {
    if let Ok(text) = value.extract::<String>() {
        return amorph_worker::parse_resolution(&text)
            .map_err(|e| PyValueError::new_err(format!("resolution: {e}")));
    }
    let counts: Vec<u64> = value.extract().map_err(|_| {
        PyValueError::new_err(format!(
            "resolution = {value}: expected \"NXxNYxNZ\" or a tuple of three positive ints"
        ))
    })?;
    let text = counts
        .iter()
        .map(u64::to_string)
        .collect::<Vec<_>>()
        .join("x");
    amorph_worker::parse_resolution(&text)
        .map_err(|e| PyValueError::new_err(format!("resolution: {e}")))
}
