//! numpy arrays in: any numeric dtype, either memory order, one image `(rows, cols)` or a batch
//! `(n, rows, cols)`. A C-contiguous float64 array is read in place; anything else is converted once by
//! numpy (`ascontiguousarray(x, dtype=float64)`).

use numpy::{PyReadonlyArrayDyn, PyUntypedArrayMethods};
use presrs::core::{FrameView, Grid};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyString};

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
/// A missing label (`None`, NaN, pandas' `NA`, empty or blank text) is refused, as the command line
/// refuses a manifest row without one: the error names the first index and how many are missing.
pub fn labels(obj: &Bound<'_, PyAny>, what: &str, expected: usize) -> PyResult<Vec<String>> {
    let items = texts(obj, what, expected)?;
    let missing: Vec<usize> = (items.iter().enumerate())
        .filter(|(_, item)| item.is_missing())
        .map(|(index, _)| index)
        .collect();
    if let Some(&first) = missing.first() {
        return Err(data_error(format!(
            "{what}[{first}] is {}: every sample needs a label ({} of {} labels missing: None, \
             NaN, empty or blank{})",
            items[first].shown,
            missing.len(),
            items.len(),
            listed_indices(&missing)
        )));
    }
    Ok(items.into_iter().map(|item| item.text).collect())
}

/// Text values that may be missing, one per sample (groups, conditions): each item as `str(item)`,
/// and a missing one (`None`, NaN, pandas' `NA`, empty or blank text) as no value, as an empty
/// manifest field is.
pub fn optional_labels(
    obj: &Bound<'_, PyAny>,
    what: &str,
    expected: usize,
) -> PyResult<Vec<Option<String>>> {
    Ok(texts(obj, what, expected)?
        .into_iter()
        .map(|item| (!item.is_missing()).then_some(item.text))
        .collect())
}

/// An item of a sequence of labels: its text, and how an error shows it when it is missing.
struct LabelItem {
    text: String,
    /// `None`, `NaN` or the text's `repr`, set when the item is missing; empty otherwise.
    shown: String,
}

impl LabelItem {
    fn is_missing(&self) -> bool {
        !self.shown.is_empty()
    }
}

/// Every item of `obj` as text, with the missing ones marked; `expected` items, one per sample.
fn texts(obj: &Bound<'_, PyAny>, what: &str, expected: usize) -> PyResult<Vec<LabelItem>> {
    if obj.is_instance_of::<PyString>() {
        return Err(data_error(format!(
            "{what}: expected a sequence of labels, got one string"
        )));
    }
    let mut out = Vec::with_capacity(expected);
    for item in obj.try_iter()? {
        out.push(label_item(&item?)?);
    }
    if out.len() != expected {
        return Err(data_error(format!(
            "{what}: {} values for {expected} samples; give one per sample",
            out.len()
        )));
    }
    Ok(out)
}

/// One label's text, marked missing when it is `None`, a NaN (Python's, numpy's, a `Decimal`'s),
/// pandas' `NA` or `NaT`, or text that is empty or blank.
fn label_item(item: &Bound<'_, PyAny>) -> PyResult<LabelItem> {
    let missing = |shown: &str, text: String| LabelItem {
        text,
        shown: shown.to_owned(),
    };
    if item.is_none() {
        return Ok(missing("None", String::new()));
    }
    // pandas' missing values, named by their types (pandas need not be installed).
    let type_name = item.get_type().name()?.to_string();
    if matches!(type_name.as_str(), "NAType" | "NaTType") {
        return Ok(missing(&item.str()?.to_string(), String::new()));
    }
    // A NaN of any type is the one value unequal to itself (no conversion, so no numpy warning).
    let is_text = item.is_instance_of::<PyString>() || item.is_instance_of::<PyBytes>();
    let unequal = || item.ne(item).unwrap_or(false);
    if !is_text && unequal() {
        return Ok(missing("NaN", String::new()));
    }
    let text = item.str()?.to_string();
    if text.trim().is_empty() {
        let shown = item.repr()?.to_string();
        return Ok(missing(&shown, text));
    }
    Ok(LabelItem {
        text,
        shown: String::new(),
    })
}

/// `: indices 3, 7, 9` (the first few, `...` after them) when more than one index is missing.
fn listed_indices(indices: &[usize]) -> String {
    const SHOWN: usize = 5;
    if indices.len() < 2 {
        return String::new();
    }
    let mut listed: Vec<String> = indices.iter().take(SHOWN).map(usize::to_string).collect();
    if indices.len() > SHOWN {
        listed.push("...".to_owned());
    }
    format!("; at indices {}", listed.join(", "))
}

/// `presrs._native._check_labels(values, what)`: the text of every label, or the error of a missing
/// one, for callers that keep the values themselves (the scikit-learn estimator's `y`).
#[pyfunction]
#[pyo3(name = "_check_labels")]
pub fn check_labels(values: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<String>> {
    labels(values, what, values.len()?)
}
