//! The bag `presrs stream --record` and `classify --mcap` write: a recording's frames on
//! [`FRAMES_TOPIC`] and the session's JSON events on [`DECISIONS_TOPIC`], in a hidden temporary file
//! that takes its name when it is finished (a run that fails leaves no file behind).

use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use presrs_core::Grid;

use super::writer::{BagWriter, ImageEncoding};
use crate::atomic::AtomicFile;
use crate::error::IoError;

/// The topic of the frames (`sensor_msgs/msg/Image`, `mono16` for integer counts, else `32FC1`).
pub const FRAMES_TOPIC: &str = "/presrs/frames";
/// The topic of the connection's JSON lines (`touchdown`, `classification`, `liftoff`, `error`, `end`),
/// JSON messages with the schema [`DECISIONS_SCHEMA`].
pub const DECISIONS_TOPIC: &str = "/presrs/decisions";
/// The schema name of [`DECISIONS_TOPIC`].
pub const DECISIONS_SCHEMA_NAME: &str = "presrs/Decision";

/// The JSON Schema of the decision lines (`docs/interface.md` describes each event's fields).
pub const DECISIONS_SCHEMA: &str = r#"{
  "title": "presrs decision",
  "description": "One JSON line of presrs stream: touchdown, classification, liftoff, error or end.",
  "type": "object",
  "properties": {
    "event": {"type": "string", "enum": ["touchdown", "classification", "liftoff", "error", "end"]},
    "file": {"type": "string", "description": "classify --mcap: the recording"},
    "kind": {"type": "string"},
    "stance": {"type": ["integer", "null"]},
    "frame": {"type": "integer"},
    "touchdown_frame": {"type": "integer"},
    "sample_frame": {"type": "integer"},
    "end_frame": {"type": "integer"},
    "peak_frame": {"type": "integer"},
    "peak_load": {"type": "number"},
    "len": {"type": "integer"},
    "partial": {"type": "boolean"},
    "sampled": {"type": "boolean"},
    "label": {"type": "string"},
    "class": {"type": "integer"},
    "confidence": {"type": "number"},
    "posteriors": {"type": "object", "additionalProperties": {"type": "number"}},
    "frames_used": {"type": "integer"},
    "decided_at": {"type": "string", "enum": ["liftoff", "offset", "length"], "description": "a whole-stance decision: what it waited for"},
    "decided_at_frame": {"type": "integer"},
    "cut": {"type": "boolean"},
    "latency_us": {"type": "number"},
    "timestamp_us": {"type": ["integer", "null"]},
    "gait": {"type": ["string", "null"]},
    "message": {"type": "string"},
    "fatal": {"type": "boolean"}
  },
  "required": ["event"]
}"#;

/// A bag with the frames and decisions topics, written to a hidden temporary file that takes its name
/// at [`DecisionBag::finish`]: what `stream --record` and `classify --mcap` write.
pub struct DecisionBag {
    bag: BagWriter<BufWriter<File>>,
    file: AtomicFile,
    frames_channel: u16,
    decisions_channel: u16,
}

impl std::fmt::Debug for DecisionBag {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("DecisionBag")
            .field("path", &self.file.path())
            .finish_non_exhaustive()
    }
}

impl DecisionBag {
    pub fn create(path: &Path) -> Result<Self, IoError> {
        let (file, handle) = AtomicFile::create(path)?;
        let name = crate::error::display_name(path);
        let mut bag = BagWriter::new(BufWriter::with_capacity(1 << 16, handle), &name)?;
        let frames_channel = bag.add_image_topic(FRAMES_TOPIC)?;
        let decisions_channel =
            bag.add_json_topic(DECISIONS_TOPIC, DECISIONS_SCHEMA_NAME, DECISIONS_SCHEMA)?;
        Ok(Self {
            bag,
            file,
            frames_channel,
            decisions_channel,
        })
    }

    pub fn path(&self) -> &Path {
        self.file.path()
    }

    pub fn write_image(
        &mut self,
        time_ns: u64,
        grid: Grid,
        values: &[f64],
        encoding: ImageEncoding,
    ) -> Result<(), IoError> {
        self.bag
            .write_image(self.frames_channel, time_ns, grid, values, encoding)
    }

    pub fn write_json(&mut self, time_ns: u64, line: &str) -> Result<(), IoError> {
        self.bag.write_json(self.decisions_channel, time_ns, line)
    }

    pub fn write_metadata(
        &mut self,
        name: &str,
        entries: std::collections::BTreeMap<String, String>,
    ) -> Result<(), IoError> {
        self.bag.write_metadata(name, entries)
    }

    /// Ends the bag (its summary and footer) and renames it into place; returns its path.
    pub fn finish(self) -> Result<PathBuf, IoError> {
        let path = self.file.path().to_path_buf();
        let buffered = self.bag.finish()?;
        buffered
            .into_inner()
            .map_err(|err| IoError::io("write", &path, err.into_error()))?;
        self.file.commit()?;
        Ok(path)
    }
}
