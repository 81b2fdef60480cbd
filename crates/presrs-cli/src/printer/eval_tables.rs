//! The text tables of `eval`: the feature x classifier comparison and accuracy against faults, as the
//! command line prints them (a face writes the returned text as is).

use std::fmt::Write;

use presrs::eval::document::{chosen_counts, protocol_heading, sigmas};
use presrs::eval::document::{comparison_conditions, perturbation_pairs};
use presrs::eval::{EvalOutcome, InternalEstimate, PerturbationRow, calibration_line};
use presrs_core::evaluation::{ComparisonRow, EvalReport, MeanStd};
use presrs_core::sample::SampleKind;

/// The comparison table: one row per feature x classifier combination, one column per tested
/// condition, then overall accuracy and the training and classification times.
pub fn comparison_table(rows: &[ComparisonRow]) -> String {
    let mut out = String::new();
    let conditions = comparison_conditions(rows);
    if let Some(report) = rows.iter().find_map(|row| row.report.as_ref().ok()) {
        let _ = writeln!(
            out,
            "accuracy in % (mean +- std over {} repeat(s)) per tested condition",
            report.repeats.len()
        );
    }
    let _ = write!(out, "{:<18} {:<5}", "features", "clf");
    for condition in &conditions {
        let _ = write!(out, " {condition:>14}");
    }
    let _ = writeln!(
        out,
        " {:>14} {:>10} {:>10}",
        "overall", "train ms", "classify us"
    );
    let percent = |mean: f64, std: f64| format!("{:.1} +- {:.1}", 100.0 * mean, 100.0 * std);
    for row in rows {
        let _ = write!(out, "{:<18} {:<5}", row.features, row.classifier);
        match &row.report {
            Ok(report) => {
                for condition in &conditions {
                    let cell = report
                        .per_condition
                        .get(*condition)
                        .map_or_else(|| "-".to_owned(), |m| percent(m.mean, m.std));
                    let _ = write!(out, " {cell:>14}");
                }
                let _ = writeln!(
                    out,
                    " {:>14} {:>10.1} {:>10.1}",
                    percent(report.overall.mean, report.overall.std),
                    1e3 * row.train_seconds.mean,
                    report.median_classify_ns as f64 / 1e3
                );
            }
            Err(err) => {
                let _ = writeln!(out, " failed: {err}");
            }
        }
    }
    out
}

/// The accuracy-against-fault table (this pipeline, and the paper's method where it ran), then a line
/// for each row with test images that could not be classified; empty without rows.
pub fn perturbation_table(rows: &[PerturbationRow]) -> String {
    let mut out = String::new();
    if rows.is_empty() {
        return out;
    }
    let pairs = perturbation_pairs(rows);
    let paper = pairs.iter().any(|(_, paper)| paper.is_some());
    let _ = write!(
        out,
        "\naccuracy with perturbed test images\n{:<20} {:>20}",
        "perturbation", "this pipeline"
    );
    if paper {
        let _ = write!(out, " {:>20}", "paper (fft1d+pwe)");
    }
    let _ = writeln!(out);
    let cell = |r: &PerturbationRow| {
        format!(
            "{:6.2} % +- {:.2}",
            100.0 * r.accuracy,
            100.0 * r.accuracy_std
        )
    };
    for (r, paper) in pairs {
        let _ = write!(out, "{:<20} {:>20}", r.perturbation, cell(r));
        if let Some(p) = paper {
            let _ = write!(out, " {:>20}", cell(p));
        }
        let _ = writeln!(out);
    }
    for r in rows.iter().filter(|r| r.unclassified > 0) {
        let method = if r.method == "paper" {
            "the paper's method"
        } else {
            "this pipeline"
        };
        let _ = writeln!(
            out,
            "{}: {} test image(s) could not be classified by {method} (counted as wrong)",
            r.perturbation, r.unclassified
        );
    }
    out
}

/// What `eval` prints after its tables: with `--sample auto` every fold's sample race, then the
/// automatic choices (how often each candidate was chosen) and their own estimate (`internal`) next
/// to the test's accuracy.
pub fn choices_text(outcome: &EvalOutcome, internal: Option<&InternalEstimate>) -> String {
    let mut out = String::new();
    for line in presrs::eval::race::race_lines(&outcome.sample_races) {
        let _ = writeln!(out, "{line}");
    }
    if let Some(first) = outcome.selections.first() {
        let (method, models) = (&first.method, outcome.selections.len());
        let _ = writeln!(
            out,
            "\nautomatic choice ({method}), over {models} trained model(s):"
        );
        for (name, count) in chosen_counts(&outcome.selections) {
            let _ = writeln!(out, "  {name}: {count}");
        }
        let below = outcome
            .selections
            .iter()
            .filter(|selection| selection.best_above_chosen().is_some())
            .count();
        if below > 0 {
            let _ = writeln!(
                out,
                "  in {below} of {models} models a candidate within one standard error of the best, earlier in \
                 the search order, was kept (--choose one-se; --choose best takes the highest)"
            );
        }
    }
    if let Some(line) = selection_costs_line(&outcome.selections) {
        let _ = writeln!(out, "{line}");
    }
    if let Some(internal) = internal {
        let _ = writeln!(
            out,
            "internal estimate (validation inside the training data): {:.2} % +- {:.2}; test: {:.2} %",
            100.0 * internal.accuracy.mean,
            100.0 * internal.accuracy.std,
            100.0 * outcome.report.overall.mean
        );
    }
    out
}

/// Where the automatic choices' time went, summed over the trained models: the scoring (what each
/// model's budget bounds) and the winners' training on all their samples, which comes after it; with
/// the subsample the candidates were scored on when there was one.
pub fn selection_costs_line(selections: &[presrs_core::selection::Selection]) -> Option<String> {
    let costs: Vec<_> = selections.iter().filter_map(|s| s.cost.as_ref()).collect();
    let first = costs.first()?;
    let sum = |field: fn(&presrs_core::selection::SelectionCost) -> f64| {
        costs.iter().map(|&c| field(c)).sum::<f64>()
    };
    let scored = if first.subsampled() {
        format!(
            "candidates scored on stratified subsamples of {} samples (of {} in the first model)",
            first.scored_on, first.samples
        )
    } else {
        "candidates scored on all the training samples".to_owned()
    };
    let over: Vec<f64> = costs
        .iter()
        .filter_map(|c| c.over_budget_seconds())
        .collect();
    let bound = match (first.budget_seconds, over.len()) {
        (None, _) => "no time budget".to_owned(),
        (Some(budget), 0) => format!("each model's within its budget of {budget:.0} s"),
        (Some(budget), n) => format!(
            "{n} of {} models' scoring ended past the budget of {budget:.0} s, by {:.1} s at most: \
             the first candidates are scored whatever the budget",
            costs.len(),
            over.iter().copied().fold(0.0, f64::max)
        ),
    };
    let pinned = costs.iter().filter(|c| c.searched_on.is_some()).count();
    let searched = if pinned > 0 {
        format!(
            " ({pinned} of them with the hyper-parameters chosen on the subsample, then fitted on all)"
        )
    } else {
        String::new()
    };
    Some(format!(
        "time over {} models: {scored}; scoring {:.1} s (features {:.1} s; {bound}), training the \
         winners{searched} {:.1} s, not covered by the budget",
        costs.len(),
        sum(|c| c.scoring_seconds),
        sum(|c| c.features_seconds),
        sum(|c| c.final_fit_seconds)
    ))
}

/// The human-readable tables of an evaluation: accuracy per tested condition and overall, the
/// confusion matrix with recall and precision, the confidences, the Parzen sigmas, the counts and the
/// classification time. `sample` is the kind every model was trained on (`None`: raced, each fold's
/// own): counts are of its samples, and only one-frame samples have their time set next to the
/// paper's per-image figure (a whole stance's summary is another computation).
pub fn report_table(report: &EvalReport, sample: Option<SampleKind>) -> String {
    let mut text = String::new();
    let out = &mut text;
    let percent = |m: &MeanStd| format!("{:6.2} % +- {:.2}", 100.0 * m.mean, 100.0 * m.std);
    let heading = protocol_heading(&report.protocol);
    let _ = writeln!(out, "{heading}; {} repeat(s)", report.repeats.len());
    let _ = writeln!(out, "{:<16} {:>20}", "tested", "accuracy");
    for (name, accuracy) in &report.per_condition {
        let _ = writeln!(out, "{:<16} {:>20}", name, percent(accuracy));
    }
    let _ = writeln!(out, "{:<16} {:>20}", "overall", percent(&report.overall));
    let confusion = &report.confusion;
    let width = confusion
        .labels
        .iter()
        .map(String::len)
        .max()
        .unwrap_or(4)
        .max(6);
    let _ = writeln!(
        out,
        "\nconfusion (rows: true, columns: predicted; all repeats)"
    );
    let _ = write!(out, "{:<width$}", "");
    for label in &confusion.labels {
        let _ = write!(out, " {label:>width$}");
    }
    let _ = writeln!(out, " {:>9} {:>9}", "recall", "precision");
    let (recall, precision) = (confusion.recall(), confusion.precision());
    for (i, row) in confusion.counts.iter().enumerate() {
        let _ = write!(out, "{:<width$}", confusion.labels[i]);
        for count in row {
            let _ = write!(out, " {count:>width$}");
        }
        let _ = writeln!(
            out,
            " {:>8.1}% {:>8.1}%",
            100.0 * recall[i],
            100.0 * precision[i]
        );
    }
    if let Some(line) = calibration_line(&report.reliability) {
        let _ = writeln!(out, "{line}");
    }
    let sigmas = sigmas(report);
    if !sigmas.is_empty() {
        let sigma = MeanStd::of(&sigmas);
        let _ = writeln!(
            out,
            "\nParzen sigma chosen on validation: {:.4} +- {:.4}",
            sigma.mean, sigma.std
        );
    }
    let first = &report.repeats[0];
    let nouns = sample.map_or("samples", |kind| kind.nouns());
    let _ = writeln!(
        out,
        "per repeat: {}; training {:.3} s",
        first.counts_text_of(nouns),
        first.train_seconds
    );
    let micros = report.median_classify_ns as f64 / 1e3;
    let _ = match sample {
        Some(SampleKind::Frame) => writeln!(
            out,
            "median classification time: {micros:.2} us per image (paper: 245 us on a 2.67 GHz \
             Core 2 Duo)"
        ),
        Some(kind) => writeln!(
            out,
            "median classification time: {micros:.2} us per {}",
            kind.name()
        ),
        None => writeln!(out, "median classification time: {micros:.2} us per sample"),
    };
    text
}
