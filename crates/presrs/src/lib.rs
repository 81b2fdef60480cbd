#![doc = include_str!("../README.md")]

pub mod dataset;
pub mod error;
pub mod evaluate;
pub mod method;
pub mod progress;
pub mod stream;
pub mod train;

pub use dataset::{Dataset, Sample, SampleOptions};
pub use error::{Context, Error, Result};
pub use method::{ClassifierChoice, CropChoice, FeatureChoice, Method};
pub use progress::{Progress, Quiet, Recorder};

/// The algorithms on plain data (frames, stance detection, features, projection, classifiers).
pub use presrs_core as core;
/// File formats, manifests, model files and the stream protocol.
pub use presrs_io as io;
/// Figures and the HTML report.
pub use presrs_report as report;
/// The hopper simulator: dynamics, terrain, skin, sensor, tracks.
pub use presrs_sim as sim;
