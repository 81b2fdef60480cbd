//! numpy arrays in: any numeric dtype, either memory order, one image `(rows, cols)` or a batch
//! `(n, rows, cols)`. A C-contiguous float64 array is read in place; anything else is converted once by
//! numpy (`ascontiguousarray(x, dtype=float64)`).

use numpy::{PyReadonlyArrayDyn, PyUntypedArrayMethods};
use presrs::core::{FrameView, Grid};
use pyo3::prelude::*;
use pyo3::types::PyString;

use crate::errors::data_error;

/// Images borrowed from a numpy array (kept alive and read-only for as long as this lives).
pub struct Images<'py> {
    array: PyReadonlyArrayDyn<'py, f64>,
    grid: Grid,
    count: usize,
    /// Whether the input was a batch `(n, rows, cols)` rather than one image.
    pub batch: bool,
    /// Whether the input was an array of Python objects (its `None`s read as NaN).
    object: bool,
}

impl<'py> Images<'py> {
    /// The images of `obj` (`what` names the argument in errors).
    pub fn new(obj: &Bound<'py, PyAny>, what: &str) -> PyResult<Self> {
        if obj.is_none() {
            return Err(data_error(format!(
                "{what}: expected a numpy array of images, got None"
            )));
        }
        let (array, object) = float64_c_array(obj, what)?;
        let shape = array.shape().to_vec();
        let (count, rows, cols, batch) = match shape[..] {
            [rows, cols] => (1, rows, cols, false),
            [n, rows, cols] => (n, rows, cols, true),
            _ => {
                return Err(data_error(format!(
                    "{what}: expected one image (rows, cols) or a batch (n, rows, cols), got an \
                     array of shape {shape:?}"
                )));
            }
        };
        if rows == 0 || cols == 0 {
            return Err(data_error(format!(
                "{what}: images of {rows} x {cols} sensels are empty (shape {shape:?})"
            )));
        }
        Ok(Self {
            array,
            grid: Grid::new(rows, cols),
            count,
            batch,
            object,
        })
    }

    pub fn grid(&self) -> Grid {
        self.grid
    }

    pub fn len(&self) -> usize {
        self.count
    }

    /// Every value, image after image, row-major.
    pub fn values(&self) -> &[f64] {
        // float64_c_array made the array C-contiguous.
        self.array.as_slice().unwrap_or(&[])
    }

    /// Image `index`, borrowed.
    pub fn frame(&self, index: usize) -> PyResult<FrameView<'_>> {
        frame_view(self.values(), self.grid, index)
    }

    /// Every image, borrowed.
    pub fn frames(&self) -> PyResult<Vec<FrameView<'_>>> {
        (0..self.count).map(|index| self.frame(index)).collect()
    }

    /// An error naming the first value that is not a finite number (image, row and column, 0-based),
    /// or `None` when every value is one. `image` names an image in the message (`image 7`,
    /// `frame 7`).
    pub fn non_finite(&self, what: &str, image: &str) -> Option<PyErr> {
        let size = self.grid.len();
        let at = self.values().iter().position(|v| !v.is_finite())?;
        let value = self.values()[at];
        let (index, within) = (at / size, at % size);
        let (row, col) = (within / self.grid.cols, within % self.grid.cols);
        let place = if self.batch {
            format!("{image} {index}, row {row}, col {col}")
        } else {
            format!("row {row}, col {col}")
        };
        Some(data_error(format!(
            "{what}: {place} (0-based) is {value}{}; every value must be a finite number",
            if self.object {
                " (a missing value in an array of dtype object)"
            } else {
                ""
            }
        )))
    }

    /// `Ok` when every value is a finite number, else the error of [`Images::non_finite`].
    pub fn require_finite(&self, what: &str, image: &str) -> PyResult<()> {
        self.non_finite(what, image).map_or(Ok(()), Err)
    }
}

/// Image `index` of contiguous `values` of `grid`-sized images.
pub fn frame_view(values: &[f64], grid: Grid, index: usize) -> PyResult<FrameView<'_>> {
    let size = grid.len();
    let values = values
        .get(index * size..(index + 1) * size)
        .ok_or_else(|| data_error(format!("image {index} is past the end of the array")))?;
    FrameView::new(grid, values, None).map_err(|err| data_error(err.to_string()))
}

/// `obj` as a C-contiguous float64 array: as it is when it already is one, else converted by numpy;
/// with whether it was an array of Python objects. Complex numbers, strings and other non-numbers are
/// a `DataError` naming `what`.
fn float64_c_array<'py>(
    obj: &Bound<'py, PyAny>,
    what: &str,
) -> PyResult<(PyReadonlyArrayDyn<'py, f64>, bool)> {
    if let Ok(array) = obj.extract::<PyReadonlyArrayDyn<'py, f64>>()
        && array.is_c_contiguous()
    {
        return Ok((array, false));
    }
    let py = obj.py();
    let numpy = py.import("numpy")?;
    let kind: Option<String> = obj
        .getattr("dtype")
        .and_then(|dtype| dtype.getattr("kind"))
        .and_then(|kind| kind.extract())
        .ok();
    if let Some(kind) = kind.as_deref()
        && !matches!(kind, "b" | "i" | "u" | "f" | "O")
    {
        let dtype = obj.getattr("dtype")?.str()?.to_string();
        return Err(data_error(format!(
            "{what}: expected numbers (any integer, unsigned or float dtype), got an array of dtype \
             {dtype}"
        )));
    }
    if obj.is_instance_of::<PyString>() {
        return Err(data_error(format!(
            "{what}: expected a numpy array of numbers, got a string"
        )));
    }
    let converted = numpy
        .getattr("ascontiguousarray")?
        .call1((obj, numpy.getattr("float64")?))
        .map_err(|err| {
            data_error(format!(
                "{what}: expected a numpy array of numbers ({})",
                err.value(py)
            ))
        })?;
    let object = kind.as_deref() == Some("O");
    let array = converted
        .extract::<PyReadonlyArrayDyn<'py, f64>>()
        .map_err(|err| data_error(format!("{what}: cannot read as float64 numbers ({err})")))?;
    Ok((array, object))
}

/// Text labels from any sequence (a list, a numpy array, a pandas Series): each item as `str(item)`.
pub fn labels(obj: &Bound<'_, PyAny>, what: &str, expected: usize) -> PyResult<Vec<String>> {
    if obj.is_instance_of::<PyString>() {
        return Err(data_error(format!(
            "{what}: expected a sequence of labels, got one string"
        )));
    }
    let mut out = Vec::with_capacity(expected);
    for item in obj.try_iter()? {
        let item = item?;
        out.push(item.str()?.to_string());
    }
    if out.len() != expected {
        return Err(data_error(format!(
            "{what}: {} values for {expected} images; give one per image",
            out.len()
        )));
    }
    Ok(out)
}
