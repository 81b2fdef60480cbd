//! The simulated hopper's motion.

use plotters::coord::Shift;
use plotters::prelude::*;
use presrs_sim::trace::HopTrace;

use super::common::{TITLE, draw_legend, finite_range, numeric_axes, padded};
use crate::error::{ReportError, Result};
use crate::render::{Figure, category_color, title_font};

/// The simulated hopper's body path and ground force over a few hops, one line per trace.
#[derive(Clone, Debug, PartialEq)]
pub struct TraceFigure {
    pub title: String,
    pub traces: Vec<HopTrace>,
}

impl Figure for TraceFigure {
    fn size(&self) -> (u32, u32) {
        (1100, 820)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        if self.traces.is_empty() {
            return Err(ReportError::Input("no hopper trace to draw".into()));
        }
        let body = root.titled(&self.title, title_font(TITLE + 2.0))?;
        let (_, h) = body.dim_in_pixel();
        let (top, bottom) = body.split_vertically(h / 2);
        let points = || self.traces.iter().flat_map(|t| t.points.iter());
        let (x0, x1) = finite_range(points().map(|p| p.x_m)).unwrap_or((0.0, 1.0));
        let (y0, y1) = finite_range(points().map(|p| p.y_m)).unwrap_or((0.0, 1.0));
        let mut chart = ChartBuilder::on(&top)
            .caption(
                "body path (thick: foot on the ground)",
                title_font(TITLE - 3.0),
            )
            .margin(10)
            .margin_right(20)
            .x_label_area_size(44)
            .y_label_area_size(70)
            .build_cartesian_2d(padded(x0, x1, 0.02), padded(y0, y1, 0.12))?;
        numeric_axes(&mut chart, "forward distance (m)", "body height (m)").draw()?;
        for (i, trace) in self.traces.iter().enumerate() {
            let color = category_color(i);
            chart
                .draw_series(LineSeries::new(
                    trace.points.iter().map(|p| (p.x_m, p.y_m)),
                    color.stroke_width(1),
                ))?
                .label(format!("{} · {}", trace.terrain, trace.gait))
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(3))
                });
            // Stance stretches drawn thick.
            let mut segment: Vec<(f64, f64)> = Vec::new();
            let mut segments = Vec::new();
            for p in &trace.points {
                if p.stance {
                    segment.push((p.x_m, p.y_m));
                } else if !segment.is_empty() {
                    segments.push(std::mem::take(&mut segment));
                }
            }
            if !segment.is_empty() {
                segments.push(segment);
            }
            chart.draw_series(
                segments
                    .into_iter()
                    .map(|s| PathElement::new(s, color.stroke_width(4))),
            )?;
        }
        draw_legend(&mut chart, SeriesLabelPosition::LowerRight)?;

        let (t0, t1) = finite_range(points().map(|p| p.t_s)).unwrap_or((0.0, 1.0));
        let (f0, f1) =
            finite_range(points().flat_map(|p| [p.normal_force_n, p.tangential_force_n]))
                .unwrap_or((0.0, 1.0));
        let mut chart = ChartBuilder::on(&bottom)
            .caption(
                "ground reaction force (solid: normal, dashed: tangential)",
                title_font(TITLE - 3.0),
            )
            .margin(10)
            .margin_right(20)
            .x_label_area_size(44)
            .y_label_area_size(70)
            .build_cartesian_2d(t0..t1, padded(f0.min(0.0), f1, 0.06))?;
        numeric_axes(&mut chart, "time (s)", "force on the foot (N)").draw()?;
        for (i, trace) in self.traces.iter().enumerate() {
            let color = category_color(i);
            chart
                .draw_series(LineSeries::new(
                    trace.points.iter().map(|p| (p.t_s, p.normal_force_n)),
                    color.stroke_width(2),
                ))?
                .label(format!("{} · {}", trace.terrain, trace.gait))
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(3))
                });
            // Dashed tangential force: every other short piece.
            let pieces: Vec<Vec<(f64, f64)>> = trace
                .points
                .windows(2)
                .enumerate()
                .filter(|(k, w)| (k / 4) % 2 == 0 && (w[0].stance || w[1].stance))
                .map(|(_, w)| {
                    vec![
                        (w[0].t_s, w[0].tangential_force_n),
                        (w[1].t_s, w[1].tangential_force_n),
                    ]
                })
                .collect();
            chart.draw_series(
                pieces
                    .into_iter()
                    .map(|p| PathElement::new(p, color.stroke_width(2))),
            )?;
        }
        draw_legend(&mut chart, SeriesLabelPosition::UpperRight)?;
        Ok(())
    }
}
