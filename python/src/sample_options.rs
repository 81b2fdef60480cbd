//! How `presrs.evaluate` reads a manifest's samples: its keyword arguments (`stance_frame=`,
//! `one_sample_per_file=`, `segment_params=`, ...) as the library's `SampleOptions`, the settings
//! `presrs eval` takes as flags (`--stance-frame`, `--one-sample-per-file`, the `--stance-*` options).

use presrs::SampleOptions;
use presrs::core::dead_sensels::DeadSenselConfig;
use presrs::core::stance::SampleFrame;
use presrs::io::ReadOptions;
use presrs::{SampleKind, train::sample_race::WholeSample};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::data_error;
use crate::recording::{array_axes, sample_frame, segment_params_from};

/// The keyword arguments of how a manifest's files are read and sampled.
pub struct ManifestSampling<'py> {
    /// Which frame of each stance is a frame sample (`"mid"`, `"peak"`, `"all"`, or `K`).
    pub stance_frame: Option<Bound<'py, PyAny>>,
    pub include_partial: bool,
    pub one_sample_per_file: bool,
    pub lenient: bool,
    pub axes: Option<String>,
    pub topic: Option<String>,
    pub frame_period_s: Option<f64>,
    pub keep_dead_sensels: bool,
    /// The stance detector's parameters, by `presrs.segment_params()`'s names.
    pub segment_params: Option<Bound<'py, PyDict>>,
}

impl ManifestSampling<'_> {
    /// The first of these arguments that was given, if any (they read files: arrays in memory are
    /// samples already).
    pub fn first_given(&self) -> Option<&'static str> {
        [
            ("stance_frame", self.stance_frame.is_some()),
            ("include_partial", self.include_partial),
            ("one_sample_per_file", self.one_sample_per_file),
            ("lenient", self.lenient),
            ("axes", self.axes.is_some()),
            ("topic", self.topic.is_some()),
            ("frame_period_s", self.frame_period_s.is_some()),
            ("keep_dead_sensels", self.keep_dead_sensels),
            ("segment_params", self.segment_params.is_some()),
        ]
        .into_iter()
        .find_map(|(name, given)| given.then_some(name))
    }

    /// The library's options for samples of `kind`, each argument checked (an error names it).
    pub fn options(&self, kind: SampleKind) -> PyResult<SampleOptions> {
        if let Some(seconds) = self.frame_period_s
            && !(seconds.is_finite() && seconds > 0.0)
        {
            return Err(data_error(format!(
                "frame_period_s={seconds}: give a positive number of seconds"
            )));
        }
        let sample = match &self.stance_frame {
            Some(frame) => sample_frame(Some(frame), "stance_frame")?,
            None => SampleFrame::default(),
        };
        Ok(SampleOptions {
            kind,
            sample,
            segment: segment_params_from(self.segment_params.as_ref(), "segment_params")?,
            include_partial: self.include_partial,
            read: ReadOptions {
                lenient: self.lenient,
                axes: array_axes(self.axes.as_deref())?,
                topic: self.topic.clone(),
            },
            dead_sensels: (!self.keep_dead_sensels).then(DeadSenselConfig::default),
            one_sample_per_file: self.one_sample_per_file,
            frame_period_s: self.frame_period_s,
            decision_points: Vec::new(),
            skip_short_stances: false,
        })
    }
}

/// The whole sample `sample="auto"` races against one frame: `stance_length=` and
/// `series_axis="rows"` (checked by `crate::model::sample_choice`).
pub fn whole_sample(stance_length: Option<usize>, series_axis: Option<&str>) -> WholeSample {
    WholeSample {
        stance_length,
        time_in_rows: series_axis.map(str::trim) == Some("rows"),
    }
}
