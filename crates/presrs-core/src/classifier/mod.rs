//! Classifiers on reduced feature vectors: the paper's Parzen-window estimator, Gaussian maximum likelihood
//! (MLE) and linear discriminant analysis (LDA), support vector machines, k-nearest neighbours and ridge
//! regression (one-vs-rest).
//!
//! Each family implements [`ClassifierFamily`] in its own file and is registered once (the built-in list
//! in `registry.rs`, or [`register`] at run time); [`ClassifierKind`] names one. [`ClassifierConfig`]
//! holds a family and its training parameters; training gives a [`ClassifierModel`] (serde-tagged by
//! `kind`, stored in trained models). Classification writes class posteriors into a caller buffer and uses
//! a caller-provided [`ClassifierScratch`], so it does not allocate.

pub mod calibration;
mod common;
mod dynamic;
mod erased;
mod family;
pub mod gaussian;
pub mod knn;
pub mod parzen;
mod registry;
pub mod ridge;
pub mod svm;

pub use dynamic::{ClassifierConfig, ClassifierModel, ClassifierScratch};
pub use family::{ClassifierFamily, FitData, FitRows};
pub use registry::{ClassifierKind, register};

pub use gaussian::{
    GaussianConfig, GaussianModel, GaussianScratch, LdaFamily, MleFamily, Shrinkage, ledoit_wolf,
};
pub use knn::{KnnConfig, KnnFamily, KnnModel, KnnScratch};
pub use parzen::{
    LabeledVectors, ParzenConfig, ParzenModel, ParzenScratch, PweFamily, SigmaChoice, SigmaPoint,
    SigmaSearch,
};
pub use ridge::{RidgeConfig, RidgeFamily, RidgeModel, RidgePin, RidgeRawFamily, RidgeScratch};
pub use svm::{Kernel, KernelKind, SvmCandidate, SvmConfig, SvmFamily, SvmModel, SvmScratch};
