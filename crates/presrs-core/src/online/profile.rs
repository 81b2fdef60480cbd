//! What a model needs to run online ([`OnlineProfile`]): the stance detector's settings, its
//! calibration, the sample frame and the terrain-to-gait table, learned from the training recordings'
//! offline segmentations.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::stance::causal::{Calibration, OnlineParams, sample_offset_for, typical_stance_frames};
use crate::stance::robust::median;
use crate::stance::{BaselineMode, SegmentParams, Segmentation, ValidSegmentParams};

/// What a model needs to run online: the detector settings, its calibration and the terrain-to-gait
/// table. Stored next to a model (in the model file or a JSON file of its own).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct OnlineProfile {
    pub params: OnlineParams,
    /// The stance detector's settings (baseline mode, levels, lengths, gaps) the model was trained
    /// with: the online detector segments with them. Profiles written before they were stored load
    /// with the defaults.
    pub segment: ValidSegmentParams,
    /// Median stance length of the data `params.sample_offset` was learned from, frames.
    pub typical_stance_frames: Option<usize>,
    pub calibration: Option<Calibration>,
    /// Terrain label -> recommended gait name.
    pub gait_table: BTreeMap<String, String>,
}

impl OnlineProfile {
    /// A profile learned from offline segmentations (with the default settings) of training recordings:
    /// calibration (medians) and `k` from the median length of their complete stances.
    pub fn learn(segmentations: &[Segmentation]) -> Self {
        Self::learn_with(segmentations, &ValidSegmentParams::default())
    }

    /// [`Self::learn`] from segmentations made with `segment`, which the profile keeps for the online
    /// detector. With [`BaselineMode::Auto`], the mode the automatic choice made on most of the
    /// segmentations is stored if it is the floor (presses on a preload): a calibrated detector has
    /// no warm-up to choose on, and judges the stream from its profile's mode.
    ///
    /// Recordings that are one contact each (trials cut to one foot contact,
    /// [`BaselineMode::Contact`], chosen or found on most of them) give a profile for a stream of
    /// steps instead: [`Self::learn_from_contacts`].
    pub fn learn_with(segmentations: &[Segmentation], segment: &ValidSegmentParams) -> Self {
        let contacts = segmentations
            .iter()
            .filter(|seg| seg.mode == BaselineMode::Contact)
            .count();
        if 2 * contacts > segmentations.len() {
            return Self::learn_from_contacts(segmentations, segment);
        }
        let floors = segmentations
            .iter()
            .filter(|seg| seg.mode == BaselineMode::Floor)
            .count();
        let mut segment = segment.clone();
        if segment.params().baseline == BaselineMode::Auto && 2 * floors > segmentations.len() {
            let floor = SegmentParams {
                baseline: BaselineMode::Floor,
                ..segment.params().clone()
            };
            if let Ok(valid) = floor.check() {
                segment = valid;
            }
        }
        let segment = &segment;
        let lengths: Vec<usize> = segmentations
            .iter()
            .flat_map(|seg| seg.complete().map(|stance| stance.len))
            .collect();
        Self {
            params: OnlineParams {
                sample_offset: sample_offset_for(&lengths),
                ..OnlineParams::default()
            },
            segment: segment.clone(),
            typical_stance_frames: typical_stance_frames(&lengths),
            calibration: Calibration::from_segmentations(segmentations),
            gait_table: BTreeMap::new(),
        }
    }

    /// A profile for a stream of steps learned from recordings that are one contact each: a stream
    /// is not one contact, so its detector finds stances above the unloaded level
    /// ([`BaselineMode::Drifting`], the other settings as `segment` gives them), calibrated on the
    /// contacts: the unloaded level around them (0, or the lowest reading when it is negative), the
    /// load range from their loaded frames (the median peak above that level), no noise (the
    /// stream's quiet frames measure it); each recording's length is its stance's, which sets the
    /// sample offset and the typical length.
    pub fn learn_from_contacts(
        segmentations: &[Segmentation],
        segment: &ValidSegmentParams,
    ) -> Self {
        let streaming = SegmentParams {
            baseline: BaselineMode::Drifting,
            ..segment.params().clone()
        };
        // Only the mode changed, and every mode is valid with valid settings.
        let segment = streaming.check().unwrap_or_else(|_| segment.clone());
        let contacts = segmentations.iter().filter_map(|seg| {
            let stance = seg.stances.first()?;
            let unloaded = seg.baseline.iter().copied().fold(0.0, f64::min);
            Some((stance.len, stance.peak_load - unloaded, unloaded))
        });
        let (mut lengths, mut ranges, mut levels) = (Vec::new(), Vec::new(), Vec::new());
        for (len, range, level) in contacts {
            lengths.push(len);
            ranges.push(range);
            levels.push(level);
        }
        let calibration = (!ranges.is_empty()).then(|| Calibration {
            baseline: median(&mut levels),
            noise: 0.0,
            load_range: median(&mut ranges),
        });
        Self {
            params: OnlineParams {
                sample_offset: sample_offset_for(&lengths),
                ..OnlineParams::default()
            },
            segment,
            typical_stance_frames: typical_stance_frames(&lengths),
            calibration,
            gait_table: BTreeMap::new(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A profile written before the detector settings were stored loads with the defaults; one
    /// with them keeps them.
    #[test]
    fn the_detector_settings_are_kept_and_default_when_absent() {
        let old: OnlineProfile =
            serde_json::from_str(r#"{"params": {"sample_offset": 7}, "gait_table": {}}"#).unwrap();
        assert_eq!(old.params.sample_offset, 7);
        assert_eq!(old.segment, ValidSegmentParams::default());
        let segment = SegmentParams {
            baseline: BaselineMode::Floor,
            min_stance_frames: 5,
            ..SegmentParams::default()
        }
        .check()
        .unwrap();
        let profile = OnlineProfile::learn_with(&[], &segment);
        let json = serde_json::to_string(&profile).unwrap();
        let back: OnlineProfile = serde_json::from_str(&json).unwrap();
        assert_eq!(back.segment, segment);
        assert!(json.contains(r#""baseline":"floor""#), "{json}");
    }

    /// A profile learned with the automatic choice from recordings segmented from the floor stores the
    /// floor (a calibrated stream has no warm-up to choose on); from others it stays automatic.
    #[test]
    fn a_profile_trained_on_preload_data_stores_the_floor() {
        let seg = |mode| Segmentation {
            stances: Vec::new(),
            baseline: vec![100.0; 10],
            noise: 1.0,
            load_range: 500.0,
            on_level: 50.0,
            off_level: 5.0,
            mode,
            mode_reason: None,
        };
        let auto = ValidSegmentParams::default();
        let floor = [
            seg(BaselineMode::Floor),
            seg(BaselineMode::Floor),
            seg(BaselineMode::Drifting),
        ];
        let profile = OnlineProfile::learn_with(&floor, &auto);
        assert_eq!(profile.segment.params().baseline, BaselineMode::Floor);
        assert_eq!(profile.segment.params().min_stance_frames, 3);
        let walking = [seg(BaselineMode::Floor), seg(BaselineMode::Drifting)];
        let profile = OnlineProfile::learn_with(&walking, &auto);
        assert_eq!(profile.segment.params().baseline, BaselineMode::Auto);
        // Asked for explicitly, the mode is kept.
        let drifting = SegmentParams {
            baseline: BaselineMode::Drifting,
            ..SegmentParams::default()
        }
        .check()
        .unwrap();
        let profile = OnlineProfile::learn_with(&floor, &drifting);
        assert_eq!(profile.segment.params().baseline, BaselineMode::Drifting);
    }
}
