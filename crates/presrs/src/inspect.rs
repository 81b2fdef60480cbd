//! What a recording file holds: sensor, size, frames, period, units, load, dead sensels and the stance
//! phases found.

use std::path::Path;

use presrs_core::dead_sensels::{DeadSensel, DeadSenselConfig, correctable, detect_dead_sensels};
use presrs_core::stance::{
    BaselineMode, SegmentParams, Segmentation, Stance, sample_frames, segment_recording,
};
use presrs_io::mcap::list_topics;
use presrs_io::{IoError, read_recording_with};
use serde::Serialize;

use crate::dataset::{SampleOptions, apply_frame_period_option};
use crate::error::{Error, Result};
use presrs_io::message::Warnings;

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

/// One topic of an MCAP file.
#[derive(Debug, Serialize)]
pub struct TopicReport {
    pub topic: String,
    /// The message type (schema name), e.g. `sensor_msgs/msg/Image`.
    #[serde(rename = "type")]
    pub schema: String,
    pub messages: u64,
    /// Whether presrs reads frames from it.
    pub frames: bool,
}

#[derive(Debug, Serialize)]
pub struct InspectReport {
    pub file: String,
    /// An MCAP file's topics (empty for other formats), and the one described.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub topics: Vec<TopicReport>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub topic: Option<String>,
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
    /// What the stances were measured from: drifting, floor or contact (see `--stance-baseline`).
    pub stance_mode: BaselineMode,
    /// Why that mode, when it was chosen automatically and is not the drifting baseline.
    pub stance_mode_reason: Option<String>,
    /// The level each frame's load was measured from (the baseline, or the local floor).
    pub stance_floor: Vec<f64>,
    pub stances: Vec<StanceReport>,
    /// Why a recording that carries load gave no stance, or suspiciously few, with the option to try.
    pub stance_notes: Vec<String>,
    pub warnings: Warnings,
}

/// Reads `path` as `options` say and describes it (the stance sample frame is `options.sample`; dead
/// sensels are reported, and said to be filled unless `options.dead_sensels` is `None`).
///
/// An MCAP file's topics are listed; the one described is `options.read.topic`, else the first topic
/// holding frames (where the other commands ask for one when there are several).
pub fn inspect(path: &Path, options: &SampleOptions) -> Result<InspectReport> {
    let mut read = options.read.clone();
    let mut topics = Vec::new();
    if presrs_io::is_mcap_file(path)? {
        let file = std::fs::File::open(path).map_err(|source| IoError::io("read", path, source))?;
        let listed = list_topics(
            std::io::BufReader::new(file),
            &presrs_io::error::display_name(path),
        )?;
        if read.topic.is_none() {
            read.topic = listed
                .iter()
                .find(|t| t.has_frames())
                .map(|t| t.topic.clone());
        }
        topics = listed
            .into_iter()
            .map(|t| TopicReport {
                frames: t.has_frames(),
                topic: t.topic,
                schema: t.schema,
                messages: t.messages,
            })
            .collect();
    }
    let mut parsed = read_recording_with(path, &read)?;
    apply_frame_period_option(&mut parsed.recording, options.frame_period_s)?;
    let recording = &parsed.recording;
    let totals = recording.total_per_frame();
    let segmentation = segment_recording(recording, &options.segment_params())
        .map_err(|err| Error::data(format!("{}: cannot segment: {err}", path.display())))?;
    let stance_notes = stance_notes(&totals, &segmentation, options);
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
        topics,
        topic: read.topic,
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
        stance_mode: segmentation.mode,
        stance_mode_reason: segmentation.mode_reason.clone(),
        stance_floor: segmentation.baseline.clone(),
        stances,
        stance_notes,
        warnings: parsed.warnings,
    })
}

impl InspectReport {
    /// What train, eval, classify, features and report do with the dead sensels, in the command
    /// line's words.
    pub fn dead_sensels_treatment(&self) -> String {
        if self.dead_sensels_filled {
            "filled from their neighbours in every frame when train, eval, classify, features or \
         report read this file (--keep-dead-sensels: as read)"
                .to_owned()
        } else if self.frames < presrs_core::dead_sensels::DeadSenselConfig::default().min_frames {
            format!(
                "not filled: {} frame(s) cannot tell a dead sensel from a gap in the terrain \
             (movies of 3 frames or more are corrected)",
                self.frames
            )
        } else {
            "kept as read (--keep-dead-sensels)".to_owned()
        }
    }
}

impl StanceReport {
    /// `no`, `yes`, or `both ends` for a stance that is the whole recording of `frames` frames.
    pub fn partial_text(&self, frames: usize) -> &'static str {
        match (self.partial, self.start == 0 && self.len == frames) {
            (false, _) => "no",
            (true, false) => "yes",
            (true, true) => "both ends",
        }
    }
}

/// A total load for the table: whole numbers as they are (raw counts), others to a precision that
/// fits their size (a float image's sum has a dozen meaningless decimals).
pub fn load_text(load: f64) -> String {
    if load.fract() == 0.0 || !load.is_finite() {
        format!("{load}")
    } else if load.abs() >= 100.0 {
        format!("{load:.1}")
    } else {
        format!("{load:.4}")
    }
}

/// A stance covering more than this fraction of a recording of several times its length is suspicious
/// in the drifting mode: a foot that never unloads.
const LONG_STANCE_FRACTION: f64 = 0.5;

/// Why a recording that carries load gave no sample, or suspiciously few stances, and what to try.
fn stance_notes(
    totals: &[f64],
    segmentation: &Segmentation,
    options: &SampleOptions,
) -> Vec<String> {
    let mut notes = Vec::new();
    let n = totals.len();
    let lowest = totals.iter().copied().fold(f64::INFINITY, f64::min);
    let highest = totals.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if n < 2 || highest <= lowest {
        return notes;
    }
    let sampled = segmentation
        .stances
        .iter()
        .filter(|stance| options.include_partial() || !stance.partial)
        .count();
    let mode = segmentation.mode;
    if segmentation.stances.is_empty() {
        let others: Vec<&str> = [
            (BaselineMode::Floor, "floor (presses on a preload)"),
            (
                BaselineMode::Contact,
                "contact (one contact from the first frame to the last)",
            ),
        ]
        .into_iter()
        .filter(|(other, _)| *other != mode)
        .map(|(_, text)| text)
        .collect();
        notes.push(format!(
            "the load varies ({lowest} .. {highest}) but no stance was found measuring from the {} \
             (on level {:.1} above it): try --stance-baseline {}, or a lower --stance-threshold",
            mode_noun(mode),
            segmentation.on_level,
            others.join(" or ")
        ));
    } else if sampled == 0 && mode == BaselineMode::Contact {
        notes.push(
            "the recording is one contact from its first frame to its last: its stance is partial \
             at both ends and gives no sample without --include-partial (--one-sample-per-file for \
             a data set of such trials)"
                .to_owned(),
        );
    } else if sampled == 0 {
        notes.push(
            "every stance found is cut by the start or end of the recording: it gives no sample \
             without --include-partial"
                .to_owned(),
        );
    }
    if mode == BaselineMode::Drifting
        && let Some(long) = segmentation
            .stances
            .iter()
            .find(|stance| stance.len as f64 > LONG_STANCE_FRACTION * n as f64)
        && segmentation.stances.len() <= 2
        && n >= 4 * options.segment.params().min_stance_frames
        && looks_like_a_preload(long, totals, segmentation, options)
    {
        notes.push(format!(
            "{} stance(s) only, one covering {} of {n} frames: if the foot never unloads (a standing \
             preload with presses on top), try --stance-baseline floor",
            segmentation.stances.len(),
            long.len
        ));
    }
    notes
}

/// Whether a long stance found from the drifting baseline looks like presses on a standing preload,
/// which the local floor tells apart: the foot is never seen unloaded (the stance is cut by the
/// recording), or the floor finds more than twice the stances. A clean single step (unloaded before
/// and after one contact) is neither: the floor splits it at most into its heel and forefoot loads, and
/// the floor is no advice for it.
fn looks_like_a_preload(
    long: &Stance,
    totals: &[f64],
    segmentation: &Segmentation,
    options: &SampleOptions,
) -> bool {
    if long.partial {
        return true;
    }
    let floor = SegmentParams {
        baseline: BaselineMode::Floor,
        ..options.segment.params().clone()
    };
    floor
        .check()
        .and_then(|params| presrs_core::stance::segment(totals, &params))
        .is_ok_and(|floor| floor.stances.len() > 2 * segmentation.stances.len())
}

fn mode_noun(mode: BaselineMode) -> &'static str {
    match mode {
        BaselineMode::Floor => "local floor",
        BaselineMode::Contact => "zero level",
        BaselineMode::Auto | BaselineMode::Drifting => "baseline",
    }
}
