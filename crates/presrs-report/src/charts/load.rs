//! Load curves: a recording's total load per frame with its stances and sampled frames.

use plotters::coord::Shift;
use plotters::prelude::*;
use presrs_core::Recording;
use presrs_core::stance::{BaselineMode, SampleFrame, ValidSegmentParams, segment_recording};

use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::common::{TICK, TITLE, draw_legend, finite_range, numeric_axes, padded};
use crate::error::Result;
use crate::render::{Figure, category_color, font, title_font};
use crate::scale::PressureScale;

/// Soft colour for shaded stance phases.
const STANCE_SHADE: RGBColor = RGBColor(255, 224, 178);
/// The shade of stances cut by the recording's ends.
const PARTIAL_SHADE: RGBColor = RGBColor(220, 220, 220);
/// The colour of the segmentation's baseline.
const BASELINE: RGBColor = RGBColor(120, 120, 120);

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
    /// What `baseline` is, by the segmentation's mode: "floor" (the local floor of presses on a
    /// preload), "baseline" (the unloaded level), "baseline (one contact)".
    pub baseline_label: &'static str,
}

impl LoadCurveData {
    /// Segments `recording` and marks the frames `sample` picks from complete stances (and from those
    /// cut by the recording's ends with `include_partial`, as a data set read with it samples them).
    pub fn from_recording(
        name: String,
        recording: &Recording,
        scale: &PressureScale,
        segment: &ValidSegmentParams,
        (sample, include_partial): (SampleFrame, bool),
    ) -> Result<Self> {
        let (load_label, factor) = scale.load_axis();
        let totals = recording.total_per_frame();
        let segmentation = segment_recording(recording, segment)?;
        // A stance too short for a fixed offset gives no sample; that is not an error for a picture.
        let sampled = segmentation
            .samples(sample, include_partial)
            .unwrap_or_default();
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
            baseline_label: baseline_label(segmentation.mode),
        })
    }

    /// The curve's title, with what its grey line is: `name; grey: floor` (movie frames have no legend).
    pub fn name_with_baseline(&self) -> String {
        format!("{}; grey: {}", self.name, self.baseline_label)
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

/// What the line a segmentation in `mode` measures stances from is called.
pub fn baseline_label(mode: BaselineMode) -> &'static str {
    match mode {
        BaselineMode::Floor => "floor",
        BaselineMode::Contact => "baseline (one contact)",
        BaselineMode::Drifting | BaselineMode::Auto => "baseline",
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
            .label(data.baseline_label)
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

/// The width of the legend beside the curves, pixels.
const LEGEND_W: u32 = 260;

impl LoadCurvesFigure {
    /// The legend's lines: `(text, how it is drawn)`, only for what some curve shows.
    fn legend(&self) -> Vec<(String, LegendMark)> {
        let any = |f: &dyn Fn(&LoadCurveData) -> bool| self.curves.iter().any(f);
        let mut lines = Vec::new();
        if any(&|c| !c.stances.is_empty()) {
            lines.push((
                "detected stance".to_owned(),
                LegendMark::Shade(STANCE_SHADE),
            ));
        }
        if any(&|c| !c.partial.is_empty()) {
            let text = "stance cut by the recording's end".to_owned();
            lines.push((text, LegendMark::Shade(PARTIAL_SHADE)));
        }
        let mut baselines: Vec<&str> = self.curves.iter().map(|c| c.baseline_label).collect();
        baselines.dedup();
        for label in baselines {
            lines.push((label.to_owned(), LegendMark::Line(BASELINE, 1)));
        }
        lines.push((
            "total load".to_owned(),
            LegendMark::Line(category_color(0), 2),
        ));
        if any(&|c| !c.sampled.is_empty()) {
            lines.push((
                "sampled frame".to_owned(),
                LegendMark::Dot(category_color(3)),
            ));
        }
        lines
    }
}

/// How a legend line is marked.
#[derive(Clone, Copy, Debug)]
enum LegendMark {
    Shade(RGBColor),
    Line(RGBColor, u32),
    Dot(RGBColor),
}

impl Figure for LoadCurvesFigure {
    fn size(&self) -> (u32, u32) {
        (1000 + LEGEND_W, 40 + 230 * self.curves.len().max(1) as u32)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        let body = root.titled(&self.title, title_font(TITLE + 2.0))?;
        let (w, _) = body.dim_in_pixel();
        // The legend beside the curves, where it covers none of them.
        let (curves, legend) = body.split_horizontally(w.saturating_sub(LEGEND_W));
        let areas = curves.split_evenly((self.curves.len().max(1), 1));
        for (area, curve) in areas.iter().zip(&self.curves) {
            draw_load_curve(area, curve, None, false)?;
        }
        for (row, (text, mark)) in self.legend().into_iter().enumerate() {
            let y = 40 + 22 * row as i32;
            match mark {
                LegendMark::Shade(color) => {
                    legend.draw(&Rectangle::new([(4, y - 6), (20, y + 6)], color.filled()))?
                }
                LegendMark::Line(color, width) => legend.draw(&PathElement::new(
                    vec![(4, y), (20, y)],
                    color.stroke_width(width),
                ))?,
                LegendMark::Dot(color) => legend.draw(&Circle::new((12, y), 4, color.filled()))?,
            }
            legend.draw(&Text::new(
                text,
                (28, y),
                font(TICK).pos(Pos::new(HPos::Left, VPos::Center)),
            ))?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use presrs_core::stance::{BaselineMode, SegmentParams};
    use presrs_core::{Grid, SensorMeta};

    use super::*;

    /// A recording that is one contact from its first frame to its last (a trial cut to one step).
    fn one_contact() -> Recording {
        let grid = Grid::new(6, 4);
        let data = (0..40)
            .flat_map(|f| {
                let load = 50.0 + 100.0 * (std::f64::consts::PI * f64::from(f) / 39.0).sin();
                (0..grid.len()).map(move |i| load * (1.0 + (i % 3) as f64 / 3.0))
            })
            .collect();
        Recording::new(grid, Some(0.01), data, None, SensorMeta::default()).unwrap()
    }

    /// With one sample per file the whole recording is the stance (cut at both ends): its sample is
    /// drawn, and the legend promises a red dot only when one is drawn.
    #[test]
    fn the_legend_promises_only_what_is_drawn() {
        let recording = one_contact();
        let segment = SegmentParams {
            baseline: BaselineMode::Contact,
            ..SegmentParams::default()
        }
        .check()
        .unwrap();
        let curve = |include_partial| {
            LoadCurveData::from_recording(
                "trial".into(),
                &recording,
                &PressureScale::default(),
                &segment,
                (SampleFrame::default(), include_partial),
            )
            .unwrap()
        };
        let legend = |curve: LoadCurveData| {
            let figure = LoadCurvesFigure {
                title: "t".into(),
                curves: vec![curve],
            };
            figure
                .legend()
                .into_iter()
                .map(|(text, _)| text)
                .collect::<Vec<_>>()
        };
        let sampled = curve(true);
        assert_eq!(sampled.sampled.len(), 1, "{sampled:?}");
        assert!(legend(sampled).contains(&"sampled frame".to_owned()));
        let unsampled = curve(false);
        assert!(unsampled.sampled.is_empty());
        let lines = legend(unsampled);
        assert!(!lines.contains(&"sampled frame".to_owned()), "{lines:?}");
        assert!(lines.contains(&"stance cut by the recording's end".to_owned()));
    }
}
