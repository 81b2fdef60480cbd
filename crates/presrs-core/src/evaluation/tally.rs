//! The running tally of one perturbation's tests: fold by fold, then repeat by repeat, into a report.

use std::collections::BTreeMap;

use super::folds::Fold;
use super::protocol::Protocol;
use super::report::{EvalReport, RepeatResult, report_of};
use crate::error::{CoreError, Result};
use crate::metrics::{Confusion, ratio};
use crate::pipeline::LabeledImage;
use crate::reliability::Reliability;

/// What became of one test image: its predicted class, confidence and classification time in
/// nanoseconds; `Ok(None)` for a perturbed image the model could not classify.
pub(super) type TestOutcome = Result<Option<(usize, f64, u64)>>;

/// What one perturbation's tests have found so far.
pub(super) struct Tally {
    confusion: Confusion,
    times_ns: Vec<u64>,
    results: Vec<RepeatResult>,
    unclassified: u64,
    reliability: Reliability,
}

impl Tally {
    pub(super) fn new(labels: Vec<String>, repeats: usize) -> Self {
        Self {
            confusion: Confusion::new(labels),
            times_ns: Vec::new(),
            results: Vec::with_capacity(repeats),
            unclassified: 0,
            reliability: Reliability::default(),
        }
    }

    /// Adds the `outcomes` of one fold's test images (`fold.test`, in order): the confusion, the
    /// times, the reliability, and `correct`, the hits and tests by condition (or held-out value).
    pub(super) fn add_fold(
        &mut self,
        correct: &mut BTreeMap<String, (u64, u64)>,
        fold: &Fold,
        samples: &[LabeledImage<'_>],
        model: &crate::pipeline::TrainedModel,
        outcomes: Vec<TestOutcome>,
    ) -> Result<()> {
        let confusion = &mut self.confusion;
        for (&i, outcome) in fold.test.iter().zip(outcomes) {
            let Some((predicted, confidence, ns)) = outcome? else {
                // A wrong answer, with no predicted class for the confusion matrix.
                self.unclassified += 1;
                correct.entry(fold.key_of(&samples[i])).or_default().1 += 1;
                continue;
            };
            self.times_ns.push(ns);
            let predicted_label = &model.class_names()[predicted];
            let truth = confusion
                .labels
                .binary_search_by(|l| l.as_str().cmp(samples[i].label));
            let guess = confusion.labels.binary_search(predicted_label);
            if let (Ok(t), Ok(g)) = (truth, guess) {
                confusion.counts[t][g] += 1;
            }
            let key = fold.key_of(&samples[i]);
            let entry = correct.entry(key).or_default();
            entry.1 += 1;
            let right = predicted_label == samples[i].label;
            if right {
                entry.0 += 1;
            }
            self.reliability.add(confidence, right);
        }
        Ok(())
    }

    /// Ends a repeat: `result` with the accuracies of `correct` (hits and tests by condition) is its
    /// result. An error if nothing was tested.
    pub(super) fn add_repeat(
        &mut self,
        result: &RepeatResult,
        correct: BTreeMap<String, (u64, u64)>,
    ) -> Result<()> {
        let (hits, total) = correct
            .values()
            .fold((0, 0), |(c, t), &(c1, t1)| (c + c1, t + t1));
        if total == 0 {
            return Err(CoreError::NotEnoughData(
                "no sample is left to test on: the training set took every sample (draw fewer \
                 per class, or train on one condition and test on the others)"
                    .into(),
            ));
        }
        let mut result = result.clone();
        result.overall_accuracy = ratio(hits, total);
        result.per_condition = correct
            .into_iter()
            .map(|(key, (c, t))| (key, ratio(c, t)))
            .collect();
        self.results.push(result);
        Ok(())
    }

    pub(super) fn into_report(self, protocol: &Protocol) -> EvalReport {
        let mut report = report_of(protocol, self.results, self.confusion, self.times_ns);
        report.unclassified = self.unclassified;
        report.reliability = self.reliability;
        report
    }
}
