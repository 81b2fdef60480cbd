//! One image and what is known about it: the one sample type of presrs (a data set's samples, the
//! simulator's stances, the report's images). Algorithms read it through the borrowed view
//! [`LabeledImage`](crate::pipeline::LabeledImage).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use crate::error::{CoreError, Result};
use crate::frame::{Frame, FrameView, Grid};
use crate::stance::offline::{SampleFrame, ValidSegmentParams};
use crate::stance::summary::{SummaryConfig, pad_to, summarise};

/// What one sample of a movie is.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum SampleKind {
    /// One frame of each stance (which one is the data set's choice): the paper's sample.
    #[default]
    Frame,
    /// Each stance's movie, summarised as channels over time
    /// ([`crate::stance::summary`]), in the recording's own time, padded with zeros after lift-off to
    /// `length` frames (by default the longest stance of the set); a longer stance is cut to its first
    /// `length` frames, with a warning.
    Stance {
        summary: SummaryConfig,
        /// Fixed once a model is trained (the length its features take).
        #[serde(default)]
        length: Option<usize>,
    },
    /// A 2-D array read as channels x time (taxels over time): rows are channels, or columns with
    /// `time_in_rows`. One-frame files only.
    Series { time_in_rows: bool },
}

impl SampleKind {
    /// The kind named `frame`, `stance` or `series`; `stance_length` applies to stances, `series_axis`
    /// (`cols`, the default, or `rows`: the axis that is time) to series. The error lists the names.
    pub fn parse(
        name: &str,
        stance_length: Option<usize>,
        series_axis: Option<&str>,
    ) -> std::result::Result<Self, String> {
        let time_in_rows = time_in_rows(series_axis)?;
        let kind = name.parse::<Self>()?;
        kind.with_settings(stance_length, time_in_rows)
    }

    /// This kind with the settings given for it: `stance_length` for a stance (at least one frame),
    /// `time_in_rows` for a series; the other kinds ignore them.
    pub fn with_settings(
        self,
        stance_length: Option<usize>,
        time_in_rows: bool,
    ) -> std::result::Result<Self, String> {
        match self {
            Self::Frame => Ok(Self::Frame),
            Self::Stance { .. } if stance_length == Some(0) => {
                Err("a stance length must be at least one frame".to_owned())
            }
            Self::Stance { summary, .. } => Ok(Self::Stance {
                summary,
                length: stance_length,
            }),
            Self::Series { .. } => Ok(Self::Series { time_in_rows }),
        }
    }

    /// The sample of this kind made from a recording's `frames`, as a model of this kind takes it: a
    /// frame sample is its one frame; a series, its one 2-D array with the channels in rows (transposed
    /// when time runs down the rows); a stance, the summary of its frames, touchdown to lift-off
    /// ([`summarise`]), laid into `length` frames when given ([`pad_to`]: zeros after lift-off, or
    /// the first `length` frames of a longer stance). Also says whether the stance was cut.
    pub fn sample_of(
        &self,
        frames: &[FrameView<'_>],
        length: Option<usize>,
    ) -> Result<(Frame, bool)> {
        let one = || match frames {
            [frame] => Ok(frame),
            _ => Err(CoreError::Param {
                name: "sample",
                reason: format!(
                    "a {} sample is one 2-D array, got {} frames",
                    self.name(),
                    frames.len()
                ),
            }),
        };
        match self {
            Self::Frame
            | Self::Series {
                time_in_rows: false,
            } => Ok((one()?.to_frame(), false)),
            Self::Series { time_in_rows: true } => Ok((one()?.transposed(), false)),
            Self::Stance { summary, .. } => {
                let stance = summarise(frames, summary)?;
                match length {
                    Some(length) => pad_to(&stance.view(), length),
                    None => Ok((stance, false)),
                }
            }
        }
    }
}

/// Whether a series' time runs down the rows: `series_axis` is `cols` (the default) or `rows`.
fn time_in_rows(series_axis: Option<&str>) -> std::result::Result<bool, String> {
    match series_axis.map(str::trim) {
        None | Some("cols") => Ok(false),
        Some("rows") => Ok(true),
        Some(other) => Err(format!("unknown series axis {other:?}; known: cols, rows")),
    }
}

impl FromStr for SampleKind {
    type Err = String;

    /// The kind named `frame`, `stance` or `series`, with the default settings. The error lists the
    /// names.
    fn from_str(name: &str) -> std::result::Result<Self, String> {
        match name.trim() {
            "frame" => Ok(Self::Frame),
            "stance" => Ok(Self::Stance {
                summary: SummaryConfig::default(),
                length: None,
            }),
            "series" => Ok(Self::Series {
                time_in_rows: false,
            }),
            other => Err(format!(
                "unknown sample kind {other:?}; known: frame, stance, series"
            )),
        }
    }
}

/// What sample a data set is read into: one kind, or `auto`, one frame raced against the whole sample
/// by validation inside the training data (as the `auto` of `presrs`'s feature and classifier choices
/// chooses a family).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SampleChoice {
    Auto,
    Kind(SampleKind),
}

impl Default for SampleChoice {
    fn default() -> Self {
        Self::Kind(SampleKind::Frame)
    }
}

impl SampleChoice {
    /// The names a choice is given by, the kinds first.
    pub const NAMES: [&'static str; 4] = ["frame", "stance", "series", "auto"];

    /// `auto`, or the kind [`SampleKind::parse`] reads (the settings apply to a named kind).
    pub fn parse(
        name: &str,
        stance_length: Option<usize>,
        series_axis: Option<&str>,
    ) -> std::result::Result<Self, String> {
        match name.parse::<Self>()? {
            Self::Auto => Ok(Self::Auto),
            Self::Kind(kind) => {
                let time_in_rows = time_in_rows(series_axis)?;
                kind.with_settings(stance_length, time_in_rows)
                    .map(Self::Kind)
            }
        }
    }

    /// This choice with the settings of [`SampleKind::with_settings`] (`auto` keeps its own: the whole
    /// sample it races is configured apart).
    pub fn with_settings(
        self,
        stance_length: Option<usize>,
        time_in_rows: bool,
    ) -> std::result::Result<Self, String> {
        match self {
            Self::Auto => Ok(Self::Auto),
            Self::Kind(kind) => kind
                .with_settings(stance_length, time_in_rows)
                .map(Self::Kind),
        }
    }

    /// Whether the kind is raced.
    pub fn is_auto(&self) -> bool {
        *self == Self::Auto
    }

    /// The kind named, `None` for `auto`.
    pub fn kind(&self) -> Option<SampleKind> {
        match self {
            Self::Auto => None,
            Self::Kind(kind) => Some(*kind),
        }
    }

    /// The name (`auto`, or the kind's).
    pub fn name(&self) -> &'static str {
        match self {
            Self::Auto => "auto",
            Self::Kind(kind) => kind.name(),
        }
    }
}

impl FromStr for SampleChoice {
    type Err = String;

    /// `auto`, or a kind named with its default settings. The error lists the names.
    fn from_str(name: &str) -> std::result::Result<Self, String> {
        if name.trim() == "auto" {
            return Ok(Self::Auto);
        }
        SampleKind::from_str(name)
            .map(Self::Kind)
            .map_err(|err| err.replacen("; known: ", "; known: auto, ", 1))
    }
}

impl SampleKind {
    /// Whether this is the paper's sample, one frame.
    pub fn is_frame(&self) -> bool {
        *self == Self::Frame
    }

    /// The name (`frame`, `stance`, `series`).
    pub fn name(&self) -> &'static str {
        match self {
            Self::Frame => "frame",
            Self::Stance { .. } => "stance",
            Self::Series { .. } => "series",
        }
    }

    /// What samples of this kind are called in text, in the plural: `images`, `stances`, `series`.
    pub fn nouns(&self) -> &'static str {
        match self {
            Self::Frame => "images",
            Self::Stance { .. } => "stances",
            Self::Series { .. } => "series",
        }
    }

    /// A sample's `grid` in this kind's own terms: `63x33 image`, `12 channels x 83 frames` (a stance's
    /// summary: channels over the frames of the stance), `8 channels x 100 time steps` (a series).
    pub fn shape_text(&self, grid: crate::frame::Grid) -> String {
        match self {
            Self::Frame => format!("{grid} image"),
            Self::Stance { .. } => format!("{} channels x {} frames", grid.rows, grid.cols),
            Self::Series { .. } => format!("{} channels x {} time steps", grid.rows, grid.cols),
        }
    }
}

/// How a model's training samples were taken from their recordings, stored in the model: the faces
/// that take samples from recordings (`presrs classify`) take them the same way unless told otherwise.
/// Absent from models trained on samples made in memory and from files written before it was stored.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sampling {
    /// The stance detector's settings (baseline mode, levels, lengths, gaps).
    pub segment: ValidSegmentParams,
    /// Every recording was one contact, its whole length the stance (`--one-sample-per-file`).
    pub one_sample_per_file: bool,
    /// Which frame of each stance was a frame sample.
    pub stance_frame: SampleFrame,
    /// Stances cut by the start or end of a recording were sampled too.
    pub include_partial: bool,
}

/// Why a frame or series of `got` cannot be a sample of a model trained on `sensor` (the grid its
/// training recordings' frames had, or its series'), as a frame model refuses a wrong image size;
/// `None` when it fits (or the model does not say).
pub fn sensor_mismatch(kind: &SampleKind, sensor: Option<Grid>, got: Grid) -> Option<CoreError> {
    let sensor = sensor.filter(|&sensor| sensor != got)?;
    let (what, expected) = match kind {
        SampleKind::Frame => return None,
        SampleKind::Stance { .. } => (
            "stance frame",
            format!("{sensor} frames, the sensor this whole-stance model was trained on"),
        ),
        SampleKind::Series { .. } => (
            "series",
            format!(
                "{sensor} ({} channel{} x {} time steps), the series this model was trained on",
                sensor.rows,
                if sensor.rows == 1 { "" } else { "s" },
                sensor.cols
            ),
        ),
    };
    Some(CoreError::Shape {
        what,
        expected,
        got: got.to_string(),
    })
}

/// One image and what is known about it.
#[derive(Clone, Debug)]
pub struct Sample {
    pub frame: Frame,
    /// The terrain (class) name.
    pub label: Option<String>,
    /// The operating condition it was recorded in (a gait, a load).
    pub condition: Option<String>,
    /// The trial, subject or session it belongs to.
    pub group: Option<String>,
    /// Body mass or load, kg, when known.
    pub load: Option<f64>,
    /// The file (or trial) it came from, and its 0-based frame index there.
    pub source: PathBuf,
    pub frame_index: usize,
    /// The 1-based manifest line that described it, when a manifest did.
    pub line: Option<usize>,
    /// The manifest row's fields as written, by column name (`path`, `label`, `condition`, `group`,
    /// `frame`, `load` and the extra columns; empty fields left out).
    pub columns: BTreeMap<String, String>,
}

impl Sample {
    /// A sample that no manifest describes.
    pub fn new(
        frame: Frame,
        label: impl Into<String>,
        source: PathBuf,
        frame_index: usize,
    ) -> Self {
        Self {
            frame,
            label: Some(label.into()),
            condition: None,
            group: None,
            load: None,
            source,
            frame_index,
            line: None,
            columns: BTreeMap::new(),
        }
    }

    /// The value of a column for this sample, as written in its manifest row (`path`, `label`,
    /// `condition`, `group`, `frame`, `load`, or an extra column); `None` when the field is empty. So
    /// `--leave-one-out path` holds out one recording at a time. Without a manifest row: label,
    /// condition, group and the source's path.
    pub fn column(&self, name: &str) -> Option<&str> {
        if self.line.is_some() {
            return self.columns.get(name).map(String::as_str);
        }
        match name {
            "path" => self.source.to_str(),
            "label" => self.label.as_deref(),
            "condition" => self.condition.as_deref(),
            "group" => self.group.as_deref(),
            _ => None,
        }
    }

    /// Where it was described, for messages: `manifest.csv line 4`, or the source and frame.
    pub fn origin(&self, manifest: &Path) -> String {
        match self.line {
            Some(line) => format!("{} line {line}", manifest.display()),
            None => format!("{} frame {}", self.source.display(), self.frame_index),
        }
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;
    use crate::frame::Grid;

    #[test]
    fn sample_choices_are_auto_or_a_kind_with_its_settings() {
        assert_eq!(" auto".parse::<SampleChoice>(), Ok(SampleChoice::Auto));
        assert_eq!(
            SampleChoice::parse("series", None, Some("rows")),
            Ok(SampleChoice::Kind(SampleKind::Series {
                time_in_rows: true
            }))
        );
        assert_eq!(
            SampleChoice::parse("auto", Some(0), Some("rows")),
            Ok(SampleChoice::Auto)
        );
        let stance = "stance".parse::<SampleChoice>().unwrap();
        assert_eq!(
            stance.with_settings(Some(40), false).unwrap().kind(),
            SampleKind::parse("stance", Some(40), None).ok()
        );
        assert!(stance.with_settings(Some(0), false).is_err());
        let err = "movie".parse::<SampleChoice>().unwrap_err();
        assert_eq!(
            err,
            "unknown sample kind \"movie\"; known: auto, frame, stance, series"
        );
        assert_eq!(
            SampleKind::parse("auto", None, None).unwrap_err(),
            "unknown sample kind \"auto\"; known: frame, stance, series"
        );
        assert!(SampleKind::parse("frame", None, Some("time")).is_err());
    }

    #[test]
    fn a_sample_is_made_the_one_way_for_each_kind() {
        let values = (0..48).map(f64::from).collect();
        let image = Frame::new(Grid::new(8, 6), values).unwrap();
        let one = [image.view()];
        let (frame, cut) = SampleKind::Frame.sample_of(&one, None).unwrap();
        assert_eq!((frame, cut), (image.clone(), false));
        let series = SampleKind::Series { time_in_rows: true };
        let (frame, _) = series.sample_of(&one, None).unwrap();
        assert_eq!(frame, image.view().transposed());
        assert!(SampleKind::Frame.sample_of(&[], None).is_err());
        let stance = SampleKind::Stance {
            summary: SummaryConfig::default(),
            length: None,
        };
        let movie = [image.view(), image.view(), image.view()];
        let (whole, cut) = stance.sample_of(&movie, None).unwrap();
        assert_eq!((whole.grid().cols, cut), (3, false));
        let (short, cut) = stance.sample_of(&movie, Some(2)).unwrap();
        assert_eq!((short.grid().cols, cut), (2, true));
        let (long, cut) = stance.sample_of(&movie, Some(5)).unwrap();
        assert_eq!((long.grid().cols, cut), (5, false));
    }
}
