//! Figures and a self-contained HTML report for presrs: pressure heat maps in physical units (the
//! paper's Fig. 5), feature spectra per terrain with the gaits overlaid (Fig. 6), load curves with the
//! detected stances, the samples in principal components, the validation curve of the Parzen width,
//! confusion matrices, accuracy per condition, accuracy against sensor-fault level, Table I and the simulated hopper's motion.
//!
//! The crate takes plain data (frames, models, evaluation reports, simulator outputs) and only writes
//! its outputs, each atomically. Every figure is drawn with plotters in the bundled DejaVu Sans font
//! (no system font, no network) and can be written as PNG or SVG; movies as GIF.

pub mod charts;
pub mod pressure;
pub mod render;
pub mod report;

use plotters::drawing::DrawingAreaErrorKind;

pub use pressure::{MovieOptions, PressureFigure, PressureGrid, PressureScale, write_movie};
pub use render::{Figure, Format, render_rgb, render_svg, save_figure};
pub use report::{
    Evaluation, FaultResult, ReportInputs, ReportRecording, ReportSample, SimulationInputs,
    write_report,
};

/// What can go wrong while drawing or writing figures.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// plotters could not draw (a backend or font error).
    #[error("drawing failed: {0}")]
    Plot(String),
    /// The data cannot be shown as asked.
    #[error("{0}")]
    Input(String),
    #[error(transparent)]
    Io(#[from] presrs_io::IoError),
    #[error(transparent)]
    Core(#[from] presrs_core::CoreError),
}

impl<E: std::error::Error + Send + Sync> From<DrawingAreaErrorKind<E>> for ReportError {
    fn from(err: DrawingAreaErrorKind<E>) -> Self {
        Self::Plot(err.to_string())
    }
}

pub type Result<T, E = ReportError> = std::result::Result<T, E>;
