//! Rust errors as Python exceptions. The classes live in `presrs/errors.py` (they need two bases each,
//! which only Python can declare): `FileError(PresrsError, OSError)` when the operating system refused
//! a file, `DataError(PresrsError, ValueError)` for everything else. Each carries the Rust message, with
//! the file, line and field it names, and the options it names spelled as Python's arguments
//! (`per_class=`, not the command line's `--per-class`).

use presrs::{Face, Warning};
use pyo3::prelude::*;

/// The Python exception for a presrs error.
pub fn to_py(err: presrs::Error) -> PyErr {
    let message = err.render(Face::Python);
    match err.io_kind() {
        Some(kind) => raise("FileError", message, Some(kind)),
        None => raise("DataError", message, None),
    }
}

/// A Python `UserWarning` saying `warning` in Python's words.
pub fn warn(py: Python<'_>, warning: &Warning) -> PyResult<()> {
    py.import("warnings")?
        .call_method1("warn", (warning.render(Face::Python),))?;
    Ok(())
}

/// A `DataError` with `message`: the input does not fit (a shape, a value, an option).
pub fn data_error(message: impl Into<String>) -> PyErr {
    raise("DataError", message.into(), None)
}

fn raise(class: &str, message: String, kind: Option<std::io::ErrorKind>) -> PyErr {
    Python::attach(|py| {
        let made = (|| -> PyResult<PyErr> {
            let class = py.import("presrs.errors")?.getattr(class)?;
            let exception = class.call1((message.clone(),))?;
            if let Some(errno) = kind.and_then(errno_of) {
                exception.setattr("errno", errno)?;
            }
            Ok(PyErr::from_value(exception))
        })();
        // Without presrs.errors (a broken install), still a ValueError with the message.
        made.unwrap_or_else(|_| pyo3::exceptions::PyValueError::new_err(message))
    })
}

/// The POSIX errno of the common file errors, so `except FileNotFoundError`-style checks on `errno`
/// work.
fn errno_of(kind: std::io::ErrorKind) -> Option<i32> {
    use std::io::ErrorKind::*;
    Some(match kind {
        NotFound => 2,
        PermissionDenied => 13,
        AlreadyExists => 17,
        IsADirectory => 21,
        NotADirectory => 20,
        _ => return None,
    })
}

/// `.map_err(to_py)` for results of the library.
pub trait IntoPyResult<T> {
    fn py_err(self) -> PyResult<T>;
}

impl<T, E: Into<presrs::Error>> IntoPyResult<T> for Result<T, E> {
    fn py_err(self) -> PyResult<T> {
        self.map_err(|err| to_py(err.into()))
    }
}
