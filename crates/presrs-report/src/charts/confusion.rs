//! Confusion matrices as heat maps, legible from 2 to 40 classes and more: the matrix keeps a bounded
//! size, the class names turn upright when they are wider than a column, and a number is written in a
//! cell only when it fits there (zeros only in small matrices, shares only in large cells).

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::FontTransform;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use presrs_core::evaluation::Confusion;

use super::common::{LABEL, TICK, TITLE};
use crate::error::Result;
use crate::render::{Figure, blues, font, title_font};

/// Confusion matrices as heat maps with counts, side by side.
#[derive(Clone, Debug, PartialEq)]
pub struct ConfusionFigure {
    pub title: String,
    /// `(panel title, matrix)`.
    pub matrices: Vec<(String, Confusion)>,
}

/// The side of the matrix (without its labels) the cells share, pixels.
const MATRIX_SIDE: f64 = 440.0;
/// The largest cell; a matrix of few classes stays this dense.
const MAX_CELL: f64 = 110.0;
/// Class names longer than this are cut (with an ellipsis): the labels' area stays bounded.
const MAX_LABEL_CHARS: usize = 22;
/// The smallest font a number is written in.
const MIN_NUMBER_FONT: f64 = 8.0;

/// Where the parts of one matrix go, in pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct ConfusionLayout {
    /// Classes.
    pub k: usize,
    /// The side of one cell.
    pub cell: f64,
    /// The font of the class names.
    pub label_font: f64,
    /// The width of the longest class name in that font.
    pub label_width: f64,
    /// The column names are written upright (they are wider than a column).
    pub upright: bool,
    /// The font of the counts; `None`: no count fits a cell.
    pub count_font: Option<f64>,
    /// Whether zero counts are written (small matrices only: in a large one they hide the errors).
    pub zeros: bool,
    /// Whether the row shares (`12.5 %`) are written under the counts.
    pub shares: bool,
}

impl ConfusionLayout {
    /// The layout of a matrix of `labels` whose largest count is `max_count`.
    pub(crate) fn new(labels: &[String], max_count: u64) -> Self {
        let k = labels.len().max(1);
        let cell = (MATRIX_SIDE * 2.0 / (k as f64 + 2.0)).clamp(4.0, MAX_CELL);
        let label_font = (TICK + 2.0).min(0.8 * cell).max(5.0);
        let label_width = labels
            .iter()
            .map(|l| text_width(&short_label(l), label_font))
            .fold(0.0, f64::max);
        let number_font = (TICK + 2.0).min(0.45 * cell);
        let widest = text_width(&max_count.to_string(), number_font);
        let count_font =
            (number_font >= MIN_NUMBER_FONT && widest <= cell - 4.0).then_some(number_font);
        let shares = count_font.is_some()
            && cell >= 3.2 * number_font
            && text_width("100.0 %", TICK - 1.0) <= cell - 4.0;
        Self {
            k,
            cell,
            label_font,
            label_width,
            upright: label_width > cell - 4.0,
            count_font,
            zeros: k <= 12,
            shares,
        }
    }

    /// The matrix's top-left corner in its panel.
    fn origin(&self) -> (f64, f64) {
        (28.0 + self.label_width + 10.0, 34.0)
    }

    /// The height of the column names under the matrix.
    fn x_labels_height(&self) -> f64 {
        if self.upright {
            self.label_width + 10.0
        } else {
            self.label_font + 10.0
        }
    }

    /// The panel's width and height.
    pub(crate) fn panel_size(&self) -> (u32, u32) {
        let (x0, y0) = self.origin();
        let side = self.cell * self.k as f64;
        let w = x0 + side + 20.0;
        let h = y0 + side + self.x_labels_height() + LABEL + 16.0;
        (w.ceil() as u32, h.ceil() as u32)
    }
}

/// A class name as the axes show it: at most [`MAX_LABEL_CHARS`] characters.
fn short_label(label: &str) -> String {
    if label.chars().count() <= MAX_LABEL_CHARS {
        label.to_owned()
    } else {
        let head: String = label.chars().take(MAX_LABEL_CHARS - 1).collect();
        format!("{head}…")
    }
}

/// The width of `text` in the figure font of `size`, pixels (measured; about 0.6 of the size a
/// character without the font).
fn text_width(text: &str, size: f64) -> f64 {
    font(size)
        .font
        .box_size(text)
        .map_or(text.chars().count() as f64 * size * 0.6, |(w, _)| {
            f64::from(w)
        })
}

impl ConfusionFigure {
    fn layouts(&self) -> Vec<ConfusionLayout> {
        self.matrices
            .iter()
            .map(|(_, c)| {
                let max = c.counts.iter().flatten().copied().max().unwrap_or(0);
                ConfusionLayout::new(&c.labels, max)
            })
            .collect()
    }

    /// Panels per row, rows, and the largest panel.
    fn grid(&self) -> (usize, usize, (u32, u32)) {
        let n = self.matrices.len().max(1);
        let cols = n.min(3);
        let panel = self
            .layouts()
            .iter()
            .map(ConfusionLayout::panel_size)
            .fold((300, 200), |(w, h), (pw, ph)| (w.max(pw), h.max(ph)));
        (cols, n.div_ceil(cols), panel)
    }
}

impl Figure for ConfusionFigure {
    fn size(&self) -> (u32, u32) {
        let (cols, rows, (w, h)) = self.grid();
        (w * cols as u32, 50 + h * rows as u32)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        let body = root.titled(&self.title, title_font(TITLE + 2.0))?;
        let (cols, rows, _) = self.grid();
        let areas = body.split_evenly((rows, cols));
        for ((area, (name, confusion)), layout) in
            areas.iter().zip(&self.matrices).zip(self.layouts())
        {
            draw_matrix(area, name, confusion, &layout)?;
        }
        Ok(())
    }
}

/// One matrix with its title, class names and axis names.
fn draw_matrix<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    name: &str,
    confusion: &Confusion,
    layout: &ConfusionLayout,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let (x0, y0) = layout.origin();
    let cell = layout.cell;
    let side = cell * layout.k as f64;
    let px = |x: f64, y: f64| (x.round() as i32, y.round() as i32);
    let centre = Pos::new(HPos::Center, VPos::Center);
    area.draw(&Text::new(
        name.to_owned(),
        px(x0 + side / 2.0, 8.0),
        title_font(TITLE - 3.0).pos(Pos::new(HPos::Center, VPos::Top)),
    ))?;
    let rows = confusion.row_normalised();
    for (i, row) in confusion.counts.iter().enumerate() {
        for (j, &count) in row.iter().enumerate() {
            let share = rows.get(i).and_then(|r| r.get(j)).copied().unwrap_or(0.0);
            let (x, y) = (x0 + j as f64 * cell, y0 + i as f64 * cell);
            area.draw(&Rectangle::new(
                [px(x, y), px(x + cell, y + cell)],
                blues(share).filled(),
            ))?;
            let Some(size) = layout.count_font else {
                continue;
            };
            if count == 0 && !layout.zeros {
                continue;
            }
            let color: &'static RGBColor = if share > 0.55 { &WHITE } else { &BLACK };
            let (cx, cy) = (x + cell / 2.0, y + cell / 2.0);
            let count_at = if layout.shares { cy - 0.12 * cell } else { cy };
            area.draw(&Text::new(
                count.to_string(),
                px(cx, count_at),
                font(size).color(color).pos(centre),
            ))?;
            if layout.shares {
                area.draw(&Text::new(
                    format!("{:.1} %", 100.0 * share),
                    px(cx, cy + 0.22 * cell),
                    font(TICK - 1.0).color(color).pos(centre),
                ))?;
            }
        }
    }
    area.draw(&Rectangle::new(
        [px(x0, y0), px(x0 + side, y0 + side)],
        BLACK.mix(0.4),
    ))?;
    draw_class_names(area, confusion, layout)?;
    let below = y0 + side + layout.x_labels_height() + 4.0;
    area.draw(&Text::new(
        "predicted class",
        px(x0 + side / 2.0, below),
        font(LABEL - 1.0).pos(Pos::new(HPos::Center, VPos::Top)),
    ))?;
    area.draw(&Text::new(
        "true class",
        px(6.0, y0 + side / 2.0),
        font(LABEL - 1.0)
            .transform(FontTransform::Rotate270)
            .pos(Pos::new(HPos::Center, VPos::Top)),
    ))?;
    Ok(())
}

/// The class names: before each row, and under each column (upright when wider than a column).
fn draw_class_names<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    confusion: &Confusion,
    layout: &ConfusionLayout,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let (x0, y0) = layout.origin();
    let (cell, side) = (layout.cell, layout.cell * layout.k as f64);
    let px = |x: f64, y: f64| (x.round() as i32, y.round() as i32);
    let style = font(layout.label_font);
    for (i, label) in confusion.labels.iter().enumerate() {
        let label = short_label(label);
        let middle = i as f64 * cell + cell / 2.0;
        area.draw(&Text::new(
            label.clone(),
            px(x0 - 6.0, y0 + middle),
            style.pos(Pos::new(HPos::Right, VPos::Center)),
        ))?;
        let under = if layout.upright {
            // Turned a quarter anticlockwise, the text's end at the top, under the column.
            style
                .transform(FontTransform::Rotate270)
                .pos(Pos::new(HPos::Right, VPos::Center))
        } else {
            style.pos(Pos::new(HPos::Center, VPos::Top))
        };
        area.draw(&Text::new(label, px(x0 + middle, y0 + side + 6.0), under))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    fn labels(k: usize) -> Vec<String> {
        (0..k).map(|i| format!("class_number_{i}")).collect()
    }

    #[test]
    fn a_matrix_stays_bounded_and_writes_only_what_fits() {
        for k in [2, 4, 8, 12, 22, 30, 40, 60] {
            let layout = ConfusionLayout::new(&labels(k), 250);
            let (w, h) = layout.panel_size();
            assert!(w <= 1100 && h <= 1100, "{k} classes: {w} x {h}");
            // Row names do not overlap: the font fits in a row.
            assert!(
                layout.label_font <= 0.8 * layout.cell + 1e-9,
                "{k}: {layout:?}"
            );
            // A column name wider than its column is written upright.
            assert_eq!(layout.upright, layout.label_width > layout.cell - 4.0);
            if let Some(size) = layout.count_font {
                assert!(
                    text_width("250", size) <= layout.cell - 4.0,
                    "{k}: {layout:?}"
                );
                assert!(size <= 0.45 * layout.cell + 1e-9);
            }
        }
        let few = ConfusionLayout::new(&labels(4), 250);
        assert!(few.count_font.is_some() && few.shares && few.zeros);
        let many = ConfusionLayout::new(&labels(22), 250);
        assert!(many.count_font.is_some() && !many.shares && !many.zeros);
        assert!(many.upright);
        let crowded = ConfusionLayout::new(&labels(60), 250);
        assert_eq!(crowded.count_font, None, "{crowded:?}");
    }

    #[test]
    fn long_class_names_are_cut() {
        let long = "a".repeat(60);
        assert_eq!(short_label(&long).chars().count(), MAX_LABEL_CHARS);
        assert_eq!(short_label("wood"), "wood");
    }
}
