//! Classifiers on reduced feature vectors: the paper's Parzen-window estimator, Gaussian maximum likelihood
//! (MLE) and linear discriminant analysis (LDA), support vector machines and k-nearest neighbours.
//!
//! [`ClassifierConfig`] chooses a classifier and its training parameters; training gives a
//! [`ClassifierModel`] (serde-tagged by `kind`, stored in trained models). Classification writes class
//! posteriors into a caller buffer and uses a caller-provided [`ClassifierScratch`], so it does not allocate.

pub mod calibration;
mod common;
pub mod gaussian;
pub mod knn;
pub mod parzen;
pub mod svm;

use serde::{Deserialize, Serialize};

use crate::error::Result;

pub use gaussian::{GaussianConfig, GaussianModel, GaussianScratch, Shrinkage, ledoit_wolf};
pub use knn::{KnnConfig, KnnModel, KnnScratch};
pub use parzen::{
    LabeledVectors, ParzenConfig, ParzenModel, ParzenScratch, SigmaChoice, SigmaPoint, SigmaSearch,
};
pub use svm::{Kernel, KernelKind, SvmCandidate, SvmConfig, SvmModel, SvmScratch};

/// The classifier families, by name (as the CLI's `--classifier` spells them).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ClassifierKind {
    /// Parzen-window estimator with a Gaussian kernel (the paper's classifier).
    Pwe,
    /// Gaussian class densities, one shrunk full covariance per class (maximum likelihood).
    Mle,
    /// Gaussian class densities with one shared shrunk covariance (linear discriminant).
    Lda,
    /// One-vs-one C-SVC, linear or RBF kernel, chosen on validation.
    Svm,
    /// k-nearest neighbours, k chosen on validation.
    Knn,
}

impl ClassifierKind {
    pub const ALL: [Self; 5] = [Self::Pwe, Self::Mle, Self::Lda, Self::Svm, Self::Knn];

    pub fn as_str(self) -> &'static str {
        match self {
            Self::Pwe => "pwe",
            Self::Mle => "mle",
            Self::Lda => "lda",
            Self::Svm => "svm",
            Self::Knn => "knn",
        }
    }

    /// Parses a name (case-insensitive).
    pub fn parse(text: &str) -> Result<Self> {
        crate::error::parse_name(text, Self::ALL, Self::as_str, "classifier", "classifier")
    }

    /// The default training parameters of this family.
    pub fn default_config(self) -> ClassifierConfig {
        match self {
            Self::Pwe => ClassifierConfig::Pwe(ParzenConfig::default()),
            Self::Mle => ClassifierConfig::Mle(GaussianConfig::default()),
            Self::Lda => ClassifierConfig::Lda(GaussianConfig::default()),
            Self::Svm => ClassifierConfig::Svm(SvmConfig::default()),
            Self::Knn => ClassifierConfig::Knn(KnnConfig::default()),
        }
    }
}

impl std::fmt::Display for ClassifierKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// A classifier family with its training parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum ClassifierConfig {
    Pwe(ParzenConfig),
    Mle(GaussianConfig),
    Lda(GaussianConfig),
    Svm(SvmConfig),
    Knn(KnnConfig),
}

impl Default for ClassifierConfig {
    fn default() -> Self {
        Self::Pwe(ParzenConfig::default())
    }
}

impl ClassifierConfig {
    pub fn kind(&self) -> ClassifierKind {
        match self {
            Self::Pwe(_) => ClassifierKind::Pwe,
            Self::Mle(_) => ClassifierKind::Mle,
            Self::Lda(_) => ClassifierKind::Lda,
            Self::Svm(_) => ClassifierKind::Svm,
            Self::Knn(_) => ClassifierKind::Knn,
        }
    }

    /// Whether fitting needs validation vectors: the Parzen window choosing σ on them (a fixed σ does
    /// not; the other classifiers use them when there are some and do without otherwise).
    pub fn needs_validation(&self) -> bool {
        matches!(
            self,
            Self::Pwe(ParzenConfig {
                sigma: SigmaChoice::Search(_),
            })
        )
    }

    /// Checks the parameters on their own (no data needed).
    pub fn check(&self) -> Result<()> {
        match self {
            Self::Pwe(config) => config.check(),
            Self::Mle(config) | Self::Lda(config) => config.check(),
            Self::Svm(config) => config.check(),
            Self::Knn(config) => config.check(),
        }
    }

    /// Trains on reduced vectors. `validation` is used for model selection (the Parzen σ, the SVM's C and
    /// gamma, k, the posterior temperature); every model but the Parzen one is then refitted on training +
    /// validation vectors (the Parzen model stores both, as in the paper).
    pub fn fit(
        &self,
        train: LabeledVectors<'_>,
        validation: LabeledVectors<'_>,
        n_classes: usize,
        dims: usize,
    ) -> Result<ClassifierModel> {
        self.fit_with(train, validation, n_classes, dims, true)
    }

    /// [`fit`](Self::fit), or, without `calibrate`, for counting right answers only: the same
    /// decisions, the posteriors possibly uncalibrated (the SVM skips the cross-validation that fits
    /// its temperature).
    pub(crate) fn fit_with(
        &self,
        train: LabeledVectors<'_>,
        validation: LabeledVectors<'_>,
        n_classes: usize,
        dims: usize,
        calibrate: bool,
    ) -> Result<ClassifierModel> {
        match self {
            Self::Pwe(config) => ParzenModel::fit(train, validation, n_classes, dims, config)
                .map(ClassifierModel::Pwe),
            Self::Mle(config) => {
                GaussianModel::fit(train, validation, n_classes, dims, false, config)
                    .map(ClassifierModel::Mle)
            }
            Self::Lda(config) => {
                GaussianModel::fit(train, validation, n_classes, dims, true, config)
                    .map(ClassifierModel::Lda)
            }
            Self::Svm(config) => {
                SvmModel::fit_with(train, validation, n_classes, dims, config, calibrate)
                    .map(ClassifierModel::Svm)
            }
            Self::Knn(config) => {
                KnnModel::fit(train, validation, n_classes, dims, config).map(ClassifierModel::Knn)
            }
        }
    }
}

/// A trained classifier.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum ClassifierModel {
    Pwe(ParzenModel),
    Mle(GaussianModel),
    Lda(GaussianModel),
    Svm(SvmModel),
    Knn(KnnModel),
}

impl ClassifierModel {
    pub fn kind(&self) -> ClassifierKind {
        match self {
            Self::Pwe(_) => ClassifierKind::Pwe,
            Self::Mle(_) => ClassifierKind::Mle,
            Self::Lda(_) => ClassifierKind::Lda,
            Self::Svm(_) => ClassifierKind::Svm,
            Self::Knn(_) => ClassifierKind::Knn,
        }
    }

    /// Length of the vectors this model classifies.
    pub fn dims(&self) -> usize {
        match self {
            Self::Pwe(model) => model.dims(),
            Self::Mle(model) | Self::Lda(model) => model.dims(),
            Self::Svm(model) => model.dims(),
            Self::Knn(model) => model.dims(),
        }
    }

    pub fn n_classes(&self) -> usize {
        match self {
            Self::Pwe(model) => model.n_classes(),
            Self::Mle(model) | Self::Lda(model) => model.n_classes(),
            Self::Svm(model) => model.n_classes(),
            Self::Knn(model) => model.n_classes(),
        }
    }

    /// The hyper-parameters training chose, in words (for reports).
    pub fn describe(&self) -> String {
        match self {
            Self::Pwe(model) => format!("sigma {:.4e}", model.sigma()),
            Self::Mle(model) | Self::Lda(model) => {
                let s = model.shrinkage();
                let mean = s.iter().sum::<f64>() / s.len().max(1) as f64;
                format!(
                    "Ledoit-Wolf shrinkage {mean:.3}, temperature {:.3e}",
                    model.temperature()
                )
            }
            Self::Svm(model) => match model.kernel() {
                Kernel::Linear => format!("linear, C {}, {} SVs", model.c(), model.n_support()),
                Kernel::Rbf { gamma } => {
                    format!(
                        "rbf gamma {gamma:.3e}, C {}, {} SVs",
                        model.c(),
                        model.n_support()
                    )
                }
            },
            Self::Knn(model) => format!("k {}, temperature {:.3e}", model.k(), model.temperature()),
        }
    }

    /// Scratch buffers sized for this model.
    pub fn scratch(&self) -> ClassifierScratch {
        match self {
            Self::Pwe(model) => ClassifierScratch::Pwe(model.scratch()),
            Self::Mle(model) | Self::Lda(model) => ClassifierScratch::Gaussian(model.scratch()),
            Self::Svm(model) => ClassifierScratch::Svm(model.scratch()),
            Self::Knn(model) => ClassifierScratch::Knn(model.scratch()),
        }
    }

    /// Classifies `x`: writes class posteriors into `posteriors` (`n_classes` long) and returns the most
    /// likely class. Does not allocate once `scratch` has been sized by [`scratch`](Self::scratch).
    /// A scratch of another family is replaced by a fresh one (which allocates once).
    pub fn classify_into(
        &self,
        x: &[f64],
        scratch: &mut ClassifierScratch,
        posteriors: &mut [f64],
    ) -> Result<usize> {
        match (self, &mut *scratch) {
            (Self::Pwe(model), ClassifierScratch::Pwe(s)) => model.classify_into(x, s, posteriors),
            (Self::Mle(model) | Self::Lda(model), ClassifierScratch::Gaussian(s)) => {
                model.classify_into(x, s, posteriors)
            }
            (Self::Svm(model), ClassifierScratch::Svm(s)) => model.classify_into(x, s, posteriors),
            (Self::Knn(model), ClassifierScratch::Knn(s)) => model.classify_into(x, s, posteriors),
            _ => {
                *scratch = self.scratch();
                self.classify_into(x, scratch, posteriors)
            }
        }
    }
}

/// Reusable buffers of [`ClassifierModel::classify_into`].
#[derive(Clone, Debug)]
pub enum ClassifierScratch {
    Pwe(ParzenScratch),
    Gaussian(GaussianScratch),
    Svm(SvmScratch),
    Knn(KnnScratch),
}
