//! The section of `eval --leave-class-out`: how the novelty score did with each class held out of
//! training.

use std::fmt::Write as _;

use super::inputs::{NoveltyResult, NoveltyRow};
use super::page::{Section, esc};

/// The table of `result`, one row per held-out class and a row of means.
pub(super) fn novelty_section<'a>(result: &NoveltyResult) -> Option<Section<'a>> {
    if result.rows.is_empty() {
        return None;
    }
    let or_dash = |v: Option<f64>| v.map_or("—".to_owned(), |v| format!("{v:.3}"));
    let percent = |v: f64| format!("{:.1} %", 100.0 * v);
    let mut table = String::from(
        "<table><tr><th>held-out class</th><th>held-out / known test samples</th><th>AUROC of the \
         novelty score</th><th>AUROC of 1 - max posterior</th><th>held-out decided known, confidence \
         ≥ 0.9</th><th>the same without novelty</th><th>known decided unknown</th></tr>",
    );
    for row in &result.rows {
        let _ = write!(
            table,
            "<tr><td>{}</td><td>{} / {}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            esc(&row.class),
            row.novel_samples,
            row.known_samples,
            or_dash(row.auroc),
            or_dash(row.auroc_posterior),
            percent(row.confident_known),
            percent(row.confident_known_without),
            percent(row.known_rejected),
        );
    }
    let n = result.rows.len() as f64;
    let mean = |f: &dyn Fn(&NoveltyRow) -> f64| result.rows.iter().map(f).sum::<f64>() / n;
    let mean_of = |f: &dyn Fn(&NoveltyRow) -> Option<f64>| {
        let values: Option<Vec<f64>> = result.rows.iter().map(f).collect();
        values.map(|v| v.iter().sum::<f64>() / n)
    };
    let _ = write!(
        table,
        "<tr><th>mean</th><td></td><th>{}</th><th>{}</th><th>{}</th><th>{}</th><th>{}</th></tr></table>",
        or_dash(mean_of(&|r| r.auroc)),
        or_dash(mean_of(&|r| r.auroc_posterior)),
        percent(mean(&|r| r.confident_known)),
        percent(mean(&|r| r.confident_known_without)),
        percent(mean(&|r| r.known_rejected)),
    );
    Some(Section {
        id: "novelty",
        heading: "A class never seen (leave one class out)".into(),
        intro: format!(
            "<p>Each class in turn is left out of training; the model (trained on the others, its \
             novelty threshold learned on them alone) decides every test sample. A held-out sample \
             should be decided <code>unknown</code>; a known one should not. {}</p>",
            esc(&result.note)
        ),
        figure: None,
        after: table,
    })
}
