#![doc = include_str!("../README.md")]

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
    EarlyAutoResult, EarlyCurve, EarlyCurvePoint, Evaluation, FaultResult, NoveltyResult,
    NoveltyRow, ReportInputs, ReportRecording, SimulationInputs, write_report,
};
