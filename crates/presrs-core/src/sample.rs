//! One image and what is known about it: the one sample type of presrs (a data set's samples, the
//! simulator's stances, the report's images). Algorithms read it through the borrowed view
//! [`LabeledImage`](crate::pipeline::LabeledImage).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use crate::frame::Frame;

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
