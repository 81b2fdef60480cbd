//! The table of `presrs eval --leave-class-out`: one row per held-out class, and the means.

use std::fmt::Write as _;

use presrs::eval::novelty::LeaveClassOut;

/// The held-out classes' AUROC, confident decisions as a known class and known samples rejected.
pub fn leave_class_out_table(result: &LeaveClassOut) -> String {
    let or_dash = |v: Option<f64>| v.map_or_else(|| "-".to_owned(), |v| format!("{v:.3}"));
    let percent = |v: f64| format!("{:.1} %", 100.0 * v);
    let mut text = format!(
        "leave one class out ({}; {} models; threshold rejects {:.0} % of held-out known training \
         samples)\n\n",
        result.protocol,
        result.models,
        100.0 * result.rejection
    );
    let _ = writeln!(
        text,
        "{:<20} {:>7} {:>7} {:>8} {:>10} {:>12} {:>14} {:>13}",
        "held-out class",
        "novel",
        "known",
        "AUROC",
        "AUROC 1-p",
        "known >=0.9",
        "(w/o novelty)",
        "known reject"
    );
    for c in &result.classes {
        let _ = writeln!(
            text,
            "{:<20} {:>7} {:>7} {:>8} {:>10} {:>12} {:>14} {:>13}",
            c.class,
            c.novel_samples,
            c.known_samples,
            or_dash(c.auroc),
            or_dash(c.auroc_posterior),
            percent(c.confident_known),
            percent(c.confident_known_without),
            percent(c.known_rejected)
        );
    }
    let _ = writeln!(
        text,
        "{:<20} {:>7} {:>7} {:>8} {:>10} {:>12} {:>14} {:>13}",
        "mean",
        "",
        "",
        or_dash(result.mean_auroc),
        or_dash(result.mean_auroc_posterior),
        percent(result.mean_confident_known),
        percent(result.mean_confident_known_without),
        percent(result.mean_known_rejected)
    );
    let _ = writeln!(
        text,
        "\nknown test samples decided as a known class at >= 0.9: {} (without the novelty score: {}); \
         with the score, the confidence is the posterior capped by the sample's credibility",
        percent(result.mean_known_confident),
        percent(result.mean_known_confident_without)
    );
    if result.models_without_novelty > 0 {
        let _ = writeln!(
            text,
            "\n{} of {} models had no novelty score: their decisions are never unknown",
            result.models_without_novelty, result.models
        );
    }
    text
}
