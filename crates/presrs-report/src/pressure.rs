//! Pressure images as heat maps in physical units: one image, a grid of images (the paper's Fig. 5) and
//! movies of a recording with its load curve.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;
use presrs_core::stance::{SampleFrame, ValidSegmentParams};
use presrs_core::{FrameView, Grid, Recording};

use crate::charts::{LoadCurveData, draw_load_curve};
use crate::format::num;
// Re-exported here, its home before it moved to a leaf module.
use crate::error::{ReportError, Result};
use crate::render::{Figure, MASKED, font, render_rgb, save_gif, title_font, title_width, viridis};
pub use crate::scale::PressureScale;

/// Sizes of the parts of a heat-map panel, pixels.
#[derive(Clone, Copy, Debug)]
struct PanelStyle {
    title: f64,
    label: f64,
    tick: f64,
    x_area: u32,
    y_area: u32,
    margin: u32,
}

const LARGE: PanelStyle = PanelStyle {
    title: 20.0,
    label: 16.0,
    tick: 13.0,
    x_area: 48,
    y_area: 58,
    margin: 12,
};

const SMALL: PanelStyle = PanelStyle {
    // plotters' bitmap text drops each glyph's left side bearing, which merges letters below ~16 px
    // ("cl" reads as "d"); titles stay above that.
    title: 17.0,
    label: 13.0,
    tick: 11.0,
    x_area: 36,
    y_area: 44,
    margin: 6,
};

/// A rectangle of sensels drawn on top of an image (the classifier's crop).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Outline {
    pub row: usize,
    pub col: usize,
    pub grid: Grid,
}

/// Tick text for a non-negative coordinate.
fn tick(v: f64) -> String {
    let v = v.abs();
    if (v - v.round()).abs() < 1e-9 {
        format!("{}", v.round())
    } else {
        format!("{v:.1}")
    }
}

/// Draws one frame as a heat map with its true aspect ratio in `area` (title on top). Values are shown
/// times `scale.factor`, coloured from 0 to `vmax`; absent sensels in grey with a cross.
#[allow(clippy::too_many_arguments)]
fn draw_heatmap<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    frame: &FrameView<'_>,
    scale: &PressureScale,
    vmax: f64,
    title: &str,
    outline: Option<Outline>,
    style: PanelStyle,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let grid = frame.grid();
    let (py, px) = scale.pitches();
    let (width, height) = (grid.cols as f64 * px, grid.rows as f64 * py);
    let body = if title.is_empty() {
        area.clone()
    } else {
        area.titled(title, title_font(style.title))?
    };
    let (bw, bh) = body.dim_in_pixel();
    let avail_w = f64::from(bw.saturating_sub(style.y_area + 2 * style.margin)).max(10.0);
    let avail_h = f64::from(bh.saturating_sub(style.x_area + 2 * style.margin)).max(10.0);
    let ratio = width / height;
    let (pw, ph) = if avail_w / avail_h > ratio {
        (avail_h * ratio, avail_h)
    } else {
        (avail_w, avail_w / ratio)
    };
    let extra_w = (avail_w - pw).max(0.0);
    let extra_h = (avail_h - ph).max(0.0);
    let unit = scale.position_unit();
    let mut chart = ChartBuilder::on(&body)
        .margin_left(style.margin + (extra_w / 2.0).floor() as u32)
        .margin_right(style.margin + (extra_w / 2.0).ceil() as u32)
        .margin_top(style.margin)
        .margin_bottom(style.margin + extra_h.round() as u32)
        .x_label_area_size(style.x_area)
        .y_label_area_size(style.y_area)
        .build_cartesian_2d(0.0..width, -height..0.0)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_labels(5)
        .y_labels(5)
        .x_desc(format!("x ({unit})"))
        .y_desc(format!("y ({unit}, from top)"))
        .axis_desc_style(font(style.label))
        .label_style(font(style.tick))
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| tick(*v))
        .draw()?;
    let vmax = if vmax > 0.0 && vmax.is_finite() {
        vmax
    } else {
        1.0
    };
    let cross = RGBColor(140, 140, 140);
    let mut cells = Vec::with_capacity(grid.len());
    let mut crosses = Vec::new();
    for r in 0..grid.rows {
        for c in 0..grid.cols {
            let (x0, y0) = (c as f64 * px, -(r as f64) * py);
            let (x1, y1) = (x0 + px, y0 - py);
            if frame.is_present(r, c) {
                let value = frame.get(r, c) * scale.factor;
                cells.push(Rectangle::new(
                    [(x0, y0), (x1, y1)],
                    viridis(value / vmax).filled(),
                ));
            } else {
                cells.push(Rectangle::new([(x0, y0), (x1, y1)], MASKED.filled()));
                crosses.push(PathElement::new(vec![(x0, y0), (x1, y1)], cross));
                crosses.push(PathElement::new(vec![(x0, y1), (x1, y0)], cross));
            }
        }
    }
    chart.draw_series(cells)?;
    chart.draw_series(crosses)?;
    if let Some(o) = outline {
        // Inset a little so that edges on the image's border stay visible.
        let (ix, iy) = (0.25 * px, 0.25 * py);
        let (x0, y0) = (o.col as f64 * px + ix, -(o.row as f64) * py - iy);
        let (x1, y1) = (
            x0 + o.grid.cols as f64 * px - 2.0 * ix,
            y0 - o.grid.rows as f64 * py + 2.0 * iy,
        );
        chart.draw_series(std::iter::once(Rectangle::new(
            [(x0, y0), (x1, y1)],
            WHITE.stroke_width(2),
        )))?;
    }
    Ok(())
}

/// Draws a vertical colour bar for 0..`vmax` with the unit, and (when `masked`) a swatch for absent
/// sensels below it.
fn draw_colorbar<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    vmax: f64,
    unit: &str,
    masked: bool,
    style: PanelStyle,
    top: u32,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let (_, h) = area.dim_in_pixel();
    let legend_h = if masked { 46 } else { 0 };
    let (bar_area, legend_area) = area.split_vertically(h.saturating_sub(legend_h));
    let vmax = if vmax > 0.0 && vmax.is_finite() {
        vmax
    } else {
        1.0
    };
    let mut chart = ChartBuilder::on(&bar_area)
        .margin_top(top)
        .margin_bottom(style.margin + style.x_area)
        .margin_left(6)
        .margin_right(4)
        .set_label_area_size(LabelAreaPosition::Right, style.y_area + 20)
        .build_cartesian_2d(0.0..1.0, 0.0..vmax)?;
    // Round ticks, but none so close to the top that it would cover the maximum's label.
    chart
        .configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .y_labels(6)
        .y_label_formatter(&|v| {
            if *v < MAX_LABEL_GAP * vmax {
                num(*v)
            } else {
                String::new()
            }
        })
        .y_desc(unit)
        .axis_desc_style(font(style.label))
        .label_style(font(style.tick))
        .draw()?;
    let steps = 128;
    chart.draw_series((0..steps).map(|i| {
        let (a, b) = (i as f64 / steps as f64, (i + 1) as f64 / steps as f64);
        Rectangle::new(
            [(0.0, a * vmax), (1.0, b * vmax)],
            viridis((a + b) / 2.0).filled(),
        )
    }))?;
    chart.draw_series(std::iter::once(Rectangle::new(
        [(0.0, 0.0), (1.0, vmax)],
        BLACK.stroke_width(1),
    )))?;
    // The maximum, labelled at the top of the bar: the brightest colour can be read off.
    let (x, y) = chart.backend_coord(&(1.0, vmax));
    let (x0, y0) = bar_area.get_base_pixel();
    let at = (x - x0, y - y0);
    bar_area.draw(&PathElement::new(vec![at, (at.0 + 5, at.1)], BLACK))?;
    bar_area.draw(&Text::new(
        num(vmax),
        (at.0 + 8, at.1 - (style.tick / 2.0) as i32),
        font(style.tick),
    ))?;
    if masked {
        let swatch = 16;
        legend_area.draw(&Rectangle::new(
            [(6, 4), (6 + swatch, 4 + swatch)],
            MASKED.filled(),
        ))?;
        legend_area.draw(&PathElement::new(
            vec![(6, 4), (6 + swatch, 4 + swatch)],
            RGBColor(140, 140, 140),
        ))?;
        legend_area.draw(&PathElement::new(
            vec![(6, 4 + swatch), (6 + swatch, 4)],
            RGBColor(140, 140, 140),
        ))?;
        legend_area.draw(&Text::new(
            "no sensel",
            (6 + swatch + 5, 5),
            font(style.tick + 1.0),
        ))?;
    }
    Ok(())
}

/// Round colour-bar ticks above this fraction of the maximum are not labelled: the maximum's label is.
const MAX_LABEL_GAP: f64 = 0.9;

/// The largest shown value of `frames` (at least a tiny positive number).
fn shown_max<'a>(frames: impl Iterator<Item = &'a FrameView<'a>>, scale: &PressureScale) -> f64 {
    let max = frames
        .flat_map(|f| f.values().iter().copied())
        .filter(|v| v.is_finite())
        .fold(0.0_f64, f64::max);
    (max * scale.factor).max(1e-9)
}

fn has_mask(frame: &FrameView<'_>) -> bool {
    frame.present().is_some_and(|p| p.iter().any(|&x| !x))
}

/// One pressure image with a colour bar.
#[derive(Debug)]
pub struct PressureFigure<'a> {
    pub frame: FrameView<'a>,
    pub scale: PressureScale,
    pub title: String,
    /// Colour scale maximum in shown units (`None`: the frame's maximum).
    pub vmax: Option<f64>,
    pub outline: Option<Outline>,
    /// Figure height in pixels (the width follows the sensor's aspect ratio).
    pub height: u32,
}

impl<'a> PressureFigure<'a> {
    pub fn new(frame: FrameView<'a>, scale: PressureScale, title: impl Into<String>) -> Self {
        Self {
            frame,
            scale,
            title: title.into(),
            vmax: None,
            outline: None,
            height: 600,
        }
    }

    fn colorbar_width() -> u32 {
        LARGE.y_area + 60
    }
}

impl Figure for PressureFigure<'_> {
    fn size(&self) -> (u32, u32) {
        let grid = self.frame.grid();
        let (py, px) = self.scale.pitches();
        let ratio = (grid.cols as f64 * px) / (grid.rows as f64 * py).max(1e-9);
        let plot_h = f64::from(
            self.height
                .saturating_sub(LARGE.x_area + 2 * LARGE.margin + 34),
        );
        let plot_w = (plot_h * ratio).clamp(200.0, 1600.0);
        let width = plot_w as u32 + LARGE.y_area + 2 * LARGE.margin + Self::colorbar_width();
        // Wide enough for the title (about 0.6 em per character).
        let title_w = (self.title.chars().count() as f64 * LARGE.title * 0.6) as u32 + 40;
        (width.max(420).max(title_w), self.height)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        let body = root.titled(&self.title, title_font(LARGE.title))?;
        let (w, _) = body.dim_in_pixel();
        let (left, right) = body.split_horizontally(w.saturating_sub(Self::colorbar_width()));
        let vmax = self
            .vmax
            .unwrap_or_else(|| shown_max(std::iter::once(&self.frame), &self.scale));
        draw_heatmap(
            &left,
            &self.frame,
            &self.scale,
            vmax,
            "",
            self.outline,
            LARGE,
        )?;
        draw_colorbar(
            &right,
            vmax,
            &self.scale.unit,
            has_mask(&self.frame),
            LARGE,
            LARGE.margin,
        )
    }
}

/// Pressure images in a grid: one row per label, one column per condition (the paper's Fig. 5), on a
/// shared colour scale.
#[derive(Debug)]
pub struct PressureGrid<'a> {
    pub title: String,
    pub row_names: Vec<String>,
    pub col_names: Vec<String>,
    /// `cells[row][col]`: the image, or `None` when there is no sample.
    pub cells: Vec<Vec<Option<FrameView<'a>>>>,
    pub scale: PressureScale,
    pub outline: Option<Outline>,
}

impl PressureGrid<'_> {
    const PANEL_H: u32 = 260;
    const COLORBAR_W: u32 = 120;
    const TITLE_H: u32 = 40;
    /// Most rows of panels: more labels wrap into further blocks of columns.
    const MAX_ROWS: usize = 8;
    /// Most columns of panels that wrapping makes (a manifest with more conditions keeps them all).
    const MAX_COLS: usize = 6;
    /// The tallest colour bar: it reads the same at any height.
    const MAX_COLORBAR_H: u32 = 2 * Self::PANEL_H;

    /// Blocks of labels side by side, and the rows of panels in each: one label per row and one
    /// condition per column in every block.
    fn blocks(&self) -> (usize, usize) {
        let labels = self.row_names.len().max(1);
        let conditions = self.col_names.len().max(1);
        let fit = (Self::MAX_COLS / conditions).max(1);
        let blocks = labels.div_ceil(Self::MAX_ROWS).clamp(1, fit);
        (blocks, labels.div_ceil(blocks))
    }

    /// Columns and rows of panels.
    fn panels(&self) -> (usize, usize) {
        let (blocks, rows) = self.blocks();
        (blocks * self.col_names.len().max(1), rows)
    }

    fn panel_w(&self) -> u32 {
        let grid = self
            .cells
            .iter()
            .flatten()
            .flatten()
            .next()
            .map_or(Grid::new(1, 1), FrameView::grid);
        let (py, px) = self.scale.pitches();
        let ratio = (grid.cols as f64 * px) / (grid.rows as f64 * py).max(1e-9);
        let plot_h = f64::from(Self::PANEL_H - SMALL.x_area - 2 * SMALL.margin - 22);
        (plot_h * ratio).clamp(120.0, 600.0) as u32 + SMALL.y_area + 2 * SMALL.margin
    }
}

impl Figure for PressureGrid<'_> {
    fn size(&self) -> (u32, u32) {
        let (cols, rows) = self.panels();
        let (cols, rows) = (cols as u32, rows as u32);
        (
            (self.panel_w() * cols + Self::COLORBAR_W)
                .max(420)
                .max(title_width(&self.title, 20.0)),
            rows * Self::PANEL_H + Self::TITLE_H,
        )
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        let body = root.titled(&self.title, title_font(20.0))?;
        let (w, _) = body.dim_in_pixel();
        let (panels, bar) = body.split_horizontally(w.saturating_sub(Self::COLORBAR_W));
        let frames: Vec<&FrameView<'_>> = self.cells.iter().flatten().flatten().collect();
        let vmax = shown_max(frames.iter().copied(), &self.scale);
        let masked = frames.iter().any(|f| has_mask(f));
        let (cols, rows) = self.panels();
        let areas = panels.split_evenly((rows, cols));
        let conditions = self.col_names.len().max(1);
        for (r, row) in self.cells.iter().enumerate() {
            for (c, cell) in row.iter().enumerate() {
                // Label r in block r / rows, on row r % rows of it.
                let col = (r / rows) * conditions + c;
                let Some(area) = areas.get((r % rows) * cols + col) else {
                    continue;
                };
                let name = match (self.row_names.get(r), self.col_names.get(c)) {
                    (Some(a), Some(b)) if !b.is_empty() => format!("{a} · {b}"),
                    (Some(a), _) => a.clone(),
                    _ => String::new(),
                };
                match cell {
                    Some(frame) => {
                        draw_heatmap(area, frame, &self.scale, vmax, &name, self.outline, SMALL)?
                    }
                    None => {
                        let body = area.titled(&name, title_font(SMALL.title))?;
                        body.draw(&Text::new("no sample", (20, 40), font(SMALL.label)))?;
                    }
                }
            }
        }
        let (_, bar_h) = bar.dim_in_pixel();
        let (bar, _) = bar.split_vertically(bar_h.min(Self::MAX_COLORBAR_H));
        draw_colorbar(
            &bar,
            vmax,
            &self.scale.unit,
            masked,
            SMALL,
            22 + SMALL.margin,
        )
    }
}

/// Options of [`write_movie`].
#[derive(Clone, Debug)]
pub struct MovieOptions {
    /// Show every `stride`-th frame (1: all).
    pub stride: usize,
    /// At most this many frames (the stride grows to fit).
    pub max_frames: usize,
    pub segment: ValidSegmentParams,
    pub sample: SampleFrame,
    pub title: String,
}

impl Default for MovieOptions {
    fn default() -> Self {
        Self {
            stride: 1,
            max_frames: 400,
            segment: ValidSegmentParams::default(),
            sample: SampleFrame::default(),
            title: String::new(),
        }
    }
}

/// One frame of a movie: the image, and the load curve with a cursor under it.
struct MovieFrame<'a> {
    frame: FrameView<'a>,
    index: usize,
    scale: &'a PressureScale,
    vmax: f64,
    curve: &'a LoadCurveData,
    title: &'a str,
    size: (u32, u32),
}

impl Figure for MovieFrame<'_> {
    fn size(&self) -> (u32, u32) {
        self.size
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        let time = match self.curve.period_s {
            Some(p) => format!(", t = {:.2} s", self.index as f64 * p),
            None => String::new(),
        };
        let title = format!("{} — frame {}{time}", self.title, self.index);
        let root = root.titled(&title, title_font(LARGE.title))?;
        let (w, h) = root.dim_in_pixel();
        let (top, bottom) = root.split_vertically(h.saturating_sub(200));
        let (image, bar) =
            top.split_horizontally(w.saturating_sub(PressureFigure::colorbar_width()));
        draw_heatmap(&image, &self.frame, self.scale, self.vmax, "", None, LARGE)?;
        draw_colorbar(
            &bar,
            self.vmax,
            &self.scale.unit,
            has_mask(&self.frame),
            LARGE,
            LARGE.margin,
        )?;
        draw_load_curve(&bottom, self.curve, Some(self.index), false)
    }
}

/// Writes an animated GIF of `recording` (frames on a fixed colour scale, the load curve with the
/// detected stances and a cursor under them).
pub fn write_movie(recording: &Recording, options: &MovieOptions, path: &Path) -> Result<usize> {
    let count = recording.frame_count();
    if count == 0 {
        return Err(ReportError::Input("the recording has no frames".into()));
    }
    let scale = PressureScale::from_meta(Some(&recording.meta));
    let mut curve = LoadCurveData::from_recording(
        "total load (shaded: detected stances; red: sampled frames)".to_owned(),
        recording,
        &scale,
        &options.segment,
        (options.sample, false),
    )?;
    // The grey line is named by what the detector measured from (a movie frame has no legend).
    curve.name = curve.name_with_baseline();
    let max_frames = options.max_frames.max(1);
    let stride = options.stride.max(1).max(count.div_ceil(max_frames));
    let vmax = shown_max(recording.frames().collect::<Vec<_>>().iter(), &scale);
    let sizer = PressureFigure::new(
        recording
            .frame(0)
            .ok_or_else(|| ReportError::Input("no frame 0".into()))?,
        scale.clone(),
        "",
    );
    let (w, _) = sizer.size();
    let size = (w.max(560), 600 + 200);
    let indices: Vec<usize> = (0..count).step_by(stride).collect();
    let mut frames = Vec::with_capacity(indices.len());
    for &index in &indices {
        let Some(frame) = recording.frame(index) else {
            continue;
        };
        let figure = MovieFrame {
            frame,
            index,
            scale: &scale,
            vmax,
            curve: &curve,
            title: &options.title,
            size,
        };
        frames.push(render_rgb(&figure)?.2);
    }
    let delay_cs = recording
        .frame_period_s()
        .map_or(10.0, |p| (p * stride as f64 * 100.0).round())
        .clamp(2.0, 100.0) as u16;
    save_gif(path, size.0, size.1, &frames, delay_cs)?;
    Ok(frames.len())
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use presrs_core::{PressureUnit, SensorMeta};

    use super::*;

    fn walking_like() -> Recording {
        let grid = Grid::new(12, 6);
        let mut data = Vec::new();
        for f in 0..30 {
            let load = ((f as f64 - 5.0) * 0.3).sin().max(0.0) * 200.0;
            data.extend((0..grid.len()).map(|i| load * ((i % 5) as f64 + 1.0) / 5.0));
        }
        let present: Vec<bool> = (0..grid.len()).map(|i| i % 6 != 0 || i < 30).collect();
        let meta = SensorMeta {
            row_pitch_mm: Some(5.08),
            col_pitch_mm: Some(5.08),
            units: Some(PressureUnit::parse("KPa")),
            ..SensorMeta::default()
        };
        Recording::new(grid, Some(0.032), data, Some(present), meta).unwrap()
    }

    /// The movie's load curve names its grey line by what the detector measured from.
    #[test]
    fn the_movie_names_the_detectors_line_by_its_mode() {
        use presrs_core::stance::{BaselineMode, SegmentParams};
        let recording = walking_like();
        let scale = PressureScale::from_meta(Some(&recording.meta));
        let curve = |baseline| {
            let segment = SegmentParams {
                baseline,
                ..SegmentParams::default()
            };
            LoadCurveData::from_recording(
                "load".into(),
                &recording,
                &scale,
                &segment.check().unwrap(),
                (SampleFrame::default(), false),
            )
            .unwrap()
        };
        assert_eq!(curve(BaselineMode::Auto).baseline_label, "baseline");
        assert_eq!(curve(BaselineMode::Drifting).baseline_label, "baseline");
        assert_eq!(
            curve(BaselineMode::Floor).name_with_baseline(),
            "load; grey: floor"
        );
        assert_eq!(
            curve(BaselineMode::Contact).baseline_label,
            "baseline (one contact)"
        );
    }

    #[test]
    fn movie_frames_show_the_image_and_a_moving_cursor() {
        let recording = walking_like();
        let scale = PressureScale::from_meta(Some(&recording.meta));
        let curve = LoadCurveData::from_recording(
            "test".into(),
            &recording,
            &scale,
            &ValidSegmentParams::default(),
            (SampleFrame::default(), false),
        )
        .unwrap();
        let render = |index| {
            let figure = MovieFrame {
                frame: recording.frame(index).unwrap(),
                index,
                scale: &scale,
                vmax: 200.0,
                curve: &curve,
                title: "test",
                size: (560, 800),
            };
            render_rgb(&figure).unwrap()
        };
        let (w, h, a) = render(8);
        let (_, _, b) = render(20);
        assert_eq!((w, h), (560, 800));
        assert_eq!(a.len(), 560 * 800 * 3);
        assert_ne!(a, b);
        if let Ok(dir) = std::env::var("PRESRS_FIGURE_DIR") {
            let path = std::path::Path::new(&dir).join("movie_frame.png");
            presrs_io::write_atomic(&path, |out| crate::render::encode_png(out, w, h, &a)).unwrap();
        }
    }

    #[test]
    fn the_colour_bar_labels_its_maximum() {
        let grid = Grid::new(3, 4);
        let mut values = vec![10.0; grid.len()];
        values[5] = 187.3;
        let frame = presrs_core::Frame::new(grid, values).unwrap();
        let figure = PressureFigure::new(frame.view(), PressureScale::default(), "one frame");
        let svg = crate::render::render_svg(&figure).unwrap();
        assert!(
            svg.contains("\n187.3\n"),
            "the maximum is not labelled: {svg}"
        );
    }

    #[test]
    fn a_grid_of_one_image_is_as_wide_as_its_title() {
        let grid = Grid::new(44, 44);
        let frame = presrs_core::Frame::new(grid, vec![1.0; grid.len()]).unwrap();
        let title = "Example pressure images (the median-load sample of each label and condition)";
        let figure = PressureGrid {
            title: title.to_owned(),
            row_names: vec!["wood".into()],
            col_names: vec![String::new()],
            cells: vec![vec![Some(frame.view())]],
            scale: PressureScale::default(),
            outline: None,
        };
        let needed = title_width(title, 20.0);
        assert!(needed > 600, "{needed}");
        assert!(figure.size().0 >= needed, "{} < {needed}", figure.size().0);
    }

    /// 22 labels of one condition wrap into blocks of columns: no longer one column 22 panels tall
    /// (694 x 5,760 px); and every label is drawn in its own panel.
    #[test]
    fn a_grid_of_many_labels_stays_bounded() {
        let grid = Grid::new(28, 50);
        let frames: Vec<_> = (0..40)
            .map(|i| presrs_core::Frame::new(grid, vec![f64::from(i); grid.len()]).unwrap())
            .collect();
        for (labels, conditions) in [(22, 1), (40, 1), (22, 3), (4, 3)] {
            let figure = PressureGrid {
                title: "Pressure images".to_owned(),
                row_names: (0..labels).map(|i| format!("class{i}")).collect(),
                col_names: (0..conditions).map(|c| format!("G{c}")).collect(),
                cells: (0..labels)
                    .map(|i| (0..conditions).map(|_| Some(frames[i].view())).collect())
                    .collect(),
                scale: PressureScale::default(),
                outline: None,
            };
            let (w, h) = figure.size();
            assert!(h <= 4000 && w <= 3200, "{labels} x {conditions}: {w} x {h}");
            let (cols, rows) = figure.panels();
            assert!(
                cols * rows >= labels * conditions,
                "{labels} x {conditions}"
            );
            assert_eq!(cols % conditions, 0, "each block holds every condition");
            if labels <= PressureGrid::MAX_ROWS {
                assert_eq!((cols, rows), (conditions, labels), "small grids as before");
            }
        }
    }
}
