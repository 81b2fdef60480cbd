//! `presrs.Model`: train from numpy arrays, load and save the CLI's model files, classify one image or
//! a batch, pickle.

use std::path::PathBuf;
use std::str::FromStr;
use std::sync::Mutex;

use numpy::{PyArray1, PyArrayMethods};
use presrs::core::FrameView;
use presrs::core::pipeline::Session;
use presrs::core::split::ValidationSize;
use presrs::io::model_file::{ModelFile, load_model, parse_model, save_model};
use presrs::train::{TrainOptions, train};
use presrs::{ClassifierChoice, CropChoice, Dataset, FeatureChoice, Method, Sample};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{PyBytes, PyTuple};
use self_cell::self_cell;

use crate::arrays::{Images, labels};
use crate::errors::{IntoPyResult, data_error, warn};
use crate::threads::detached;

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

    /// Classifies every image of a batch in parallel, without the GIL; the first failure is an error
    /// naming its image.
    fn classify_many(
        &self,
        py: Python<'_>,
        images: &Images<'_>,
    ) -> PyResult<Vec<presrs::core::pipeline::Classification>> {
        let frames = images.frames()?;
        let model = &self.file().model;
        let results = detached(py, || model.classify_batch(&frames))?;
        results
            .into_iter()
            .enumerate()
            .map(|(index, result)| {
                result.map_err(|err| data_error(format!("image {index} of the batch: {err}")))
            })
            .collect()
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
    /// Trains a model on images `(n, rows, cols)` with one label each (any values; kept as text).
    ///
    /// `features` and `classifier` take the CLI's names (`auto`, `fft1d`, `fft2d`, `fft2d-polar`,
    /// `glcm`, combinations with `+`; `auto`, `pwe`, `lda`, `svm`, `knn`, ...). `groups` and
    /// `conditions` (one per image) are kept with the samples: the automatic choice validates across
    /// conditions. `validation` is a share of each class (0 < v < 1) or a count per class (>= 1).
    /// `validate_by` (`auto`, `group`, `condition`, `split`): how the automatic choice validates its
    /// candidates; `auto` leaves one group out when there are 3 or more groups, else one condition.
    /// `budget`: seconds the automatic choice may spend scoring candidates (the texture families,
    /// scored last, are cut first, with a warning); `None` or 0: no limit. `choose`: `best` (the
    /// highest validation mean) or `one-se` (the earliest candidate within one standard error of it).
    #[staticmethod]
    #[pyo3(signature = (images, labels, *, features = "auto", classifier = "auto", groups = None,
        conditions = None, seed = 0, dims = None, per_class = None, validation = 0.35, crop = "auto",
        full_search = false, validate_by = "auto", budget = Some(60.0), choose = "best"))]
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
    ) -> PyResult<Self> {
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
        let dataset = dataset_of(images, labels, groups, conditions)?;
        let options = TrainOptions {
            condition: None,
            per_class,
            validation: validation_size(validation)?,
            seed,
            method,
        };
        let training = detached(py, || train(&dataset, &options))?.py_err()?;
        for warning in &training.warnings {
            warn(py, warning)?;
        }
        let command = format!(
            "python: presrs.Model.train({} images, features={features:?}, classifier={classifier:?}, \
             seed={seed})",
            dataset.samples.len()
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

    /// Writes the model file (atomically: a reader never sees half a file).
    fn save(&self, path: PathBuf) -> PyResult<()> {
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

    /// The label of one image `(rows, cols)` (a `str`), or of every image of a batch
    /// `(n, rows, cols)` (a numpy array of `classes_` values).
    fn predict<'py>(&self, py: Python<'py>, x: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        let images = Images::new(x, "x")?;
        if !images.batch {
            let frame = images.frame(0)?;
            let label = self.classify_one(&frame, |p| p.label.to_owned())?;
            return Ok(label.into_pyobject(py)?.into_any());
        }
        let classes: Vec<usize> = self
            .classify_many(py, &images)?
            .into_iter()
            .map(|c| c.class)
            .collect();
        let indices = PyArray1::from_vec(py, classes);
        self.classes_array(py)?.call_method1("take", (indices,))
    }

    /// The posterior of every class (in `classes_` order): shape `(n_classes,)` for one image,
    /// `(n, n_classes)` for a batch.
    fn predict_proba<'py>(
        &self,
        py: Python<'py>,
        x: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let images = Images::new(x, "x")?;
        if !images.batch {
            let frame = images.frame(0)?;
            let posteriors = self.classify_one(&frame, |p| p.posteriors.to_vec())?;
            return Ok(PyArray1::from_vec(py, posteriors).into_any());
        }
        let classes = self.file().model.class_names().len();
        let classified = self.classify_many(py, &images)?;
        let rows = classified.len();
        let flat: Vec<f64> = classified.into_iter().flat_map(|c| c.posteriors).collect();
        Ok(PyArray1::from_vec(py, flat)
            .reshape([rows, classes])?
            .into_any())
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

/// A data set of images in memory with their labels and, when given, groups and conditions.
pub fn dataset_of(
    images: &Bound<'_, PyAny>,
    label_values: &Bound<'_, PyAny>,
    groups: Option<&Bound<'_, PyAny>>,
    conditions: Option<&Bound<'_, PyAny>>,
) -> PyResult<Dataset> {
    let images = Images::new(images, "images")?;
    if !images.batch {
        return Err(data_error(
            "images: expected a batch (n, rows, cols); for one image use images[None]",
        ));
    }
    let n = images.len();
    let names = labels(label_values, "labels", n)?;
    let groups = groups.map(|g| labels(g, "groups", n)).transpose()?;
    let conditions = conditions.map(|c| labels(c, "conditions", n)).transpose()?;
    let mut samples = Vec::with_capacity(n);
    for (index, label) in names.into_iter().enumerate() {
        let frame = images.frame(index)?.to_frame();
        let mut sample = Sample::new(frame, label, PathBuf::from("images"), index);
        sample.group = groups.as_ref().map(|g| g[index].clone());
        sample.condition = conditions.as_ref().map(|c| c[index].clone());
        samples.push(sample);
    }
    Dataset::from_samples(format!("numpy images ({n})"), samples).py_err()
}
