//! Stance detection: which frames of a recording or stream are stances, and which frame of each to
//! classify.
//!
//! - [`offline`]: a whole recording at once (the paper's method, from a drifting baseline).
//! - [`modes`]: what the stances rise above (drifting baseline, local floor, one contact) and the
//!   automatic choice ([`segment`], [`segment_recording`]).
//! - [`summary`]: a whole stance as channels over time (load, area, centre of pressure, regions).
//! - [`causal`]: one total load at a time, without looking ahead ([`CausalSegmenter`]), with the offline
//!   method's rules and levels learned from offline segmentations ([`Calibration`]).
//!
//! Both measure the baseline and its noise with the same robust statistics (median, 1.4826 x MAD) from
//! one private module. The offline items are also nameable here (`stance::segment`), as before the split.

mod baseline;
pub mod causal;
pub mod modes;
pub mod offline;
pub(crate) mod robust;
pub mod summary;

pub use causal::{
    Calibration, CausalSegmenter, Levels, Liftoff, OnlineParams, SegEvent, SegEvents, Touchdown,
};
pub use modes::{segment, segment_recording};
pub use offline::{
    BaselineMode, SampleFrame, SegmentParams, Segmentation, Stance, ValidSegmentParams,
    sample_frames,
};
