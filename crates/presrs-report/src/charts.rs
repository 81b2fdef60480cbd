//! The report's charts: load curves, feature spectra, principal components, validation curve, confusion
//! matrices, grouped bars (accuracy, Table I) and the hopper's motion.

use plotters::chart::MeshStyle;
use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use presrs_core::Recording;
use presrs_core::evaluation::Confusion;
use presrs_core::stance::{SampleFrame, ValidSegmentParams, segment_recording};
use presrs_sim::trace::HopTrace;

use crate::pressure::PressureScale;
use crate::render::{Figure, blues, category_color, font, title_font};
use crate::{ReportError, Result};

const TITLE: f64 = 18.0;
const LABEL: f64 = 15.0;
const TICK: f64 = 13.0;

/// The legend of every chart: a translucent white box with a black border, in the tick font.
fn draw_legend<'a, DB, CT>(
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
fn numeric_axes<'a, 'b, DB: DrawingBackend>(
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

/// Soft colour for shaded stance phases.
const STANCE_SHADE: RGBColor = RGBColor(255, 224, 178);

/// Smallest and largest finite values (`None` when there is none).
fn finite_range(values: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    values
        .filter(|v| v.is_finite())
        .fold(None, |acc, v| match acc {
            None => Some((v, v)),
            Some((lo, hi)) => Some((lo.min(v), hi.max(v))),
        })
}

/// A tick label: integers without a decimal point, others with up to three decimals.
pub fn num(v: f64) -> String {
    let a = v.abs();
    if a < 1e-12 {
        return "0".to_owned();
    }
    if (v - v.round()).abs() < 1e-9 * a.max(1.0) && a < 1e9 {
        return format!("{v:.0}");
    }
    if !(1e-3..1e9).contains(&a) {
        return format!("{v:.1e}");
    }
    let text = format!("{v:.3}");
    text.trim_end_matches('0').trim_end_matches('.').to_owned()
}

/// `lo..hi` widened by `pad` of its span (and made non-empty).
fn padded(lo: f64, hi: f64, pad: f64) -> std::ops::Range<f64> {
    let span = (hi - lo).abs().max(1e-9 * hi.abs().max(1.0));
    (lo - pad * span)..(hi + pad * span)
}

/// Draws `text` centred under (or, `left`, right-aligned before) the chart coordinate `at`.
fn draw_category_text<DB: DrawingBackend>(
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

// ---------------------------------------------------------------------------------------------------
// Load curves.

/// A recording's total load per frame with its detected stances and sampled frames.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadCurveData {
    pub name: String,
    pub period_s: Option<f64>,
    /// Load per frame in the axis unit.
    pub load: Vec<f64>,
    pub load_label: String,
    /// Complete stances `(first frame, one past the last)`, and stances cut by the recording's ends.
    pub stances: Vec<(usize, usize)>,
    pub partial: Vec<(usize, usize)>,
    /// Frames used as samples.
    pub sampled: Vec<usize>,
    /// The segmentation's baseline (same unit as `load`).
    pub baseline: Vec<f64>,
}

impl LoadCurveData {
    /// Segments `recording` and marks the frames `sample` picks from complete stances.
    pub fn from_recording(
        name: String,
        recording: &Recording,
        scale: &PressureScale,
        segment: &ValidSegmentParams,
        sample: SampleFrame,
    ) -> Result<Self> {
        let (load_label, factor) = scale.load_axis();
        let totals = recording.total_per_frame();
        let segmentation = segment_recording(recording, segment)?;
        // A stance too short for a fixed offset gives no sample; that is not an error for a picture.
        let sampled = segmentation.samples(sample, false).unwrap_or_default();
        let (mut stances, mut partial) = (Vec::new(), Vec::new());
        for s in &segmentation.stances {
            if s.partial {
                partial.push((s.start, s.end()));
            } else {
                stances.push((s.start, s.end()));
            }
        }
        Ok(Self {
            name,
            period_s: recording.frame_period_s(),
            load: totals.iter().map(|v| v * factor).collect(),
            load_label,
            stances,
            partial,
            sampled,
            baseline: segmentation.baseline.iter().map(|v| v * factor).collect(),
        })
    }

    fn time(&self, frame: f64) -> f64 {
        self.period_s.map_or(frame, |p| frame * p)
    }

    fn time_label(&self) -> &'static str {
        if self.period_s.is_some() {
            "time (s)"
        } else {
            "frame"
        }
    }
}

/// Draws one load curve in `area`: stances shaded, sampled frames marked, an optional cursor.
pub fn draw_load_curve<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    data: &LoadCurveData,
    cursor: Option<usize>,
    legend: bool,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let n = data.load.len().max(1);
    let (lo, hi) = finite_range(
        data.load
            .iter()
            .copied()
            .chain(data.baseline.iter().copied()),
    )
    .unwrap_or((0.0, 1.0));
    let mut y_range = padded(lo.min(0.0), hi, 0.08);
    if legend {
        // Room above the curve for the legend.
        y_range.end += 0.8 * (y_range.end - y_range.start);
    }
    let x_range = data.time(0.0)..data.time((n - 1).max(1) as f64);
    let mut chart = ChartBuilder::on(area)
        .caption(&data.name, title_font(TITLE - 2.0))
        .margin(8)
        .margin_right(16)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(x_range, y_range.clone())?;
    numeric_axes(&mut chart, data.time_label(), &data.load_label)
        .y_labels(5)
        .draw()?;
    let shade = |spans: &[(usize, usize)], color: RGBAColor| {
        spans
            .iter()
            .map(|&(a, b)| {
                Rectangle::new(
                    [
                        (data.time(a as f64 - 0.5), y_range.start),
                        (data.time(b as f64 - 0.5), y_range.end),
                    ],
                    color.filled(),
                )
            })
            .collect::<Vec<_>>()
    };
    chart
        .draw_series(shade(&data.stances, STANCE_SHADE.to_rgba()))?
        .label("detected stance")
        .legend(|(x, y)| Rectangle::new([(x, y - 6), (x + 16, y + 6)], STANCE_SHADE.filled()));
    if !data.partial.is_empty() {
        chart
            .draw_series(shade(&data.partial, RGBColor(220, 220, 220).to_rgba()))?
            .label("stance cut by the recording's end")
            .legend(|(x, y)| {
                Rectangle::new(
                    [(x, y - 6), (x + 16, y + 6)],
                    RGBColor(220, 220, 220).filled(),
                )
            });
    }
    if !data.baseline.is_empty() {
        chart
            .draw_series(LineSeries::new(
                data.baseline
                    .iter()
                    .enumerate()
                    .map(|(i, &v)| (data.time(i as f64), v)),
                RGBColor(120, 120, 120).stroke_width(1),
            ))?
            .label("baseline")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], RGBColor(120, 120, 120)));
    }
    let line = category_color(0);
    chart
        .draw_series(LineSeries::new(
            data.load
                .iter()
                .enumerate()
                .map(|(i, &v)| (data.time(i as f64), v)),
            line.stroke_width(2),
        ))?
        .label("total load")
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], line.stroke_width(2)));
    let mark = category_color(3);
    chart
        .draw_series(data.sampled.iter().filter_map(|&i| {
            data.load
                .get(i)
                .map(|&v| Circle::new((data.time(i as f64), v), 4, mark.filled()))
        }))?
        .label("sampled frame")
        .legend(move |(x, y)| Circle::new((x + 8, y), 4, mark.filled()));
    if let Some(c) = cursor {
        let t = data.time(c as f64);
        chart.draw_series(std::iter::once(PathElement::new(
            vec![(t, y_range.start), (t, y_range.end)],
            BLACK.stroke_width(2),
        )))?;
    }
    if legend {
        draw_legend(&mut chart, SeriesLabelPosition::UpperRight)?;
    }
    Ok(())
}

/// Load curves of a few recordings, stacked.
#[derive(Debug)]
pub struct LoadCurvesFigure {
    pub title: String,
    pub curves: Vec<LoadCurveData>,
}

impl Figure for LoadCurvesFigure {
    fn size(&self) -> (u32, u32) {
        (1000, 40 + 230 * self.curves.len().max(1) as u32)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        let body = root.titled(&self.title, title_font(TITLE + 2.0))?;
        let areas = body.split_evenly((self.curves.len().max(1), 1));
        for (i, (area, curve)) in areas.iter().zip(&self.curves).enumerate() {
            draw_load_curve(area, curve, None, i == 0)?;
        }
        Ok(())
    }
}

// ---------------------------------------------------------------------------------------------------
// Spectra.

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

// ---------------------------------------------------------------------------------------------------
// Scatter in principal components.

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

fn marker<DB: DrawingBackend>(
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

// ---------------------------------------------------------------------------------------------------
// Hyper-parameters.

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

// ---------------------------------------------------------------------------------------------------
// Confusion matrices.

/// Confusion matrices as heat maps with counts, side by side.
#[derive(Clone, Debug, PartialEq)]
pub struct ConfusionFigure {
    pub title: String,
    /// `(panel title, matrix)`.
    pub matrices: Vec<(String, Confusion)>,
}

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

// ---------------------------------------------------------------------------------------------------
// Grouped bars.

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

// ---------------------------------------------------------------------------------------------------
// Accuracy against fault level.

/// A point of [`FaultPanel`]: `(level, mean accuracy %, s.d. %)`.
pub type FaultPoint = (f64, f64, f64);

/// One panel of [`FaultFigure`]: one kind of fault, a line per method.
#[derive(Clone, Debug, PartialEq)]
pub struct FaultPanel {
    /// The kind (`dead`, `rotate`, ...).
    pub title: String,
    /// What the level measures (`fraction of sensels dead`, ...).
    pub x_label: String,
    /// `(method, points)`, in level order.
    pub lines: Vec<(String, Vec<FaultPoint>)>,
}

/// Accuracy (%) against fault level, a panel per kind of fault and a line per method (with ±1 s.d.
/// whiskers); the methods share colours and markers across panels and one legend.
#[derive(Clone, Debug, PartialEq)]
pub struct FaultFigure {
    pub title: String,
    pub panels: Vec<FaultPanel>,
    /// Legend text for the whiskers, e.g. `±1 std over 3 repeats`.
    pub spread_name: Option<String>,
}

impl FaultFigure {
    /// Panels per row and rows; one more cell than panels holds the legend.
    fn grid(&self) -> (usize, usize) {
        let cells = self.panels.len() + 1;
        let cols = cells.clamp(1, 4);
        (cells.div_ceil(cols), cols)
    }

    fn methods(&self) -> Vec<&str> {
        let mut names: Vec<&str> = Vec::new();
        for panel in &self.panels {
            for (name, _) in &panel.lines {
                if !names.contains(&name.as_str()) {
                    names.push(name);
                }
            }
        }
        names
    }
}

impl Figure for FaultFigure {
    fn size(&self) -> (u32, u32) {
        let (rows, cols) = self.grid();
        (340 * cols as u32, 44 + 310 * rows as u32)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        let body = root.titled(&self.title, title_font(TITLE + 2.0))?;
        let areas = body.split_evenly(self.grid());
        let methods = self.methods();
        let style_of = |name: &str| {
            let i = methods.iter().position(|m| *m == name).unwrap_or(0);
            (category_color(i), i)
        };
        // One accuracy axis for every panel, so that the kinds compare at a glance.
        let low = self
            .panels
            .iter()
            .flat_map(|p| p.lines.iter().flat_map(|(_, points)| points.iter()))
            .map(|p| p.1 - p.2)
            .fold(100.0_f64, f64::min);
        let y0 = ((low - 5.0) / 10.0).floor().clamp(0.0, 9.0) * 10.0;
        for (area, panel) in areas.iter().zip(&self.panels) {
            let levels = panel
                .lines
                .iter()
                .flat_map(|(_, points)| points.iter().map(|p| p.0));
            let (x0, x1) = finite_range(levels).unwrap_or((0.0, 1.0));
            let mut chart = ChartBuilder::on(area)
                .caption(&panel.title, title_font(TITLE - 1.0))
                .margin(8)
                .margin_right(18)
                .x_label_area_size(44)
                .y_label_area_size(56)
                .build_cartesian_2d(padded(x0, x1, 0.06), y0..101.0)?;
            numeric_axes(&mut chart, &panel.x_label, "accuracy (%)")
                .axis_desc_style(font(LABEL - 2.0))
                .x_labels(5)
                .y_labels(6)
                .draw()?;
            for (name, points) in &panel.lines {
                let (color, shape) = style_of(name);
                // The first method wider, so that coinciding lines both show.
                let width = if shape == 0 && methods.len() > 1 {
                    5
                } else {
                    2
                };
                chart.draw_series(LineSeries::new(
                    points.iter().map(|p| (p.0, p.1)),
                    color.stroke_width(width),
                ))?;
                chart.draw_series(points.iter().filter(|p| p.2 > 0.0).map(|&(x, m, sd)| {
                    PathElement::new(
                        vec![(x, (m - sd).max(y0)), (x, (m + sd).min(101.0))],
                        color.mix(0.6).stroke_width(2),
                    )
                }))?;
                chart.draw_series(
                    points
                        .iter()
                        .map(|&(x, m, _)| EmptyElement::at((x, m)) + marker(shape, (0, 0), color)),
                )?;
            }
        }
        // The legend in the last cell.
        if let Some(area) = areas.get(self.panels.len()) {
            let (_, h) = area.dim_in_pixel();
            let mut entries: Vec<(Option<(RGBColor, usize)>, String)> = methods
                .iter()
                .map(|m| (Some(style_of(m)), (*m).to_owned()))
                .collect();
            if let Some(spread) = &self.spread_name {
                entries.push((None, format!("whiskers: {spread}")));
            }
            let x = 24;
            let top = (h as i32 / 2 - 18 * entries.len() as i32).max(10);
            for (k, (style, text)) in entries.iter().enumerate() {
                let y = top + 36 * k as i32;
                match style {
                    Some((color, shape)) => {
                        area.draw(&PathElement::new(
                            vec![(x, y), (x + 36, y)],
                            color.stroke_width(3),
                        ))?;
                        area.draw(
                            &(EmptyElement::at((x + 18, y)) + marker(*shape, (0, 0), *color)),
                        )?;
                    }
                    None => {
                        area.draw(&PathElement::new(
                            vec![(x + 18, y - 9), (x + 18, y + 9)],
                            BLACK.mix(0.6).stroke_width(2),
                        ))?;
                    }
                }
                area.draw(&Text::new(
                    text.clone(),
                    (x + 48, y),
                    font(LABEL).pos(Pos::new(HPos::Left, VPos::Center)),
                ))?;
            }
        }
        Ok(())
    }
}

// ---------------------------------------------------------------------------------------------------
// The hopper.

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
