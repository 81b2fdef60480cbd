//! One image and what is known about it: the one sample type of presrs (a data set's samples, the
//! simulator's stances, the report's images). Algorithms read it through the borrowed view
//! [`LabeledImage`](crate::pipeline::LabeledImage).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::frame::Frame;
use crate::stance::summary::SummaryConfig;

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
        let time_in_rows = match series_axis.map(str::trim) {
            None | Some("cols") => false,
            Some("rows") => true,
            Some(other) => return Err(format!("unknown series axis {other:?}; known: cols, rows")),
        };
        match name.trim() {
            "frame" => Ok(Self::Frame),
            "stance" if stance_length == Some(0) => {
                Err("a stance length must be at least one frame".to_owned())
            }
            "stance" => Ok(Self::Stance {
                summary: SummaryConfig::default(),
                length: stance_length,
            }),
            "series" => Ok(Self::Series { time_in_rows }),
            other => Err(format!(
                "unknown sample kind {other:?}; known: frame, stance, series"
            )),
        }
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
