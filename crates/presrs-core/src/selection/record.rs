//! The record of an automatic choice: every candidate's validation scores and the one chosen. Plain data,
//! stored in the trained model; the procedure that makes it is [`crate::selection::select`].

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::metrics::MeanStd;
use crate::pipeline::config::TrainConfig;

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
    /// Not scored: the automatic choice's time budget was spent before its turn (`error` says so).
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
    /// and its principal components (`fft1d (sqrt) + pwe, 51 dims`).
    pub fn name(&self) -> String {
        let intensity = self.config.preprocess.intensity;
        let transform = if intensity.is_none() {
            String::new()
        } else {
            format!(" ({intensity})")
        };
        format!(
            "{}{transform} + {}, {} dims",
            self.features, self.classifier, self.config.dims
        )
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
}

impl Selection {
    pub fn chosen(&self) -> Option<&CandidateScore> {
        self.scores.get(self.chosen)
    }
}
