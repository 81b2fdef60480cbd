//! A whole stance's duration as one more feature after MiniRocket's (the `rocket_duration` preset).
//!
//! A stance is laid into the model's length with zeros after lift-off ([`crate::stance::summary`]), so
//! its duration is the number of frames before that padding: one past the last frame where any channel
//! is non-zero (a stance's frames carry load). MiniRocket sees the duration only through how the padding
//! shifts its proportions of positive values; on `jiku-walk` the walking speeds differ mostly in it.
//!
//! The feature is the duration standardised over the training samples, times
//! `DURATION_WEIGHT * sqrt(features)`: MiniRocket's features are proportions in [0, 1], so a ridge on
//! the raw features weighs a lone standardised value next to thousands of them as almost nothing; the
//! weight gives it a share of the distances between samples that grows with theirs.

use serde::{Deserialize, Serialize};

use crate::error::{CoreError, Result};
use crate::features::family::FitImages;

/// The duration feature's weight per square root of MiniRocket's features (see the module's doc).
pub const DURATION_WEIGHT: f64 = 0.1;

/// Frames before the padding of a sample of `channels x length` values (row-major): one past the last
/// frame where any channel is non-zero, 0 for a sample of zeros.
pub fn frames_before_padding(sample: &[f64], length: usize) -> usize {
    let rows: Vec<&[f64]> = sample.chunks_exact(length.max(1)).collect();
    (0..length)
        .rev()
        .find(|&frame| rows.iter().any(|row| row[frame] != 0.0))
        .map_or(0, |frame| frame + 1)
}

/// What training learned for the duration feature.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DurationScale {
    /// The training samples' mean duration, in frames.
    pub mean: f64,
    /// Their standard deviation (1 when every duration is the same).
    pub spread: f64,
    /// The standardised duration is multiplied by it.
    pub weight: f64,
}

impl DurationScale {
    /// From the training samples (`images`: channels x time), for a model of `features` MiniRocket
    /// features.
    pub fn fit(images: FitImages<'_>, features: usize) -> Self {
        let length = images.grid.cols;
        let durations: Vec<f64> = (0..images.len())
            .map(|i| frames_before_padding(images.image(i), length) as f64)
            .collect();
        let count = durations.len().max(1) as f64;
        let mean = durations.iter().sum::<f64>() / count;
        let variance = durations.iter().map(|d| (d - mean).powi(2)).sum::<f64>() / count;
        let spread = variance.sqrt();
        Self {
            mean,
            spread: if spread > 0.0 { spread } else { 1.0 },
            weight: DURATION_WEIGHT * (features as f64).sqrt(),
        }
    }

    /// The feature of a sample of `frames` frames before its padding.
    pub fn feature(&self, frames: usize) -> f64 {
        (frames as f64 - self.mean) / self.spread * self.weight
    }

    /// `Ok` when every number is finite and the spread and weight positive.
    pub fn check(&self) -> Result<()> {
        let finite = [self.mean, self.spread, self.weight]
            .iter()
            .all(|v| v.is_finite());
        if finite && self.spread > 0.0 && self.weight > 0.0 {
            Ok(())
        } else {
            Err(CoreError::Param {
                name: "duration",
                reason: "the duration's mean must be finite, its spread and weight positive".into(),
            })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::Grid;

    /// A sample of 2 channels x 6 frames whose first `frames` frames carry a value (one channel may
    /// be zero there: only a frame where every channel is zero is padding).
    fn stance(frames: usize) -> Vec<f64> {
        let mut sample = vec![0.0; 12];
        for t in 0..frames {
            sample[t] = if t % 2 == 0 { 1.5 } else { 0.0 };
            sample[6 + t] = if t % 2 == 1 { -2.0 } else { 0.0 };
        }
        sample
    }

    #[test]
    fn the_duration_is_the_frames_before_the_padding() {
        for frames in 0..=6 {
            assert_eq!(frames_before_padding(&stance(frames), 6), frames);
        }
        // A zero inside the stance is not padding.
        let mut gap = stance(5);
        gap[2] = 0.0;
        gap[8] = 0.0;
        assert_eq!(frames_before_padding(&gap, 6), 5);
    }

    #[test]
    fn the_feature_is_the_standardised_duration_times_the_weight() {
        let values: Vec<f64> = [2, 4, 6].iter().flat_map(|&f| stance(f)).collect();
        let images = FitImages {
            grid: Grid::new(2, 6),
            values: &values,
        };
        let scale = DurationScale::fit(images, 400);
        assert_eq!(scale.mean, 4.0);
        let spread = (8.0_f64 / 3.0).sqrt();
        assert!((scale.spread - spread).abs() < 1e-12);
        assert_eq!(scale.weight, DURATION_WEIGHT * 20.0);
        assert!((scale.feature(6) - 2.0 / spread * scale.weight).abs() < 1e-12);
        assert_eq!(scale.feature(4), 0.0);
        assert!(scale.check().is_ok());
        // Equal durations leave a spread of 1; a bad model file is refused.
        let same: Vec<f64> = [3, 3].iter().flat_map(|&f| stance(f)).collect();
        let flat = DurationScale::fit(
            FitImages {
                grid: Grid::new(2, 6),
                values: &same,
            },
            84,
        );
        assert_eq!((flat.spread, flat.feature(3)), (1.0, 0.0));
        let bad = DurationScale {
            spread: 0.0,
            ..flat
        };
        assert!(
            bad.check()
                .is_err_and(|e| e.to_string().contains("duration"))
        );
    }
}
