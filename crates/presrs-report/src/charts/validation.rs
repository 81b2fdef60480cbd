//! The validation curve of the hyper-parameters and the PCA's explained variance.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::common::{LABEL, TICK, TITLE, draw_legend, finite_range, numeric_axes};
use crate::error::Result;
use crate::format::num;
use crate::render::{Figure, category_color, font, title_font};

/// The validation curve used to choose the Parzen width, and the PCA's explained variance.
#[derive(Clone, Debug, PartialEq)]
pub struct ValidationFigure {
    pub title: String,
    /// `(sigma, validation accuracy in [0, 1])`.
    pub curve: Vec<(f64, f64)>,
    /// `(sigma, geometric mean over the validation images of the posterior of their true class)`, the
    /// tie-break among the most accurate widths (empty for models that did not record it).
    pub confidence: Vec<(f64, f64)>,
    pub chosen_sigma: Option<f64>,
    /// Explained variance ratio per principal component, and how many the model keeps.
    pub explained: Vec<f64>,
    pub kept: usize,
}

impl Figure for ValidationFigure {
    fn size(&self) -> (u32, u32) {
        (1100, 460)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        let body = root.titled(&self.title, title_font(TITLE + 2.0))?;
        let (w, _) = body.dim_in_pixel();
        let (left, right) = body.split_horizontally(w / 2);
        // Accuracy against sigma.
        let (s0, s1) = finite_range(self.curve.iter().map(|p| p.0).filter(|s| *s > 0.0))
            .unwrap_or((0.1, 10.0));
        let (a0, _) = finite_range(
            self.curve
                .iter()
                .chain(&self.confidence)
                .map(|p| 100.0 * p.1),
        )
        .unwrap_or((0.0, 100.0));
        let mut chart = ChartBuilder::on(&left)
            .caption(
                "validation accuracy and confidence against the Parzen width σ",
                title_font(TITLE - 3.0),
            )
            .margin(10)
            .margin_right(20)
            .x_label_area_size(44)
            .y_label_area_size(60)
            .build_cartesian_2d(
                (s0 / 1.3..s1 * 1.3).log_scale(),
                (a0 - 5.0).clamp(0.0, 95.0)..101.0,
            )?;
        chart
            .configure_mesh()
            .light_line_style(WHITE)
            .x_desc("σ (PCA feature units, log scale)")
            .y_desc("validation accuracy, confidence (%)")
            .axis_desc_style(font(LABEL - 1.0))
            .label_style(font(TICK))
            .y_label_formatter(&|v| num(*v))
            .x_label_formatter(&|v| format!("{v:.2e}"))
            .x_labels(5)
            .draw()?;
        let line = category_color(0);
        chart
            .draw_series(LineSeries::new(
                self.curve.iter().map(|&(s, a)| (s, 100.0 * a)),
                line.stroke_width(2),
            ))?
            .label("validation accuracy")
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 18, y)], line.stroke_width(2))
            });
        chart.draw_series(
            self.curve
                .iter()
                .map(|&(s, a)| Circle::new((s, 100.0 * a), 3, line.filled())),
        )?;
        if !self.confidence.is_empty() {
            let line = category_color(1);
            chart
                .draw_series(LineSeries::new(
                    self.confidence.iter().map(|&(s, c)| (s, 100.0 * c)),
                    line.stroke_width(2),
                ))?
                .label("confidence in the true class (geometric mean)")
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], line.stroke_width(2))
                });
        }
        if let Some(sigma) = self.chosen_sigma {
            let mark = category_color(3);
            chart
                .draw_series(std::iter::once(PathElement::new(
                    vec![(sigma, (a0 - 5.0).clamp(0.0, 95.0)), (sigma, 101.0)],
                    mark.stroke_width(2),
                )))?
                .label(format!("chosen σ = {sigma:.3e}"))
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], mark.stroke_width(2))
                });
        }
        draw_legend(&mut chart, SeriesLabelPosition::LowerRight)?;
        // Cumulative explained variance.
        let n = self.explained.len().max(1);
        let mut cumulative = Vec::with_capacity(n);
        let mut sum = 0.0;
        for v in &self.explained {
            sum += v;
            cumulative.push(100.0 * sum);
        }
        let mut chart = ChartBuilder::on(&right)
            .caption(
                "PCA: variance kept against components",
                title_font(TITLE - 3.0),
            )
            .margin(10)
            .margin_right(20)
            .x_label_area_size(44)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..(n as f64 + 1.0), 0.0..101.0)?;
        numeric_axes(
            &mut chart,
            "principal components kept",
            "cumulative explained variance (%)",
        )
        .draw()?;
        let line = category_color(2);
        chart
            .draw_series(LineSeries::new(
                cumulative
                    .iter()
                    .enumerate()
                    .map(|(i, &v)| ((i + 1) as f64, v)),
                line.stroke_width(2),
            ))?
            .label("cumulative explained variance")
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 18, y)], line.stroke_width(2))
            });
        if self.kept > 0 {
            let mark = category_color(3);
            let kept_pct = cumulative.get(self.kept - 1).copied().unwrap_or(100.0);
            chart
                .draw_series(std::iter::once(PathElement::new(
                    vec![(self.kept as f64, 0.0), (self.kept as f64, 101.0)],
                    mark.stroke_width(2),
                )))?
                .label(format!("kept: {} components ({kept_pct:.1} %)", self.kept))
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], mark.stroke_width(2))
                });
        }
        draw_legend(&mut chart, SeriesLabelPosition::LowerRight)?;
        Ok(())
    }
}
