//! Confusion matrices as heat maps.

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use presrs_core::evaluation::Confusion;

use super::common::{LABEL, TICK, TITLE, draw_category_text};
use crate::error::Result;
use crate::render::{Figure, blues, font, title_font};

/// Confusion matrices as heat maps with counts, side by side.
#[derive(Clone, Debug, PartialEq)]
pub struct ConfusionFigure {
    pub title: String,
    /// `(panel title, matrix)`.
    pub matrices: Vec<(String, Confusion)>,
}

impl Figure for ConfusionFigure {
    fn size(&self) -> (u32, u32) {
        let n = self.matrices.len().max(1) as u32;
        let cols = n.min(3);
        let rows = n.div_ceil(cols);
        (470 * cols, 50 + 450 * rows)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        let body = root.titled(&self.title, title_font(TITLE + 2.0))?;
        let n = self.matrices.len().max(1);
        let cols = n.min(3);
        let areas = body.split_evenly((n.div_ceil(cols), cols));
        for (area, (name, confusion)) in areas.iter().zip(&self.matrices) {
            let k = confusion.labels.len().max(1);
            let kf = k as f64;
            let mut chart = ChartBuilder::on(area)
                .caption(name, title_font(TITLE - 3.0))
                .margin(10)
                .margin_right(20)
                .x_label_area_size(54)
                .y_label_area_size(80)
                .build_cartesian_2d(-0.5..kf - 0.5, -(kf - 0.5)..0.5)?;
            chart
                .configure_mesh()
                .disable_mesh()
                .x_labels(0)
                .y_labels(0)
                .x_desc("predicted class")
                .y_desc("true class")
                .axis_desc_style(font(LABEL - 1.0))
                .label_style(font(TICK))
                .draw()?;
            let rows = confusion.row_normalised();
            let mut cells = Vec::new();
            let mut texts = Vec::new();
            for (i, row) in confusion.counts.iter().enumerate() {
                for (j, &count) in row.iter().enumerate() {
                    let share = rows.get(i).and_then(|r| r.get(j)).copied().unwrap_or(0.0);
                    let (x, y) = (j as f64, -(i as f64));
                    cells.push(Rectangle::new(
                        [(x - 0.5, y + 0.5), (x + 0.5, y - 0.5)],
                        blues(share).filled(),
                    ));
                    let color: &'static RGBColor = if share > 0.55 { &WHITE } else { &BLACK };
                    texts.push(Text::new(
                        count.to_string(),
                        (x, y),
                        font(TICK + 2.0)
                            .color(color)
                            .pos(Pos::new(HPos::Center, VPos::Center)),
                    ));
                    let pct = format!("{:.1} %", 100.0 * share);
                    texts.push(Text::new(
                        pct,
                        (x, y - 0.22),
                        font(TICK - 1.0)
                            .color(color)
                            .pos(Pos::new(HPos::Center, VPos::Center)),
                    ));
                }
            }
            chart.draw_series(cells)?;
            chart.draw_series(texts)?;
            for (i, label) in confusion.labels.iter().enumerate() {
                let bottom = chart.backend_coord(&(i as f64, -(kf - 0.5)));
                draw_category_text(area, bottom, label, false)?;
                let left = chart.backend_coord(&(-0.5, -(i as f64)));
                draw_category_text(area, left, label, true)?;
            }
        }
        Ok(())
    }
}
