//! The accuracy-against-sensor-fault section.

use std::fmt::Write as _;

use presrs_core::perturb::Perturbation;

use super::inputs::FaultResult;
use super::page::{Job, Section, esc, pct};
use crate::charts::{FaultFigure, FaultPanel};

/// The panels of the fault chart: a panel per kind present in `faults` (in [`Perturbation::KINDS`]
/// order), a line per method, the clean run at the kind's clean level.
pub fn fault_panels(faults: &[FaultResult]) -> Vec<FaultPanel> {
    let mut methods: Vec<&str> = Vec::new();
    for f in faults {
        if !methods.contains(&f.method.as_str()) {
            methods.push(&f.method);
        }
    }
    let mut panels = Vec::new();
    for kind in Perturbation::KINDS {
        let of_kind: Vec<&FaultResult> = faults
            .iter()
            .filter(|f| f.perturbation.is_some_and(|p| p.kind() == kind))
            .collect();
        let Some(example) = of_kind.first().and_then(|f| f.perturbation) else {
            continue;
        };
        let lines = methods
            .iter()
            .filter_map(|&method| {
                let clean = faults
                    .iter()
                    .filter(|f| f.perturbation.is_none() && f.method == method)
                    .map(|f| (example.clean_level(), f.accuracy));
                let perturbed = of_kind
                    .iter()
                    .filter(|f| f.method == method)
                    .filter_map(|f| Some((f.perturbation?.level(), f.accuracy)));
                let mut points: Vec<(f64, f64, f64)> = clean
                    .chain(perturbed)
                    .map(|(level, a)| (level, 100.0 * a.mean, 100.0 * a.std))
                    .collect();
                points.sort_by(|a, b| a.0.total_cmp(&b.0));
                (!points.is_empty()).then(|| (method.to_owned(), points))
            })
            .collect();
        panels.push(FaultPanel {
            title: kind.to_owned(),
            x_label: example.level_name().to_owned(),
            lines,
        });
    }
    panels
}

/// The section of the accuracy-against-fault chart and its table (`None` without perturbed results).
pub(super) fn fault_section<'a>(faults: &[FaultResult], note: Option<&str>) -> Option<Section<'a>> {
    let panels = fault_panels(faults);
    if panels.is_empty() {
        return None;
    }
    let mut methods: Vec<&str> = Vec::new();
    for f in faults {
        if !methods.contains(&f.method.as_str()) {
            methods.push(&f.method);
        }
    }
    let mut table = String::from("<table><tr><th>test images</th>");
    for m in &methods {
        let _ = write!(table, "<th>{}</th>", esc(m));
    }
    table.push_str("</tr>");
    let mut rows: Vec<Option<Perturbation>> = Vec::new();
    for f in faults {
        if !rows.contains(&f.perturbation) {
            rows.push(f.perturbation);
        }
    }
    for row in rows {
        let name = row.map_or_else(|| "as recorded".to_owned(), |p| p.to_string());
        let _ = write!(table, "<tr><td>{}</td>", esc(&name));
        for m in &methods {
            let cell = faults
                .iter()
                .find(|f| f.perturbation == row && f.method == *m)
                .map_or("—".to_owned(), |f| pct(&f.accuracy));
            let _ = write!(table, "<td>{cell}</td>");
        }
        table.push_str("</tr>");
    }
    table.push_str("</table>");
    let repeats = note.map_or(String::new(), |n| format!(" {}", esc(n)));
    Some(Section {
        id: "faults",
        heading: "Accuracy against sensor faults".into(),
        intro: String::new(),
        figure: Some((
            "fault_sweep.png".into(),
            Job::Faults(FaultFigure {
                title: "Accuracy with faulty test images, per kind of fault".into(),
                panels,
                spread_name: Some("±1 std over repeats".into()),
            }),
            format!(
                "Every test image perturbed (training images as recorded; the same training draws \
                 and models at every level): dead = a fraction of the sensels read 0, stuck = read \
                 the image's maximum, gain = each sensel's gain drawn around 1, noise = Gaussian \
                 noise on every reading, shift = the foot print moved by whole sensels, rotate = \
                 turned about its centre of pressure, load = every value scaled. The leftmost point \
                 of each panel (the one at factor 1 for load) is the clean test set; where the \
                 lines coincide, the automatic choice picked the paper's method.{repeats}"
            ),
        )),
        after: table,
    })
}
