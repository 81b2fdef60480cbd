//! Reliability diagrams of the reported confidences.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::common::{TITLE, draw_legend, marker, numeric_axes};
use crate::error::Result;
use crate::render::{Figure, category_color, title_font};

/// Reliability diagrams: for each evaluation, the accuracy of the test images against the confidence the
/// model gave them (ten equal-width bins), with the diagonal a calibrated model follows.
#[derive(Clone, Debug, PartialEq)]
pub struct ReliabilityFigure {
    pub title: String,
    /// Per evaluation: its name and its non-empty bins.
    pub series: Vec<(String, Vec<ReliabilityPoint>)>,
}

/// One confidence bin of a [`ReliabilityFigure`]: `(mean confidence, accuracy, images)`, both in `[0, 1]`.
pub type ReliabilityPoint = (f64, f64, u64);

impl Figure for ReliabilityFigure {
    fn size(&self) -> (u32, u32) {
        (760, 600)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        let body = root.titled(&self.title, title_font(TITLE + 2.0))?;
        let mut chart = ChartBuilder::on(&body)
            .margin(12)
            .margin_right(24)
            .x_label_area_size(48)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..101.0, 0.0..101.0)?;
        numeric_axes(
            &mut chart,
            "confidence the model gave (%, bin mean)",
            "share of those images classified right (%)",
        )
        .x_labels(11)
        .y_labels(11)
        .draw()?;
        chart
            .draw_series(LineSeries::new(
                [(0.0, 0.0), (100.0, 100.0)],
                BLACK.mix(0.5).stroke_width(1),
            ))?
            .label("calibrated")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], BLACK.mix(0.5)));
        for (i, (name, bins)) in self.series.iter().enumerate() {
            let color = category_color(i);
            let points: Vec<(f64, f64)> = bins
                .iter()
                .map(|&(confidence, accuracy, _)| (100.0 * confidence, 100.0 * accuracy))
                .collect();
            chart
                .draw_series(LineSeries::new(
                    points.iter().copied(),
                    color.stroke_width(2),
                ))?
                .label(name.clone())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2))
                });
            chart.draw_series(
                points
                    .iter()
                    .map(|&p| EmptyElement::at(p) + marker(i, (0, 0), color)),
            )?;
        }
        draw_legend(&mut chart, SeriesLabelPosition::UpperLeft)?;
        Ok(())
    }
}
