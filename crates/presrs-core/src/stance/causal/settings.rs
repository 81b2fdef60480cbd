//! The online detector's settings ([`OnlineParams`]), its calibration from offline segmentations
//! ([`Calibration`]) and the sample offset learned from stance lengths.

use serde::{Deserialize, Serialize};

use crate::error::{CoreError, Result};
use crate::stance::offline::Segmentation;
use crate::stance::robust::median;

/// Quiet frames needed before the online baseline/noise estimate replaces the calibration.
pub const MIN_QUIET_FRAMES: usize = 32;
/// The load range is the stream's running maximum above the baseline, but at least this fraction of the
/// calibrated range: before the first stance, noise must not set the levels.
pub const RANGE_PRIOR_FRACTION: f64 = 0.5;
/// Most fusion offsets accepted.
pub const MAX_FUSION_FRAMES: usize = 32;
/// The paper's sample: the 7th frame of a stance (0-based offset 6), the default `k`.
pub const PAPER_SAMPLE_OFFSET: usize = 6;
/// Largest sample or fusion offset accepted, frames (1000 s at 100 Hz; a stance lasts well under a
/// second).
pub const MAX_OFFSET_FRAMES: usize = 100_000;

/// Baseline, noise and load range of the total load, as the offline segmentation measures them.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Calibration {
    /// Unloaded level of the total load.
    pub baseline: f64,
    /// Standard deviation of the unloaded level.
    pub noise: f64,
    /// Largest load above the baseline.
    pub load_range: f64,
}

impl Calibration {
    /// The medians of the per-recording baseline (each recording's median baseline), noise and load
    /// range of offline segmentations, e.g. of the training recordings. `None` without any.
    pub fn from_segmentations<'a>(
        segmentations: impl IntoIterator<Item = &'a Segmentation>,
    ) -> Option<Self> {
        let (mut baselines, mut noises, mut ranges) = (Vec::new(), Vec::new(), Vec::new());
        for seg in segmentations {
            let mut base = seg.baseline.clone();
            if base.is_empty() {
                continue;
            }
            baselines.push(median(&mut base));
            noises.push(seg.noise);
            ranges.push(seg.load_range);
        }
        if baselines.is_empty() {
            return None;
        }
        Some(Self {
            baseline: median(&mut baselines),
            noise: median(&mut noises),
            load_range: median(&mut ranges),
        })
    }

    pub(super) fn check(&self) -> Result<()> {
        let ok = self.baseline.is_finite()
            && self.noise.is_finite()
            && self.noise >= 0.0
            && self.load_range.is_finite()
            && self.load_range >= 0.0;
        if ok {
            Ok(())
        } else {
            Err(CoreError::Param {
                name: "calibration",
                reason: format!(
                    "baseline must be finite and noise, load range finite and >= 0, got {self:?}"
                ),
            })
        }
    }
}

/// `k = (L - 1) / 2` for the median `L` of `stance_lengths` (frames): the offset after touchdown that is
/// the paper's mid-stance frame on a stance of typical length. [`PAPER_SAMPLE_OFFSET`] without data.
pub fn sample_offset_for(stance_lengths: &[usize]) -> usize {
    typical_stance_frames(stance_lengths)
        .map_or(PAPER_SAMPLE_OFFSET, |len| len.saturating_sub(1) / 2)
}

/// The median stance length (the lower median for an even count), `None` without stances.
pub fn typical_stance_frames(stance_lengths: &[usize]) -> Option<usize> {
    let mut lengths = stance_lengths.to_vec();
    lengths.sort_unstable();
    lengths.get(lengths.len().saturating_sub(1) / 2).copied()
}

/// When a whole-stance model decides before lift-off: `K` frames after touchdown, or at the first of its
/// decision points whose calibrated confidence passes its learned threshold (`auto`). Written as a
/// number or `"auto"`; read from either, or from the text `K`/`auto` ([`std::str::FromStr`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum DecideAt {
    /// `K` frames after touchdown, on the stance so far (its `K + 1` frames).
    Frames(usize),
    /// At the first decision point whose confidence passes the model's threshold (else at lift-off).
    Auto(AutoWord),
}

/// The word `auto` of [`DecideAt::Auto`] in JSON.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AutoWord {
    Auto,
}

impl DecideAt {
    /// `auto`.
    pub const AUTO: Self = Self::Auto(AutoWord::Auto);

    /// Whether this is `auto`.
    pub fn is_auto(self) -> bool {
        self == Self::AUTO
    }
}

impl std::fmt::Display for DecideAt {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Frames(k) => write!(f, "{k}"),
            Self::Auto(_) => f.write_str("auto"),
        }
    }
}

impl std::str::FromStr for DecideAt {
    type Err = String;

    /// `auto`, or `K` frames after touchdown.
    fn from_str(text: &str) -> std::result::Result<Self, String> {
        match text.trim() {
            "auto" => Ok(Self::AUTO),
            other => other.parse().map(Self::Frames).map_err(|_| {
                format!("expected auto or a number of frames after touchdown, got {other:?}")
            }),
        }
    }
}

/// Settings of the online detector and classifier beyond the offline [`SegmentParams`](crate::stance::SegmentParams).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct OnlineParams {
    /// `k`: the frame classified is the `k`-th after touchdown (0 = touchdown), at most
    /// [`MAX_OFFSET_FRAMES`]. Default 6, the paper's 7th frame; learn it with [`sample_offset_for`].
    pub sample_offset: usize,
    /// Offsets after touchdown whose posteriors are averaged into a second, fused decision (empty: none;
    /// at most [`MAX_FUSION_FRAMES`] of them, each at most [`MAX_OFFSET_FRAMES`]).
    pub fusion_offsets: Vec<usize>,
    /// Without a calibration, the first frames are used to calibrate (default 128; at least 8).
    pub warmup_frames: usize,
    /// For a whole-stance model (trained on stance samples): decide `K` frames after touchdown, on the
    /// stance so far (frames touchdown to touchdown + K, zero-padded as offline), instead of at
    /// lift-off (`None`, the default); or [`DecideAt::Auto`], at the first decision point whose
    /// confidence passes the threshold learned at training. At most [`MAX_OFFSET_FRAMES`]. A model
    /// decides only at points it was trained for (its decision points, or its whole length); a
    /// one-frame model has no use for it (it decides on frame [`Self::sample_offset`]): the online
    /// classifier refuses both.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub decide_at: Option<DecideAt>,
}

impl Default for OnlineParams {
    fn default() -> Self {
        Self {
            sample_offset: PAPER_SAMPLE_OFFSET,
            fusion_offsets: Vec::new(),
            warmup_frames: 128,
            decide_at: None,
        }
    }
}

impl OnlineParams {
    pub(super) fn check(&self) -> Result<()> {
        if self.sample_offset > MAX_OFFSET_FRAMES {
            return Err(CoreError::Param {
                name: "sample_offset",
                reason: format!(
                    "must be at most {MAX_OFFSET_FRAMES} frames after touchdown, got {}",
                    self.sample_offset
                ),
            });
        }
        if let Some(DecideAt::Frames(k)) = self.decide_at
            && k > MAX_OFFSET_FRAMES
        {
            return Err(CoreError::Param {
                name: "decide_at",
                reason: format!(
                    "must be at most {MAX_OFFSET_FRAMES} frames after touchdown, got {k}"
                ),
            });
        }
        if let Some(&offset) = self
            .fusion_offsets
            .iter()
            .find(|&&offset| offset > MAX_OFFSET_FRAMES)
        {
            return Err(CoreError::Param {
                name: "fusion_offsets",
                reason: format!(
                    "each must be at most {MAX_OFFSET_FRAMES} frames after touchdown, got {offset}"
                ),
            });
        }
        if self.fusion_offsets.len() > MAX_FUSION_FRAMES {
            return Err(CoreError::Param {
                name: "fusion_offsets",
                reason: format!(
                    "at most {MAX_FUSION_FRAMES} offsets, got {}",
                    self.fusion_offsets.len()
                ),
            });
        }
        if self.warmup_frames < 8 {
            return Err(CoreError::Param {
                name: "warmup_frames",
                reason: format!("must be at least 8, got {}", self.warmup_frames),
            });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offset_from_typical_length() {
        assert_eq!(sample_offset_for(&[14, 14, 13, 15, 14]), 6);
        assert_eq!(sample_offset_for(&[17, 16, 16]), 7);
        assert_eq!(sample_offset_for(&[]), PAPER_SAMPLE_OFFSET);
    }

    /// Old settings (no `decide_at`) load as deciding at lift-off, and write back as they were.
    #[test]
    fn decide_at_defaults_to_liftoff_and_is_checked() {
        let old: OnlineParams = serde_json::from_str(r#"{"sample_offset": 7}"#).unwrap();
        assert_eq!(old.decide_at, None);
        assert!(!serde_json::to_string(&old).unwrap().contains("decide_at"));
        let k: OnlineParams = serde_json::from_str(r#"{"decide_at": 9}"#).unwrap();
        assert_eq!(k.decide_at, Some(DecideAt::Frames(9)));
        let auto: OnlineParams = serde_json::from_str(r#"{"decide_at": "auto"}"#).unwrap();
        assert_eq!(auto.decide_at, Some(DecideAt::AUTO));
        assert!(
            serde_json::to_string(&auto)
                .unwrap()
                .contains(r#""decide_at":"auto""#)
        );
        assert_eq!("auto".parse::<DecideAt>(), Ok(DecideAt::AUTO));
        assert_eq!(" 12".parse::<DecideAt>(), Ok(DecideAt::Frames(12)));
        assert!("soon".parse::<DecideAt>().is_err());
        assert!(k.check().is_ok());
        let far = OnlineParams {
            decide_at: Some(DecideAt::Frames(MAX_OFFSET_FRAMES + 1)),
            ..OnlineParams::default()
        };
        assert!(far.check().unwrap_err().to_string().contains("decide_at"));
    }
}
