//! The page itself: its sections, the figures they hold, and the HTML around them.

use std::fmt::Write as _;
use std::path::Path;

use presrs_core::evaluation::MeanStd;

use super::inputs::ReportInputs;
use crate::charts::{
    BarsFigure, ConfusionFigure, FaultFigure, LoadCurvesFigure, ReliabilityFigure, ScatterFigure,
    SpectraFigure, TraceFigure, ValidationFigure,
};
use crate::error::Result;
use crate::pressure::PressureGrid;
use crate::render::{Figure, save_figure};

/// A figure the report writes, with its file name.
pub(super) enum Job<'a> {
    Grid(PressureGrid<'a>),
    Spectra(SpectraFigure),
    Curves(LoadCurvesFigure),
    Scatter(ScatterFigure),
    Validation(ValidationFigure),
    Confusion(ConfusionFigure),
    Bars(BarsFigure),
    Trace(TraceFigure),
    Faults(FaultFigure),
    Reliability(ReliabilityFigure),
}

impl Job<'_> {
    pub(super) fn save(&self, path: &Path) -> Result<()> {
        match self {
            Self::Grid(f) => save_figure(f, path),
            Self::Spectra(f) => save_figure(f, path),
            Self::Curves(f) => save_figure(f, path),
            Self::Scatter(f) => save_figure(f, path),
            Self::Validation(f) => save_figure(f, path),
            Self::Confusion(f) => save_figure(f, path),
            Self::Bars(f) => save_figure(f, path),
            Self::Trace(f) => save_figure(f, path),
            Self::Faults(f) => save_figure(f, path),
            Self::Reliability(f) => save_figure(f, path),
        }
    }

    pub(super) fn size(&self) -> (u32, u32) {
        match self {
            Self::Grid(f) => f.size(),
            Self::Spectra(f) => f.size(),
            Self::Curves(f) => f.size(),
            Self::Scatter(f) => f.size(),
            Self::Validation(f) => f.size(),
            Self::Confusion(f) => f.size(),
            Self::Bars(f) => f.size(),
            Self::Trace(f) => f.size(),
            Self::Faults(f) => f.size(),
            Self::Reliability(f) => f.size(),
        }
    }
}

/// A section of the page.
pub(super) struct Section<'a> {
    pub(super) id: &'static str,
    pub(super) heading: String,
    /// HTML before the figure.
    pub(super) intro: String,
    pub(super) figure: Option<(String, Job<'a>, String)>,
    /// HTML after the figure (tables).
    pub(super) after: String,
}

/// `text` escaped for HTML text and attribute values.
pub(super) fn esc(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// A mean accuracy with its standard deviation, in percent.
pub(super) fn pct(m: &MeanStd) -> String {
    format!("{:.1} % ± {:.1}", 100.0 * m.mean, 100.0 * m.std)
}

/// The page: title, notes, a table of contents, then every section in order.
pub(super) fn html_page(inputs: &ReportInputs<'_>, sections: &[Section<'_>]) -> String {
    let mut page = String::new();
    let _ = write!(
        page,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\
         <title>{title}</title><style>\
         body{{font-family:sans-serif;max-width:1200px;margin:2em auto;padding:0 1em;color:#222;line-height:1.45}}\
         h1{{font-size:1.6em}}h2{{font-size:1.25em;margin-top:2em;border-bottom:1px solid #ccc}}\
         figure{{margin:1em 0}}figure img{{max-width:100%;height:auto;border:1px solid #eee}}\
         figcaption{{color:#444;font-size:.95em}}table{{border-collapse:collapse;margin:1em 0}}\
         td,th{{border:1px solid #bbb;padding:.25em .6em;text-align:right}}th{{background:#f2f2f2}}\
         td:first-child{{text-align:left}}.ref{{color:#666}}nav a{{margin-right:1em}}\
         </style></head><body>\n<h1>{title}</h1>\n",
        title = esc(&inputs.title)
    );
    for note in &inputs.notes {
        let _ = writeln!(page, "<p>{}</p>", esc(note));
    }
    page.push_str("<nav>");
    for s in sections {
        let _ = write!(page, "<a href=\"#{}\">{}</a>", s.id, esc(&s.heading));
    }
    page.push_str("</nav>\n");
    for s in sections {
        let _ = write!(
            page,
            "<section id=\"{}\"><h2>{}</h2>{}",
            s.id,
            esc(&s.heading),
            s.intro
        );
        if let Some((name, job, caption)) = &s.figure {
            let (w, h) = job.size();
            let _ = write!(
                page,
                "<figure><img src=\"{name}\" width=\"{w}\" height=\"{h}\" alt=\"{}\">\
                 <figcaption>{caption}</figcaption></figure>",
                esc(&s.heading)
            );
        }
        let _ = writeln!(page, "{}</section>", s.after);
    }
    let _ = writeln!(
        page,
        "<footer><p class=\"ref\">Written by presrs {}.</p></footer></body></html>",
        env!("CARGO_PKG_VERSION")
    );
    page
}
