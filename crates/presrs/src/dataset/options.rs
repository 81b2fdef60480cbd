//! How a data set's samples are taken: their kind, which stance frames, the stance settings, and how
//! the manifest's recordings are read.

use presrs_core::dead_sensels::DeadSenselConfig;
use presrs_core::sample::{SampleChoice, SampleKind, Sampling};
use presrs_core::stance::{BaselineMode, SampleFrame, SegmentParams, ValidSegmentParams};
use presrs_io::ReadOptions;
use presrs_io::message::{Message, Opt, Warnings};

use crate::error::Error;

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
    /// Whole-stance samples are also made of each stance cut at these decision points (frames after
    /// touchdown: the first `K + 1` frames), for models that decide early ([`super::StanceCuts`]).
    pub decision_points: Vec<usize>,
    /// Frame samples at an offset `K` ([`SampleFrame::Offset`]) leave out the stances that lift off
    /// before frame `K` instead of refusing them: the one-frame model beside a decision point late
    /// in the stance (`eval --decide-at`), tested on the stances that reach it.
    pub skip_short_stances: bool,
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
            decision_points: Vec::new(),
            skip_short_stances: false,
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

/// The settings of one sample kind that a user gave (`None`: not given), judged against the sample
/// kind chosen by [`check_sample_settings`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GivenSampleSettings<'a> {
    /// Frames each whole stance is laid into (`--stance-length`, `stance_length=`).
    pub stance_length: Option<usize>,
    /// Which frame of each stance is a one-frame sample (`--stance-frame`).
    pub stance_frame: Option<SampleFrame>,
    /// The axis that is time in a series (`--series-axis`, `series_axis=`).
    pub series_axis: Option<&'a str>,
}

/// The settings given that do nothing with the sample kind chosen: a warning, or an error, per
/// setting. With `auto` every one is accepted: the race reads the data set both ways, the frame (which
/// the stance frame picks) and the whole sample (the stance length's or the series axis's).
///
/// - A stance length with a frame or series sample, and a series axis with a frame or stance sample,
///   are refused: Python's `Model.train` refuses `stance_length=` and `series_axis=` with another
///   sample kind, and a setting of the whole sample says the user meant a whole-sample model; training
///   a model of another kind than the one meant, without a word, is worse than stopping.
/// - A stance frame with a stance or series sample is a warning: the stance detector's settings are
///   shared by every kind, command lines are rerun switching only the sample kind to compare them,
///   and a whole stance uses every frame of it, so the model is the one asked for and only this
///   option is idle.
pub fn check_sample_settings(
    choice: SampleChoice,
    given: &GivenSampleSettings<'_>,
) -> crate::error::Result<Warnings> {
    let mut warnings = Warnings::new();
    let Some(kind) = choice.kind() else {
        return Ok(warnings);
    };
    let is_stance = matches!(kind, SampleKind::Stance { .. });
    let is_series = matches!(kind, SampleKind::Series { .. });
    let applies = |given: Message, to: &str| {
        given.text(format!(
            " applies to {to}, not to the {} sample chosen; leave it out, or choose ",
            kind.name()
        ))
    };
    if let (false, Some(length)) = (is_stance, given.stance_length) {
        return Err(Error::invalid(
            applies(
                Message::new().opt_is(Opt::StanceLength, length),
                "whole-stance samples",
            )
            .opt_text(Opt::Sample, "stance"),
        ));
    }
    if let (false, Some(axis)) = (is_series, given.series_axis) {
        return Err(Error::invalid(
            applies(
                Message::new().opt_text(Opt::SeriesAxis, axis),
                "series samples",
            )
            .opt_text(Opt::Sample, "series"),
        ));
    }
    if let (false, Some(frame)) = (kind.is_frame(), given.stance_frame) {
        warnings.push(Message::new().opt_is(Opt::StanceFrame, frame).text(format!(
            " picks one frame of each stance, but a {} sample uses {}: it changes nothing here",
            kind.name(),
            if is_stance {
                "every frame of the stance"
            } else {
                "the whole array"
            }
        )));
    }
    Ok(warnings)
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
