#![doc = include_str!("../README.md")]

pub mod crop;
pub mod error;
pub mod frame;
pub mod recording;

pub use crop::Crop;
pub use error::CoreError;
pub use frame::{Frame, FrameView, Grid};
pub use recording::{FrameInfo, PressureUnit, Recording, SensorMeta};
