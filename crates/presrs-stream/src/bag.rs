//! Recording a stream connection as a ROS 2 bag (MCAP, [`DecisionBag`]): the frames read and every
//! event the connection emitted, written as the connection runs and renamed into place
//! when it ends ([`BagRecorder::finish`]); a connection that fails or is dropped leaves no file behind.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{SystemTime, UNIX_EPOCH};

use presrs_core::Grid;
use presrs_io::IoError;
use presrs_io::mcap::{DecisionBag, ImageEncoding};

use presrs::error::Result;
use presrs::session::{NoObserver, SessionEvent, SessionObserver};

/// What a recorded bag holds.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RecordedBag {
    pub path: PathBuf,
    pub frames: u64,
    pub lines: u64,
    /// Where the frames' stamps came from (`None`: no frame).
    pub frame_times: Option<FrameTimes>,
}

/// The name of the metadata record that says where a recorded bag's times come from
/// ([`FRAME_TIMES_KEY`]).
pub const RECORDING_METADATA: &str = "presrs.recording";
/// The key of [`RECORDING_METADATA`] whose value is [`FrameTimes::as_str`].
pub const FRAME_TIMES_KEY: &str = "frame_times";

/// Where the stamps of a recorded bag's frames come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameTimes {
    /// The input's own frame times: a TekScan file's frame period, the given frame period, an MCAP
    /// input's stamps, a sender's timestamps.
    Input,
    /// The wall clock when each frame was read: the input states no frame times.
    WallClock,
    /// Some frames had their own times and others did not.
    Mixed,
}

impl FrameTimes {
    /// The metadata's words: `input`, `wall_clock`, `mixed`.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Input => "input",
            Self::WallClock => "wall_clock",
            Self::Mixed => "mixed",
        }
    }
}

impl RecordedBag {
    /// What was recorded, in a line: `recorded 205 frames and 12 lines to s.mcap (frame times: input)`.
    pub fn text(&self) -> String {
        let times = self.frame_times.map_or("none", FrameTimes::as_str);
        format!(
            "recorded {} frames and {} lines to {} (frame times: {times})",
            self.frames,
            self.lines,
            self.path.display()
        )
    }
}

/// What a server's connection bags tell their caller: the client's name and its bag (or why there is
/// none).
pub type BagReport = Arc<dyn Fn(&str, Result<RecordedBag>) + Send + Sync>;

/// One bag per connection of a server (`stream --listen --record OUT.mcap`): the N-th connection's is
/// `OUT-N.mcap` beside `OUT.mcap` (N from 1, in the order the clients connected), its metadata naming
/// the client; each is finished and reported when its connection ends.
pub struct ConnectionBags {
    path: PathBuf,
    connections: AtomicUsize,
    report: BagReport,
}

impl std::fmt::Debug for ConnectionBags {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ConnectionBags")
            .field("path", &self.path)
            .finish_non_exhaustive()
    }
}

impl ConnectionBags {
    /// Bags named after `path`, each reported to `report` when its connection ends.
    pub fn new(path: &Path, report: BagReport) -> Self {
        Self {
            path: path.to_path_buf(),
            connections: AtomicUsize::new(0),
            report,
        }
    }

    /// The bag of the `n`-th connection (from 1): `OUT-n.mcap`.
    pub fn path_of(&self, n: usize) -> PathBuf {
        let stem = self
            .path
            .file_stem()
            .map_or_else(|| "session".into(), |s| s.to_string_lossy().into_owned());
        let name = match self.path.extension() {
            Some(ext) => format!("{stem}-{n}.{}", ext.to_string_lossy()),
            None => format!("{stem}-{n}"),
        };
        self.path.with_file_name(name)
    }

    /// The observer of a new connection from `peer`: a bag being recorded (nothing when it cannot be
    /// created, which is reported at once).
    pub fn observer(&self, peer: &str) -> Box<dyn SessionObserver + Send> {
        let n = self.connections.fetch_add(1, Ordering::SeqCst) + 1;
        match BagRecorder::create(&self.path_of(n)) {
            Ok(recorder) => Box::new(ConnectionBag {
                recorder: Some(recorder.from_source(peer)),
                peer: peer.to_owned(),
                report: Arc::clone(&self.report),
            }),
            Err(err) => {
                (self.report)(peer, Err(err));
                Box::new(NoObserver)
            }
        }
    }
}

/// The bag of one server connection, finished when the connection ends.
struct ConnectionBag {
    recorder: Option<BagRecorder>,
    peer: String,
    report: BagReport,
}

impl SessionObserver for ConnectionBag {
    fn frame(
        &mut self,
        index: u64,
        grid: Grid,
        values: &[f64],
        present: Option<&[bool]>,
        timestamp_us: Option<u64>,
    ) {
        if let Some(recorder) = &mut self.recorder {
            recorder.frame(index, grid, values, present, timestamp_us);
        }
    }

    fn event(&mut self, event: &SessionEvent) -> bool {
        if let Some(recorder) = &mut self.recorder {
            recorder.event(event);
        }
        true
    }

    fn end(&mut self) {
        if let Some(recorder) = self.recorder.take() {
            (self.report)(&self.peer, recorder.finish());
        }
    }
}

/// A [`SessionObserver`] writing a bag. Frames are stamped with the input's own times when it gives them
/// (the TekScan frame period, MCAP stamps, the sender's timestamps), else the wall clock when they are
/// read; the bag's [`RECORDING_METADATA`] record says which. Each line is logged at the time of the
/// frame before it. A write that fails stops the recording; [`BagRecorder::finish`] then reports it.
pub struct BagRecorder {
    bag: DecisionBag,
    time_ns: u64,
    frames: u64,
    /// Frames stamped with the input's own time.
    timed: u64,
    lines: u64,
    failed: Option<IoError>,
    /// Who sent the frames (a client's address), for the metadata.
    source: Option<String>,
}

impl std::fmt::Debug for BagRecorder {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BagRecorder")
            .field("path", &self.bag.path())
            .field("frames", &self.frames)
            .field("lines", &self.lines)
            .finish_non_exhaustive()
    }
}

fn now_ns() -> u64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| u64::try_from(d.as_nanos()).unwrap_or(u64::MAX))
}

impl BagRecorder {
    /// Starts recording to `path` (a hidden temporary file beside it until [`Self::finish`]).
    pub fn create(path: &Path) -> Result<Self> {
        Ok(Self {
            bag: DecisionBag::create(path)?,
            time_ns: 0,
            frames: 0,
            timed: 0,
            lines: 0,
            failed: None,
            source: None,
        })
    }

    /// The recorder, its metadata naming `source` as the sender of the frames.
    #[must_use]
    pub fn from_source(mut self, source: &str) -> Self {
        self.source = Some(source.to_owned());
        self
    }

    /// Where the frames' stamps came from so far (`None` before the first frame).
    pub fn frame_times(&self) -> Option<FrameTimes> {
        match (self.frames, self.timed) {
            (0, _) => None,
            (_, 0) => Some(FrameTimes::WallClock),
            (all, timed) if timed == all => Some(FrameTimes::Input),
            _ => Some(FrameTimes::Mixed),
        }
    }

    /// Ends the bag (its summary and footer) and renames it into place; the first write error, if any,
    /// instead (and no file).
    pub fn finish(mut self) -> Result<RecordedBag> {
        if let Some(err) = self.failed {
            return Err(err.into());
        }
        let frame_times = self.frame_times();
        if let Some(times) = frame_times {
            let mut entries = std::collections::BTreeMap::new();
            entries.insert(FRAME_TIMES_KEY.to_owned(), times.as_str().to_owned());
            if let Some(source) = &self.source {
                entries.insert("source".to_owned(), source.clone());
            }
            self.bag.write_metadata(RECORDING_METADATA, entries)?;
        }
        Ok(RecordedBag {
            path: self.bag.finish()?,
            frames: self.frames,
            lines: self.lines,
            frame_times,
        })
    }

    fn keep(&mut self, written: std::result::Result<(), IoError>) {
        if let Err(err) = written {
            self.failed.get_or_insert(err);
        }
    }
}

impl SessionObserver for BagRecorder {
    fn frame(
        &mut self,
        _index: u64,
        grid: Grid,
        values: &[f64],
        _present: Option<&[bool]>,
        timestamp_us: Option<u64>,
    ) {
        if self.failed.is_some() {
            return;
        }
        self.time_ns = timestamp_us.map_or_else(now_ns, |us| us.saturating_mul(1000));
        self.timed += u64::from(timestamp_us.is_some());
        let encoding = ImageEncoding::for_values(values.iter());
        let written = self.bag.write_image(self.time_ns, grid, values, encoding);
        self.frames += 1;
        self.keep(written);
    }

    /// Logged at the time of the frame before it; a failed recording is reported by `finish`, not
    /// here (the session's output is not the bag).
    fn event(&mut self, event: &SessionEvent) -> bool {
        if self.failed.is_some() {
            return true;
        }
        let written = self.bag.write_json(self.time_ns, &event.to_line());
        self.lines += 1;
        self.keep(written);
        true
    }
}
