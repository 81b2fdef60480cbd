//! Grouped bars (accuracy per condition, Table I).

use plotters::coord::Shift;
use plotters::prelude::*;

use super::common::{LABEL, TICK, TITLE, draw_category_text};
use crate::error::Result;
use crate::format::num;
use crate::render::{Figure, category_color, font, title_font};

/// One series of [`BarsFigure`]: a value (and spread) per category.
#[derive(Clone, Debug, PartialEq)]
pub struct BarSeries {
    pub name: String,
    /// `(mean, spread)` per category; `None` for no bar.
    pub values: Vec<Option<(f64, f64)>>,
    /// Reference values per category (e.g. the paper's), drawn as black diamonds on the bars; may be empty.
    pub reference: Vec<Option<f64>>,
}

/// Bars grouped by category, with whiskers and optional reference markers (the paper's values).
#[derive(Clone, Debug, PartialEq)]
pub struct BarsFigure {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub categories: Vec<String>,
    pub series: Vec<BarSeries>,
    /// Legend name of the series' reference values (e.g. `paper`).
    pub reference_name: Option<String>,
    /// Fixed y range (`None`: from 0 to above the largest value).
    pub y_range: Option<(f64, f64)>,
    /// Legend text for the whiskers, e.g. `±1 std over 10 repeats`.
    pub spread_name: Option<String>,
}

impl BarsFigure {
    /// Pixels to the right of the bars for the legend.
    const LEGEND_ROOM: u32 = 240;

    fn plot_width(&self) -> u32 {
        (90 * (self.categories.len() * self.series.len().max(1)) as u32 + 80).clamp(480, 1200)
    }
}

impl Figure for BarsFigure {
    fn size(&self) -> (u32, u32) {
        (self.plot_width() + Self::LEGEND_ROOM + 120, 520)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        let n = self.categories.len().max(1) as f64;
        let (y0, y1) = self.y_range.unwrap_or_else(|| {
            let hi = self
                .series
                .iter()
                .flat_map(|s| s.values.iter().flatten().map(|(m, s)| m + s))
                .chain(
                    self.series
                        .iter()
                        .flat_map(|s| s.reference.iter().flatten().copied()),
                )
                .fold(0.0_f64, f64::max);
            (0.0, if hi > 0.0 { hi * 1.25 } else { 1.0 })
        });
        let mut chart = ChartBuilder::on(root)
            .caption(&self.title, title_font(TITLE + 2.0))
            .margin(12)
            .margin_right(20)
            .x_label_area_size(56)
            .y_label_area_size(70)
            .build_cartesian_2d(
                -0.5..n - 0.5 + n * f64::from(Self::LEGEND_ROOM) / f64::from(self.plot_width()),
                y0..y1,
            )?;
        chart
            .configure_mesh()
            .disable_x_mesh()
            .light_line_style(WHITE)
            .x_labels(0)
            .x_desc(&self.x_label)
            .y_desc(&self.y_label)
            .axis_desc_style(font(LABEL))
            .label_style(font(TICK))
            .y_label_formatter(&|v| num(*v))
            .draw()?;
        let k = self.series.len().max(1) as f64;
        let group = 0.8;
        let bar = group / k;
        let offset = |s: usize| -group / 2.0 + bar * (s as f64 + 0.5);
        for (s, series) in self.series.iter().enumerate() {
            let color = category_color(s);
            let bars = series.values.iter().enumerate().filter_map(|(c, v)| {
                v.map(|(mean, _)| {
                    let x = c as f64 + offset(s);
                    Rectangle::new(
                        [(x - bar * 0.45, y0), (x + bar * 0.45, mean.max(y0))],
                        color.filled(),
                    )
                })
            });
            chart
                .draw_series(bars)?
                .label(&series.name)
                .legend(move |(x, y)| {
                    Rectangle::new([(x, y - 6), (x + 16, y + 6)], color.filled())
                });
            let whiskers = series.values.iter().enumerate().filter_map(|(c, v)| {
                v.filter(|(_, spread)| *spread > 0.0).map(|(mean, spread)| {
                    let x = c as f64 + offset(s);
                    let (lo, hi) = ((mean - spread).max(y0), (mean + spread).min(y1));
                    let cap = bar * 0.15;
                    PathElement::new(
                        vec![
                            (x - cap, lo),
                            (x + cap, lo),
                            (x, lo),
                            (x, hi),
                            (x - cap, hi),
                            (x + cap, hi),
                        ],
                        BLACK.stroke_width(2),
                    )
                })
            });
            chart.draw_series(whiskers)?;
        }
        if let Some(spread) = &self.spread_name {
            chart
                .draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())?
                .label(spread)
                .legend(|(x, y)| {
                    PathElement::new(vec![(x + 8, y - 7), (x + 8, y + 7)], BLACK.stroke_width(2))
                });
        }
        let diamonds: Vec<(f64, f64)> = self
            .series
            .iter()
            .enumerate()
            .flat_map(|(s, series)| {
                series
                    .reference
                    .iter()
                    .enumerate()
                    .filter_map(move |(c, v)| v.map(|value| (c as f64 + offset(s), value)))
            })
            .collect();
        if let Some(name) = self
            .reference_name
            .as_ref()
            .filter(|_| !diamonds.is_empty())
        {
            chart
                .draw_series(diamonds.into_iter().map(|at| {
                    EmptyElement::at(at)
                        + Polygon::new(vec![(0, -7), (7, 0), (0, 7), (-7, 0)], BLACK.filled())
                }))?
                .label(name)
                .legend(|(x, y)| {
                    Polygon::new(
                        vec![(x + 8, y - 6), (x + 14, y), (x + 8, y + 6), (x + 2, y)],
                        BLACK.filled(),
                    )
                });
        }
        for (c, name) in self.categories.iter().enumerate() {
            let pixel = chart.backend_coord(&(c as f64, y0));
            draw_category_text(root, pixel, name, false)?;
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::MiddleRight)
            .background_style(WHITE.mix(0.9))
            .border_style(BLACK)
            .label_font(font(TICK + 1.0))
            .draw()?;
        Ok(())
    }
}
