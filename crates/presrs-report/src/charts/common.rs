//! What every chart shares: font sizes, the legend and axes style, ranges.

use plotters::chart::MeshStyle;
use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::error::Result;
use crate::format::num;
use crate::render::font;

pub(super) const TITLE: f64 = 18.0;
pub(super) const LABEL: f64 = 15.0;
pub(super) const TICK: f64 = 13.0;

/// The legend of every chart: a translucent white box with a black border, in the tick font.
pub(super) fn draw_legend<'a, DB, CT>(
    chart: &mut ChartContext<'a, DB, CT>,
    position: SeriesLabelPosition,
) -> Result<()>
where
    DB: DrawingBackend + 'a,
    CT: CoordTranslate,
{
    chart
        .configure_series_labels()
        .position(position)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(font(TICK))
        .draw()?;
    Ok(())
}

/// The axes of a chart with numeric f64 coordinates on both axes: white light grid lines, the axis
/// descriptions, and ticks labelled with [`num`]. Callers chain what differs (tick counts, a larger
/// description font) before `.draw()`.
pub(super) fn numeric_axes<'a, 'b, DB: DrawingBackend>(
    chart: &'b mut ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    x_desc: &str,
    y_desc: &str,
) -> MeshStyle<'a, 'b, RangedCoordf64, RangedCoordf64, DB> {
    let mut mesh = chart.configure_mesh();
    mesh.light_line_style(WHITE)
        .x_desc(x_desc)
        .y_desc(y_desc)
        .axis_desc_style(font(LABEL - 1.0))
        .label_style(font(TICK))
        .x_label_formatter(&num_label)
        .y_label_formatter(&num_label);
    mesh
}

/// [`num`] as a tick formatter.
fn num_label(v: &f64) -> String {
    num(*v)
}

/// Smallest and largest finite values (`None` when there is none).
pub(super) fn finite_range(values: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    values
        .filter(|v| v.is_finite())
        .fold(None, |acc, v| match acc {
            None => Some((v, v)),
            Some((lo, hi)) => Some((lo.min(v), hi.max(v))),
        })
}

/// `lo..hi` widened by `pad` of its span (and made non-empty).
pub(super) fn padded(lo: f64, hi: f64, pad: f64) -> std::ops::Range<f64> {
    let span = (hi - lo).abs().max(1e-9 * hi.abs().max(1.0));
    (lo - pad * span)..(hi + pad * span)
}

/// Draws `text` centred under (or, `left`, right-aligned before) the chart coordinate `at`.
pub(super) fn draw_category_text<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    pixel: (i32, i32),
    text: &str,
    left: bool,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let base = area.get_base_pixel();
    let (x, y) = (pixel.0 - base.0, pixel.1 - base.1);
    let (pos, at) = if left {
        (Pos::new(HPos::Right, VPos::Center), (x - 8, y))
    } else {
        (Pos::new(HPos::Center, VPos::Top), (x, y + 6))
    };
    area.draw(&Text::new(text.to_owned(), at, font(TICK + 2.0).pos(pos)))?;
    Ok(())
}

/// A point marker of one of five shapes (by `shape`), e.g. a condition or a method.
pub(super) fn marker<DB: DrawingBackend>(
    shape: usize,
    at: (i32, i32),
    color: RGBColor,
) -> DynElement<'static, DB, (i32, i32)> {
    let style = color.filled();
    let (x, y) = at;
    match shape % 5 {
        0 => Circle::new((x, y), 4, style).into_dyn(),
        1 => TriangleMarker::new((x, y), 5, style).into_dyn(),
        2 => Rectangle::new([(x - 4, y - 4), (x + 4, y + 4)], style).into_dyn(),
        3 => Cross::new((x, y), 4, color.stroke_width(2)).into_dyn(),
        _ => Polygon::new(vec![(x, y - 5), (x + 5, y), (x, y + 5), (x - 5, y)], style).into_dyn(),
    }
}
