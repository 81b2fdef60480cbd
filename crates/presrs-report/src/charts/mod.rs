//! The report's charts: load curves, feature spectra, principal components, validation curve, confusion
//! matrices, grouped bars (accuracy, Table I) and the hopper's motion; one file per figure family.

mod bars;
mod common;
mod confusion;
mod faults;
mod hopper;
mod load;
mod pca;
mod reliability;
mod spectra;
mod validation;

pub use bars::{BarSeries, BarsFigure};
pub use confusion::ConfusionFigure;
pub use faults::{FaultFigure, FaultPanel, FaultPoint};
pub use hopper::TraceFigure;
pub use load::{LoadCurveData, LoadCurvesFigure, draw_load_curve};
pub use pca::ScatterFigure;
pub use reliability::{ReliabilityFigure, ReliabilityPoint};
pub use spectra::{SpectraFigure, SpectrumPanel};
pub use validation::ValidationFigure;

// Formatting lives in a leaf module shared with the heat maps; re-exported where it always was.
pub use crate::format::num;
