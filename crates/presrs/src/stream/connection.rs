//! One connection: frames from a source through the causal classifier, JSON lines to a sink.

use std::io::{BufRead, Read, Write};
use std::time::Instant;

use presrs_core::online::{OnlineClassifier, OnlineEvent, OnlineProfile};
use presrs_core::pipeline::TrainedModel;
use presrs_core::sample::SampleKind;
use presrs_core::{FrameView, Grid};
use presrs_io::frame_protocol::{DEFAULT_MAX_PAYLOAD_BYTES, FrameError, FrameReader};
use presrs_io::mcap::BagFrames;
use presrs_io::tekscan::TekscanStream;
use serde_json::Value;

use super::events::{end_event, error_event, event_values};
use super::shutdown::ShutdownHandle;
pub use super::summary::ConnectionSummary;
use super::tap::{ConnectionTap, NoTap};
use crate::error::Result;

/// How the frames of a connection are encoded.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum InputFormat {
    /// TekScan ASCII movie text, frame by frame.
    #[default]
    Tekscan,
    /// The binary frame protocol of `docs/stream-protocol.md`.
    Binary,
    /// An MCAP file (a ROS 2 bag), read message by message: the frames of one topic
    /// ([`ConnectionOptions::topic`]; see [`presrs_io::mcap`]), stamped with their header stamps.
    Mcap,
}

/// How to read one connection.
#[derive(Clone, Debug, PartialEq)]
pub struct ConnectionOptions {
    pub format: InputFormat,
    /// The source's name in messages (`stdin`, a client's address).
    pub name: String,
    /// Largest binary frame payload accepted, bytes (checked before it is read).
    pub max_frame_bytes: usize,
    /// Set when the connection is being stopped (a signal): the input then ends where it was cut, and a
    /// frame cut short by the stop is dropped, not an error. Whoever stops it must also end the input
    /// (the reader returns end of file).
    pub stop: Option<ShutdownHandle>,
    /// The topic of an MCAP input (`None`: the only topic holding frames).
    pub topic: Option<String>,
    /// The frame period, seconds, of a TekScan input whose header states none: its frames are then
    /// timed from it (`None`: untimed, as are frames of a header without `SECONDS_PER_FRAME`).
    pub frame_period_s: Option<f64>,
}

impl Default for ConnectionOptions {
    fn default() -> Self {
        Self {
            format: InputFormat::Tekscan,
            name: "stdin".to_owned(),
            max_frame_bytes: DEFAULT_MAX_PAYLOAD_BYTES,
            stop: None,
            topic: None,
            frame_period_s: None,
        }
    }
}

/// What a connection tells the person watching it, as it happens.
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum ConnectionNotice {
    /// An `error` event's message (only the first [`MAX_ERROR_NOTICES`] of a connection).
    Error(String),
    /// More errors came than are noticed one by one: further ones are only counted.
    ErrorsMuted,
    /// The warm-up calibration ended after `frames` frames: stances before then were not classified.
    WarmupDone { frames: u64 },
    /// The input ended during the warm-up calibration (`frames` frames): no stance was classified.
    WarmupUnfinished { frames: u64 },
}

/// Errors of a connection noticed one by one; a faulty client must not flood the log.
pub const MAX_ERROR_NOTICES: u64 = 10;

/// Runs one connection: frames from `input` as `options` say, through the causal classifier, every JSON
/// line written (and flushed) to `output` at once. A line that cannot be written is dropped and counted;
/// a closed output (a broken pipe) ends the connection as the end of the input would. Returns when the
/// input ends or cannot go on.
pub fn run_connection<R: BufRead>(
    model: &TrainedModel,
    profile: &OnlineProfile,
    input: R,
    output: &mut dyn Write,
    options: &ConnectionOptions,
    notify: &dyn Fn(&ConnectionNotice),
) -> Result<ConnectionSummary> {
    run_connection_tapped(model, profile, input, output, options, notify, &mut NoTap)
}

/// [`run_connection`] with a [`ConnectionTap`] that sees every frame read and every line emitted.
pub fn run_connection_tapped<R: BufRead>(
    model: &TrainedModel,
    profile: &OnlineProfile,
    input: R,
    output: &mut dyn Write,
    options: &ConnectionOptions,
    notify: &dyn Fn(&ConnectionNotice),
    tap: &mut dyn ConnectionTap,
) -> Result<ConnectionSummary> {
    // A closed output (`presrs stream | head`): nobody reads the decisions any more, so the connection
    // ends as if the input had (a live input may never end by itself).
    let closed = std::cell::Cell::new(false);
    let mut emit = |_: &Value, line: String| -> bool {
        let written = writeln!(output, "{line}").and_then(|()| output.flush());
        if let Err(err) = &written {
            closed.set(closed.get() || err.kind() == std::io::ErrorKind::BrokenPipe);
        }
        written.is_ok()
    };
    // After a stop, what is left of the input is not judged: the end of a cut frame is the end.
    let until_stopped = |input: Input| match (&options.stop, input) {
        _ if closed.get() => Input::End,
        (Some(stop), Input::Skipped(_) | Input::Fatal(_)) if stop.is_stopped() => Input::End,
        (_, input) => input,
    };
    match options.format {
        InputFormat::Tekscan => {
            let mut source = tekscan_source(input, &options.name, options.frame_period_s);
            let next = |values: &mut Vec<f64>, present: &mut Vec<bool>| {
                until_stopped(source(values, present))
            };
            drive_connection(model, profile, next, &mut emit, notify, tap)
        }
        InputFormat::Binary => {
            let mut source = binary_source(input, &options.name, options.max_frame_bytes);
            let next = |values: &mut Vec<f64>, present: &mut Vec<bool>| {
                until_stopped(source(values, present))
            };
            drive_connection(model, profile, next, &mut emit, notify, tap)
        }
        InputFormat::Mcap => {
            let mut source = mcap_source(input, &options.name, options.topic.as_deref());
            let next = |values: &mut Vec<f64>, present: &mut Vec<bool>| {
                until_stopped(source(values, present))
            };
            drive_connection(model, profile, next, &mut emit, notify, tap)
        }
    }
}

/// What a frame source gives the session for one step ([`run_frames`]): it has filled `values`/`present`
/// with a frame, skipped a bad one, cannot go on, or ended.
#[derive(Debug)]
pub enum Input {
    /// A frame of `grid` is in `values` (and in `present` when `has_mask`), stamped `timestamp_us` by
    /// its sender when it was; `arrival` is when it came (the events' latency counts from it).
    Frame {
        grid: Grid,
        has_mask: bool,
        timestamp_us: Option<u64>,
        arrival: Instant,
    },
    /// A bad frame was skipped; the stream goes on.
    Skipped(String),
    /// The stream cannot go on.
    Fatal(String),
    End,
}

/// A connection in progress: the classifier, the counters, and where lines and notices go.
struct Connection<'a, 'm> {
    model: &'m TrainedModel,
    profile: &'a OnlineProfile,
    classifier: OnlineClassifier<'m>,
    summary: ConnectionSummary,
    emit: &'a mut dyn FnMut(&Value, String) -> bool,
    notify: &'a dyn Fn(&ConnectionNotice),
    tap: &'a mut dyn ConnectionTap,
    /// Errors reported so far (the first few are noticed).
    reported: u64,
}

impl Connection<'_, '_> {
    fn emit(&mut self, event: Value) {
        let line = event.to_string();
        self.tap.line(&line);
        if !(self.emit)(&event, line) {
            self.summary.dropped_events += 1;
        }
    }

    /// Counts an error, notices it (the first few), and emits its `error` line.
    fn error(&mut self, message: &str, fatal: bool) {
        self.summary.errors += 1;
        if self.reported < MAX_ERROR_NOTICES {
            (self.notify)(&ConnectionNotice::Error(message.to_owned()));
        } else if self.reported == MAX_ERROR_NOTICES {
            (self.notify)(&ConnectionNotice::ErrorsMuted);
        }
        self.reported += 1;
        self.emit(error_event(message, fatal));
    }

    /// Classifies one frame (input frame `index`, as it came), emitting its events or its error. False
    /// when the connection cannot go on: the first frame has a size the model cannot use. A stream's frames
    /// come from one sensor, so every later one would be rejected too: one fatal error instead of one
    /// per frame. A later frame of another size (a glitch) is rejected alone.
    fn frame(
        &mut self,
        index: u64,
        grid: Grid,
        frame: (&[f64], Option<&[bool]>),
        arrival: Instant,
        timestamp_us: Option<u64>,
    ) -> bool {
        self.tap.frame(index, grid, frame.0, frame.1, timestamp_us);
        let frames_before = self.classifier.stats().frames;
        let pushed = match unusable_for_model(self.model, grid) {
            Some(why) if frames_before == 0 => {
                self.summary.rejected_frames += 1;
                self.summary.fatal = true;
                let message = format!(
                    "input frame {index} rejected: {why}; the stream stops (its frames come from a \
                     sensor this model was not trained on)"
                );
                self.error(&message, true);
                return false;
            }
            Some(why) => Err(why),
            None => match FrameView::new(grid, frame.0, frame.1)
                .and_then(|view| self.classifier.push(&view))
            {
                Ok(step) => {
                    let latency_us = arrival.elapsed().as_secs_f64() * 1e6;
                    // A frame taken but not classified is an `error` event (event_values) and one of
                    // the connection's errors.
                    let failed = step
                        .events
                        .iter()
                        .filter(|event| matches!(event, OnlineEvent::Failed(_)))
                        .count();
                    let events =
                        event_values(&step, self.model, self.profile, latency_us, timestamp_us);
                    self.summary.errors += failed as u64;
                    events.into_iter().for_each(|event| self.emit(event));
                    Ok(())
                }
                Err(err) => Err(err.to_string()),
            },
        };
        let message = match pushed {
            Ok(()) => return true,
            // Not taken: the classifier's frame count did not move.
            Err(err) if self.classifier.stats().frames == frames_before => {
                self.summary.rejected_frames += 1;
                format!("input frame {index} rejected: {err}")
            }
            // Taken (frame `frames_before` of the stream), then not classified.
            Err(err) => {
                format!("input frame {index} (frame {frames_before}): classification failed: {err}")
            }
        };
        self.error(&message, false);
        true
    }
}

/// The per-frame session of a face that reads frames its own way (a ROS 2 node): the same session,
/// classifier, error policy, JSON lines and summary as [`run_connection`], over `next` until it returns
/// [`Input::End`] or [`Input::Fatal`]; every event goes to `emit` as its JSON value and its line (false:
/// the line was dropped), so that a face that builds messages of its own need not parse the line back.
pub fn run_frames(
    model: &TrainedModel,
    profile: &OnlineProfile,
    next: impl FnMut(&mut Vec<f64>, &mut Vec<bool>) -> Input,
    emit: &mut dyn FnMut(&Value, String) -> bool,
    notify: &dyn Fn(&ConnectionNotice),
) -> Result<ConnectionSummary> {
    drive_connection(model, profile, next, emit, notify, &mut NoTap)
}

/// Runs the online classifier over `next` until it ends, handing every event (value and line) to `emit` (which
/// returns false when it had to drop the line).
pub(super) fn drive_connection(
    model: &TrainedModel,
    profile: &OnlineProfile,
    mut next: impl FnMut(&mut Vec<f64>, &mut Vec<bool>) -> Input,
    emit: &mut dyn FnMut(&Value, String) -> bool,
    notify: &dyn Fn(&ConnectionNotice),
    tap: &mut dyn ConnectionTap,
) -> Result<ConnectionSummary> {
    let classifier = OnlineClassifier::new(
        model,
        &profile.segment,
        &profile.params,
        profile.calibration,
    )?;
    let mut warming_up = classifier.segmenter().warming_up();
    let mut conn = Connection {
        model,
        profile,
        classifier,
        summary: ConnectionSummary::default(),
        emit,
        notify,
        tap,
        reported: 0,
    };
    let (mut values, mut present) = (Vec::new(), Vec::new());
    // Frames as they came (rejected ones included), for the messages; event frame indices count only
    // the accepted ones.
    let mut received = 0u64;
    loop {
        match next(&mut values, &mut present) {
            Input::Frame {
                grid,
                has_mask,
                timestamp_us,
                arrival,
            } => {
                let mask = has_mask.then_some(present.as_slice());
                let go_on = conn.frame(received, grid, (&values, mask), arrival, timestamp_us);
                received += 1;
                if !go_on {
                    break;
                }
                if warming_up && !conn.classifier.segmenter().warming_up() {
                    warming_up = false;
                    conn.summary.warmup_frames = conn.classifier.stats().frames;
                    let frames = conn.summary.warmup_frames;
                    notify(&ConnectionNotice::WarmupDone { frames });
                }
            }
            Input::Skipped(message) => {
                received += 1;
                conn.summary.rejected_frames += 1;
                conn.error(&message, false);
            }
            Input::Fatal(message) => {
                conn.summary.fatal = true;
                conn.error(&message, true);
                break;
            }
            Input::End => break,
        }
    }
    finish(conn, warming_up)
}

/// Ends the connection: the stances still open, the warm-up notice if it never ended, the `end` line.
fn finish(mut conn: Connection<'_, '_>, warming_up: bool) -> Result<ConnectionSummary> {
    let events = event_values(
        &conn.classifier.finish()?,
        conn.model,
        conn.profile,
        0.0,
        None,
    );
    events.into_iter().for_each(|event| conn.emit(event));
    conn.summary.stats = conn.classifier.stats();
    let frames = conn.summary.stats.frames;
    if warming_up && frames > 0 {
        conn.summary.warmup_frames = frames;
        conn.summary.warmup_unfinished = true;
        (conn.notify)(&ConnectionNotice::WarmupUnfinished { frames });
    }
    let end = end_event(&conn.summary);
    conn.emit(end);
    Ok(conn.summary)
}

/// Why `grid` frames cannot be classified by `model` (its crop does not give the grid it was trained
/// on), or `None` when they can. A whole-stance model classifies the stance's summary, whose channels
/// any sensor's frames give (the online classifier checks that one stream keeps one size).
fn unusable_for_model(model: &TrainedModel, grid: Grid) -> Option<String> {
    if matches!(model.sample(), SampleKind::Stance { .. }) {
        return None;
    }
    let crop = model.crop();
    match crop.window(grid) {
        Ok((_, _, cropped)) if cropped == model.image_grid() => None,
        Ok((_, _, cropped)) => Some(format!(
            "a {grid} frame gives {cropped} sensels after the model's crop {crop}, the model needs {}",
            model.image_grid()
        )),
        Err(err) => Some(format!(
            "a {grid} frame does not fit the model's crop {crop}: {err}"
        )),
    }
}

/// A binary-protocol source over any reader.
pub(super) fn binary_source<R: Read>(
    mut reader: R,
    name: &str,
    max_frame_bytes: usize,
) -> impl FnMut(&mut Vec<f64>, &mut Vec<bool>) -> Input {
    let mut frames = FrameReader::new(name, max_frame_bytes);
    move |values, _present| match frames.read_frame(&mut reader, values) {
        Ok(Some(header)) => Input::Frame {
            grid: Grid::new(header.rows, header.cols),
            has_mask: false,
            timestamp_us: Some(header.timestamp_us),
            arrival: Instant::now(),
        },
        Ok(None) => Input::End,
        Err(err @ FrameError::Skipped { .. }) => Input::Skipped(err.to_string()),
        Err(err) => Input::Fatal(err.to_string()),
    }
}

/// An MCAP source over any reader: the frames of one topic, their stamps as timestamps (µs). A damaged
/// file or a frame of another size ends the stream (the bag's own error names the topic and message).
fn mcap_source<R: Read>(
    reader: R,
    name: &str,
    topic: Option<&str>,
) -> impl FnMut(&mut Vec<f64>, &mut Vec<bool>) -> Input {
    let mut frames = BagFrames::new(reader, name, topic);
    move |values, _present| match frames.next_frame(values) {
        Ok(Some(frame)) => Input::Frame {
            grid: frame.grid,
            has_mask: false,
            timestamp_us: Some(frame.time_ns / 1000),
            arrival: Instant::now(),
        },
        Ok(None) => Input::End,
        Err(err) => Input::Fatal(err.to_string()),
    }
}

/// A TekScan ASCII source over a buffered reader. Frames are timed by the file's own clock: their
/// `Frame` numbers times its `SECONDS_PER_FRAME` (else `frame_period_s`), from 0 at the first frame;
/// untimed when neither is known.
fn tekscan_source<R: BufRead>(
    reader: R,
    name: &str,
    frame_period_s: Option<f64>,
) -> impl FnMut(&mut Vec<f64>, &mut Vec<bool>) -> Input {
    let mut stream = TekscanStream::new(reader, name);
    let mut failures = 0usize;
    let mut first_number = None;
    move |values, present| match stream.next_frame(values, present) {
        Ok(Some(frame)) => {
            failures = 0;
            match stream.header() {
                Some(header) => Input::Frame {
                    grid: header.grid,
                    has_mask: frame.has_absent,
                    timestamp_us: header.period_s.or(frame_period_s).map(|period| {
                        let first = *first_number.get_or_insert(frame.number);
                        let frames = frame.number.saturating_sub(first).max(0) as f64;
                        (frames * period * 1e6).round() as u64
                    }),
                    arrival: Instant::now(),
                },
                None => Input::Fatal("no header".to_owned()),
            }
        }
        Ok(None) => Input::End,
        Err(err) if stream.header().is_none() || stream.stopped() => Input::Fatal(err.to_string()),
        Err(err) => {
            failures += 1;
            if failures > 1000 {
                Input::Fatal(format!("{err} (too many bad frames in a row)"))
            } else {
                Input::Skipped(err.to_string())
            }
        }
    }
}
