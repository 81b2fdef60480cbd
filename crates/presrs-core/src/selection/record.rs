//! The record of an automatic choice: every candidate's validation scores and the one chosen. Plain data,
//! stored in the trained model; the procedure that makes it is [`crate::selection::select`].

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::metrics::MeanStd;
use crate::pipeline::config::TrainConfig;
use crate::selection::validate_by::ValidateBy;

/// One candidate's validation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CandidateScore {
    pub features: String,
    pub classifier: String,
    pub config: TrainConfig,
    /// Accuracy over the folds (mean and spread); 0 when the candidate failed.
    pub accuracy: MeanStd,
    /// Accuracy of each fold, by held-out condition (or `split k`).
    pub per_fold: BTreeMap<String, f64>,
    /// Why the candidate could not be trained, if it could not.
    pub error: Option<String>,
    /// Not scored, or in a race scored on the first folds only: the automatic choice's time budget
    /// was spent before its turn (`error` says so). Never chosen.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub skipped: bool,
    /// Scored on the first folds only: it was clearly behind the best there, and the race
    /// ([`crate::selection::RACE_FOLDS`]) left it out of the other folds. Never chosen.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub dropped_early: bool,
}

impl CandidateScore {
    /// Scored on every fold: it can be chosen.
    pub fn is_contender(&self) -> bool {
        self.error.is_none() && !self.dropped_early
    }

    /// The candidate in words: its features (after an intensity transform, if any) + its classifier,
    /// and its principal components (`fft1d (sqrt) + pwe, 51 dims`), or `all features` for a
    /// classifier that takes every feature without a PCA step (`rocket + ridge, all features`).
    pub fn name(&self) -> String {
        let intensity = self.config.preprocess.intensity;
        let transform = if intensity.is_none() {
            String::new()
        } else {
            format!(" ({intensity})")
        };
        let dims = if self.config.classifier.kind().takes_all_features() {
            "all features".to_owned()
        } else {
            format!("{} dims", self.config.dims)
        };
        format!("{}{transform} + {}, {dims}", self.features, self.classifier)
    }
}

/// What the automatic choice ([`crate::selection::select`]) did: plain data, stored in the model.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Selection {
    /// How the candidates were validated (in words).
    pub method: String,
    /// Index of the chosen candidate in `scores`.
    pub chosen: usize,
    pub scores: Vec<CandidateScore>,
    /// The validation the data (or the caller) asked for, when it could not be used: a held-out fold
    /// held a class its training part lacks, so every candidate would have scored 0 on that class.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fallback: Option<ValidationFallback>,
    /// On how many samples the candidates were scored and where the time went (absent in models
    /// written before it was recorded).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cost: Option<SelectionCost>,
}

/// What an automatic choice scored its candidates on, and where its time went: the budget bounds the
/// scoring (the candidates' features included); training the winner on every sample comes after it.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SelectionCost {
    /// The samples the winner is trained on (training + validation).
    pub samples: usize,
    /// The samples the candidates were scored on: all of them, or a stratified subsample of
    /// [`crate::selection::AutoChoice::scoring_samples`] when there are more.
    pub scored_on: usize,
    /// Seconds spent computing the candidates' features (part of the scoring).
    pub features_seconds: f64,
    /// Seconds spent scoring the candidates, their features included: what the budget bounds.
    pub scoring_seconds: f64,
    /// Seconds spent training the winner on every sample, after the scoring and outside the budget.
    pub final_fit_seconds: f64,
}

impl SelectionCost {
    /// Whether the candidates were scored on a subsample.
    pub fn subsampled(&self) -> bool {
        self.scored_on < self.samples
    }
}

/// A validation scheme passed over for another ([`Selection::fallback`]).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct ValidationFallback {
    /// The scheme asked for (or that `auto` resolved to first): group or condition.
    pub wanted: ValidateBy,
    /// The scheme used instead.
    pub used: ValidateBy,
    /// The classes a held-out fold of `wanted` held and its training part lacked, each with the first
    /// such fold's name (`carpet`, `carpet_G2_000`), in the order of the folds.
    pub unseen: Vec<(String, String)>,
}

impl Selection {
    pub fn chosen(&self) -> Option<&CandidateScore> {
        self.scores.get(self.chosen)
    }
}
