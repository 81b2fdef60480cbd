//! Rendering a figure to PNG, SVG or an RGB buffer; the bundled font; colours.

use std::path::Path;
use std::sync::OnceLock;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::{FontStyle, register_font};

use crate::error::{ReportError, Result};

/// DejaVu Sans (Bitstream Vera licence, see `assets/LICENSE-DejaVu.txt`): every figure uses it, so no
/// system font is needed.
static FONT: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");

/// The font family every figure asks for.
pub const FONT_FAMILY: &str = "sans-serif";

/// Registers the bundled font under the generic family names (once per process).
pub fn ensure_fonts() -> Result<()> {
    static REGISTERED: OnceLock<std::result::Result<(), String>> = OnceLock::new();
    REGISTERED
        .get_or_init(|| {
            for family in ["sans-serif", "serif", "monospace"] {
                for style in [
                    FontStyle::Normal,
                    FontStyle::Bold,
                    FontStyle::Italic,
                    FontStyle::Oblique,
                ] {
                    register_font(family, style, FONT)
                        .map_err(|_| "the bundled font cannot be read".to_owned())?;
                }
            }
            Ok(())
        })
        .clone()
        .map_err(ReportError::Plot)
}

/// Something that can be drawn on any plotters backend.
pub trait Figure {
    /// Width and height in pixels.
    fn size(&self) -> (u32, u32);
    /// Draws the figure on `root` (already filled white).
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static;
}

/// Output formats, chosen by file extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Png,
    Svg,
    Gif,
}

impl Format {
    /// The format named by `path`'s extension (case-insensitive).
    pub fn of(path: &Path) -> Result<Self> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("png") => Ok(Self::Png),
            Some("svg") => Ok(Self::Svg),
            Some("gif") => Ok(Self::Gif),
            _ => Err(ReportError::Input(format!(
                "{}: the output must end in .png, .svg (or .gif for a movie)",
                path.display()
            ))),
        }
    }
}

/// Draws `figure` into an RGB buffer (`width * height * 3` bytes).
pub fn render_rgb(figure: &impl Figure) -> Result<(u32, u32, Vec<u8>)> {
    ensure_fonts()?;
    let (w, h) = figure.size();
    let mut buffer = vec![255u8; w as usize * h as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut buffer, (w, h)).into_drawing_area();
        root.fill(&WHITE)?;
        figure.draw(&root)?;
        root.present()?;
    }
    Ok((w, h, buffer))
}

/// Draws `figure` as an SVG document.
pub fn render_svg(figure: &impl Figure) -> Result<String> {
    ensure_fonts()?;
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, figure.size()).into_drawing_area();
        root.fill(&WHITE)?;
        figure.draw(&root)?;
        root.present()?;
    }
    Ok(text)
}

/// Encodes an RGB buffer as PNG into `w`.
pub fn encode_png(
    w: &mut dyn std::io::Write,
    width: u32,
    height: u32,
    rgb: &[u8],
) -> std::io::Result<()> {
    let mut encoder = png::Encoder::new(w, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().map_err(std::io::Error::other)?;
    writer
        .write_image_data(rgb)
        .map_err(std::io::Error::other)?;
    writer.finish().map_err(std::io::Error::other)
}

/// Writes `figure` to `path` (PNG or SVG by extension), atomically.
pub fn save_figure(figure: &impl Figure, path: &Path) -> Result<()> {
    match Format::of(path)? {
        Format::Png => {
            let (w, h, rgb) = render_rgb(figure)?;
            presrs_io::write_atomic(path, |out| encode_png(out, w, h, &rgb))?;
        }
        Format::Svg => {
            let svg = render_svg(figure)?;
            presrs_io::write_atomic(path, |out| out.write_all(svg.as_bytes()))?;
        }
        Format::Gif => {
            return Err(ReportError::Input(format!(
                "{}: a single figure is written as .png or .svg (.gif is for movies)",
                path.display()
            )));
        }
    }
    Ok(())
}

/// Writes an animation of `frames` (each an RGB buffer of `width x height`) as a looping GIF.
pub fn save_gif(
    path: &Path,
    width: u32,
    height: u32,
    frames: &[Vec<u8>],
    delay_cs: u16,
) -> Result<()> {
    let (w16, h16) = (
        u16::try_from(width).map_err(|_| ReportError::Input("movie too wide".into()))?,
        u16::try_from(height).map_err(|_| ReportError::Input("movie too tall".into()))?,
    );
    presrs_io::write_atomic(path, |out| {
        let mut encoder = gif::Encoder::new(out, w16, h16, &[]).map_err(std::io::Error::other)?;
        encoder
            .set_repeat(gif::Repeat::Infinite)
            .map_err(std::io::Error::other)?;
        for rgb in frames {
            let mut frame = gif::Frame::from_rgb_speed(w16, h16, rgb, 20);
            frame.delay = delay_cs;
            encoder.write_frame(&frame).map_err(std::io::Error::other)?;
        }
        Ok(())
    })?;
    Ok(())
}

/// Distinct colours for categories (Tableau 10).
pub const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// The colour of category `i`.
pub fn category_color(i: usize) -> RGBColor {
    PALETTE[i % PALETTE.len()]
}

/// Viridis, sampled at nine points (perceptually uniform, readable in greyscale and by most colour-blind
/// readers).
const VIRIDIS: [(u8, u8, u8); 9] = [
    (68, 1, 84),
    (71, 44, 122),
    (59, 81, 139),
    (44, 113, 142),
    (33, 144, 141),
    (39, 173, 129),
    (92, 200, 99),
    (170, 220, 50),
    (253, 231, 37),
];

/// The colour of `t` in [0, 1] (clamped) on the viridis map.
pub fn viridis(t: f64) -> RGBColor {
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let x = t * (VIRIDIS.len() - 1) as f64;
    let i = (x.floor() as usize).min(VIRIDIS.len() - 2);
    let f = x - i as f64;
    let lerp = |a: u8, b: u8| (f64::from(a) + f * (f64::from(b) - f64::from(a))).round() as u8;
    let (a, b) = (VIRIDIS[i], VIRIDIS[i + 1]);
    RGBColor(lerp(a.0, b.0), lerp(a.1, b.1), lerp(a.2, b.2))
}

/// White to dark blue, for counts (confusion matrices).
pub fn blues(t: f64) -> RGBColor {
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let lerp = |a: f64, b: f64| (a + t * (b - a)).round() as u8;
    RGBColor(lerp(247.0, 8.0), lerp(251.0, 48.0), lerp(255.0, 107.0))
}

/// The colour of sensels that do not exist (masked): a neutral grey that is not on the colour map.
pub const MASKED: RGBColor = RGBColor(205, 205, 205);

/// Text style of the given size in the bundled font.
pub fn font(size: f64) -> TextStyle<'static> {
    (FONT_FAMILY, size).into_font().into()
}

/// Text style of a figure title.
pub fn title_font(size: f64) -> TextStyle<'static> {
    (FONT_FAMILY, size, FontStyle::Bold).into_font().into()
}

/// The width in pixels a figure needs for its title in the title font of `size` (and a margin each
/// side), so that a long title is not clipped.
pub fn title_width(title: &str, size: f64) -> u32 {
    let measured = ensure_fonts()
        .ok()
        .and_then(|()| title_font(size).font.box_size(title).ok())
        .map(|(w, _)| w);
    // Without the font: about 0.6 of the size per character, a fair guess for sans-serif.
    measured.unwrap_or((title.chars().count() as f64 * size * 0.6) as u32) + 40
}
