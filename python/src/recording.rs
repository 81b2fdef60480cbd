//! `presrs.read`, `presrs.Recording`, `presrs.segment` and `presrs.features`: recordings as numpy
//! arrays, their stance phases, and feature vectors.

use std::path::PathBuf;
use std::str::FromStr;

use numpy::{PyArray1, PyArray3, PyArrayMethods};
use presrs::core::features::FeatureConfig;
use presrs::core::pipeline::extract_features_many;
use presrs::core::preprocess::Preprocess;
use presrs::core::stance::{SampleFrame, SegmentParams, Stance as CoreStance, ValidSegmentParams};
use presrs::core::{Recording as CoreRecording, SensorMeta};
use presrs::io::{ArrayAxes, ReadOptions, read_recording_with};
use presrs::{CropChoice, Face, Warnings};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::arrays::Images;
use crate::errors::{IntoPyResult, data_error, warn};
use crate::threads::detached;

/// A recording: frames of one pressure array, with what the file says about the sensor.
#[pyclass(module = "presrs", name = "Recording", frozen)]
#[derive(Debug)]
pub struct Recording {
    pub recording: CoreRecording,
    /// The file it was read from (`None` for one made from an array).
    path: Option<PathBuf>,
    /// What the reader had to say (a truncated last frame dropped, a header value kept verbatim).
    warnings: Warnings,
}

impl Recording {
    pub fn of(recording: CoreRecording, path: Option<PathBuf>, warnings: Warnings) -> Self {
        Self {
            recording,
            path,
            warnings,
        }
    }
}

#[pymethods]
impl Recording {
    /// A recording from frames `(n, rows, cols)` (or one image `(rows, cols)`), e.g. from a driver
    /// or another reader. `frame_period_s`: seconds between frames, when known.
    #[new]
    #[pyo3(signature = (frames, *, frame_period_s = None))]
    fn new(frames: &Bound<'_, PyAny>, frame_period_s: Option<f64>) -> PyResult<Self> {
        let images = Images::new(frames, "frames")?;
        if let Some(period) = frame_period_s
            && !(period.is_finite() && period > 0.0)
        {
            return Err(data_error(format!(
                "frame_period_s={period}: give the seconds between frames (> 0), or None"
            )));
        }
        let recording = CoreRecording::new(
            images.grid(),
            frame_period_s,
            images.values().to_vec(),
            None,
            SensorMeta::default(),
        )
        .py_err()?;
        Ok(Self::of(recording, None, Warnings::new()))
    }

    /// The frames, float64 `(n_frames, rows, cols)`, in the file's unit (a new array each time).
    #[getter]
    fn frames<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray3<f64>>> {
        let grid = self.recording.grid();
        let n = self.recording.frame_count();
        PyArray1::from_slice(py, self.recording.data()).reshape([n, grid.rows, grid.cols])
    }

    /// Absent sensels (outside the sensor's outline): boolean `(rows, cols)`, True where absent.
    #[getter]
    fn mask<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let grid = self.recording.grid();
        let absent: Vec<bool> = match self.recording.present() {
            Some(present) => present.iter().map(|&here| !here).collect(),
            None => vec![false; grid.len()],
        };
        Ok(PyArray1::from_vec(py, absent)
            .reshape([grid.rows, grid.cols])?
            .into_any())
    }

    /// Seconds between frames, or None when the file states no rate.
    #[getter]
    fn frame_period_s(&self) -> Option<f64> {
        self.recording.frame_period_s()
    }

    /// The unit of the values (`raw`, `KPa`, `MPa`, `PSI`, or as the file wrote it).
    #[getter]
    fn units(&self) -> String {
        self.recording.meta.units_or_raw().to_string()
    }

    /// Whether the file stated its unit (else the values are taken as raw counts).
    #[getter]
    fn units_stated(&self) -> bool {
        self.recording.meta.units.is_some()
    }

    /// The sensor: model, sensel pitch (mm), full scale and noise threshold, as far as the file says.
    #[getter]
    fn sensor<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let meta = &self.recording.meta;
        let sensor = PyDict::new(py);
        sensor.set_item("model", meta.sensor.clone())?;
        sensor.set_item("row_pitch_mm", meta.row_pitch_mm)?;
        sensor.set_item("col_pitch_mm", meta.col_pitch_mm)?;
        sensor.set_item("full_scale", meta.full_scale)?;
        sensor.set_item("noise_threshold", meta.noise_threshold)?;
        Ok(sensor)
    }

    /// `(rows, cols)` of every frame.
    #[getter]
    fn shape(&self) -> (usize, usize) {
        let grid = self.recording.grid();
        (grid.rows, grid.cols)
    }

    /// The file it was read from (None for one made from an array or simulated).
    #[getter]
    fn path(&self) -> Option<PathBuf> {
        self.path.clone()
    }

    /// What the reader reported without failing (each names the file and line).
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.warnings.render(Face::Python)
    }

    /// The total load of every frame (sum over present sensels), float64 `(n_frames,)`.
    fn total_load<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_vec(py, self.recording.total_per_frame())
    }

    fn __len__(&self) -> usize {
        self.recording.frame_count()
    }

    fn __repr__(&self) -> String {
        let grid = self.recording.grid();
        let rate = self.recording.frame_period_s().map_or_else(
            || "rate unknown".to_owned(),
            |p| format!("{:.1} Hz", 1.0 / p),
        );
        let name = self
            .path
            .as_ref()
            .map_or_else(|| "in memory".to_owned(), |p| p.display().to_string());
        format!(
            "<presrs.Recording {name}: {} frames of {grid}, {}, {rate}>",
            self.recording.frame_count(),
            self.recording.meta.units_or_raw()
        )
    }
}

/// Reads a recording in any format the CLI reads (TekScan ASCII, NPY, PNG, MCAP bags, text matrices),
/// told apart by content. `lenient`: drop a truncated last frame (with a warning) instead of failing.
/// `axes`: what the axes of a 3-D `.npy` are, in the file's order (`"rows,cols,frames"` for an array
/// whose time axis is last; default `"frames,rows,cols"`). `topic`: the topic of an MCAP file (a ROS 2
/// bag) to read (default: the only topic holding frames).
#[pyfunction]
#[pyo3(signature = (path, *, lenient = false, axes = None, topic = None))]
pub fn read(
    py: Python<'_>,
    path: PathBuf,
    lenient: bool,
    axes: Option<&str>,
    topic: Option<String>,
) -> PyResult<Recording> {
    let axes = array_axes(axes)?;
    let options = ReadOptions {
        lenient,
        axes,
        topic,
    };
    let parsed = detached(py, || read_recording_with(&path, &options))?.py_err()?;
    for warning in &parsed.warnings {
        warn(py, warning)?;
    }
    Ok(Recording::of(parsed.recording, Some(path), parsed.warnings))
}

/// `axes=`: what the axes of a 3-D `.npy` are (`None`: frames, rows, cols).
pub fn array_axes(axes: Option<&str>) -> PyResult<Option<ArrayAxes>> {
    axes.map(|text| {
        text.parse::<ArrayAxes>()
            .map_err(|err| data_error(format!("axes={text:?}: {err}")))
    })
    .transpose()
}

/// One stance phase (foot contact) of a recording; frames are 0-based.
#[pyclass(module = "presrs", name = "Stance", frozen, get_all)]
#[derive(Clone, Debug)]
pub struct Stance {
    /// First loaded frame (touchdown, unless partial).
    start: usize,
    /// Frames from touchdown to lift-off, inclusive.
    length: usize,
    /// One past the last frame.
    end: usize,
    /// The frame a classifier would take (the `sample` asked for; the mid-stance frame by default).
    sample_frame: usize,
    /// The largest total load in the stance.
    peak_load: f64,
    /// The frame of `peak_load`.
    peak_frame: usize,
    /// The stance touches the first or last frame of the recording, so it may have been cut.
    partial: bool,
}

#[pymethods]
impl Stance {
    fn __repr__(&self) -> String {
        format!(
            "Stance(start={}, length={}, sample_frame={}, peak_load={}, partial={})",
            self.start,
            self.length,
            self.sample_frame,
            self.peak_load,
            if self.partial { "True" } else { "False" }
        )
    }
}

/// The stance phases of a recording (a `Recording`, frames `(n, rows, cols)`, or the total load per
/// frame `(n,)`), partial ones included and flagged. `sample` picks each stance's sample frame (`mid`,
/// `peak`, or the k-th frame after touchdown as an int). Detector parameters are keyword arguments
/// with the CLI's names (`on_fraction`, `off_fraction`, `min_stance_frames`, ...): `segment_params()`
/// lists them with their defaults.
#[pyfunction]
#[pyo3(signature = (recording, *, sample = None, **params))]
pub fn segment(
    recording: &Bound<'_, PyAny>,
    sample: Option<&Bound<'_, PyAny>>,
    params: Option<&Bound<'_, PyDict>>,
) -> PyResult<Vec<Stance>> {
    let totals = total_load(recording)?;
    let params = segment_params_from(params, "segment")?;
    let sample = sample_frame(sample, "sample")?;
    let segmentation = presrs::core::stance::segment(&totals, &params).py_err()?;
    segmentation
        .stances
        .iter()
        .map(|stance| stance_of(stance, sample))
        .collect()
}

/// The stance detector's parameters and their defaults, by name.
#[pyfunction]
pub fn segment_params<'py>(py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
    let defaults = serde_json::to_value(SegmentParams::default())
        .map_err(|err| data_error(err.to_string()))?;
    crate::json::to_py(py, &defaults)
}

fn stance_of(stance: &CoreStance, sample: SampleFrame) -> PyResult<Stance> {
    let sample_frame = match sample {
        SampleFrame::Mid | SampleFrame::All => stance.mid_frame(),
        SampleFrame::Peak => stance.peak_frame,
        SampleFrame::Offset(k) => stance.start + k.min(stance.len.saturating_sub(1)),
    };
    Ok(Stance {
        start: stance.start,
        length: stance.len,
        end: stance.end(),
        sample_frame,
        peak_load: stance.peak_load,
        peak_frame: stance.peak_frame,
        partial: stance.partial,
    })
}

fn total_load(obj: &Bound<'_, PyAny>) -> PyResult<Vec<f64>> {
    if let Ok(recording) = obj.cast::<Recording>() {
        return Ok(recording.get().recording.total_per_frame());
    }
    let ndim: Option<usize> = obj.getattr("ndim").and_then(|n| n.extract()).ok();
    if ndim == Some(1) {
        let totals: Vec<f64> = obj
            .call_method1("astype", ("float64",))?
            .call_method0("tolist")?
            .extract()?;
        return Ok(totals);
    }
    let images = Images::new(obj, "recording")?;
    let size = images.grid().len();
    Ok(images
        .values()
        .chunks_exact(size)
        .map(|frame| frame.iter().sum())
        .collect())
}

/// The detector's parameters: the defaults, with the keyword arguments given (unknown names and
/// invalid values are errors naming them, after `what`).
pub fn segment_params_from(
    kwargs: Option<&Bound<'_, PyDict>>,
    what: &str,
) -> PyResult<ValidSegmentParams> {
    let mut params = serde_json::to_value(SegmentParams::default())
        .map_err(|err| data_error(err.to_string()))?;
    if let Some(kwargs) = kwargs {
        let serde_json::Value::Object(fields) = &mut params else {
            return Err(data_error(
                "the detector's parameters are not a JSON object",
            ));
        };
        for (key, value) in kwargs.iter() {
            let key: String = key.extract()?;
            if !fields.contains_key(&key) {
                let known: Vec<&str> = fields.keys().map(String::as_str).collect();
                return Err(data_error(format!(
                    "{what}: unknown parameter {key:?} (known: {})",
                    known.join(", ")
                )));
            }
            fields.insert(key, crate::json::from_py(&value)?);
        }
    }
    serde_json::from_value(params).map_err(|err| data_error(format!("{what}: {err}")))
}

/// Which frame of a stance is its sample: `"mid"` (also `None`), `"peak"`, `"all"` or `K` frames after
/// touchdown; `what` names the argument in errors.
pub fn sample_frame(sample: Option<&Bound<'_, PyAny>>, what: &str) -> PyResult<SampleFrame> {
    let Some(sample) = sample else {
        return Ok(SampleFrame::Mid);
    };
    if let Ok(k) = sample.extract::<usize>() {
        return Ok(SampleFrame::Offset(k));
    }
    let text: String = sample.str()?.to_string();
    SampleFrame::from_str(&text).map_err(|err| data_error(format!("{what}={text:?}: {err}")))
}

/// The feature vector of one image `(rows, cols)` -> `(n_features,)`, or of a batch
/// `(n, rows, cols)` -> `(n, n_features)`, as training computes it: crop, then the feature family
/// (a name of `presrs.FEATURE_FAMILIES`, e.g. `fft1d`, or several joined with `+`).
#[pyfunction]
#[pyo3(signature = (images, family = "fft1d", crop = "auto"))]
pub fn features<'py>(
    py: Python<'py>,
    images: &Bound<'py, PyAny>,
    family: &str,
    crop: &str,
) -> PyResult<Bound<'py, PyAny>> {
    let images = Images::new(images, "images")?;
    let config = feature_config(family)?;
    let crop = CropChoice::from_str(crop)
        .map_err(|err| data_error(format!("crop={crop:?}: {err}")))?
        .resolve(images.grid());
    let frames = images.frames()?;
    let (values, width) = detached(py, || {
        extract_features_many(&frames, &crop, Preprocess::NONE, &config)
    })?
    .py_err()?;
    let array = PyArray1::from_vec(py, values);
    if images.batch {
        Ok(array.reshape([images.len(), width])?.into_any())
    } else {
        Ok(array.into_any())
    }
}

fn feature_config(family: &str) -> PyResult<FeatureConfig> {
    match presrs::FeatureChoice::from_str(family) {
        Ok(presrs::FeatureChoice::Kinds(kinds)) => Ok(FeatureConfig::combined(&kinds)),
        Ok(presrs::FeatureChoice::Auto) => Err(data_error(format!(
            "family=\"auto\": name a feature family ({})",
            presrs::core::features::FeatureKind::names().join(", ")
        ))),
        Err(err) => Err(data_error(format!("family={family:?}: {err}"))),
    }
}
