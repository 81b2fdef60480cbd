//! Feature spectra per label, conditions overlaid (the paper's Fig. 6).

use plotters::coord::Shift;
use plotters::prelude::*;

use super::common::{LABEL, TICK, TITLE, draw_legend, finite_range};
use crate::error::Result;
use crate::format::num;
use crate::render::{Figure, category_color, font, title_font};

/// One panel of [`SpectraFigure`]: the lines of one label.
#[derive(Clone, Debug, PartialEq)]
pub struct SpectrumPanel {
    pub title: String,
    /// `(legend name, values)`; values are indexed like [`SpectraFigure::x`].
    pub lines: Vec<(String, Vec<f64>)>,
}

/// Feature vectors per label with the conditions overlaid (the paper's Fig. 6), log magnitude.
#[derive(Clone, Debug, PartialEq)]
pub struct SpectraFigure {
    pub title: String,
    pub x: Vec<f64>,
    pub x_label: String,
    pub y_label: String,
    pub panels: Vec<SpectrumPanel>,
}

impl SpectraFigure {
    fn grid(&self) -> (usize, usize) {
        let n = self.panels.len().max(1);
        let cols = if n <= 1 { 1 } else { 2 };
        (n.div_ceil(cols), cols)
    }
}

impl Figure for SpectraFigure {
    fn size(&self) -> (u32, u32) {
        let (rows, cols) = self.grid();
        (560 * cols as u32, 40 + 330 * rows as u32)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        let body = root.titled(&self.title, title_font(TITLE + 2.0))?;
        let areas = body.split_evenly(self.grid());
        // One shared magnitude range so that panels compare.
        let positive = self
            .panels
            .iter()
            .flat_map(|p| p.lines.iter().flat_map(|(_, v)| v.iter().copied()))
            .filter(|v| *v > 0.0);
        let (lo, hi) = finite_range(positive).unwrap_or((1e-3, 1.0));
        let lo = lo.max(hi * 1e-6);
        let (x0, x1) = finite_range(self.x.iter().copied()).unwrap_or((0.0, 1.0));
        for (area, panel) in areas.iter().zip(&self.panels) {
            let mut chart = ChartBuilder::on(area)
                .caption(&panel.title, title_font(TITLE - 2.0))
                .margin(8)
                .margin_right(16)
                .x_label_area_size(42)
                .y_label_area_size(64)
                .build_cartesian_2d(x0..x1, (lo * 0.8..hi * 1.25).log_scale())?;
            chart
                .configure_mesh()
                .light_line_style(WHITE)
                .x_desc(&self.x_label)
                .y_desc(&self.y_label)
                .axis_desc_style(font(LABEL - 1.0))
                .label_style(font(TICK))
                .x_label_formatter(&|v| num(*v))
                .y_label_formatter(&|v| format!("{v:.0e}"))
                .x_labels(6)
                .draw()?;
            let n = panel.lines.len();
            for (i, (name, values)) in panel.lines.iter().enumerate() {
                let color = category_color(i);
                // The first line a little wider, so that overlaid, near-identical spectra all show.
                let width = if n > 1 && i == 0 { 2 } else { 1 };
                chart
                    .draw_series(LineSeries::new(
                        self.x.iter().zip(values).map(|(&x, &v)| (x, v.max(lo))),
                        color.mix(0.75).stroke_width(width),
                    ))?
                    .label(name)
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(3))
                    });
            }
            draw_legend(&mut chart, SeriesLabelPosition::UpperRight)?;
        }
        Ok(())
    }
}
