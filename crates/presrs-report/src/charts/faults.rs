//! Accuracy against the level of each kind of sensor fault.

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::common::{LABEL, TITLE, finite_range, marker, numeric_axes, padded};
use crate::error::Result;
use crate::render::{Figure, category_color, font, title_font};

/// A point of [`FaultPanel`]: `(level, mean accuracy %, s.d. %)`.
pub type FaultPoint = (f64, f64, f64);

/// One panel of [`FaultFigure`]: one kind of fault, a line per method.
#[derive(Clone, Debug, PartialEq)]
pub struct FaultPanel {
    /// The kind (`dead`, `rotate`, ...).
    pub title: String,
    /// What the level measures (`fraction of sensels dead`, ...).
    pub x_label: String,
    /// `(method, points)`, in level order.
    pub lines: Vec<(String, Vec<FaultPoint>)>,
}

/// Accuracy (%) against fault level, a panel per kind of fault and a line per method (with ±1 s.d.
/// whiskers); the methods share colours and markers across panels and one legend.
#[derive(Clone, Debug, PartialEq)]
pub struct FaultFigure {
    pub title: String,
    pub panels: Vec<FaultPanel>,
    /// Legend text for the whiskers, e.g. `±1 std over 3 repeats`.
    pub spread_name: Option<String>,
}

impl FaultFigure {
    /// Panels per row and rows; one more cell than panels holds the legend.
    fn grid(&self) -> (usize, usize) {
        let cells = self.panels.len() + 1;
        let cols = cells.clamp(1, 4);
        (cells.div_ceil(cols), cols)
    }

    fn methods(&self) -> Vec<&str> {
        let mut names: Vec<&str> = Vec::new();
        for panel in &self.panels {
            for (name, _) in &panel.lines {
                if !names.contains(&name.as_str()) {
                    names.push(name);
                }
            }
        }
        names
    }
}

impl Figure for FaultFigure {
    fn size(&self) -> (u32, u32) {
        let (rows, cols) = self.grid();
        (340 * cols as u32, 44 + 310 * rows as u32)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        let body = root.titled(&self.title, title_font(TITLE + 2.0))?;
        let areas = body.split_evenly(self.grid());
        let methods = self.methods();
        let style_of = |name: &str| {
            let i = methods.iter().position(|m| *m == name).unwrap_or(0);
            (category_color(i), i)
        };
        // One accuracy axis for every panel, so that the kinds compare at a glance.
        let low = self
            .panels
            .iter()
            .flat_map(|p| p.lines.iter().flat_map(|(_, points)| points.iter()))
            .map(|p| p.1 - p.2)
            .fold(100.0_f64, f64::min);
        let y0 = ((low - 5.0) / 10.0).floor().clamp(0.0, 9.0) * 10.0;
        for (area, panel) in areas.iter().zip(&self.panels) {
            let levels = panel
                .lines
                .iter()
                .flat_map(|(_, points)| points.iter().map(|p| p.0));
            let (x0, x1) = finite_range(levels).unwrap_or((0.0, 1.0));
            let mut chart = ChartBuilder::on(area)
                .caption(&panel.title, title_font(TITLE - 1.0))
                .margin(8)
                .margin_right(18)
                .x_label_area_size(44)
                .y_label_area_size(56)
                .build_cartesian_2d(padded(x0, x1, 0.06), y0..101.0)?;
            numeric_axes(&mut chart, &panel.x_label, "accuracy (%)")
                .axis_desc_style(font(LABEL - 2.0))
                .x_labels(5)
                .y_labels(6)
                .draw()?;
            for (name, points) in &panel.lines {
                let (color, shape) = style_of(name);
                // The first method wider, so that coinciding lines both show.
                let width = if shape == 0 && methods.len() > 1 {
                    5
                } else {
                    2
                };
                chart.draw_series(LineSeries::new(
                    points.iter().map(|p| (p.0, p.1)),
                    color.stroke_width(width),
                ))?;
                chart.draw_series(points.iter().filter(|p| p.2 > 0.0).map(|&(x, m, sd)| {
                    PathElement::new(
                        vec![(x, (m - sd).max(y0)), (x, (m + sd).min(101.0))],
                        color.mix(0.6).stroke_width(2),
                    )
                }))?;
                chart.draw_series(
                    points
                        .iter()
                        .map(|&(x, m, _)| EmptyElement::at((x, m)) + marker(shape, (0, 0), color)),
                )?;
            }
        }
        // The legend in the last cell.
        if let Some(area) = areas.get(self.panels.len()) {
            let (_, h) = area.dim_in_pixel();
            let mut entries: Vec<(Option<(RGBColor, usize)>, String)> = methods
                .iter()
                .map(|m| (Some(style_of(m)), (*m).to_owned()))
                .collect();
            if let Some(spread) = &self.spread_name {
                entries.push((None, format!("whiskers: {spread}")));
            }
            let x = 24;
            let top = (h as i32 / 2 - 18 * entries.len() as i32).max(10);
            for (k, (style, text)) in entries.iter().enumerate() {
                let y = top + 36 * k as i32;
                match style {
                    Some((color, shape)) => {
                        area.draw(&PathElement::new(
                            vec![(x, y), (x + 36, y)],
                            color.stroke_width(3),
                        ))?;
                        area.draw(
                            &(EmptyElement::at((x + 18, y)) + marker(*shape, (0, 0), *color)),
                        )?;
                    }
                    None => {
                        area.draw(&PathElement::new(
                            vec![(x + 18, y - 9), (x + 18, y + 9)],
                            BLACK.mix(0.6).stroke_width(2),
                        ))?;
                    }
                }
                area.draw(&Text::new(
                    text.clone(),
                    (x + 48, y),
                    font(LABEL).pos(Pos::new(HPos::Left, VPos::Center)),
                ))?;
            }
        }
        Ok(())
    }
}
