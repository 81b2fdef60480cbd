//! The sections only simulated data sets have: Table I and the hopper's motion.

use std::fmt::Write as _;

use presrs_sim::VelocityTable;

use super::inputs::SimulationInputs;
use super::page::{Job, Section, esc};
use crate::charts::{BarSeries, BarsFigure, TraceFigure};

/// Table I: the simulated hopper's forward velocity per gait and terrain, with the paper's.
pub(super) fn table1_section<'a>(sim: &SimulationInputs<'_>) -> Section<'a> {
    let table = sim.velocity;
    let series: Vec<BarSeries> = table
        .gaits
        .iter()
        .enumerate()
        .map(|(g, gait)| BarSeries {
            name: format!("{gait} simulated"),
            values: table
                .terrains
                .iter()
                .enumerate()
                .map(|(t, _)| {
                    table
                        .velocity_m_per_s
                        .get(g)
                        .and_then(|row| row.get(t))
                        .copied()
                        .filter(|v| v.is_finite())
                        .map(|v| (v, 0.0))
                })
                .collect(),
            reference: table
                .terrains
                .iter()
                .map(|t| VelocityTable::paper_value(gait, t))
                .collect(),
        })
        .collect();
    let mut html = String::from("<table><tr><th>gait</th>");
    for t in &table.terrains {
        let _ = write!(html, "<th>{}</th>", esc(t));
    }
    html.push_str("</tr>");
    for (g, gait) in table.gaits.iter().enumerate() {
        let _ = write!(html, "<tr><td>{}</td>", esc(gait));
        for (t, terrain) in table.terrains.iter().enumerate() {
            let v = table
                .velocity_m_per_s
                .get(g)
                .and_then(|row| row.get(t))
                .copied()
                .unwrap_or(f64::NAN);
            let paper = VelocityTable::paper_value(gait, terrain).map_or(String::new(), |p| {
                format!(" <span class=\"ref\">(paper {p:.2})</span>")
            });
            let _ = write!(html, "<td>{v:.2}{paper}</td>");
        }
        html.push_str("</tr>");
    }
    html.push_str("</table>");
    Section {
        id: "table1",
        heading: "Table I: forward velocity of the simulated hopper".into(),
        intro: String::new(),
        figure: Some((
            "table1_velocity.png".into(),
            Job::Bars(BarsFigure {
                title: "Mean forward velocity per terrain and gait".into(),
                x_label: "terrain".into(),
                y_label: "forward velocity (m/s)".into(),
                categories: table.terrains.clone(),
                series,
                reference_name: Some("paper (Table I)".into()),
                y_range: None,
                spread_name: None,
            }),
            "Mean forward velocity over the recorded hops (m/s); diamonds: the paper's Table I."
                .to_owned(),
        )),
        after: html,
    }
}

/// A few hops of the simulated hopper: body path and ground force; `None` without traces.
pub(super) fn hopper_section<'a>(sim: &SimulationInputs<'_>) -> Option<Section<'a>> {
    if sim.traces.is_empty() {
        return None;
    }
    Some(Section {
        id: "hopper",
        heading: "The hopper over a few hops".into(),
        intro: String::new(),
        figure: Some((
            "hopper.png".into(),
            Job::Trace(TraceFigure {
                title: "Simulated hopper: body path and ground force".into(),
                traces: sim.traces.to_vec(),
            }),
            "Top: the body's path (thick where the foot is on the ground). Bottom: the \
             ground's normal force (solid) and tangential force (dashed, negative = braking) \
             on the foot."
                .to_owned(),
        )),
        after: String::new(),
    })
}
