//! Figures and a self-contained HTML report for presrs: pressure heat maps in physical units (the
//! paper's Fig. 5), feature spectra per terrain with the gaits overlaid (Fig. 6), load curves with the
//! detected stances, the samples in principal components, the validation curve of the Parzen width,
//! confusion matrices, accuracy per condition, accuracy against sensor-fault level, Table I and the simulated hopper's motion.
//!
//! The crate takes plain data (frames, models, evaluation reports, simulator outputs) and only writes
//! its outputs, each atomically. Every figure is drawn with plotters in the bundled DejaVu Sans font
//! (no system font, no network) and can be written as PNG or SVG; movies as GIF.

pub mod charts;
mod error;
mod format;
pub mod pressure;
pub mod render;
pub mod report;
mod scale;

pub use error::{ReportError, Result};
pub use pressure::{MovieOptions, PressureFigure, PressureGrid, PressureScale, write_movie};
pub use render::{Figure, Format, render_rgb, render_svg, save_figure};
pub use report::{
    Evaluation, FaultResult, ReportInputs, ReportRecording, ReportSample, SimulationInputs,
    write_report,
};
