//! What an evaluation found: each repeat's result ([`RepeatResult`]) and their summary ([`EvalReport`]).

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::protocol::Protocol;
use crate::metrics::{Confusion, MeanStd};
use crate::reliability::Reliability;

/// What one repeat found.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RepeatResult {
    pub seed: u64,
    pub overall_accuracy: f64,
    pub per_condition: BTreeMap<String, f64>,
    /// The Parzen σ of each model trained in this repeat (one per held-out value for leave-one-out).
    pub sigmas: Vec<f64>,
    /// Training, validation and test images, summed over the repeat's folds (see `folds`).
    pub n_train: usize,
    pub n_validation: usize,
    pub n_test: usize,
    pub train_seconds: f64,
    /// Models trained in this repeat: one, or one per held-out value with leave-one-out. An image
    /// trains in every fold but the one that holds it out, so `n_train` and `n_validation` may exceed
    /// the images there are; `n_test` counts each tested image once per repeat.
    #[serde(default = "one_fold")]
    pub folds: usize,
}

/// Repeats stored before `folds` was recorded trained one model (the paper's protocol) or did not say.
fn one_fold() -> usize {
    1
}

impl RepeatResult {
    /// The image counts in words: `13 training + 7 validation images, 60 tested` for one model, and per
    /// fold (on average) with the total tested for several.
    pub fn counts_text(&self) -> String {
        self.counts_text_of("images")
    }

    /// [`Self::counts_text`] with the samples called `nouns` (`stances`, `series`, `samples`).
    pub fn counts_text_of(&self, nouns: &str) -> String {
        if self.folds <= 1 {
            return format!(
                "{} training + {} validation {nouns}, {} tested",
                self.n_train, self.n_validation, self.n_test
            );
        }
        let per_fold = |n: usize| n as f64 / self.folds as f64;
        format!(
            "{} folds, per fold (on average) {:.0} training + {:.0} validation {nouns} and {:.0} \
             tested; {} tested in all (summed over the folds: {} training + {} validation)",
            self.folds,
            per_fold(self.n_train),
            per_fold(self.n_validation),
            per_fold(self.n_test),
            self.n_test,
            self.n_train,
            self.n_validation
        )
    }
}

/// The result of an evaluation ([`Evaluation::run`](super::run::Evaluation::run)): every repeat, and
/// their summary.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EvalReport {
    pub protocol: Protocol,
    pub repeats: Vec<RepeatResult>,
    pub overall: MeanStd,
    /// Accuracy per tested condition (or held-out value), mean and spread over repeats.
    pub per_condition: BTreeMap<String, MeanStd>,
    pub confusion: Confusion,
    /// Median wall time of one classification (crop + features + PCA + classifier), nanoseconds.
    pub median_classify_ns: u64,
    /// Perturbed test images the model could not classify (e.g. values beyond what its features can
    /// represent), over all repeats. Each counts as a wrong answer in the accuracies and is missing from
    /// the confusion matrix (it has no predicted class). An unperturbed image that cannot be classified
    /// is an error instead: that is bad data, not a fault the evaluation injected.
    #[serde(default)]
    pub unclassified: u64,
    /// The confidences of every classified test image against whether it was right, over all repeats:
    /// how far the model's confidences can be trusted.
    #[serde(default)]
    pub reliability: Reliability,
}

/// The report of one evaluation's repeats.
pub(super) fn report_of(
    protocol: &Protocol,
    results: Vec<RepeatResult>,
    confusion: Confusion,
    mut times_ns: Vec<u64>,
) -> EvalReport {
    let overall = MeanStd::of(
        &results
            .iter()
            .map(|r| r.overall_accuracy)
            .collect::<Vec<_>>(),
    );
    let mut keys: Vec<&String> = results
        .iter()
        .flat_map(|r| r.per_condition.keys())
        .collect();
    keys.sort();
    keys.dedup();
    let per_condition = keys
        .into_iter()
        .map(|key| {
            let values: Vec<f64> = results
                .iter()
                .filter_map(|r| r.per_condition.get(key).copied())
                .collect();
            (key.clone(), MeanStd::of(&values))
        })
        .collect();
    times_ns.sort_unstable();
    let median_classify_ns = times_ns.get(times_ns.len() / 2).copied().unwrap_or(0);
    EvalReport {
        protocol: protocol.clone(),
        repeats: results,
        overall,
        per_condition,
        confusion,
        median_classify_ns,
        unclassified: 0,
        reliability: Reliability::default(),
    }
}
