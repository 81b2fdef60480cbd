//! What an evaluation gives out, as values: the `presrs eval --json` document (which Python's
//! `Evaluation.to_dict()` returns too), the report's fault rows, and what the CLI's tables show. Nothing
//! here prints.

use std::collections::BTreeMap;

use presrs_core::evaluation::{ComparisonRow, EvalReport, MeanStd, Protocol};
use presrs_core::selection::Selection;
use serde::Serialize;

use crate::error::{Error, Result};
use crate::eval::race::FoldRaceJson;
use crate::eval::{CalibrationJson, EvalOutcome, InternalEstimate, PerturbationRow};
use crate::method::{ClassifierChoice, FeatureChoice, Method};

/// The `--json` document (the contract's fields first).
#[derive(Debug, Serialize)]
pub struct EvalJson<'r> {
    pub overall_accuracy: f64,
    pub overall_accuracy_std: f64,
    pub per_condition: BTreeMap<String, f64>,
    pub per_condition_std: BTreeMap<String, f64>,
    pub confusion: ConfusionJson,
    pub median_classify_ns: u64,
    pub per_class: BTreeMap<String, ClassMetrics>,
    pub sigmas: Vec<f64>,
    /// How far the reported confidences can be trusted (the full tally: `report.reliability`).
    pub calibration: CalibrationJson,
    pub report: &'r EvalReport,
    /// The automatic choice of every trained model (with `--features auto` or `--classifier auto`).
    #[serde(skip_serializing_if = "<[_]>::is_empty")]
    pub selections: &'r [Selection],
    /// With an automatic choice: its own estimate inside the training data (the chosen candidates'
    /// validation accuracy) and how it validated, to compare with `overall_accuracy`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub internal_estimate: Option<InternalEstimate>,
    /// Tested labels no training set of the protocol holds, by held-out value (`all` for a training
    /// condition); those samples are wrong whatever the model.
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub labels_never_trained: BTreeMap<String, Vec<String>>,
    /// With `--sample auto`: every fold's race of the sample kinds (both validation scores, the
    /// winner and why), in the draws' order.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub sample_races: Vec<FoldRaceJson>,
    /// The run's peak resident memory and what it comes to per sample, where the caller measured it
    /// (`presrs eval --json`: at the end of the run).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub memory: Option<crate::resources::MemoryUse>,
    /// The evaluation's warnings, in the caller's words (`presrs eval --json`: what it also prints on
    /// stderr; empty, and absent, where the caller keeps them elsewhere, as Python's `warnings()`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
}

/// The confusion matrix of every repeat: counts and rows scaled to 1.
#[derive(Debug, Serialize)]
pub struct ConfusionJson {
    pub labels: Vec<String>,
    pub counts: Vec<Vec<u64>>,
    pub row_normalised: Vec<Vec<f64>>,
}

/// One class's precision and recall over every repeat.
#[derive(Debug, Serialize)]
pub struct ClassMetrics {
    pub precision: f64,
    pub recall: f64,
}

impl<'r> EvalJson<'r> {
    /// The document of an evaluation: `outcome`'s report and automatic choices, and the labels no
    /// training set held (`EvalSetup::never_trained`). The one builder of the CLI's `eval --json` and
    /// of Python's `Evaluation.to_dict()`.
    pub fn of(
        outcome: &'r EvalOutcome,
        labels_never_trained: &BTreeMap<String, Vec<String>>,
    ) -> Self {
        Self {
            selections: &outcome.selections,
            internal_estimate: outcome.internal_estimate(),
            labels_never_trained: labels_never_trained.clone(),
            sample_races: outcome.sample_races.iter().map(FoldRaceJson::of).collect(),
            ..Self::new(&outcome.report)
        }
    }

    /// The document's fields that one report gives (no automatic choice, every label trained).
    pub fn new(report: &'r EvalReport) -> Self {
        let confusion = &report.confusion;
        let (precision, recall) = (confusion.precision(), confusion.recall());
        let per_condition = |field: fn(&MeanStd) -> f64| {
            report
                .per_condition
                .iter()
                .map(|(k, v)| (k.clone(), field(v)))
                .collect()
        };
        Self {
            overall_accuracy: report.overall.mean,
            overall_accuracy_std: report.overall.std,
            per_condition: per_condition(|m| m.mean),
            per_condition_std: per_condition(|m| m.std),
            confusion: ConfusionJson {
                labels: confusion.labels.clone(),
                counts: confusion.counts.clone(),
                row_normalised: confusion.row_normalised(),
            },
            median_classify_ns: report.median_classify_ns,
            calibration: CalibrationJson::new(&report.reliability),
            per_class: confusion
                .labels
                .iter()
                .enumerate()
                .map(|(i, label)| {
                    let metrics = ClassMetrics {
                        precision: precision[i],
                        recall: recall[i],
                    };
                    (label.clone(), metrics)
                })
                .collect(),
            sigmas: sigmas(report),
            report,
            selections: &[],
            internal_estimate: None,
            labels_never_trained: BTreeMap::new(),
            sample_races: Vec::new(),
            memory: None,
            warnings: Vec::new(),
        }
    }
}

/// The `--json` document with `--perturb`: the usual fields plus the perturbation rows.
#[derive(Debug, Serialize)]
pub struct PerturbedJson<'r> {
    #[serde(flatten)]
    pub eval: EvalJson<'r>,
    pub perturbations: &'r [PerturbationRow],
}

/// The `--compare --json` document: the usual `--json` fields of one combination (named in
/// `summary_of`), and every combination under `comparison`.
#[derive(Debug, Serialize)]
pub struct CompareJson<'r> {
    pub summary_of: SummaryOf<'r>,
    #[serde(flatten)]
    pub eval: EvalJson<'r>,
    pub comparison: Vec<CompareRowJson<'r>>,
}

/// Which combination the top-level fields of the `--compare --json` document describe, and why.
#[derive(Debug, Serialize)]
pub struct SummaryOf<'r> {
    pub features: &'r str,
    pub classifier: &'r str,
    /// `configured` (the --features and --classifier given) or `best` (highest overall accuracy).
    pub reason: &'static str,
}

/// One combination of the comparison: its accuracies, timings and full report, or why it failed.
#[derive(Debug, Serialize)]
pub struct CompareRowJson<'r> {
    pub features: &'r str,
    pub classifier: &'r str,
    pub config: &'r presrs_core::pipeline::TrainConfig,
    /// `null` when the combination could not be trained (see `error`).
    pub overall_accuracy: Option<f64>,
    pub overall_accuracy_std: Option<f64>,
    pub per_condition: BTreeMap<String, f64>,
    pub median_classify_ns: Option<u64>,
    /// Training time per trained model, seconds (mean and spread over repeats).
    pub train_seconds: MeanStd,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub report: Option<&'r EvalReport>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<&'r str>,
}

impl<'r> CompareJson<'r> {
    /// The document of `rows`; fails when no combination could be evaluated.
    pub fn new(rows: &'r [ComparisonRow], method: &Method) -> Result<Self> {
        let (chosen, reason) = summary_of(rows, method)?;
        let row = &rows[chosen];
        let report = row
            .report
            .as_ref()
            .map_err(|err| Error::data(err.clone()))?;
        Ok(Self {
            summary_of: SummaryOf {
                features: &row.features,
                classifier: &row.classifier,
                reason,
            },
            eval: EvalJson::new(report),
            comparison: rows.iter().map(CompareRowJson::new).collect(),
        })
    }
}

impl<'r> CompareRowJson<'r> {
    fn new(row: &'r ComparisonRow) -> Self {
        let report = row.report.as_ref().ok();
        Self {
            features: &row.features,
            classifier: &row.classifier,
            config: &row.config,
            overall_accuracy: report.map(|r| r.overall.mean),
            overall_accuracy_std: report.map(|r| r.overall.std),
            per_condition: report
                .map(|r| {
                    r.per_condition
                        .iter()
                        .map(|(k, v)| (k.clone(), v.mean))
                        .collect()
                })
                .unwrap_or_default(),
            median_classify_ns: report.map(|r| r.median_classify_ns),
            train_seconds: row.train_seconds,
            report,
            error: row.report.as_ref().err().map(String::as_str),
        }
    }
}

/// The rule of `summary_of`: the row of the combination `method` names (--features and --classifier
/// both given) when it was evaluated (`configured`), else the row with the highest overall accuracy
/// (`best`); an error when no combination could be evaluated.
pub fn summary_of(rows: &[ComparisonRow], method: &Method) -> Result<(usize, &'static str)> {
    let configured = match (&method.features, method.classifier) {
        (FeatureChoice::Kinds(kinds), ClassifierChoice::Kind(kind)) => {
            let features = presrs_core::features::FeatureConfig::combined(kinds).name();
            rows.iter().position(|row| {
                row.report.is_ok() && row.features == features && row.classifier == kind.as_str()
            })
        }
        _ => None,
    };
    if let Some(i) = configured {
        return Ok((i, "configured"));
    }
    let mut best: Option<(usize, f64)> = None;
    for (i, row) in rows.iter().enumerate() {
        if let Ok(report) = &row.report
            && best.is_none_or(|(_, accuracy)| report.overall.mean > accuracy)
        {
            best = Some((i, report.overall.mean));
        }
    }
    match best {
        Some((i, _)) => Ok((i, "best")),
        None => Err(Error::data(format!(
            "no feature x classifier combination could be evaluated (the first: {} + {}: {})",
            rows.first().map_or("-", |r| r.features.as_str()),
            rows.first().map_or("-", |r| r.classifier.as_str()),
            rows.first()
                .and_then(|r| r.report.as_ref().err())
                .map_or("no combination", String::as_str)
        ))),
    }
}

/// The Parzen window's sigma of every trained model, repeat after repeat (empty for other classifiers).
pub fn sigmas(report: &EvalReport) -> Vec<f64> {
    report
        .repeats
        .iter()
        .flat_map(|r| r.sigmas.iter().copied())
        .collect()
}

/// What an evaluation's table is headed with: the protocol in words.
pub fn protocol_heading(protocol: &Protocol) -> String {
    match protocol {
        Protocol::TrainCondition { condition, .. } => format!(
            "trained on {}, tested on every other sample",
            condition.as_deref().map_or_else(
                || "a random draw of all samples".to_owned(),
                |c| format!("condition {c}")
            )
        ),
        Protocol::LeaveOneOut { column, .. } => format!("leave one `{column}` out"),
    }
}

/// The tested conditions of a comparison's table: every evaluated row's, sorted, each once.
pub fn comparison_conditions(rows: &[ComparisonRow]) -> Vec<&String> {
    let mut conditions: Vec<&String> = rows
        .iter()
        .filter_map(|row| row.report.as_ref().ok())
        .flat_map(|report| report.per_condition.keys())
        .collect();
    conditions.sort();
    conditions.dedup();
    conditions
}

/// How often the automatic choice picked each candidate, by the candidate's name.
pub fn chosen_counts(selections: &[Selection]) -> BTreeMap<String, usize> {
    let mut chosen: BTreeMap<String, usize> = BTreeMap::new();
    for selection in selections {
        if let Some(score) = selection.chosen() {
            *chosen.entry(score.name()).or_default() += 1;
        }
    }
    chosen
}

/// The rows of the accuracy-against-fault table: each perturbation's row of the configured method,
/// beside the paper's method's row of the same perturbation when it was evaluated too.
pub fn perturbation_pairs(
    rows: &[PerturbationRow],
) -> Vec<(&PerturbationRow, Option<&PerturbationRow>)> {
    let paper = |perturbation: &str| {
        rows.iter()
            .find(|q| q.method == "paper" && q.perturbation == perturbation)
    };
    rows.iter()
        .filter(|r| r.method == "configured")
        .map(|r| (r, paper(&r.perturbation)))
        .collect()
}

/// `eval --perturb`'s rows as the report's fault results: `configured` is the automatic choice with
/// `auto`, else this pipeline.
pub fn perturbation_fault_results(
    rows: &[PerturbationRow],
    auto: bool,
) -> Vec<presrs_report::FaultResult> {
    rows.iter()
        .map(|r| presrs_report::FaultResult {
            perturbation: r.perturbation.parse().ok(),
            method: match (r.method, auto) {
                ("paper", _) => crate::report::PAPER_METHOD.to_owned(),
                (_, true) => crate::report::AUTO_METHOD.to_owned(),
                _ => "this pipeline".to_owned(),
            },
            accuracy: MeanStd {
                mean: r.accuracy,
                std: r.accuracy_std,
            },
        })
        .collect()
}
