//! `presrs.evaluate`: the evaluation protocols (train on a draw and test on the rest, or leave one
//! group out), on a manifest or on numpy arrays.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use numpy::{PyArray1, PyArrayMethods};
use presrs::core::sample::SampleChoice;
use presrs::eval::document::EvalJson;
use presrs::eval::race::{RaceReadings, evaluate_racing_samples};
use presrs::eval::{CalibrationJson, EvalOptions, EvalOutcome, EvalSetup, Holdout};
use presrs::train::sample_race::WholeSample;
use presrs::{Dataset, Face, Progress, Quiet, SampleKind, SampleOptions, Warnings};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};

use crate::errors::{IntoPyResult, data_error, warn};
use crate::model::{dataset_of, method, sample_choice, validation_size};
use crate::progress::PyProgress;
use crate::sample_options::{ManifestSampling, whole_sample};
use crate::threads::detached;

/// What an evaluation measured.
#[pyclass(module = "presrs", name = "Evaluation", frozen)]
#[derive(Debug)]
pub struct Evaluation {
    outcome: EvalOutcome,
    /// Tested labels no training set held, by held-out value (part of the `to_dict()` document).
    never_trained: BTreeMap<String, Vec<String>>,
    warnings: Warnings,
}

#[pymethods]
impl Evaluation {
    /// Mean accuracy over the repeats (0-1).
    #[getter]
    fn accuracy(&self) -> f64 {
        self.outcome.report.overall.mean
    }

    /// Standard deviation of the accuracy over the repeats.
    #[getter]
    fn accuracy_std(&self) -> f64 {
        self.outcome.report.overall.std
    }

    /// Accuracy per tested condition (or held-out value): `{name: (mean, std)}`.
    #[getter]
    fn per_condition(&self) -> BTreeMap<String, (f64, f64)> {
        self.outcome
            .report
            .per_condition
            .iter()
            .map(|(name, m)| (name.clone(), (m.mean, m.std)))
            .collect()
    }

    /// The accuracy of every repeat.
    #[getter]
    fn repeats(&self) -> Vec<f64> {
        self.outcome
            .report
            .repeats
            .iter()
            .map(|r| r.overall_accuracy)
            .collect()
    }

    /// The class names of the confusion matrix's rows (true) and columns (predicted).
    #[getter]
    fn classes(&self) -> Vec<String> {
        self.outcome.report.confusion.labels.clone()
    }

    /// Counts over all repeats: row = true class, column = predicted class (`classes` order).
    #[getter]
    fn confusion<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let n = self.outcome.report.confusion.labels.len();
        let flat: Vec<u64> = self
            .outcome
            .report
            .confusion
            .counts
            .iter()
            .flatten()
            .copied()
            .collect();
        Ok(PyArray1::from_vec(py, flat).reshape([n, n])?.into_any())
    }

    /// How far the confidences can be trusted: mean confidence (overall, when right, when wrong) and
    /// the expected calibration error.
    #[getter]
    fn calibration<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let value = serde_json::to_value(CalibrationJson::new(&self.outcome.report.reliability))
            .map_err(|err| data_error(err.to_string()))?;
        crate::json::to_py(py, &value)
    }

    /// Median time to classify one image, in microseconds.
    #[getter]
    fn classify_us(&self) -> f64 {
        self.outcome.report.median_classify_ns as f64 / 1e3
    }

    /// What the user should know (labels no training set holds, fewer components than asked).
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.warnings.render(Face::Python)
    }

    /// The document `presrs eval --json` prints for the same data, options and seed, as plain dicts
    /// and lists (built by the same function): the summary fields, `report` (the whole report),
    /// `selections` and `internal_estimate` with an automatic choice, `labels_never_trained`.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let document = EvalJson::of(&self.outcome, &self.never_trained);
        let value = serde_json::to_value(&document).map_err(|err| data_error(err.to_string()))?;
        crate::json::to_py(py, &value)
    }

    fn __repr__(&self) -> String {
        format!(
            "<presrs.Evaluation accuracy {:.2} % +- {:.2} over {} repeats>",
            100.0 * self.outcome.report.overall.mean,
            100.0 * self.outcome.report.overall.std,
            self.outcome.report.repeats.len()
        )
    }
}

/// Evaluates a method on `data`: a manifest (a path) or samples in memory with `labels`.
///
/// With `per_class`, a model is trained on a random draw and tested on every other sample (the
/// paper's protocol), `repeats` times; without it (and without a protocol), on G2 when there is such a
/// condition, else leaving one group out when every sample has a group (as `presrs report`).
/// `leave_one_out="group"` (or `"condition"`, or a manifest column) holds out each value in turn;
/// `train_condition` trains on one condition only. The method options are `Model.train`'s.
///
/// `sample`, as `presrs eval --sample`: `"frame"` (a frame of each stance), `"stance"` (each stance's
/// movie, laid into `stance_length` frames), `"series"` (`series_axis="rows"` when time runs down the
/// rows) or `"auto"` (a manifest only: each stance's frame raced against its whole sample inside every
/// fold, `to_dict()["sample_races"]`). In memory, `data` is what `Model.train` takes for the kind.
/// How a manifest's files are read and sampled, as the command line's options: `stance_frame`
/// (`"mid"`, `"peak"`, `"all"` or frames after touchdown), `include_partial` (stances cut by the
/// recording too), `one_sample_per_file` (each file one contact), `segment_params` (the stance
/// detector's parameters, a dict of `presrs.segment_params()`'s names), `lenient`, `axes`, `topic`
/// (as `presrs.read`), `frame_period_s` (of files that state none), `keep_dead_sensels` (use the
/// recordings as read).
///
/// `progress=True` writes a line to `sys.stderr` every few seconds; a callable is called with
/// `(task, done, total)` instead.
#[pyfunction]
#[pyo3(signature = (data, labels = None, *, groups = None, conditions = None, leave_one_out = None,
    train_condition = None, per_class = None, validation = 0.35, repeats = 10, seed = 1,
    features = "auto", classifier = "auto", dims = None, crop = "auto", full_search = false,
    validate_by = "auto", budget = Some(60.0), choose = "auto", sample = "frame",
    stance_length = None, series_axis = None, stance_frame = None, include_partial = false,
    one_sample_per_file = false, segment_params = None, lenient = false, axes = None, topic = None,
    frame_period_s = None, keep_dead_sensels = false, progress = None))]
#[allow(clippy::too_many_arguments)]
pub fn evaluate<'py>(
    py: Python<'py>,
    data: &Bound<'py, PyAny>,
    labels: Option<&Bound<'py, PyAny>>,
    groups: Option<&Bound<'py, PyAny>>,
    conditions: Option<&Bound<'py, PyAny>>,
    leave_one_out: Option<String>,
    train_condition: Option<String>,
    per_class: Option<usize>,
    validation: f64,
    repeats: usize,
    seed: u64,
    features: &str,
    classifier: &str,
    dims: Option<usize>,
    crop: &str,
    full_search: bool,
    validate_by: &str,
    budget: Option<f64>,
    choose: &str,
    sample: &str,
    stance_length: Option<usize>,
    series_axis: Option<&str>,
    stance_frame: Option<Bound<'py, PyAny>>,
    include_partial: bool,
    one_sample_per_file: bool,
    segment_params: Option<Bound<'py, PyDict>>,
    lenient: bool,
    axes: Option<String>,
    topic: Option<String>,
    frame_period_s: Option<f64>,
    keep_dead_sensels: bool,
    progress: Option<&Bound<'py, PyAny>>,
) -> PyResult<Evaluation> {
    let reporter = PyProgress::from_arg(progress)?;
    let progress: &dyn Progress = match &reporter {
        Some(reporter) => reporter,
        None => &Quiet,
    };
    if repeats == 0 {
        return Err(data_error("repeats=0: give at least one repeat"));
    }
    if leave_one_out.is_some() && train_condition.is_some() {
        return Err(data_error(
            "leave_one_out and train_condition: choose one protocol",
        ));
    }
    let method = method(
        features,
        classifier,
        crop,
        dims,
        full_search,
        validate_by,
        budget,
        choose,
    )?;
    let validation = validation_size(validation)?;
    let options_for = |dataset: &Dataset| EvalOptions {
        holdout: Holdout::resolve(
            dataset,
            leave_one_out.clone(),
            train_condition.clone(),
            per_class,
        ),
        per_class,
        validation,
        repeats,
        seed,
        method: method.clone(),
    };
    let choice = sample_choice(sample, stance_length, series_axis)?;
    let reading = ManifestSampling {
        stance_frame,
        include_partial,
        one_sample_per_file,
        lenient,
        axes,
        topic,
        frame_period_s,
        keep_dead_sensels,
        segment_params,
    };
    let source = Source::of(data, [labels, groups, conditions], &reading)?;
    let kind = match (choice, &source) {
        (SampleChoice::Kind(kind), _) => kind,
        (SampleChoice::Auto, Source::Manifest(path)) => {
            let frames = reading.options(SampleKind::Frame)?;
            let whole = whole_sample(stance_length, series_axis);
            return evaluate_racing(py, path, (&frames, whole), options_for, progress);
        }
        (SampleChoice::Auto, Source::Arrays) => {
            return Err(data_error(
                "sample=\"auto\" reads a manifest's files both as frames and as whole stances (or \
                 series): pass a manifest's path",
            ));
        }
    };
    let dataset = match &source {
        Source::Manifest(path) => {
            let options = reading.options(kind)?;
            detached(py, || Dataset::load(path, &options, progress))?.py_err()?
        }
        Source::Arrays => {
            let Some(labels) = labels else {
                return Err(data_error(
                    "labels: samples in memory need one label each (or pass a manifest's path \
                     instead)",
                ));
            };
            dataset_of(data, labels, groups, conditions, kind)?
        }
    };
    let options = options_for(&dataset);
    for warning in &dataset.warnings {
        warn(py, warning)?;
    }
    let setup = EvalSetup::new(&dataset, &options).py_err()?;
    let mut warnings = setup.warnings.clone();
    let outcome = detached(py, || setup.evaluate(progress))?.py_err()?;
    warnings.extend(outcome.warnings.iter().cloned());
    for warning in &warnings {
        warn(py, warning)?;
    }
    Ok(Evaluation {
        outcome,
        never_trained: setup.never_trained,
        warnings,
    })
}

/// `sample="auto"`: the manifest read as frames and as its whole samples, the kinds raced inside every
/// fold (`presrs::eval::race`).
fn evaluate_racing(
    py: Python<'_>,
    path: &Path,
    (frames, whole): (&SampleOptions, WholeSample),
    options_for: impl Fn(&Dataset) -> EvalOptions,
    progress: &dyn Progress,
) -> PyResult<Evaluation> {
    let readings = detached(py, || RaceReadings::load(path, frames, whole, progress))?.py_err()?;
    for warning in &readings.frames.warnings {
        warn(py, warning)?;
    }
    let options = options_for(&readings.frames);
    let raced = detached(py, || {
        evaluate_racing_samples(&readings, &options, progress)
    })?
    .py_err()?;
    let warnings = raced.outcome.warnings.clone();
    for warning in &warnings {
        warn(py, warning)?;
    }
    Ok(Evaluation {
        outcome: raced.outcome,
        never_trained: raced.never_trained,
        warnings,
    })
}

/// Where an evaluation's samples come from: a manifest's files, or arrays in memory.
enum Source {
    Manifest(PathBuf),
    Arrays,
}

impl Source {
    /// A manifest when `data` is a path (with none of `extra`: a manifest gives its own labels, groups
    /// and conditions), else arrays (with none of the arguments that read files).
    fn of(
        data: &Bound<'_, PyAny>,
        extra: [Option<&Bound<'_, PyAny>>; 3],
        reading: &ManifestSampling<'_>,
    ) -> PyResult<Self> {
        let is_path = data.is_instance_of::<PyString>() || data.hasattr("__fspath__")?;
        if !is_path {
            if let Some(name) = reading.first_given() {
                return Err(data_error(format!(
                    "{name}= applies to reading a manifest's files; samples in memory are taken as \
                     given"
                )));
            }
            return Ok(Self::Arrays);
        }
        if extra.iter().any(Option::is_some) {
            return Err(data_error(
                "a manifest gives its own labels, groups and conditions: pass only its path",
            ));
        }
        Ok(Self::Manifest(data.extract()?))
    }
}
