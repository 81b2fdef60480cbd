//! The features of a recording's frames (what `presrs features` prints): which frames are described,
//! and their feature vectors with the features' names.

use presrs_core::features::{FeatureConfig, FeatureKind};
use presrs_core::pipeline::extract_features;
use presrs_core::stance::{SampleFrame, ValidSegmentParams, segment_recording};
use presrs_core::{Crop, Recording};

use crate::error::{Context, Error, Result};
use crate::method::CropChoice;

/// The frames to describe: `frame` when given, the only frame of a one-frame recording, else every
/// stance phase's `sample` frame (found with the default detector; stances cut by the recording's ends
/// with `include_partial`). `name` names the recording in errors.
pub fn feature_frames(
    recording: &Recording,
    name: &str,
    frame: Option<usize>,
    sample: SampleFrame,
    include_partial: bool,
) -> Result<Vec<usize>> {
    let count = recording.frame_count();
    match frame {
        Some(frame) if frame >= count => Err(Error::invalid(format!(
            "{name}: --frame {frame} is past the end ({})",
            crate::classify::frames_numbered(count)
        ))),
        Some(frame) => Ok(vec![frame]),
        None if count == 1 => Ok(vec![0]),
        None => {
            let segmentation = segment_recording(recording, &ValidSegmentParams::default())
                .with_context(|| format!("{name}: cannot segment"))?;
            let frames = segmentation
                .samples(sample, include_partial)
                .with_context(|| name.to_owned())?;
            if frames.is_empty() {
                return Err(Error::data(format!(
                    "{name}: {count} frames but no complete stance phase; choose one with --frame K"
                )));
            }
            Ok(frames)
        }
    }
}

/// The features of a recording's frames: the crop and families, and the name of every feature.
#[derive(Clone, Debug)]
pub struct FrameFeatures<'r> {
    recording: &'r Recording,
    name: String,
    crop: Crop,
    config: FeatureConfig,
    /// One name per feature, in the vectors' order.
    pub names: Vec<String>,
}

impl<'r> FrameFeatures<'r> {
    /// The features of `recording` (`name` in errors) with `crop` and the families `kinds` (joined as
    /// in a model: each part scaled to unit norm).
    pub fn new(
        recording: &'r Recording,
        name: &str,
        crop: CropChoice,
        kinds: &[FeatureKind],
    ) -> Result<Self> {
        let crop = crop.resolve(recording.grid());
        let config = FeatureConfig::combined(kinds);
        let image_grid = crop
            .output_grid(recording.grid())
            .with_context(|| format!("{name}: cannot crop"))?;
        let names = config
            .feature_names(image_grid)
            .with_context(|| format!("{name}: {image_grid} images"))?;
        Ok(Self {
            recording,
            name: name.to_owned(),
            crop,
            config,
            names,
        })
    }

    /// The feature vector of frame `index` (`None` past the end).
    pub fn row(&self, index: usize) -> Result<Option<Vec<f64>>> {
        let Some(frame) = self.recording.frame(index) else {
            return Ok(None);
        };
        extract_features(&frame, &self.crop, &self.config)
            .with_context(|| format!("{}: frame {index}", self.name))
            .map(Some)
    }
}
