//! Python values to scene values and back.

use dalembert::SceneValue;
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyFloat, PyInt, PyList, PyString, PyTuple};

/// A scene value from a Python number, string, bool or list/tuple of those.
pub fn scene_value(v: &Bound<'_, PyAny>, path: &str) -> PyResult<SceneValue> {
    if v.is_instance_of::<PyBool>() {
        return Ok(SceneValue::Flag(v.extract()?));
    }
    if v.is_instance_of::<PyInt>() {
        return Ok(match v.extract::<i64>() {
            Ok(i) => SceneValue::Integer(i),
            Err(_) => SceneValue::Number(v.extract::<f64>()?),
        });
    }
    if v.is_instance_of::<PyFloat>() {
        return Ok(SceneValue::Number(v.extract()?));
    }
    if v.is_instance_of::<PyString>() {
        return Ok(SceneValue::Text(v.extract()?));
    }
    if v.is_instance_of::<PyList>() || v.is_instance_of::<PyTuple>() {
        let items: Vec<Bound<'_, PyAny>> = v.try_iter()?.collect::<PyResult<_>>()?;
        return Ok(SceneValue::List(
            items.iter().map(|x| scene_value(x, path)).collect::<PyResult<_>>()?,
        ));
    }
    // numpy scalars and other numbers.
    if let Ok(x) = v.extract::<f64>() {
        return Ok(SceneValue::Number(x));
    }
    Err(PyTypeError::new_err(format!(
        "{path}: a scene value is a number, a string, a bool or a list of them, got {}",
        v.get_type().name()?
    )))
}
