//! The crate's error type, in a leaf module so that every module can use it without importing the
//! crate root (which imports them all).

use plotters::drawing::DrawingAreaErrorKind;

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
