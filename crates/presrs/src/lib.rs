#![doc = include_str!("../README.md")]

pub mod bench;
pub mod classify;
pub mod convert;
pub mod dataset;
pub mod describe;
pub mod error;
pub mod eval;
pub mod frame_features;
pub mod inspect;
pub mod method;
pub mod plot;
pub mod progress;
pub mod report;
pub mod reproduce;
pub mod resources;
pub mod session;
pub mod sim;
pub mod train;

pub use dataset::{Dataset, Sample, SampleKind, SampleOptions};
pub use describe::describe_model;
pub use error::{Context, Error, Result};
pub use method::{ClassifierChoice, CropChoice, FeatureChoice, Method};
pub use progress::{Progress, Quiet, Recorder};
// Messages that name options as data, and the one warning type.
pub use presrs_io::message::{self, Face, Message, Opt, Warning, Warnings};

/// The algorithms on plain data (frames, stance detection, features, projection, classifiers).
pub use presrs_core as core;
/// File formats, manifests, model files and the stream protocol.
pub use presrs_io as io;
/// The hopper simulator: dynamics, terrain, skin, sensor, tracks.
pub use presrs_sim as simulator;

/// The top-level README's examples, compiled (and run where they can be) by `cargo test --doc`.
#[cfg(doctest)]
#[doc = include_str!("../../../README.md")]
struct ReadmeDoctests;
