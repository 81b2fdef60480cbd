//! Comparing configurations: every one evaluated on the same draws ([`Evaluation::compare`]).

use serde::{Deserialize, Serialize};

use super::protocol::Protocol;
use super::report::EvalReport;
use super::run::{Evaluation, Models};
use crate::error::{CoreError, Result};
use crate::metrics::MeanStd;
use crate::pipeline::CheckedTrainConfig;

/// One combination of a comparison ([`Evaluation::compare`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ComparisonRow {
    /// The feature family (or `a+b` for a combination).
    pub features: String,
    pub classifier: String,
    pub config: crate::pipeline::TrainConfig,
    /// The evaluation, or why this combination could not be trained.
    pub report: std::result::Result<EvalReport, String>,
    /// Training time per trained model, seconds (mean and spread over repeats).
    pub train_seconds: MeanStd,
}

impl Evaluation<'_, '_> {
    /// Evaluates every configuration of `configs` with the same draws (so every combination sees the same
    /// training sets). A combination that cannot be trained (e.g. too few samples per class for its
    /// classifier) is reported with its error instead of stopping the comparison.
    pub fn compare(&self, configs: &[CheckedTrainConfig]) -> Result<Vec<ComparisonRow>> {
        let mut rows = Vec::with_capacity(configs.len());
        for config in configs {
            let inner = config.config();
            let report = match self.run(Models::Config(config)) {
                // a parameter error is the caller's mistake, not this combination's limitation
                Err(err @ CoreError::Param { .. }) => return Err(err),
                other => other,
            };
            let train_seconds = match &report {
                Ok(report) => {
                    let per_model: Vec<f64> = report
                        .repeats
                        .iter()
                        .map(|r| {
                            let models = match self.protocol {
                                Protocol::TrainCondition { .. } => 1,
                                Protocol::LeaveOneOut { .. } => r.per_condition.len().max(1),
                            };
                            r.train_seconds / models as f64
                        })
                        .collect();
                    MeanStd::of(&per_model)
                }
                Err(_) => MeanStd::default(),
            };
            rows.push(ComparisonRow {
                features: inner.features.name(),
                classifier: inner.classifier.kind().as_str().to_owned(),
                config: inner.clone(),
                report: report.map_err(|err| err.to_string()),
                train_seconds,
            });
        }
        Ok(rows)
    }
}
