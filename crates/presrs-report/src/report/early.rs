//! The early-decisions section (`eval --decide-at`): accuracy against the decision point after
//! touchdown, the one-frame model at the same offsets beside it, the whole stance at lift-off, and
//! `auto`'s accuracy at its mean decision time.

use std::fmt::Write as _;

use super::inputs::EarlyCurve;
use super::page::{Job, Section, esc};
use crate::charts::{FaultFigure, FaultPanel};

/// Percent with one decimal, or a dash when not measured.
fn percent(value: Option<f64>) -> String {
    value.map_or_else(|| "—".to_owned(), |v| format!("{:.1} %", 100.0 * v))
}

/// `12 frames (96 ms)`: a time after touchdown in frames, and in ms when the frame period is known.
fn after_touchdown(frames: f64, period_ms: Option<f64>) -> String {
    match period_ms {
        Some(ms) => format!("{frames:.1} frames ({:.0} ms)", frames * ms),
        None => format!("{frames:.1} frames"),
    }
}

/// The chart's panel: a line for the stance model's points (lift-off last, at the median stance),
/// one for the one-frame model, and `auto` as one point at its mean decision frame.
fn curve_panel(early: &EarlyCurve) -> FaultPanel {
    let median = early.median_stance_frames as f64;
    let mut stance: Vec<(f64, f64, f64)> = early
        .points
        .iter()
        .map(|p| (p.frames as f64, 100.0 * p.accuracy, 0.0))
        .collect();
    stance.push((median, 100.0 * early.whole_accuracy, 0.0));
    let one_frame: Vec<(f64, f64, f64)> = early
        .points
        .iter()
        .filter_map(|p| Some((p.frames as f64, 100.0 * p.frame_accuracy?, 0.0)))
        .collect();
    let mut lines = vec![("stance model for K, then lift-off".to_owned(), stance)];
    if !one_frame.is_empty() {
        lines.push(("one-frame model at frame K".to_owned(), one_frame));
    }
    if let Some(auto) = &early.auto {
        lines.push((
            "auto, at its mean decision".to_owned(),
            vec![(auto.mean_frames, 100.0 * auto.accuracy, 0.0)],
        ));
    }
    let x_label = match early.frame_period_ms {
        Some(ms) => format!("decision point K, frames after touchdown (1 frame = {ms:.1} ms)"),
        None => "decision point K, frames after touchdown".to_owned(),
    };
    FaultPanel {
        title: "accuracy against decision time".into(),
        x_label,
        lines,
    }
}

/// The table: a row per point, the lift-off, and `auto`.
fn curve_table(early: &EarlyCurve) -> String {
    let median = early.median_stance_frames.max(1) as f64;
    let mut table = String::from(
        "<table><tr><th>decided at</th><th>share of the median stance</th>\
         <th>stance model trained for it</th><th>one-frame model at that frame</th></tr>",
    );
    for point in &early.points {
        let _ = write!(
            table,
            "<tr><td>{}</td><td>{:.0} %</td><td>{}</td><td>{}</td></tr>",
            esc(&after_touchdown(point.frames as f64, early.frame_period_ms)),
            100.0 * point.frames as f64 / median,
            percent(Some(point.accuracy)),
            percent(point.frame_accuracy),
        );
    }
    let _ = write!(
        table,
        "<tr><td>lift-off (whole stance; median {})</td><td>100 %</td><td>{}</td><td>—</td></tr>",
        esc(&after_touchdown(median, early.frame_period_ms)),
        percent(Some(early.whole_accuracy)),
    );
    if let Some(auto) = &early.auto {
        let _ = write!(
            table,
            "<tr><td>auto: mean {}</td><td>{:.0} %</td><td>{}</td><td>—</td></tr>",
            esc(&after_touchdown(auto.mean_frames, early.frame_period_ms)),
            100.0 * auto.mean_frames / median,
            percent(Some(auto.accuracy)),
        );
    }
    table.push_str("</table>");
    table
}

/// The section of [`EarlyCurve`] (`None` without one, or without a point).
pub(super) fn early_section<'a>(early: Option<&EarlyCurve>) -> Option<Section<'a>> {
    let early = early.filter(|e| !e.points.is_empty())?;
    let auto = early.auto.as_ref().map_or(String::new(), |auto| {
        format!(
            " <code>auto</code> decided at its first point whose confidence passed the threshold \
             learned on validation, else at the deadline point learned with it (when validation \
             found one safe by mid-stance): {} right, at a mean {} after touchdown ({:.0} % of the median \
             stance; {:.0} % of the stances decided before their lift-off, {:.0} % by their \
             mid-stance).",
            percent(Some(auto.accuracy)),
            esc(&after_touchdown(auto.mean_frames, early.frame_period_ms)),
            100.0 * auto.mean_frames / early.median_stance_frames.max(1) as f64,
            100.0 * auto.decided_early,
            100.0 * auto.decided_by_mid_stance,
        )
    });
    Some(Section {
        id: "early",
        heading: "Early decisions: accuracy against decision time".into(),
        intro: format!(
            "<p>Each held-out stance decided K frames after its touchdown by a classifier trained on \
             the training stances cut there (a stance that lifts off first: at its lift-off, whole), \
             beside the one-frame model on frame K of the same stances and the whole stance at \
             lift-off ({} stances, {}).{auto}</p>",
            early.tested,
            esc(&early.note),
        ),
        figure: Some((
            "early_decisions.png".into(),
            Job::Faults(FaultFigure {
                title: "Early decisions".into(),
                panels: vec![curve_panel(early)],
                spread_name: None,
            }),
            "Accuracy of the held-out stances against the decision point: the stance model's \
             classifier for each point, the one-frame model on the same frame, and auto's accuracy \
             at its mean decision frame."
                .into(),
        )),
        after: curve_table(early),
    })
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;
    use crate::report::inputs::{EarlyAutoResult, EarlyCurvePoint};

    fn curve() -> EarlyCurve {
        EarlyCurve {
            points: vec![
                EarlyCurvePoint {
                    frames: 6,
                    accuracy: 0.8,
                    frame_accuracy: Some(0.75),
                },
                EarlyCurvePoint {
                    frames: 12,
                    accuracy: 0.9,
                    frame_accuracy: None,
                },
            ],
            whole_accuracy: 0.95,
            auto: Some(EarlyAutoResult {
                accuracy: 0.93,
                mean_frames: 15.0,
                decided_early: 0.7,
                decided_by_mid_stance: 0.5,
            }),
            median_stance_frames: 60,
            frame_period_ms: Some(10.0),
            tested: 120,
            note: "leave one group out".into(),
        }
    }

    /// The section shows every point in frames and ms, the one-frame model beside it, the lift-off
    /// and auto's accuracy at its mean decision time; none without points.
    #[test]
    fn the_section_shows_the_curve_the_one_frame_model_and_auto() {
        let early = curve();
        let section = early_section(Some(&early)).unwrap();
        let table = &section.after;
        assert!(table.contains("6.0 frames (60 ms)"), "{table}");
        assert!(
            table.contains("80.0 %") && table.contains("75.0 %"),
            "{table}"
        );
        assert!(table.contains("12.0 frames (120 ms)") && table.contains("—"));
        assert!(table.contains("lift-off") && table.contains("95.0 %"));
        assert!(table.contains("auto: mean 15.0 frames (150 ms)") && table.contains("25 %"));
        assert!(section.intro.contains("93.0 % right") && section.intro.contains("70 %"));
        assert!(
            section
                .intro
                .contains("70 % of the stances decided before their lift-off, 50 % by"),
            "{}",
            section.intro
        );
        let panel = curve_panel(&early);
        assert_eq!(panel.lines.len(), 3);
        assert_eq!(panel.lines[0].1.last(), Some(&(60.0, 95.0, 0.0)));
        assert_eq!(panel.lines[1].1, vec![(6.0, 75.0, 0.0)]);
        assert_eq!(panel.lines[2].1, vec![(15.0, 93.0, 0.0)]);
        assert!(panel.x_label.contains("10.0 ms"));
        let without = EarlyCurve {
            points: Vec::new(),
            ..curve()
        };
        assert!(early_section(Some(&without)).is_none());
        assert!(early_section(None).is_none());
    }

    /// The figure renders (a PNG is written).
    #[test]
    fn the_figure_renders() {
        let early = curve();
        let section = early_section(Some(&early)).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let (name, job, _) = section.figure.as_ref().unwrap();
        let path = dir.path().join(name);
        job.save(&path).unwrap();
        assert!(std::fs::metadata(&path).unwrap().len() > 1000);
    }
}
