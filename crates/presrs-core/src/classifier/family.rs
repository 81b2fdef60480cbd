//! What a classifier family is: the one trait a classifier file implements to be trained, stored and
//! chosen by the pipeline (in the manner of linfa's `Fit`/`Predict`, with the hyper-parameters checked
//! once before fitting).
//!
//! A family is a unit type (`PweFamily`, `LdaFamily`, ...) naming its hyper-parameters
//! ([`ClassifierFamily::Config`]), its trained state ([`ClassifierFamily::Model`]) and the buffers
//! classification reuses ([`ClassifierFamily::Scratch`]). Adding one is one new file with its
//! `impl ClassifierFamily` and one registration line: a line in the built-in list
//! (`classifier/registry.rs`) or, for an extension or a test, [`register`](super::register). The model
//! file format (`{"kind": NAME, ...}`), the automatic search and the Python names follow from it.

use std::fmt::Debug;

use serde::Serialize;
use serde::de::DeserializeOwned;

use super::common::LabeledVectors;
use crate::error::Result;

/// The data a classifier is fitted on: reduced vectors of training and validation images (in single
/// precision, `FitData<'_, f32>`, for [`ClassifierFamily::fit_single`]).
#[derive(Debug)]
pub struct FitData<'a, T = f64> {
    pub train: LabeledVectors<'a, T>,
    /// For model selection (σ, C, k, the posterior temperature); may be empty unless
    /// [`ClassifierFamily::needs_validation`] says otherwise.
    pub validation: LabeledVectors<'a, T>,
    pub n_classes: usize,
    /// Length of every vector.
    pub dims: usize,
    /// Whether the posteriors must be calibrated; without it only the decisions count (the automatic
    /// choice counting right answers), and a family may skip its calibration.
    pub calibrate: bool,
}

impl<T> Clone for FitData<'_, T> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<T> Copy for FitData<'_, T> {}

/// The data of [`FitData`] as rows held elsewhere (each `dims` values, e.g. some rows of a feature
/// table), for a family that reads them in place ([`ClassifierFamily::fit_rows`]).
#[derive(Clone, Copy, Debug)]
pub struct FitRows<'a> {
    pub train: &'a [&'a [f64]],
    pub train_classes: &'a [usize],
    pub validation: &'a [&'a [f64]],
    pub validation_classes: &'a [usize],
    pub n_classes: usize,
    pub dims: usize,
    pub calibrate: bool,
}

/// A classifier family: its name, hyper-parameters, training and classification.
pub trait ClassifierFamily: Send + Sync + 'static {
    /// The name users and files know it by (`--classifier NAME`, `{"kind": NAME}`): lower-case.
    const NAME: &'static str;
    /// Whether the automatic choice tries it.
    const JOINS_AUTO: bool = true;
    /// Whether it takes every feature rather than the principal components: a family that standardises
    /// and regularises on its own (ridge, whose fit is cheap in its Gram form) skips the PCA step, which
    /// keeps the directions of largest variance, not those that separate the classes.
    const TAKES_ALL_FEATURES: bool = false;

    /// Hyper-parameters; `Default` is what users get when they only name the family.
    type Config: Clone + Debug + Default + PartialEq + Serialize + DeserializeOwned + Send + Sync;
    /// The trained state, stored in model files; loading it must check it (it may be crafted).
    type Model: Clone + Debug + PartialEq + Serialize + DeserializeOwned + Send + Sync;
    /// Buffers [`classify_into`](Self::classify_into) reuses, so that it does not allocate.
    type Scratch: Debug + Send + 'static;

    /// Checks the hyper-parameters on their own (no data needed); fitting may assume they passed.
    fn check(config: &Self::Config) -> Result<()>;

    /// Whether fitting needs validation vectors (the others use them when there are some).
    fn needs_validation(config: &Self::Config) -> bool {
        let _ = config;
        false
    }

    /// Trains on `data` with checked hyper-parameters.
    fn fit(config: &Self::Config, data: FitData<'_>) -> Result<Self::Model>;

    /// Whether [`fit_single`](Self::fit_single) trains on vectors in single precision: a family that
    /// takes every feature (thousands per vector) and reads them block by block, so that the pipeline
    /// keeps its feature table at half the memory.
    const READS_SINGLE: bool = false;

    /// [`fit`](Self::fit) on vectors in single precision; only called when
    /// [`READS_SINGLE`](Self::READS_SINGLE).
    fn fit_single(config: &Self::Config, data: FitData<'_, f32>) -> Result<Self::Model> {
        let _ = (config, data);
        Err(crate::error::CoreError::Param {
            name: "classifier",
            reason: format!("{} does not read single-precision vectors", Self::NAME),
        })
    }

    /// Whether [`fit_rows`](Self::fit_rows) trains on rows held elsewhere: a family that takes every
    /// feature, so that the automatic choice scores it on its feature table's rows without a copy.
    const READS_ROWS: bool = false;

    /// [`fit`](Self::fit) on rows held elsewhere; only called when [`READS_ROWS`](Self::READS_ROWS).
    fn fit_rows(config: &Self::Config, data: FitRows<'_>) -> Result<Self::Model> {
        let _ = (config, data);
        Err(crate::error::CoreError::Param {
            name: "classifier",
            reason: format!("{} does not read rows in place", Self::NAME),
        })
    }

    /// Whether [`pinned`](Self::pinned) gives a configuration: the family searches hyper-parameters
    /// (or calibrates) at a cost that grows faster than its final fit, so that on large data the
    /// search is run on a subsample and the choice fitted on every vector.
    const PINS: bool = false;

    /// `config` with the hyper-parameters (and calibration) `model`, fitted with it, chose, fixed:
    /// fitting it searches nothing. `None`: the family has nothing to pin (its fit is refitted with
    /// `config` on all the data).
    fn pinned(config: &Self::Config, model: &Self::Model) -> Option<Self::Config> {
        let _ = (config, model);
        None
    }

    /// Length of the vectors `model` classifies.
    fn dims(model: &Self::Model) -> usize;

    fn n_classes(model: &Self::Model) -> usize;

    /// The hyper-parameters training chose, in words (for reports).
    fn describe(model: &Self::Model) -> String;

    /// Buffers sized for `model`.
    fn scratch(model: &Self::Model) -> Self::Scratch;

    /// Writes the posterior of every class into `posteriors` (`n_classes` long) and returns the most
    /// likely class. Must not allocate once `scratch` comes from [`scratch`](Self::scratch).
    fn classify_into(
        model: &Self::Model,
        x: &[f64],
        scratch: &mut Self::Scratch,
        posteriors: &mut [f64],
    ) -> Result<usize>;
}
