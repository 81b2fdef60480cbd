//! The samples scattered in two principal components.

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::common::{LABEL, TICK, TITLE, finite_range, marker, numeric_axes, padded};
use crate::error::Result;
use crate::render::{Figure, PALETTE, category_color, font, title_font};

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

/// The point shapes [`marker`] draws.
const SHAPES: usize = 5;

/// The colour and shape of class `i` of `classes`: the palette's colours with one shape while they
/// last; past that, every colour again with each further shape, so no two classes look alike up to
/// `PALETTE.len() x 5` classes. Shapes show the condition only while the colours alone tell the classes.
pub(crate) fn class_style(i: usize, classes: usize) -> (RGBColor, Option<usize>) {
    if classes <= PALETTE.len() {
        (category_color(i), None)
    } else {
        (category_color(i), Some((i / PALETTE.len()) % SHAPES))
    }
}

impl ScatterFigure {
    /// The legend's entries: `(text, colour, shape)`, the classes then (when shapes show them) the
    /// conditions.
    fn legend(&self) -> Vec<(String, RGBColor, usize)> {
        let n = self.labels.len();
        let mut entries: Vec<_> = self
            .labels
            .iter()
            .enumerate()
            .map(|(i, name)| {
                let (color, shape) = class_style(i, n);
                (name.clone(), color, shape.unwrap_or(0))
            })
            .collect();
        if self.conditions.len() > 1 && n <= PALETTE.len() {
            entries.extend(
                self.conditions
                    .iter()
                    .enumerate()
                    .map(|(i, name)| (name.clone(), RGBColor(60, 60, 60), i)),
            );
        }
        entries
    }

    /// The legend's column width, pixels.
    fn legend_width(&self) -> u32 {
        let widest = self
            .legend()
            .iter()
            .map(|(name, ..)| name.chars().count())
            .max()
            .unwrap_or(0);
        (40.0 + widest as f64 * 0.62 * (TICK + 1.0)).min(260.0) as u32
    }
}

/// The height of one legend line, pixels.
const LEGEND_LINE: u32 = 18;

impl Figure for ScatterFigure {
    fn size(&self) -> (u32, u32) {
        let lines = self.legend().len() as u32;
        (900 + self.legend_width(), 700.max(80 + LEGEND_LINE * lines))
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        let (w, _) = root.dim_in_pixel();
        let (plot, legend) = root.split_horizontally(w.saturating_sub(self.legend_width()));
        let (x0, x1) = finite_range(self.points.iter().map(|p| p.0)).unwrap_or((0.0, 1.0));
        let (y0, y1) = finite_range(self.points.iter().map(|p| p.1)).unwrap_or((0.0, 1.0));
        let mut chart = ChartBuilder::on(&plot)
            .caption(&self.title, title_font(TITLE + 2.0))
            .margin(12)
            .x_label_area_size(48)
            .y_label_area_size(70)
            .build_cartesian_2d(padded(x0, x1, 0.06), padded(y0, y1, 0.06))?;
        numeric_axes(&mut chart, &self.x_label, &self.y_label)
            .axis_desc_style(font(LABEL))
            .draw()?;
        let n = self.labels.len();
        let base = plot.get_base_pixel();
        for &(x, y, l, c) in &self.points {
            let (color, shape) = class_style(l, n);
            let pixel = chart.backend_coord(&(x, y));
            plot.draw(&marker::<DB>(
                shape.unwrap_or(c),
                (pixel.0 - base.0, pixel.1 - base.1),
                color.mix(0.8).to_rgba().into_rgb(),
            ))?;
        }
        // Beside the plot, not over it: with many classes a legend inside covers the points.
        for (row, (name, color, shape)) in self.legend().into_iter().enumerate() {
            let y = 50 + (row as u32 * LEGEND_LINE) as i32;
            legend.draw(&marker::<DB>(shape, (12, y), color))?;
            legend.draw(&Text::new(
                name,
                (26, y),
                font(TICK + 1.0).pos(Pos::new(HPos::Left, VPos::Center)),
            ))?;
        }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_two_classes_look_alike_up_to_fifty() {
        for n in [4, 10, 11, 22, 40, 50] {
            let mut seen = std::collections::BTreeSet::new();
            for i in 0..n {
                let (color, shape) = class_style(i, n);
                assert!(
                    seen.insert((color.0, color.1, color.2, shape)),
                    "{n} classes: class {i}"
                );
            }
        }
        // Few classes: colours alone, shapes left to the conditions.
        assert_eq!(class_style(3, 10).1, None);
    }
}
