//! The text tables of `eval`: the feature x classifier comparison and accuracy against faults, as the
//! command line prints them (a face writes the returned text as is).

use std::fmt::Write;

use presrs_core::evaluation::ComparisonRow;

use crate::eval_document::{comparison_conditions, perturbation_pairs};
use crate::evaluate::PerturbationRow;

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
