//! `presrs.Model`: train from numpy arrays, load and save the CLI's model files, classify one image or
//! a batch, pickle.

use std::path::PathBuf;
use std::str::FromStr;
use std::sync::Mutex;

use numpy::{PyArray1, PyArrayMethods};
use presrs::classify::model_sample;
use presrs::core::novelty::{Novelty, UNKNOWN_LABEL};
use presrs::core::pipeline::{Classification, Session};
use presrs::core::sample::SampleChoice;
use presrs::core::split::ValidationSize;
use presrs::core::{Frame, FrameView, Grid};
use presrs::io::model_file::{ModelFile, load_model, parse_model, save_model};
use presrs::io::output_path::check_output_file;
use presrs::train::{TrainOptions, train};
use presrs::{ClassifierChoice, CropChoice, Dataset, FeatureChoice, Method, Sample, SampleKind};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{PyBytes, PyTuple};
use self_cell::self_cell;

use crate::arrays::{Images, labels, optional_labels};
use crate::errors::{IntoPyResult, data_error, warn};
use crate::threads::detached;
use presrs::Warning;

type SessionSlot<'a> = Mutex<Session<'a>>;

self_cell!(
    /// A model file and a classification session on its model, reused from call to call so that
    /// classifying one image allocates nothing.
    struct Loaded {
        owner: ModelFile,
        #[not_covariant]
        dependent: SessionSlot,
    }
    impl {Debug}
);

/// A trained terrain classifier: the same model files as `presrs train` writes and `presrs classify`
/// reads.
#[pyclass(module = "presrs", name = "Model", frozen)]
pub struct Model {
    loaded: Loaded,
    /// `classes_` as a numpy array, made on first use (labels of a batch are taken from it).
    classes: PyOnceLock<Py<PyAny>>,
}

impl std::fmt::Debug for Model {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Model")
            .field("classes", &self.file().model.class_names())
            .finish_non_exhaustive()
    }
}

impl Model {
    pub fn new(file: ModelFile) -> Self {
        Self {
            loaded: Loaded::new(file, |file| Mutex::new(file.model.session())),
            classes: PyOnceLock::new(),
        }
    }

    pub fn file(&self) -> &ModelFile {
        self.loaded.borrow_owner()
    }

    /// Classifies one image with the shared session (or a new one when another thread holds it).
    fn classify_one<T>(
        &self,
        frame: &FrameView<'_>,
        take: impl Fn(&presrs::core::pipeline::Prediction<'_>) -> T,
    ) -> PyResult<T> {
        self.loaded.with_dependent(|file, slot| {
            let result = match slot.try_lock() {
                Ok(mut session) => session.classify(frame).map(|p| take(&p)),
                Err(_) => file.model.session().classify(frame).map(|p| take(&p)),
            };
            result.py_err()
        })
    }

    /// Classifies every image of a batch: a few in this thread with the shared session, more in
    /// parallel without the GIL (starting the workers costs more than a few classifications). The
    /// first failure is an error naming its image.
    fn classify_many(
        &self,
        py: Python<'_>,
        frames: &[FrameView<'_>],
    ) -> PyResult<Vec<Classification>> {
        let model = &self.file().model;
        let results = if frames.len() < PARALLEL_FROM {
            let classify_all = |session: &mut Session<'_>| -> Vec<_> {
                frames
                    .iter()
                    .map(|frame| session.classify(frame).map(|p| p.to_classification()))
                    .collect()
            };
            self.loaded
                .with_dependent(|file, slot| match slot.try_lock() {
                    Ok(mut session) => classify_all(&mut session),
                    Err(_) => classify_all(&mut file.model.session()),
                })
        } else {
            detached(py, || model.classify_batch(frames))?
        };
        results
            .into_iter()
            .enumerate()
            .map(|(index, result)| {
                result.map_err(|err| data_error(format!("image {index} of the batch: {err}")))
            })
            .collect()
    }

    /// The class index of every sample of a batch (its failures explained in the caller's terms).
    fn batch_classes(&self, py: Python<'_>, samples: &Samples<'_>) -> PyResult<Vec<usize>> {
        Ok(self
            .classify_many(py, &samples.views()?)
            .map_err(|err| samples.explain(err))?
            .into_iter()
            .map(|c| c.class)
            .collect())
    }

    /// `take` of one sample's classification (a `float`) or of every sample's of a batch (an array).
    fn per_sample<'py>(
        &self,
        py: Python<'py>,
        x: &Bound<'py, PyAny>,
        take: impl Fn(&Classification) -> f64,
    ) -> PyResult<Bound<'py, PyAny>> {
        let samples = self.samples_of(py, x)?;
        if !samples.batch() {
            let value = self
                .classify_one(&samples.view(0)?, |p| take(&p.to_classification()))
                .map_err(|err| samples.explain(err))?;
            return Ok(value.into_pyobject(py)?.into_any());
        }
        let classified = self
            .classify_many(py, &samples.views()?)
            .map_err(|err| samples.explain(err))?;
        let values: Vec<f64> = classified.iter().map(take).collect();
        Ok(PyArray1::from_vec(py, values).into_any())
    }

    /// The samples of `x` as this model takes them: images as they are; a stance's movie summarised
    /// and laid into the model's length (a warning when it was cut); a series transposed when its time
    /// runs down the rows.
    fn samples_of<'py>(&self, py: Python<'py>, x: &Bound<'py, PyAny>) -> PyResult<Samples<'py>> {
        let model = &self.file().model;
        match model.sample() {
            // An image is its own sample: read in place, not copied.
            SampleKind::Frame => Ok(Samples::Images(Images::new(x, "x")?)),
            SampleKind::Series { .. } => {
                let images = Images::new(x, "x")?;
                images.require_finite("x", "series")?;
                let frames = images
                    .frames()?
                    .iter()
                    .map(|f| Ok(model_sample(model, &[*f]).py_err()?.0))
                    .collect::<PyResult<_>>()?;
                Ok(Samples::Owned(frames, images.batch))
            }
            SampleKind::Stance { .. } => {
                let ndim = x.getattr("ndim").and_then(|n| n.extract::<usize>()).ok();
                if x.is_none() {
                    return Err(not_a_movie("x", "None"));
                }
                if let Some(ndim) = ndim
                    && ndim < 3
                {
                    return Err(not_a_movie("x", &array_shape(x)?));
                }
                let one = ndim == Some(3);
                let movies: Vec<Bound<'py, PyAny>> = if one {
                    vec![x.clone()]
                } else {
                    x.try_iter()?.collect::<PyResult<_>>()?
                };
                let mut frames = Vec::with_capacity(movies.len());
                for (index, movie) in movies.iter().enumerate() {
                    let what = if one {
                        "x".to_owned()
                    } else {
                        format!("x[{index}]")
                    };
                    let movie = stance_movie(movie, &what)?;
                    movie.require_finite(&what, "frame")?;
                    let (sample, warning) = model_sample(model, &movie.frames()?)
                        .map_err(|err| data_error(format!("{what}: {err}")))?;
                    if let Some(warning) = warning {
                        warn(py, &Warning::from(format!("{what}: {}", warning.message())))?;
                    }
                    frames.push(sample);
                }
                Ok(Samples::Owned(frames, !one))
            }
        }
    }

    fn classes_array<'py>(&self, py: Python<'py>) -> PyResult<&Bound<'py, PyAny>> {
        self.classes
            .get_or_try_init(py, || {
                let names = self.file().model.class_names().to_vec();
                Ok::<_, PyErr>(
                    py.import("numpy")?
                        .getattr("array")?
                        .call1((names,))?
                        .unbind(),
                )
            })
            .map(|classes| classes.bind(py))
    }
}

#[pymethods]
impl Model {
    /// Trains a model on images `(n, rows, cols)` with one label each (any values; kept as text). A
    /// missing label (`None`, NaN, empty or blank text) is an error naming its index; a missing group
    /// or condition is none.
    ///
    /// `features` takes `auto` or the names of `presrs.FEATURE_FAMILIES` (several joined with `+`),
    /// `classifier` `auto` or a name of `presrs.CLASSIFIERS`: the command line's names. `groups` and
    /// `conditions` (one per image) are kept with the samples: the automatic choice validates across
    /// conditions. `seed` draws the validation images (1 by default, as the command line's).
    /// `validation` is a share of each class (0 < v < 1) or a count per class (>= 1).
    /// `validate_by` (`auto`, `group`, `condition`, `split`): how the automatic choice validates its
    /// candidates; `auto` leaves one group out when there are 3 or more groups, else one condition.
    /// `budget`: seconds the automatic choice may spend scoring candidates (the texture families,
    /// scored last, are cut first, with a warning); `None` or 0: no limit. `choose`: `best` (the
    /// highest validation mean), `one-se` (the earliest candidate within one standard error of it; the
    /// highest with fewer than three validation folds) or `auto` (`one-se` on stances and series,
    /// `best` on frames).
    /// `sample`: what an item of `images` is: `frame` (one image), `stance` (a stance's movie
    /// `(frames, rows, cols)`, summarised over time as `presrs train --sample stance` does, laid into
    /// `stance_length` frames, by default the longest's) or `series` (channels x time;
    /// `series_axis="rows"` when time runs down the rows).
    #[staticmethod]
    #[pyo3(signature = (images, labels, *, features = "auto", classifier = "auto", groups = None,
        conditions = None, seed = 1, dims = None, per_class = None, validation = 0.35, crop = "auto",
        full_search = false, validate_by = "auto", budget = Some(60.0), choose = "auto",
        sample = "frame", stance_length = None, series_axis = None, novelty = true))]
    #[allow(clippy::too_many_arguments)]
    fn train(
        py: Python<'_>,
        images: &Bound<'_, PyAny>,
        labels: &Bound<'_, PyAny>,
        features: &str,
        classifier: &str,
        groups: Option<&Bound<'_, PyAny>>,
        conditions: Option<&Bound<'_, PyAny>>,
        seed: u64,
        dims: Option<usize>,
        per_class: Option<usize>,
        validation: f64,
        crop: &str,
        full_search: bool,
        validate_by: &str,
        budget: Option<f64>,
        choose: &str,
        sample: &str,
        stance_length: Option<usize>,
        series_axis: Option<&str>,
        novelty: bool,
    ) -> PyResult<Self> {
        let kind = sample_kind(sample, stance_length, series_axis)?;
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
        let dataset = dataset_of(images, labels, groups, conditions, kind)?;
        for warning in &dataset.warnings {
            warn(py, warning)?;
        }
        let options = TrainOptions {
            condition: None,
            per_class,
            validation: validation_size(validation)?,
            seed,
            method,
            novelty,
        };
        let training = detached(py, || train(&dataset, &options))?.py_err()?;
        for warning in &training.warnings {
            warn(py, warning)?;
        }
        let command = format!(
            "python: presrs.Model.train({} {}s, features={features:?}, classifier={classifier:?}, \
             sample={:?}, seed={seed})",
            dataset.samples.len(),
            if kind.is_frame() {
                "image"
            } else {
                kind.name()
            },
            kind.name()
        );
        Ok(Self::new(training.model_file(
            &dataset,
            &options,
            false,
            Some(command),
        )))
    }

    /// Reads a model file written by `presrs train` or [`Model.save`].
    #[staticmethod]
    fn load(path: PathBuf) -> PyResult<Self> {
        Ok(Self::new(load_model(&path).py_err()?))
    }

    /// Writes the model file (atomically: a reader never sees half a file), after checking that its
    /// folder exists and accepts it.
    fn save(&self, path: PathBuf) -> PyResult<()> {
        // As the command line does before its work: a missing folder is named as such.
        check_output_file(&path).py_err()?;
        save_model(&path, self.file()).py_err()
    }

    /// The model file's JSON text.
    fn to_json(&self) -> PyResult<String> {
        serde_json::to_string(self.file()).map_err(|err| data_error(err.to_string()))
    }

    /// A model from a model file's JSON text (or bytes).
    #[staticmethod]
    fn from_json(data: &Bound<'_, PyAny>) -> PyResult<Self> {
        let bytes: Vec<u8> = match data.extract::<String>() {
            Ok(text) => text.into_bytes(),
            Err(_) => data.extract::<Vec<u8>>()?,
        };
        Ok(Self::new(parse_model(&bytes, "model JSON").py_err()?))
    }

    /// The label of one sample (a `str`), or of every sample of a batch (a numpy array of
    /// `classes_` values). A sample is what the model was trained on: an image `(rows, cols)` (a batch
    /// `(n, rows, cols)`), a stance's movie `(frames, rows, cols)` (a batch: a list of movies), or a
    /// series `(channels, time)` (a batch `(n, channels, time)`).
    ///
    /// With a model that scores novelty, a sample far from every class is `"unknown"` (the nearest
    /// class is `predict_index`'s); `novelty=False` names one of the classes for every sample, as
    /// before.
    #[pyo3(signature = (x, *, novelty = true))]
    fn predict<'py>(
        &self,
        py: Python<'py>,
        x: &Bound<'py, PyAny>,
        novelty: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        let unknown = |n: Option<Novelty>| novelty && n.is_some_and(|n| n.unknown);
        let samples = self.samples_of(py, x)?;
        if !samples.batch() {
            let label = self
                .classify_one(&samples.view(0)?, |p| {
                    if unknown(p.novelty) {
                        UNKNOWN_LABEL.to_owned()
                    } else {
                        p.label.to_owned()
                    }
                })
                .map_err(|err| samples.explain(err))?;
            return Ok(label.into_pyobject(py)?.into_any());
        }
        let classified = self
            .classify_many(py, &samples.views()?)
            .map_err(|err| samples.explain(err))?;
        if classified.iter().any(|c| unknown(c.novelty)) {
            let names = self.file().model.class_names();
            let labels: Vec<&str> = classified
                .iter()
                .map(|c| {
                    if unknown(c.novelty) {
                        UNKNOWN_LABEL
                    } else {
                        names[c.class].as_str()
                    }
                })
                .collect();
            return py.import("numpy")?.getattr("array")?.call1((labels,));
        }
        let indices = PyArray1::from_vec(py, classified.into_iter().map(|c| c.class).collect());
        self.classes_array(py)?.call_method1("take", (indices,))
    }

    /// The novelty score of one sample (a `float`) or of every sample of a batch (an array): in
    /// [0, 1], 1 - the nearest class's posterior x the credibility of the distance to the nearest
    /// training sample, in the model's discriminant space (older models: that distance); above
    /// `novelty_threshold`, `predict` says `"unknown"`. An error for a model without a novelty score.
    fn novelty<'py>(&self, py: Python<'py>, x: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        if self.file().model.novelty().is_none() {
            return Err(data_error(
                "this model has no novelty score (trained before it existed, or with novelty=False): \
                 train it again to have one",
            ));
        }
        self.per_sample(py, x, |c| c.novelty.map_or(f64::NAN, |n| n.score))
    }

    /// The confidence a decision reports, of one sample (a `float`) or of every sample of a batch (an
    /// array): the posterior of the class `predict_index` names, capped by the sample's credibility
    /// when the model scores novelty (the share of held-out known training samples at least as far
    /// from the training data), so that a sample unlike the known ones is never reported as sure.
    /// `predict_proba` gives the classifier's own posteriors.
    fn confidence<'py>(
        &self,
        py: Python<'py>,
        x: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        self.per_sample(py, x, |c| c.confidence)
    }

    /// The novelty score above which `predict` says `"unknown"`; `None` for a model without one.
    #[getter]
    fn novelty_threshold(&self) -> Option<f64> {
        self.file().model.novelty().map(|n| n.threshold())
    }

    /// The index in `classes_` of the label of one sample (an `int`), or of every sample of a batch
    /// (an integer array): `predict` without making the labels.
    fn predict_index<'py>(
        &self,
        py: Python<'py>,
        x: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let samples = self.samples_of(py, x)?;
        if !samples.batch() {
            let class = self
                .classify_one(&samples.view(0)?, |p| p.class)
                .map_err(|err| samples.explain(err))?;
            return Ok(class.into_pyobject(py)?.into_any());
        }
        let classes = self.batch_classes(py, &samples)?;
        Ok(PyArray1::from_vec(py, classes).into_any())
    }

    /// The posterior of every class (in `classes_` order): shape `(n_classes,)` for one sample,
    /// `(n, n_classes)` for a batch.
    fn predict_proba<'py>(
        &self,
        py: Python<'py>,
        x: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let samples = self.samples_of(py, x)?;
        if !samples.batch() {
            let posteriors = self
                .classify_one(&samples.view(0)?, |p| p.posteriors.to_vec())
                .map_err(|err| samples.explain(err))?;
            return Ok(PyArray1::from_vec(py, posteriors).into_any());
        }
        let classes = self.file().model.class_names().len();
        let classified = self
            .classify_many(py, &samples.views()?)
            .map_err(|err| samples.explain(err))?;
        let rows = classified.len();
        let flat: Vec<f64> = classified.into_iter().flat_map(|c| c.posteriors).collect();
        Ok(PyArray1::from_vec(py, flat)
            .reshape([rows, classes])?
            .into_any())
    }

    /// What a sample is for this model: `"frame"`, `"stance"` or `"series"`.
    #[getter]
    fn sample(&self) -> &'static str {
        self.file().model.sample().name()
    }

    /// The class names, in the order of `predict_proba`'s columns.
    #[getter]
    fn classes_<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.classes_array(py)?.call_method0("copy")
    }

    /// The image size the classifier sees after the crop, `(rows, cols)`.
    #[getter]
    fn cropped_shape(&self) -> (usize, usize) {
        let grid = self.file().model.image_grid();
        (grid.rows, grid.cols)
    }

    /// Whether the model file carries an online profile (detector calibration for a stream).
    #[getter]
    fn has_online_profile(&self) -> bool {
        self.file().online.is_some()
    }

    /// What the model is made of and where it came from, in a few lines.
    fn describe(&self) -> String {
        presrs::describe_model(self.file()).trim_end().to_owned()
    }

    fn __repr__(&self) -> String {
        let model = &self.file().model;
        format!(
            "<presrs.Model {} + {}, {} classes: {}>",
            model.features().name(),
            model.classifier().kind(),
            model.class_names().len(),
            model.class_names().join(", ")
        )
    }

    /// Pickles as the model file's JSON.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        let json = serde_json::to_vec(self.file()).map_err(|err| data_error(err.to_string()))?;
        let rebuild = py.get_type::<Self>().getattr("from_json")?;
        (rebuild, (PyBytes::new(py, &json),)).into_pyobject(py)
    }
}

/// A method from the CLI's option values.
#[allow(clippy::too_many_arguments)]
pub fn method(
    features: &str,
    classifier: &str,
    crop: &str,
    dims: Option<usize>,
    full_search: bool,
    validate_by: &str,
    budget: Option<f64>,
    choose: &str,
) -> PyResult<Method> {
    let budget = match budget {
        Some(seconds) => presrs::method::budget_from_seconds(seconds)
            .map_err(|err| data_error(format!("budget={seconds}: {err} (or None)")))?,
        None => None,
    };
    Ok(Method {
        budget,
        choose: choose
            .parse()
            .map_err(|err| data_error(format!("choose={choose:?}: {err}")))?,
        validate_by: validate_by
            .parse()
            .map_err(|err| data_error(format!("validate_by={validate_by:?}: {err}")))?,
        features: FeatureChoice::from_str(features)
            .map_err(|err| data_error(format!("features={features:?}: {err}")))?,
        classifier: ClassifierChoice::from_str(classifier)
            .map_err(|err| data_error(format!("classifier={classifier:?}: {err}")))?,
        crop: CropChoice::from_str(crop)
            .map_err(|err| data_error(format!("crop={crop:?}: {err}")))?,
        dims,
        full_search,
        ..Method::default()
    })
}

/// A validation size: a share of each class below 1, a count per class from 1 up.
pub fn validation_size(validation: f64) -> PyResult<ValidationSize> {
    if validation > 0.0 && validation < 1.0 {
        Ok(ValidationSize::Fraction(validation))
    } else if validation >= 0.0 && validation.fract() == 0.0 {
        Ok(ValidationSize::Count(validation as usize))
    } else {
        Err(data_error(format!(
            "validation={validation}: give a share of each class (0 < v < 1) or a whole count per \
             class"
        )))
    }
}

/// The sample kind named by `sample=`, `stance_length=` and `series_axis=` (a model is trained on one:
/// `auto` is for evaluations).
pub fn sample_kind(
    sample: &str,
    stance_length: Option<usize>,
    series_axis: Option<&str>,
) -> PyResult<SampleKind> {
    sample_choice(sample, stance_length, series_axis)?
        .kind()
        .ok_or_else(|| {
            data_error(
                "sample=\"auto\" races one frame against the whole sample inside an evaluation \
                 (presrs.evaluate); a model is trained on one kind: name it (\"frame\", \"stance\" \
                 or \"series\")",
            )
        })
}

/// The sample kind, or `auto`, named by `sample=`, with `stance_length=` and `series_axis=` (each
/// only with its kind, or with `auto`, whose whole sample they describe).
pub fn sample_choice(
    sample: &str,
    stance_length: Option<usize>,
    series_axis: Option<&str>,
) -> PyResult<SampleChoice> {
    let name = sample.trim();
    if !matches!(name, "stance" | "auto") && stance_length.is_some() {
        return Err(data_error(format!(
            "stance_length= applies to sample=\"stance\", not sample={sample:?}"
        )));
    }
    if !matches!(name, "series" | "auto") && series_axis.is_some() {
        return Err(data_error(format!(
            "series_axis= applies to sample=\"series\", not sample={sample:?}"
        )));
    }
    let argument = |err: String| {
        let argument = match name {
            "stance" => "stance_length",
            "series" => "series_axis",
            _ => "sample",
        };
        data_error(format!("{argument}: {err}"))
    };
    if name == "auto" {
        // The whole sample's settings are checked as its kind checks them.
        SampleChoice::parse("stance", stance_length, None)
            .map_err(|err| data_error(format!("stance_length: {err}")))?;
        SampleChoice::parse("series", None, series_axis)
            .map_err(|err| data_error(format!("series_axis: {err}")))?;
    }
    SampleChoice::parse(sample, stance_length, series_axis).map_err(argument)
}

/// A data set of samples in memory with their labels and, when given, groups and conditions: images
/// `(n, rows, cols)` for frames and series, a sequence of movies `(frames, rows, cols)` for stances.
pub fn dataset_of(
    images: &Bound<'_, PyAny>,
    label_values: &Bound<'_, PyAny>,
    groups: Option<&Bound<'_, PyAny>>,
    conditions: Option<&Bound<'_, PyAny>>,
    kind: SampleKind,
) -> PyResult<Dataset> {
    let (frames, sensor) = match kind {
        SampleKind::Stance { .. } => stance_summaries(images, kind)?,
        SampleKind::Frame | SampleKind::Series { .. } => (image_samples(images, kind)?, None),
    };
    let n = frames.len();
    let names = labels(label_values, "labels", n)?;
    let groups = groups
        .map(|g| optional_labels(g, "groups", n))
        .transpose()?;
    let conditions = conditions
        .map(|c| optional_labels(c, "conditions", n))
        .transpose()?;
    let mut samples = Vec::with_capacity(n);
    for (index, (label, frame)) in names.into_iter().zip(frames).enumerate() {
        let mut sample = Sample::new(frame, label, PathBuf::from("images"), index);
        sample.group = groups.as_ref().and_then(|g| g[index].clone());
        sample.condition = conditions.as_ref().and_then(|c| c[index].clone());
        samples.push(sample);
    }
    let what = if kind.is_frame() {
        "image"
    } else {
        kind.name()
    };
    let mut dataset =
        Dataset::from_samples_of(format!("numpy {what}s ({n})"), samples, kind).py_err()?;
    if sensor.is_some() {
        dataset.sensor = sensor;
    }
    Ok(dataset)
}

/// The images of a batch `(n, rows, cols)`, each checked for values that are not numbers, as samples of
/// `kind` (a frame or a series: [`SampleKind::sample_of`]).
fn image_samples(images: &Bound<'_, PyAny>, kind: SampleKind) -> PyResult<Vec<Frame>> {
    let images = Images::new(images, "images")?;
    if !images.batch {
        return Err(data_error(
            "images: expected a batch (n, rows, cols); for one image use images[None]",
        ));
    }
    images.require_finite("images", "image")?;
    (0..images.len())
        .map(|index| Ok(kind.sample_of(&[images.frame(index)?], None).py_err()?.0))
        .collect()
}

/// Each movie `(frames, rows, cols)` of `movies` (a sequence, or a 4-D array) as a whole-stance sample
/// of `kind`, summarised over time (laid into one length later, with the rest of the data set), and
/// the one sensor grid they share (a model of summaries takes one sensor: movies of another grid than
/// the first are refused, naming both).
fn stance_summaries(
    movies: &Bound<'_, PyAny>,
    kind: SampleKind,
) -> PyResult<(Vec<Frame>, Option<Grid>)> {
    if movies.is_none() {
        return Err(data_error(
            "images: expected a sequence of movies (frames, rows, cols), got None",
        ));
    }
    let mut out = Vec::new();
    let mut sensor: Option<Grid> = None;
    for (index, movie) in movies.try_iter()?.enumerate() {
        let what = format!("images[{index}]");
        let (summary, grid) = movie_summary(&movie?, &what, kind)?;
        match sensor {
            Some(first) if first != grid => {
                return Err(data_error(format!(
                    "{what}: a movie of {grid} frames where images[0] has {first}: a stance model \
                     is trained on one sensor; crop or resample the movies to one grid, or train a \
                     model per sensor"
                )));
            }
            Some(_) => {}
            None => sensor = Some(grid),
        }
        out.push(summary);
    }
    Ok((out, sensor))
}

/// One stance's movie summarised (as the CLI's data sets are), with its frames' grid; `what` names it
/// in errors.
fn movie_summary(
    movie: &Bound<'_, PyAny>,
    what: &str,
    kind: SampleKind,
) -> PyResult<(Frame, Grid)> {
    let frames = Images::new(movie, what)?;
    if !frames.batch {
        return Err(data_error(format!(
            "{what}: a whole-stance sample is a movie (frames, rows, cols), got one image {:?}",
            (frames.grid().rows, frames.grid().cols)
        )));
    }
    frames.require_finite(what, "frame")?;
    kind.sample_of(&frames.frames()?, None)
        .map(|(summary, _)| (summary, frames.grid()))
        .map_err(|err| data_error(format!("{what}: {err}")))
}

/// One stance's movie `(frames, rows, cols)` of a whole-stance model's input, or an error saying
/// that the model takes whole stances and what `movie` is.
fn stance_movie<'py>(movie: &Bound<'py, PyAny>, what: &str) -> PyResult<Images<'py>> {
    let ndim = movie
        .getattr("ndim")
        .and_then(|n| n.extract::<usize>())
        .ok();
    if movie.is_none() {
        return Err(not_a_movie(what, "None"));
    }
    if ndim.is_some_and(|ndim| ndim != 3) {
        return Err(not_a_movie(what, &array_shape(movie)?));
    }
    let images = Images::new(movie, what)?;
    if !images.batch {
        let grid = images.grid();
        return Err(not_a_movie(
            what,
            &format!("one image of {} x {} (rows x cols)", grid.rows, grid.cols),
        ));
    }
    Ok(images)
}

/// What a numpy array is, for an error: `one image of 20 x 33 (rows x cols)`, `an array of shape
/// (33,)`, `a number`.
fn array_shape(array: &Bound<'_, PyAny>) -> PyResult<String> {
    let shape: Vec<usize> = array.getattr("shape")?.extract()?;
    Ok(match shape[..] {
        [] => "a number (an array of no dimension)".to_owned(),
        [rows, cols] => format!("one image of {rows} x {cols} (rows x cols)"),
        [length] => format!("an array of shape ({length},)"),
        _ => format!(
            "an array of shape ({})",
            shape
                .iter()
                .map(usize::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        ),
    })
}

/// The error of a whole-stance model given something other than a stance's movie.
fn not_a_movie(what: &str, got: &str) -> PyErr {
    data_error(format!(
        "{what}: the model classifies whole stances: it takes a stance's movie (frames, rows, cols), \
         or a list of movies; got {got}"
    ))
}

/// Batches at least this long are classified in parallel.
const PARALLEL_FROM: usize = 8;

/// The samples of a call to `predict`: a numpy array's images read in place, or samples made from the
/// input (stance summaries, transposed series), with whether the input was a batch.
enum Samples<'py> {
    Images(Images<'py>),
    Owned(Vec<Frame>, bool),
}

impl Samples<'_> {
    fn batch(&self) -> bool {
        match self {
            Self::Images(images) => images.batch,
            Self::Owned(_, batch) => *batch,
        }
    }

    fn view(&self, index: usize) -> PyResult<FrameView<'_>> {
        match self {
            Self::Images(images) => images.frame(index),
            Self::Owned(frames, _) => frames
                .get(index)
                .map(Frame::view)
                .ok_or_else(|| data_error("x: no sample to classify")),
        }
    }

    fn views(&self) -> PyResult<Vec<FrameView<'_>>> {
        match self {
            Self::Images(images) => images.frames(),
            Self::Owned(frames, _) => Ok(frames.iter().map(Frame::view).collect()),
        }
    }

    /// The error of a failed classification, or a clearer one when the input holds a value that is
    /// not a finite number (checked only after a failure: the hot path does not scan its input twice).
    fn explain(&self, err: PyErr) -> PyErr {
        match self {
            Self::Images(images) => images.non_finite("x", "image").unwrap_or(err),
            Self::Owned(..) => err,
        }
    }
}
