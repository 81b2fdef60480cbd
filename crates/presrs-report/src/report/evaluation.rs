//! The sections about the model and its evaluations: validation curve, confusion matrices, accuracy per
//! condition and the reliability of the confidences.

use std::collections::BTreeSet;
use std::fmt::Write as _;

use presrs_core::pipeline::TrainedModel;

use super::inputs::Evaluation;
use super::page::{Job, Section, esc, pct};
use crate::charts::{BarSeries, BarsFigure, ConfusionFigure, ReliabilityFigure, ValidationFigure};

/// The validation curve of the model's hyper-parameters and its PCA; `None` without a curve.
pub(super) fn validation_section<'a>(model: &TrainedModel) -> Option<Section<'a>> {
    let curve: Vec<(f64, f64)> = model
        .validation_curve()
        .iter()
        .map(|p| (p.sigma, p.accuracy))
        .collect();
    let confidence: Vec<(f64, f64)> = model
        .validation_curve()
        .iter()
        .filter_map(|p| Some((p.sigma, p.mean_log_posterior?.exp())))
        .collect();
    // (a validation curve is the Parzen window's, which always sees principal components)
    let pca = model.pca()?;
    if curve.is_empty() {
        return None;
    }
    Some(Section {
        id: "validation",
        heading: "Choosing the hyper-parameters".into(),
        intro: String::new(),
        figure: Some((
            "validation.png".into(),
            Job::Validation(ValidationFigure {
                title: "Validation curve and principal components".into(),
                curve,
                confidence,
                chosen_sigma: model.sigma(),
                explained: pca.explained_variance_ratio(),
                kept: pca.n_components(),
            }),
            "Left: accuracy on the validation images of a model trained on the training \
             images only, for each Parzen width σ tried, and the geometric mean of the \
             posterior it gives their true class; the red line is the σ kept: the most \
             accurate, and among those the most confident in the right answers (the lowest \
             log-loss). Right: \
             share of the training variance the kept principal components explain."
                .to_owned(),
        )),
        after: String::new(),
    })
}

/// The evaluations' confusion matrices, side by side.
pub(super) fn confusion_section<'a>(evaluations: &[Evaluation<'_>]) -> Section<'a> {
    let matrices = evaluations
        .iter()
        .map(|e| {
            let total: u64 = e.report.confusion.counts.iter().flatten().sum();
            (
                format!("{} ({} tests)", e.name, total),
                e.report.confusion.clone(),
            )
        })
        .collect();
    Section {
        id: "confusion",
        heading: "Confusion matrices".into(),
        intro: String::new(),
        figure: Some((
            "confusion.png".into(),
            Job::Confusion(ConfusionFigure {
                title: "Confusion matrices (counts summed over repeats)".into(),
                matrices,
            }),
            "Rows: true class; columns: predicted class. Each cell gives the count over all \
             repeats and its share of the row; the colour is that share."
                .to_owned(),
        )),
        after: String::new(),
    }
}

/// Accuracy per tested condition of every evaluation (with the paper's where known): bars and a table.
pub(super) fn accuracy_section<'a>(evaluations: &[Evaluation<'_>]) -> Section<'a> {
    let mut categories: Vec<String> = evaluations
        .iter()
        .flat_map(|e| e.report.per_condition.keys().cloned())
        .collect::<BTreeSet<_>>()
        .into_iter()
        .collect();
    // With one tested condition its bar is the overall accuracy: no second, identical bar.
    if categories.len() != 1 {
        categories.push("overall".into());
    }
    let value = |e: &Evaluation<'_>, c: &str| {
        if c == "overall" {
            Some(e.report.overall)
        } else {
            e.report.per_condition.get(c).copied()
        }
    };
    let series: Vec<BarSeries> = evaluations
        .iter()
        .map(|e| BarSeries {
            name: e.name.clone(),
            values: categories
                .iter()
                .map(|c| value(e, c).map(|m| (100.0 * m.mean, 100.0 * m.std)))
                .collect(),
            reference: categories
                .iter()
                .map(|c| e.reference.get(c).map(|v| 100.0 * v))
                .collect(),
        })
        .collect();
    let repeats = evaluations
        .iter()
        .map(|e| e.report.repeats.len())
        .max()
        .unwrap_or(1);
    let has_reference = evaluations.iter().any(|e| !e.reference.is_empty());
    let mut table = String::from("<table><tr><th>evaluation</th>");
    for c in &categories {
        let _ = write!(table, "<th>{}</th>", esc(c));
    }
    table.push_str("</tr>");
    for e in evaluations {
        let _ = write!(table, "<tr><td>{}</td>", esc(&e.name));
        for c in &categories {
            let _ = write!(
                table,
                "<td>{}</td>",
                value(e, c).map_or("—".into(), |m| pct(&m))
            );
        }
        table.push_str("</tr>");
        if !e.reference.is_empty() {
            let _ = write!(table, "<tr class=\"ref\"><td>{} — paper</td>", esc(&e.name));
            for c in &categories {
                let _ = write!(
                    table,
                    "<td>{}</td>",
                    e.reference
                        .get(c)
                        .map_or("—".into(), |v| format!("{:.1} %", 100.0 * v))
                );
            }
            table.push_str("</tr>");
        }
    }
    table.push_str("</table>");
    let first = &evaluations[0].report;
    let _ = write!(
        table,
        "<p>Median classification time {:.1} µs per image.</p>",
        first.median_classify_ns as f64 / 1e3
    );
    Section {
        id: "accuracy",
        heading: "Accuracy per condition".into(),
        intro: String::new(),
        figure: Some((
            "accuracy.png".into(),
            Job::Bars(BarsFigure {
                title: "Accuracy per tested condition".into(),
                x_label: "tested condition".into(),
                y_label: "accuracy (%)".into(),
                categories,
                series,
                reference_name: has_reference.then(|| "paper".to_owned()),
                // From 0: a truncated axis makes small differences look large.
                y_range: Some((0.0, 100.5)),
                spread_name: (repeats > 1).then(|| format!("±1 std over {repeats} repeats")),
            }),
            format!(
                "Bars: mean accuracy over repeats with new random training draws; whiskers: one \
                 standard deviation{}.",
                if has_reference {
                    "; diamonds: the paper's values"
                } else {
                    ""
                }
            ),
        )),
        after: table,
    }
}

/// How far the evaluations' confidences can be trusted: a reliability diagram and a table (`None` when
/// no evaluation tallied a confidence, e.g. one read from a file written before they were).
pub(super) fn reliability_section<'a>(evaluations: &[Evaluation<'_>]) -> Option<Section<'a>> {
    let tallied: Vec<&Evaluation<'_>> = evaluations
        .iter()
        .filter(|e| e.report.reliability.count() > 0)
        .collect();
    if tallied.is_empty() {
        return None;
    }
    let series = tallied
        .iter()
        .map(|e| {
            let bins = e
                .report
                .reliability
                .bins
                .iter()
                .filter_map(|bin| Some((bin.mean_confidence()?, bin.accuracy()?, bin.count)))
                .collect();
            (e.name.clone(), bins)
        })
        .collect();
    let mut table = String::from(
        "<table><tr><th>evaluation</th><th>images</th><th>right</th><th>mean confidence when \
         right</th><th>when wrong</th><th>calibration error</th></tr>",
    );
    let or_dash = |v: Option<f64>| v.map_or("—".to_owned(), |v| format!("{v:.3}"));
    for e in &tallied {
        let r = &e.report.reliability;
        let _ = write!(
            table,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            esc(&e.name),
            r.count(),
            r.accuracy()
                .map_or("—".to_owned(), |a| format!("{:.1} %", 100.0 * a)),
            or_dash(r.mean_confidence_right()),
            or_dash(r.mean_confidence_wrong()),
            or_dash(r.expected_calibration_error()),
        );
    }
    table.push_str("</table>");
    Some(Section {
        id: "reliability",
        heading: "How far the confidences can be trusted".into(),
        intro: String::new(),
        figure: Some((
            "reliability.png".into(),
            Job::Reliability(ReliabilityFigure {
                title: "Reliability of the reported confidence (all repeats)".into(),
                series,
            }),
            "Test images grouped by the confidence the model gave their label (ten bins of 0.1); \
             each point is a bin's mean confidence against the share of its images that were right. \
             A calibrated model follows the diagonal; points above it are under-confident, below \
             over-confident. The calibration error is the image-weighted mean distance to it."
                .to_owned(),
        )),
        after: table,
    })
}
