//! How a data set's samples are taken: their kind, which stance frames, the stance settings, and how
//! the manifest's recordings are read.

use presrs_core::dead_sensels::DeadSenselConfig;
use presrs_core::sample::{SampleKind, Sampling};
use presrs_core::stance::{BaselineMode, SampleFrame, SegmentParams, ValidSegmentParams};
use presrs_io::ReadOptions;

/// How samples are picked from movies.
#[derive(Clone, Debug)]
pub struct SampleOptions {
    /// A frame of each stance, or each stance whole.
    pub kind: SampleKind,
    /// Which frame(s) of each stance, for frame samples.
    pub sample: SampleFrame,
    pub segment: ValidSegmentParams,
    /// Also sample stances cut by the start or end of a recording.
    pub include_partial: bool,
    pub read: ReadOptions,
    /// Find dead sensels in each recording and fill them from their neighbours (the default, with
    /// the default thresholds); `None` keeps the recordings as read.
    pub dead_sensels: Option<DeadSenselConfig>,
    /// Every movie is one contact (a trial cut to one foot contact): one sample from each, whatever
    /// the segmentation would find (the stance is the whole recording, [`BaselineMode::Contact`]).
    pub one_sample_per_file: bool,
    /// Frame period, in seconds, of recordings whose format states none (a manifest's
    /// `frame_period_s` column overrides it per row).
    pub frame_period_s: Option<f64>,
}

impl Default for SampleOptions {
    fn default() -> Self {
        Self {
            kind: SampleKind::Frame,
            sample: SampleFrame::default(),
            segment: ValidSegmentParams::default(),
            include_partial: false,
            read: ReadOptions::default(),
            dead_sensels: Some(DeadSenselConfig::default()),
            one_sample_per_file: false,
            frame_period_s: None,
        }
    }
}

impl SampleOptions {
    /// The segmentation settings a row uses: the whole recording as one contact with
    /// [`Self::one_sample_per_file`], else [`Self::segment`].
    pub fn segment_params(&self) -> ValidSegmentParams {
        if !self.one_sample_per_file {
            return self.segment.clone();
        }
        let params = SegmentParams {
            baseline: BaselineMode::Contact,
            ..self.segment.params().clone()
        };
        // Only the mode changed, and every mode is valid with valid settings.
        params.check().unwrap_or_else(|_| self.segment.clone())
    }

    /// Whether stances cut by the recording are sampled (always with one sample per file).
    pub fn include_partial(&self) -> bool {
        self.include_partial || self.one_sample_per_file
    }
}

impl SampleOptions {
    /// How these options take samples from recordings, as a model stores it.
    pub fn sampling(&self) -> Sampling {
        Sampling {
            segment: self.segment.clone(),
            one_sample_per_file: self.one_sample_per_file,
            stance_frame: self.sample,
            include_partial: self.include_partial,
        }
    }

    /// These options with a model's `sampling` in place of the settings left at their defaults: the
    /// stance detector's settings (unless some were given, which then apply with
    /// [`Self::one_sample_per_file`] as given), one sample per file, the stance frame, partial
    /// stances. So a model trained on one-contact trials classifies such a trial as it was trained.
    pub fn or_model(&self, sampling: &Sampling) -> Self {
        let default = Self::default();
        let mut options = self.clone();
        if self.segment == default.segment && !self.one_sample_per_file {
            options.segment = sampling.segment.clone();
            options.one_sample_per_file = sampling.one_sample_per_file;
        }
        if self.sample == default.sample {
            options.sample = sampling.stance_frame;
        }
        options.include_partial |= sampling.include_partial;
        options
    }
}
