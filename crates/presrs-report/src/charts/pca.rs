//! The samples scattered in two principal components.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::common::{LABEL, TICK, TITLE, finite_range, marker, numeric_axes, padded};
use crate::error::Result;
use crate::render::{Figure, category_color, font, title_font};

/// Points coloured by label and shaped by condition.
#[derive(Clone, Debug, PartialEq)]
pub struct ScatterFigure {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub labels: Vec<String>,
    pub conditions: Vec<String>,
    /// `(x, y, label index, condition index)`.
    pub points: Vec<(f64, f64, usize, usize)>,
}

impl Figure for ScatterFigure {
    fn size(&self) -> (u32, u32) {
        (900, 700)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        let (x0, x1) = finite_range(self.points.iter().map(|p| p.0)).unwrap_or((0.0, 1.0));
        let (y0, y1) = finite_range(self.points.iter().map(|p| p.1)).unwrap_or((0.0, 1.0));
        let mut chart = ChartBuilder::on(root)
            .caption(&self.title, title_font(TITLE + 2.0))
            .margin(12)
            .x_label_area_size(48)
            .y_label_area_size(70)
            .build_cartesian_2d(padded(x0, x1, 0.06), padded(y0, y1, 0.06))?;
        numeric_axes(&mut chart, &self.x_label, &self.y_label)
            .axis_desc_style(font(LABEL))
            .draw()?;
        for &(x, y, l, c) in &self.points {
            let color = category_color(l);
            let pixel = chart.backend_coord(&(x, y));
            let base = root.get_base_pixel();
            root.draw(&marker::<DB>(
                c,
                (pixel.0 - base.0, pixel.1 - base.1),
                color.mix(0.8).to_rgba().into_rgb(),
            ))?;
        }
        for (i, name) in self.labels.iter().enumerate() {
            let color = category_color(i);
            chart
                .draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())?
                .label(name)
                .legend(move |(x, y)| Circle::new((x + 8, y), 5, color.filled()));
        }
        if self.conditions.len() > 1 {
            for (i, name) in self.conditions.iter().enumerate() {
                chart
                    .draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())?
                    .label(name)
                    .legend(move |(x, y)| marker::<DB>(i, (x + 8, y), RGBColor(60, 60, 60)));
            }
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(font(TICK + 1.0))
            .draw()?;
        Ok(())
    }
}

trait IntoRgb {
    fn into_rgb(self) -> RGBColor;
}

impl IntoRgb for RGBAColor {
    /// Blends onto white.
    fn into_rgb(self) -> RGBColor {
        let blend = |c: u8| (f64::from(c) * self.3 + 255.0 * (1.0 - self.3)).round() as u8;
        RGBColor(blend(self.0), blend(self.1), blend(self.2))
    }
}
