//! What a recording file holds: sensor, size, frames, period, units, load, dead sensels and the stance
//! phases found.

use std::path::Path;

use presrs_core::dead_sensels::{DeadSensel, DeadSenselConfig, correctable, detect_dead_sensels};
use presrs_core::stance::{ValidSegmentParams, sample_frames, segment_recording};
use presrs_io::read_recording_with;
use serde::Serialize;

use crate::dataset::SampleOptions;
use crate::error::{Error, Result};

#[derive(Debug, Serialize)]
pub struct StanceReport {
    pub start: usize,
    pub len: usize,
    pub peak_load: f64,
    pub peak_frame: usize,
    /// The frame used as this stance's sample (`--stance-frame`; the first one for `all`).
    pub sample_frame: Option<usize>,
    pub partial: bool,
}

#[derive(Debug, Serialize)]
pub struct InspectReport {
    pub file: String,
    pub sensor: Option<String>,
    pub rows: usize,
    pub cols: usize,
    pub frames: usize,
    pub frame_period_s: Option<f64>,
    /// The unit of the values: the file's, or `raw` when it states none (`units_stated` false).
    pub units: String,
    pub units_stated: bool,
    pub row_pitch_mm: Option<f64>,
    pub col_pitch_mm: Option<f64>,
    pub absent_sensels: usize,
    /// Present sensels that read 0 in every frame while their neighbours carry load
    /// ([`presrs_core::dead_sensels`]), 0-based.
    pub dead_sensels: Vec<DeadSensel>,
    /// Whether train, eval, classify, features and report fill those sensels from their neighbours
    /// when they read this file: yes unless `--keep-dead-sensels`, and only in a recording of at least
    /// three frames (one image is not evidence enough).
    pub dead_sensels_filled: bool,
    /// Smallest and largest total load of a frame (sum of sensel values, in `units`).
    pub load_min: f64,
    pub load_max: f64,
    /// The same as a force in newtons, when the unit is a pressure and the sensel pitch is known (what
    /// `plot --movie` and the report draw).
    pub force_min_n: Option<f64>,
    pub force_max_n: Option<f64>,
    pub baseline_noise: f64,
    pub stances: Vec<StanceReport>,
    pub warnings: Vec<String>,
}

/// Reads `path` as `options` say and describes it (the stance sample frame is `options.sample`; dead
/// sensels are reported, and said to be filled unless `options.dead_sensels` is `None`).
pub fn inspect(path: &Path, options: &SampleOptions) -> Result<InspectReport> {
    let parsed = read_recording_with(path, &options.read)?;
    let recording = &parsed.recording;
    let totals = recording.total_per_frame();
    let segmentation = segment_recording(recording, &ValidSegmentParams::default())
        .map_err(|err| Error::data(format!("{}: cannot segment: {err}", path.display())))?;
    let stances = segmentation
        .stances
        .iter()
        .map(|stance| StanceReport {
            start: stance.start,
            len: stance.len,
            peak_load: stance.peak_load,
            peak_frame: stance.peak_frame,
            sample_frame: sample_frames(stance, options.sample)
                .ok()
                .and_then(|frames| frames.first().copied()),
            partial: stance.partial,
        })
        .collect();
    let grid = recording.grid();
    let dead_config = DeadSenselConfig::default();
    let dead_sensels = detect_dead_sensels(recording, &dead_config);
    let newtons = presrs_report::PressureScale::from_meta(Some(&recording.meta)).newtons_per_unit();
    let (load_min, load_max) = (
        totals.iter().copied().fold(f64::INFINITY, f64::min),
        totals.iter().copied().fold(f64::NEG_INFINITY, f64::max),
    );
    let dead_sensels_filled = !dead_sensels.is_empty()
        && options.dead_sensels.is_some()
        && correctable(recording.frame_count(), &dead_config);
    Ok(InspectReport {
        file: path.display().to_string(),
        sensor: recording.meta.sensor.clone(),
        rows: grid.rows,
        cols: grid.cols,
        frames: recording.frame_count(),
        frame_period_s: recording.frame_period_s(),
        units: recording.meta.units_or_raw().to_string(),
        units_stated: recording.meta.units.is_some(),
        row_pitch_mm: recording.meta.row_pitch_mm,
        col_pitch_mm: recording.meta.col_pitch_mm,
        absent_sensels: recording
            .present()
            .map_or(0, |mask| mask.iter().filter(|&&here| !here).count()),
        dead_sensels,
        dead_sensels_filled,
        load_min,
        load_max,
        force_min_n: newtons.map(|n| load_min * n),
        force_max_n: newtons.map(|n| load_max * n),
        baseline_noise: segmentation.noise,
        stances,
        warnings: parsed.warnings,
    })
}
