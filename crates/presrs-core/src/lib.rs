#![doc = include_str!("../README.md")]

pub mod classifier;
pub mod crop;
pub mod dead_sensels;
pub mod error;
pub mod evaluation;
pub mod features;
pub mod frame;
mod kernels;
mod linalg;
pub mod metrics;
pub mod novelty;
pub mod online;
pub mod perturb;
pub mod pipeline;
pub mod preprocess;
pub mod projection;
pub mod recording;
pub mod reliability;
pub mod sample;
pub mod selection;
pub mod split;
pub mod stance;
pub mod synthetic;
#[cfg(any(test, feature = "testing"))]
pub mod testing;

pub use crop::Crop;
pub use error::CoreError;
pub use frame::{Frame, FrameView, Grid};
pub use pipeline::{
    CheckedTrainConfig, LabeledImage, Prediction, Session, TrainConfig, TrainedModel, train,
};
pub use recording::{FrameInfo, PressureUnit, Recording, SensorMeta};
pub use sample::Sample;
