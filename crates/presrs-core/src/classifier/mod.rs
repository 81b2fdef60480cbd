//! Classifiers on reduced feature vectors (the paper's Parzen-window estimator, and more).
//!
//! [`ClassifierConfig`] chooses a classifier and its training parameters; training gives a
//! [`ClassifierModel`] (serde-tagged by `kind`, stored in trained models). Classification writes class
//! posteriors into a caller buffer and uses a caller-provided [`ClassifierScratch`], so it does not allocate.

pub mod parzen;

use serde::{Deserialize, Serialize};

use crate::error::{CoreError, Result};

pub use parzen::{
    LabeledVectors, ParzenConfig, ParzenModel, ParzenScratch, SigmaChoice, SigmaPoint, SigmaSearch,
};

/// The classifier families, by name (as the CLI's `--classifier` spells them).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ClassifierKind {
    /// Parzen-window estimator with a Gaussian kernel (the paper's classifier).
    Pwe,
}

impl ClassifierKind {
    pub const ALL: [Self; 1] = [Self::Pwe];

    pub fn as_str(self) -> &'static str {
        match self {
            Self::Pwe => "pwe",
        }
    }

    /// Parses a name (case-insensitive).
    pub fn parse(text: &str) -> Result<Self> {
        let wanted = text.trim().to_ascii_lowercase();
        Self::ALL
            .into_iter()
            .find(|kind| kind.as_str() == wanted)
            .ok_or_else(|| CoreError::Param {
                name: "classifier",
                reason: format!(
                    "unknown classifier {text:?}; known: {}",
                    Self::ALL.map(Self::as_str).join(", ")
                ),
            })
    }

    /// The default training parameters of this family.
    pub fn default_config(self) -> ClassifierConfig {
        match self {
            Self::Pwe => ClassifierConfig::Pwe(ParzenConfig::default()),
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
        }
    }

    /// Checks the parameters on their own (no data needed).
    pub fn check(&self) -> Result<()> {
        match self {
            Self::Pwe(config) => config.check(),
        }
    }

    /// Trains on reduced vectors. `validation` is used for model selection (e.g. the Parzen σ); whether it
    /// is also kept in the model depends on the classifier (the Parzen model keeps it, as in the paper).
    pub fn fit(
        &self,
        train: LabeledVectors<'_>,
        validation: LabeledVectors<'_>,
        n_classes: usize,
        dims: usize,
    ) -> Result<ClassifierModel> {
        match self {
            Self::Pwe(config) => ParzenModel::fit(train, validation, n_classes, dims, config)
                .map(ClassifierModel::Pwe),
        }
    }
}

/// A trained classifier.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum ClassifierModel {
    Pwe(ParzenModel),
}

impl ClassifierModel {
    pub fn kind(&self) -> ClassifierKind {
        match self {
            Self::Pwe(_) => ClassifierKind::Pwe,
        }
    }

    /// Length of the vectors this model classifies.
    pub fn dims(&self) -> usize {
        match self {
            Self::Pwe(model) => model.dims(),
        }
    }

    pub fn n_classes(&self) -> usize {
        match self {
            Self::Pwe(model) => model.n_classes(),
        }
    }

    /// Scratch buffers sized for this model.
    pub fn scratch(&self) -> ClassifierScratch {
        match self {
            Self::Pwe(model) => ClassifierScratch::Pwe(model.scratch()),
        }
    }

    /// Classifies `x`: writes class posteriors into `posteriors` (`n_classes` long) and returns the most
    /// likely class. Does not allocate once `scratch` has been sized by [`scratch`](Self::scratch).
    pub fn classify_into(
        &self,
        x: &[f64],
        scratch: &mut ClassifierScratch,
        posteriors: &mut [f64],
    ) -> Result<usize> {
        // When more families exist, a scratch of the wrong family is an error (see `scratch`).
        match (self, scratch) {
            (Self::Pwe(model), ClassifierScratch::Pwe(scratch)) => {
                model.classify_into(x, scratch, posteriors)
            }
        }
    }
}

/// Reusable buffers of [`ClassifierModel::classify_into`].
#[derive(Clone, Debug)]
pub enum ClassifierScratch {
    Pwe(ParzenScratch),
}
