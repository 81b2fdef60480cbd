//! `presrs eval`: the evaluation protocols on any manifest.

use std::collections::BTreeMap;
use std::io::Write;
use std::path::PathBuf;

use anyhow::Context;
use presrs::evaluate::{
    CalibrationJson, EvalOptions, EvalOutcome, EvalSetup, Holdout, PerturbationRow,
    calibration_line,
};
use presrs::method::{ClassifierChoice, FeatureChoice, Method};
use presrs_core::evaluation::{ComparisonRow, EvalReport, Protocol};
use presrs_core::split::ValidationSize;
use serde::Serialize;

use super::common::{PipelineArgs, SampleArgs, TerminalProgress, load_manifest, write_json};

/// Evaluate the pipeline on a manifest: accuracy per condition/group, overall, confusion, timing.
#[derive(Debug, clap::Args)]
#[command(
    after_help = "Besides accuracy and the confusion matrix it reports how far the confidences can be \
trusted: the mean confidence when right and when wrong, and the expected calibration error over ten \
confidence bins (0: calibrated; `calibration` in --json, the full tally under report.reliability).\n\n\
Examples:
  presrs eval --manifest sim/manifest.csv --train-condition G2 \\
    --per-class 20 --validation 7 --repeats 10
  presrs eval --manifest walks.csv --leave-one-out subject --json"
)]
pub struct EvalArgs {
    /// The dataset manifest.
    #[arg(long)]
    pub manifest: PathBuf,
    /// Train on samples of this condition only; test on every other sample (the paper's protocol).
    #[arg(long, conflicts_with = "leave_one_out")]
    pub train_condition: Option<String>,
    /// Hold out each value of this manifest column in turn (e.g. condition, group, or an extra column;
    /// not label: a held-out class could never be recognised).
    #[arg(long, value_parser = parse_leave_one_out)]
    pub leave_one_out: Option<String>,
    /// Random samples drawn per class for training + validation, at least 1 (default: all available);
    /// a class (or held-out fold) with fewer gives all it has, with one warning.
    #[arg(long, value_parser = super::common::parse_positive)]
    pub per_class: Option<usize>,
    /// Of those, how many per class validate the hyper-parameters: a count (7) or a fraction (0.35).
    #[arg(long, default_value = "0.35", value_parser = |t: &str| t.parse::<ValidationSize>().map_err(|e| e.to_string()))]
    pub validation: ValidationSize,
    /// Repeats with seeds seed, seed+1, ...; results are mean +- std (at least 1).
    #[arg(long, default_value_t = 10, value_parser = super::common::parse_positive)]
    pub repeats: usize,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Print one JSON document instead of tables.
    #[arg(long)]
    pub json: bool,
    /// Evaluate every feature x classifier combination with the same draws and print the comparison
    /// (accuracy per tested condition, training time, classification time). With --json the document
    /// holds every combination under `comparison`, and the usual fields (overall_accuracy,
    /// per_condition, confusion, median_classify_ns, ...) of one of them, named in `summary_of`: the
    /// combination given by --features and --classifier when both are given and compared, else the one
    /// with the highest overall accuracy.
    #[arg(long)]
    pub compare: bool,
    /// Also write an HTML report with figures in this folder (DIR/index.html).
    #[arg(long, value_name = "DIR")]
    pub report: Option<PathBuf>,
    /// Also evaluate with every test image perturbed (repeatable; same draws): dead=FRACTION,
    /// stuck=FRACTION, gain=SD, noise=SD (counts), shift=ROWS or ROWS,COLS, rotate=DEGREES, load=FACTOR or
    /// load=+-50%. Prints accuracy under each (for the paper's method too with --features/--classifier
    /// auto).
    #[arg(long, value_name = "KIND=LEVEL", value_parser = |t: &str| t.parse::<presrs_core::perturb::Perturbation>().map_err(|e| e.to_string()))]
    pub perturb: Vec<presrs_core::perturb::Perturbation>,
    /// Also write into this folder the samples as evaluated (`images.npy`: samples x rows x cols, absent
    /// sensels as 0) and the draws (`draws.json`: each sample's label, condition and group, and every
    /// repeat's folds as training, validation and test indices), so another implementation can be
    /// evaluated on the same images with the same draws (bench/real/ does).
    #[arg(long, value_name = "DIR")]
    pub export_draws: Option<PathBuf>,
    #[command(flatten)]
    pub pipeline: PipelineArgs,
    #[command(flatten)]
    pub samples: SampleArgs,
}

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
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub selections: Vec<presrs_core::selection::Selection>,
    /// With an automatic choice: its own estimate inside the training data (the chosen candidates'
    /// validation accuracy) and how it validated, to compare with `overall_accuracy`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub internal_estimate: Option<presrs::evaluate::InternalEstimate>,
    /// Tested labels no training set of the protocol holds, by held-out value (`all` for a training
    /// condition); those samples are wrong whatever the model.
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub labels_never_trained: BTreeMap<String, Vec<String>>,
}

#[derive(Debug, Serialize)]
pub struct ConfusionJson {
    pub labels: Vec<String>,
    pub counts: Vec<Vec<u64>>,
    pub row_normalised: Vec<Vec<f64>>,
}

#[derive(Debug, Serialize)]
pub struct ClassMetrics {
    pub precision: f64,
    pub recall: f64,
}

impl<'r> EvalJson<'r> {
    pub fn new(report: &'r EvalReport) -> Self {
        let confusion = &report.confusion;
        let (precision, recall) = (confusion.precision(), confusion.recall());
        Self {
            overall_accuracy: report.overall.mean,
            overall_accuracy_std: report.overall.std,
            per_condition: report
                .per_condition
                .iter()
                .map(|(k, v)| (k.clone(), v.mean))
                .collect(),
            per_condition_std: report
                .per_condition
                .iter()
                .map(|(k, v)| (k.clone(), v.std))
                .collect(),
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
                    (
                        label.clone(),
                        ClassMetrics {
                            precision: precision[i],
                            recall: recall[i],
                        },
                    )
                })
                .collect(),
            sigmas: report
                .repeats
                .iter()
                .flat_map(|r| r.sigmas.iter().copied())
                .collect(),
            report,
            selections: Vec::new(),
            internal_estimate: None,
            labels_never_trained: BTreeMap::new(),
        }
    }
}

pub fn run(args: &EvalArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    let dataset = load_manifest(&args.manifest, &args.samples)?;
    let options = EvalOptions {
        holdout: match &args.leave_one_out {
            Some(column) => Holdout::LeaveOneOut(column.clone()),
            None => Holdout::TrainCondition(args.train_condition.clone()),
        },
        per_class: args.per_class,
        validation: args.validation,
        repeats: args.repeats,
        seed: args.seed,
        method: args.pipeline.method(),
    };
    let setup = EvalSetup::new(&dataset, &options)?;
    for warning in &setup.warnings {
        stderr_line!("warning: {warning}");
    }
    if let Some(dir) = &args.export_draws {
        setup.export_draws(dir)?;
    }
    let progress = TerminalProgress::default();
    if args.compare {
        let rows = setup.compare(&progress)?;
        if args.json {
            let json = CompareJson::new(&rows, &options.method)
                .with_context(|| args.manifest.display().to_string())?;
            return write_json(out, &json);
        }
        return print_comparison(&rows, out);
    }
    let outcome = setup.evaluate(&progress)?;
    let internal = outcome.internal_estimate();
    for warning in &outcome.warnings {
        stderr_line!("warning: {warning}");
    }
    let perturbed = setup.perturbed(&args.perturb, &outcome.report, &progress)?;
    if let Some(dir) = &args.report {
        let path = presrs::report::write_eval_report(
            &dataset,
            &options,
            &outcome,
            &fault_results(&perturbed, options.method.is_auto()),
            &args.samples.options()?,
            Some(&std::env::args().collect::<Vec<_>>().join(" ")),
            dir,
        )?;
        stderr_line!("report written to {}", path.display());
    }
    let EvalOutcome {
        report, selections, ..
    } = outcome;
    if args.json {
        let mut json = EvalJson::new(&report);
        json.selections = selections;
        json.internal_estimate = internal;
        json.labels_never_trained = setup.never_trained.clone();
        if !perturbed.is_empty() {
            return write_json(
                out,
                &PerturbedJson {
                    eval: json,
                    perturbations: perturbed,
                },
            );
        }
        return write_json(out, &json);
    }
    print_report(&report, out)?;
    print_perturbations(&perturbed, out)?;
    if !selections.is_empty() {
        let mut chosen: BTreeMap<String, usize> = BTreeMap::new();
        for selection in &selections {
            if let Some(score) = selection.chosen() {
                *chosen.entry(score.name()).or_default() += 1;
            }
        }
        writeln!(
            out,
            "\nautomatic choice ({}), over {} trained model(s):",
            selections[0].method,
            selections.len()
        )?;
        for (name, count) in chosen {
            writeln!(out, "  {name}: {count}")?;
        }
    }
    if let Some(internal) = &internal {
        writeln!(
            out,
            "internal estimate (validation inside the training data): {:.2} % +- {:.2}; test: {:.2} %",
            100.0 * internal.accuracy.mean,
            100.0 * internal.accuracy.std,
            100.0 * report.overall.mean
        )?;
    }
    Ok(())
}

/// The human-readable tables of an evaluation.
pub fn print_report(report: &EvalReport, out: &mut dyn Write) -> anyhow::Result<()> {
    let percent = |m: &presrs_core::evaluation::MeanStd| {
        format!("{:6.2} % +- {:.2}", 100.0 * m.mean, 100.0 * m.std)
    };
    let heading = match &report.protocol {
        Protocol::TrainCondition { condition, .. } => format!(
            "trained on {}, tested on every other sample",
            condition.as_deref().map_or_else(
                || "a random draw of all samples".to_owned(),
                |c| format!("condition {c}")
            )
        ),
        Protocol::LeaveOneOut { column, .. } => format!("leave one `{column}` out"),
    };
    writeln!(out, "{heading}; {} repeat(s)", report.repeats.len())?;
    writeln!(out, "{:<16} {:>20}", "tested", "accuracy")?;
    for (name, accuracy) in &report.per_condition {
        writeln!(out, "{:<16} {:>20}", name, percent(accuracy))?;
    }
    writeln!(out, "{:<16} {:>20}", "overall", percent(&report.overall))?;
    let confusion = &report.confusion;
    let width = confusion
        .labels
        .iter()
        .map(String::len)
        .max()
        .unwrap_or(4)
        .max(6);
    writeln!(
        out,
        "\nconfusion (rows: true, columns: predicted; all repeats)"
    )?;
    write!(out, "{:<width$}", "")?;
    for label in &confusion.labels {
        write!(out, " {label:>width$}")?;
    }
    writeln!(out, " {:>9} {:>9}", "recall", "precision")?;
    let (recall, precision) = (confusion.recall(), confusion.precision());
    for (i, row) in confusion.counts.iter().enumerate() {
        write!(out, "{:<width$}", confusion.labels[i])?;
        for count in row {
            write!(out, " {count:>width$}")?;
        }
        writeln!(
            out,
            " {:>8.1}% {:>8.1}%",
            100.0 * recall[i],
            100.0 * precision[i]
        )?;
    }
    if let Some(line) = calibration_line(&report.reliability) {
        writeln!(out, "{line}")?;
    }
    let sigmas: Vec<f64> = report
        .repeats
        .iter()
        .flat_map(|r| r.sigmas.iter().copied())
        .collect();
    if !sigmas.is_empty() {
        let sigma = presrs_core::evaluation::MeanStd::of(&sigmas);
        writeln!(
            out,
            "\nParzen sigma chosen on validation: {:.4} +- {:.4}",
            sigma.mean, sigma.std
        )?;
    }
    let first = &report.repeats[0];
    writeln!(
        out,
        "per repeat: {} training + {} validation images, {} tested; training {:.3} s",
        first.n_train, first.n_validation, first.n_test, first.train_seconds
    )?;
    writeln!(
        out,
        "median classification time: {:.2} us per image (paper: 245 us on a 2.67 GHz Core 2 Duo)",
        report.median_classify_ns as f64 / 1e3
    )?;
    Ok(())
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
    pub train_seconds: presrs_core::evaluation::MeanStd,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub report: Option<&'r EvalReport>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<&'r str>,
}

impl<'r> CompareJson<'r> {
    /// The document of `rows`; fails when no combination could be evaluated.
    pub fn new(rows: &'r [ComparisonRow], method: &Method) -> anyhow::Result<Self> {
        let configured = match (&method.features, method.classifier) {
            (FeatureChoice::Kinds(kinds), ClassifierChoice::Kind(kind)) => {
                let features = presrs_core::features::FeatureConfig::combined(kinds).name();
                rows.iter().position(|row| {
                    row.report.is_ok()
                        && row.features == features
                        && row.classifier == kind.as_str()
                })
            }
            _ => None,
        };
        let best = || {
            let mut best: Option<(usize, f64)> = None;
            for (i, row) in rows.iter().enumerate() {
                if let Ok(report) = &row.report
                    && best.is_none_or(|(_, accuracy)| report.overall.mean > accuracy)
                {
                    best = Some((i, report.overall.mean));
                }
            }
            best.map(|(i, _)| i)
        };
        let (chosen, reason) = match configured {
            Some(i) => (i, "configured"),
            None => match best() {
                Some(i) => (i, "best"),
                None => anyhow::bail!(
                    "no feature x classifier combination could be evaluated (the first: {} + {}: {})",
                    rows.first().map_or("-", |r| r.features.as_str()),
                    rows.first().map_or("-", |r| r.classifier.as_str()),
                    rows.first()
                        .and_then(|r| r.report.as_ref().err())
                        .map_or("no combination", String::as_str)
                ),
            },
        };
        let row = &rows[chosen];
        let report = row
            .report
            .as_ref()
            .map_err(|err| anyhow::anyhow!("{err}"))?;
        Ok(Self {
            summary_of: SummaryOf {
                features: &row.features,
                classifier: &row.classifier,
                reason,
            },
            eval: EvalJson::new(report),
            comparison: rows
                .iter()
                .map(|row| {
                    let report = row.report.as_ref().ok();
                    CompareRowJson {
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
                })
                .collect(),
        })
    }
}

/// `--leave-one-out`: any column but `label` (holding out a class leaves none of its samples to train on).
pub(crate) fn parse_leave_one_out(text: &str) -> Result<String, String> {
    if text.trim() == "label" {
        return Err(
            "cannot hold out `label`: the held-out class would have no training samples, so none of \
             its test samples could be recognised; hold out another column (condition, group, path \
             or an extra one)"
                .to_owned(),
        );
    }
    Ok(text.to_owned())
}

/// The comparison table: one row per feature x classifier combination.
pub fn print_comparison(rows: &[ComparisonRow], out: &mut dyn Write) -> anyhow::Result<()> {
    let mut conditions: Vec<&String> = rows
        .iter()
        .filter_map(|row| row.report.as_ref().ok())
        .flat_map(|report| report.per_condition.keys())
        .collect();
    conditions.sort();
    conditions.dedup();
    if let Some(report) = rows.iter().find_map(|row| row.report.as_ref().ok()) {
        writeln!(
            out,
            "accuracy in % (mean +- std over {} repeat(s)) per tested condition",
            report.repeats.len()
        )?;
    }
    write!(out, "{:<18} {:<5}", "features", "clf")?;
    for condition in &conditions {
        write!(out, " {condition:>14}")?;
    }
    writeln!(
        out,
        " {:>14} {:>10} {:>10}",
        "overall", "train ms", "classify us"
    )?;
    for row in rows {
        write!(out, "{:<18} {:<5}", row.features, row.classifier)?;
        match &row.report {
            Ok(report) => {
                for condition in &conditions {
                    match report.per_condition.get(*condition) {
                        Some(m) => write!(
                            out,
                            " {:>14}",
                            format!("{:.1} +- {:.1}", 100.0 * m.mean, 100.0 * m.std)
                        )?,
                        None => write!(out, " {:>14}", "-")?,
                    }
                }
                writeln!(
                    out,
                    " {:>14} {:>10.1} {:>10.1}",
                    format!(
                        "{:.1} +- {:.1}",
                        100.0 * report.overall.mean,
                        100.0 * report.overall.std
                    ),
                    1e3 * row.train_seconds.mean,
                    report.median_classify_ns as f64 / 1e3
                )?;
            }
            Err(err) => writeln!(out, " failed: {err}")?,
        }
    }
    Ok(())
}

/// The `--json` document with `--perturb`: the usual fields plus the perturbation rows.
#[derive(Debug, Serialize)]
pub struct PerturbedJson<'r> {
    #[serde(flatten)]
    pub eval: EvalJson<'r>,
    pub perturbations: Vec<PerturbationRow>,
}

/// The perturbation rows as the report's fault results: `configured` is the automatic choice with
/// `auto`, else this pipeline.
fn fault_results(rows: &[PerturbationRow], auto: bool) -> Vec<presrs_report::FaultResult> {
    rows.iter()
        .map(|r| presrs_report::FaultResult {
            perturbation: r.perturbation.parse().ok(),
            method: match (r.method, auto) {
                ("paper", _) => presrs::report::PAPER_METHOD.to_owned(),
                (_, true) => presrs::report::AUTO_METHOD.to_owned(),
                _ => "this pipeline".to_owned(),
            },
            accuracy: presrs_core::evaluation::MeanStd {
                mean: r.accuracy,
                std: r.accuracy_std,
            },
        })
        .collect()
}

/// The accuracy-against-fault table (one column per method).
fn print_perturbations(rows: &[PerturbationRow], out: &mut dyn Write) -> anyhow::Result<()> {
    if rows.is_empty() {
        return Ok(());
    }
    let paper = rows.iter().any(|r| r.method == "paper");
    write!(
        out,
        "\naccuracy with perturbed test images\n{:<20} {:>20}",
        "perturbation", "this pipeline"
    )?;
    if paper {
        write!(out, " {:>20}", "paper (fft1d+pwe)")?;
    }
    writeln!(out)?;
    let cell = |r: &PerturbationRow| {
        format!(
            "{:6.2} % +- {:.2}",
            100.0 * r.accuracy,
            100.0 * r.accuracy_std
        )
    };
    for r in rows.iter().filter(|r| r.method == "configured") {
        write!(out, "{:<20} {:>20}", r.perturbation, cell(r))?;
        if let Some(p) = rows
            .iter()
            .find(|q| q.method == "paper" && q.perturbation == r.perturbation)
        {
            write!(out, " {:>20}", cell(p))?;
        }
        writeln!(out)?;
    }
    for r in rows.iter().filter(|r| r.unclassified > 0) {
        let method = if r.method == "paper" {
            "the paper's method"
        } else {
            "this pipeline"
        };
        writeln!(
            out,
            "{}: {} test image(s) could not be classified by {method} (counted as wrong)",
            r.perturbation, r.unclassified
        )?;
    }
    Ok(())
}
