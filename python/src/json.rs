//! JSON values to Python objects and back, through pythonize (serde for pyo3): the stream's events and
//! the evaluation's report become plain dicts and lists, as `json.loads` would give them (ints stay
//! ints, floats floats, objects dicts in their order); keyword arguments become JSON values that the
//! parameters' own deserialisers then check.

use pyo3::prelude::*;
use pyo3::types::PyFloat;
use serde_json::Value;

use crate::errors::data_error;

/// `value` as Python `None`, `bool`, `int`, `float`, `str`, `list` or `dict`.
pub fn to_py<'py>(py: Python<'py>, value: &Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(pythonize::pythonize(py, value)?)
}

/// A Python value (`None`, `bool`, `int`, `float`, `str`, or lists and dicts of them; numpy scalars
/// as `float`) as a JSON value. NaN and the infinities are refused here: JSON has none, and
/// serde_json would quietly turn them into `null`.
pub fn from_py(obj: &Bound<'_, PyAny>) -> PyResult<Value> {
    if let Ok(x) = obj.cast::<PyFloat>() {
        let x = x.value();
        if !x.is_finite() {
            return Err(data_error(format!("{x} is not a finite number")));
        }
    }
    match pythonize::depythonize::<Value>(obj) {
        Ok(value) => Ok(value),
        // numpy scalars and other numbers: through float, as `float(obj)` would.
        Err(err) => match obj.extract::<f64>() {
            Ok(x) => from_py(&PyFloat::new(obj.py(), x).into_any()),
            Err(_) => Err(data_error(format!(
                "cannot use a {} as a parameter value ({err})",
                obj.get_type().name()?
            ))),
        },
    }
}
