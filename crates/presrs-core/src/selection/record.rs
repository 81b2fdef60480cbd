//! The record of an automatic choice: every candidate's validation scores and the one chosen. Plain data,
//! stored in the trained model; the procedure that makes it is [`crate::selection::select`].

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::features::minirocket_draws;
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

    /// The candidate in words: its [`method`](Self::method) and its principal components
    /// (`fft1d (sqrt) + pwe, 51 dims`), or `all features` for a classifier that takes every feature
    /// without a PCA step (`rocket + ridge, all features`), and MiniRocket's draws when there are
    /// several (`rocket_unscaled + ridge_raw, all features, 4 draws`).
    pub fn name(&self) -> String {
        let dims = if self.config.classifier.kind().takes_all_features() {
            "all features".to_owned()
        } else {
            format!("{} dims", self.config.dims)
        };
        let draws = minirocket_draws(&self.config.features);
        if draws > 1 {
            format!("{}, {dims}, {draws} draws", self.method())
        } else {
            format!("{}, {dims}", self.method())
        }
    }

    /// Its features (after an intensity transform, if any) + its classifier, whatever the principal
    /// components: `rocket_unscaled + ridge_raw`, `fft1d (sqrt) + pwe`.
    pub fn method(&self) -> String {
        let intensity = self.config.preprocess.intensity;
        if intensity.is_none() {
            format!("{} + {}", self.features, self.classifier)
        } else {
            format!("{} ({intensity}) + {}", self.features, self.classifier)
        }
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
/// scoring (the candidates' features included; [`SelectionCost::over_budget_seconds`] says when it
/// ended past it anyway); training the winner on every sample comes after it.
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
    /// The time budget of the scoring, in seconds (`None`: no budget, or a model written before it
    /// was recorded).
    #[serde(default)]
    pub budget_seconds: Option<f64>,
    /// On how many samples the winner's hyper-parameters (its classifier's search and calibration)
    /// were chosen, when not on all of them: on large data, the subsample the candidates were scored
    /// on, and only the chosen ones fitted on every sample (`None`: searched on every sample, as on
    /// data no larger than the subsample, or for a classifier with nothing to search apart from its
    /// fit).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub searched_on: Option<usize>,
}

impl SelectionCost {
    /// Whether the candidates were scored on a subsample.
    pub fn subsampled(&self) -> bool {
        self.scored_on < self.samples
    }

    /// The seconds the scoring took beyond its budget, when it did: the first feature group of each
    /// phase is scored whatever the budget (so that there is a choice), and a group's turn is judged
    /// from the slowest candidate scored before it, so a slow first group, or a group slower than
    /// those before it, ends past the budget.
    pub fn over_budget_seconds(&self) -> Option<f64> {
        let budget = self.budget_seconds?;
        (self.scoring_seconds > budget).then_some(self.scoring_seconds - budget)
    }

    /// What bounded the scoring, in words: `within the budget of 60 s`, `62.3 s over the budget of
    /// 60 s (the first candidates are scored whatever the budget)`, or `no time budget`.
    pub fn budget_text(&self) -> String {
        match (self.budget_seconds, self.over_budget_seconds()) {
            (None, _) => "no time budget".to_owned(),
            (Some(budget), None) => format!("within the budget of {budget:.0} s"),
            (Some(budget), Some(over)) => format!(
                "{over:.1} s over the budget of {budget:.0} s: the first candidates are scored \
                 whatever the budget, and each later group's time is foreseen from the slowest \
                 candidate before it"
            ),
        }
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

    /// The other methods whose validation score is the chosen candidate's, each once (its first
    /// candidate; another number of principal components of the chosen method does not count): the
    /// validation could not rank them, so a prior (the preferred candidate, else the candidates'
    /// order), not the data, made the choice. Empty
    /// when the chosen candidate stands alone, failed, or is not the best (a rule such as one standard
    /// error chose it below the best on purpose).
    pub fn tied(&self) -> Vec<&CandidateScore> {
        let Some(chosen) = self.chosen().filter(|chosen| chosen.is_contender()) else {
            return Vec::new();
        };
        if self.best_above_chosen().is_some() {
            return Vec::new();
        }
        let mut tied: Vec<&CandidateScore> = Vec::new();
        for score in &self.scores {
            let same_score = (score.accuracy.mean - chosen.accuracy.mean).abs() <= TIE_TOLERANCE;
            if score.is_contender()
                && same_score
                && !same_method(score, chosen)
                && !tied.iter().any(|other| same_method(other, score))
            {
                tied.push(score);
            }
        }
        tied
    }

    /// The best-scoring candidate when it scored above the chosen one: the one-standard-error rule
    /// took an earlier candidate within the best's standard error ([`crate::selection::ChoiceRule`]).
    /// `None` when the chosen candidate is (or ties) the best, or failed.
    pub fn best_above_chosen(&self) -> Option<&CandidateScore> {
        let chosen = self.chosen().filter(|chosen| chosen.is_contender())?;
        let mut best: Option<&CandidateScore> = None;
        for score in &self.scores {
            let above = score.is_contender()
                && score.accuracy.mean > chosen.accuracy.mean + TIE_TOLERANCE
                && best.is_none_or(|best| score.accuracy.mean > best.accuracy.mean);
            if above {
                best = Some(score);
            }
        }
        best
    }
}

/// Validation scores closer than this are equal: fold accuracies are fractions of counts, and two
/// candidates right on the same samples have the same mean to the last bit or nearly.
pub(crate) const TIE_TOLERANCE: f64 = 1e-9;

/// The same features (after the same intensity transform) and classifier, whatever the principal
/// components.
fn same_method(a: &CandidateScore, b: &CandidateScore) -> bool {
    a.features == b.features
        && a.classifier == b.classifier
        && a.config.preprocess.intensity == b.config.preprocess.intensity
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cost(scoring_seconds: f64, budget_seconds: Option<f64>) -> SelectionCost {
        SelectionCost {
            scoring_seconds,
            budget_seconds,
            ..SelectionCost::default()
        }
    }

    #[test]
    fn a_scoring_past_its_budget_says_by_how_much_and_why() {
        assert_eq!(cost(12.0, None).budget_text(), "no time budget");
        assert_eq!(cost(12.0, Some(60.0)).over_budget_seconds(), None);
        assert_eq!(
            cost(12.0, Some(60.0)).budget_text(),
            "within the budget of 60 s"
        );
        let over = cost(92.5, Some(60.0));
        assert_eq!(over.over_budget_seconds(), Some(32.5));
        let text = over.budget_text();
        assert!(
            text.starts_with("32.5 s over the budget of 60 s: "),
            "{text}"
        );
        assert!(
            text.contains("the first candidates are scored whatever the budget"),
            "{text}"
        );
    }

    #[test]
    fn a_cost_recorded_before_the_budget_was_reads_as_without_one() {
        let old = r#"{"samples": 10, "scored_on": 10, "features_seconds": 1.0,
            "scoring_seconds": 2.0, "final_fit_seconds": 0.5}"#;
        let cost: SelectionCost = serde_json::from_str(old).unwrap();
        assert_eq!(cost.budget_seconds, None);
        assert_eq!(cost.budget_text(), "no time budget");
    }
}
