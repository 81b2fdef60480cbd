//! The stance detector's settings as a user gives them (the `--stance-*` options): each one not given
//! keeps the detector's default.

use presrs_core::stance::{BaselineMode, SegmentParams, ValidSegmentParams};

use crate::error::{Context, Result};

/// The settings a user may change; `None` keeps the default.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StanceOptions {
    /// What a stance's load rises above.
    pub baseline: BaselineMode,
    /// Fraction of the load range a stance must exceed somewhere.
    pub threshold: Option<f64>,
    /// Fraction of the load range a frame of a stance exceeds (hysteresis).
    pub hysteresis: Option<f64>,
    /// Shortest stance kept, frames.
    pub min_frames: Option<usize>,
    /// Longest stance kept, frames (default: no limit).
    pub max_frames: Option<usize>,
    /// Fewest unloaded frames between two stances (at least 1): a shorter dropout is bridged.
    pub min_gap: Option<usize>,
}

impl StanceOptions {
    /// The detector's settings, checked to fit together.
    pub fn segment_params(&self) -> Result<ValidSegmentParams> {
        let default = SegmentParams::default();
        let params = SegmentParams {
            baseline: self.baseline,
            on_fraction: self.threshold.unwrap_or(default.on_fraction),
            off_fraction: self.hysteresis.unwrap_or(default.off_fraction),
            min_stance_frames: self.min_frames.unwrap_or(default.min_stance_frames),
            max_stance_frames: self.max_frames,
            // A gap of N unloaded frames ends a stance: dropouts of up to N - 1 are bridged.
            max_gap_frames: self
                .min_gap
                .map_or(default.max_gap_frames, |gap| gap.saturating_sub(1)),
            ..default
        };
        params
            .check()
            .context("the --stance-* options do not fit together")
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    #[test]
    fn options_not_given_keep_the_defaults_and_a_gap_bridges_one_frame_less() {
        let default = SegmentParams::default().check().unwrap();
        assert_eq!(StanceOptions::default().segment_params().unwrap(), default);
        let options = StanceOptions {
            min_gap: Some(5),
            ..StanceOptions::default()
        };
        assert_eq!(options.segment_params().unwrap().params().max_gap_frames, 4);
        let clash = StanceOptions {
            threshold: Some(0.05),
            hysteresis: Some(0.5),
            ..StanceOptions::default()
        };
        let err = clash.segment_params().unwrap_err().to_string();
        assert!(
            err.starts_with("the --stance-* options do not fit together"),
            "{err}"
        );
    }
}
