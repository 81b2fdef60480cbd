//! The table of `eval --decide-at`: accuracy against decision time (frames and ms after touchdown) of
//! the classifiers trained for each decision point, the one-frame model at the same offsets beside
//! them, and `auto`'s accuracy and mean decision time.

use std::fmt::Write;

use presrs::eval::early::EarlyEvaluation;

/// The early decisions' table and `auto`'s line, as `eval --decide-at` prints them.
pub fn early_table(early: &EarlyEvaluation) -> String {
    let ms = |value: Option<f64>| value.map_or_else(|| "-".to_owned(), |ms| format!("{ms:.0}"));
    let median = format!(
        "{} frames{}",
        early.median_stance_frames,
        early
            .median_stance_ms
            .map_or_else(String::new, |ms| format!(", {ms:.0} ms"))
    );
    let mut out = format!(
        "early decisions ({} held-out stances, {} folds; median stance {median}):\n",
        early.tested, early.folds
    );
    let _ = writeln!(
        out,
        "{:>8} {:>8} {:>10} {:>16} {:>16}",
        "frames", "ms", "of median", "stance model %", "one frame %"
    );
    for point in &early.points {
        let frame = point.frame_accuracy.map_or_else(
            || "-".to_owned(),
            |a| format!("{:.1} (n={})", 100.0 * a, point.frame_tested),
        );
        let _ = writeln!(
            out,
            "{:>8} {:>8} {:>9.0}% {:>16.1} {:>16}",
            point.frames,
            ms(point.ms),
            100.0 * point.share_of_median_stance,
            100.0 * point.accuracy,
            frame
        );
    }
    let _ = writeln!(
        out,
        "{:>8} {:>8} {:>10} {:>16.1} {:>16}",
        "lift-off",
        "-",
        "100%",
        100.0 * early.whole_accuracy,
        "-"
    );
    let auto = &early.auto;
    let _ = writeln!(
        out,
        "auto: {:.1} % (whole stance {:.1} %), mean decision {:.1} frames ({} ms) after touchdown: \
         {:.0} % of the median stance, {:.0} % of each stance on average; {:.0} % decided before \
         lift-off, {:.0} % by mid-stance (half their own length)",
        100.0 * auto.accuracy,
        100.0 * early.whole_accuracy,
        auto.mean_frames,
        ms(auto.mean_ms),
        100.0 * auto.mean_over_median_stance,
        100.0 * auto.mean_share_of_stance,
        100.0 * auto.decided_early,
        100.0 * auto.decided_by_mid_stance
    );
    let _ = writeln!(out, "auto's rule by fold: {}", fold_rules(auto));
    if let Some(ahead) = &early.frame_ahead {
        let points: Vec<String> = ahead.points.iter().map(usize::to_string).collect();
        let above = ahead.above_whole.map_or_else(String::new, |(k, accuracy)| {
            format!(
                ", and at {k} frames above the whole stance ({:.1} against {:.1} %)",
                100.0 * accuracy,
                100.0 * early.whole_accuracy
            )
        });
        let _ = writeln!(
            out,
            "the one-frame model is ahead at {} frames after touchdown (by up to {:.1} points, past 2 \
             standard errors){above}: one frame carries the class better than the stance's summary \
             there; --sample frame decides from one frame, --sample auto races the two",
            points.join(", "),
            100.0 * ahead.largest_lead
        );
    }
    if let Some(best) = auto.hindsight_best_by(0.5) {
        let threshold = best
            .threshold
            .map_or_else(|| "none".to_owned(), |t| format!("{t:.3}"));
        let deadline = best
            .deadline
            .map_or_else(|| "none".to_owned(), |k| k.to_string());
        let _ = writeln!(
            out,
            "in hindsight (one rule chosen on these held-out stances: a bound, not a result): \
             deciding by half the median stance on average, at best {:.1} % (threshold {threshold}, \
             deadline {deadline}, mean decision at {:.0} % of the median stance, {:.0} % decided before lift-off, {:.0} % \
             by mid-stance)",
            100.0 * best.accuracy,
            100.0 * best.mean_over_median_stance,
            100.0 * best.decided_early,
            100.0 * best.decided_by_mid_stance
        );
    }
    out
}

/// Each fold's threshold and deadline, with what it gave on the fold's held-out stances and the
/// whole stance's there: `0.986 else 31 (91.7 %, whole 96.7 %)`, `never else 31 (...)`, `0.991 else
/// lift-off (...)`.
fn fold_rules(auto: &presrs::eval::early::EarlyAuto) -> String {
    let rules: Vec<String> = auto
        .thresholds
        .iter()
        .zip(&auto.deadlines)
        .enumerate()
        .map(|(fold, (threshold, deadline))| {
            let threshold = if *threshold > 1.0 {
                "never".to_owned()
            } else {
                format!("{threshold:.3}")
            };
            let deadline = deadline.map_or_else(|| "lift-off".to_owned(), |k| k.to_string());
            let measured = match (
                auto.fold_accuracies.get(fold),
                auto.fold_whole_accuracies.get(fold),
            ) {
                (Some(auto), Some(whole)) => {
                    format!(" ({:.1} %, whole {:.1} %)", 100.0 * auto, 100.0 * whole)
                }
                _ => String::new(),
            };
            format!("{threshold} else {deadline}{measured}")
        })
        .collect();
    format!(
        "{} (threshold, else the deadline point or lift-off; auto's accuracy and the whole stance's \
         on the fold's held-out stances)",
        rules.join("; ")
    )
}
