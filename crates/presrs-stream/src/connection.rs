//! One connection: frames read from a byte stream in one of the input formats, through a session, its
//! events as JSON lines to a sink.

use std::io::{BufRead, Read, Write};
use std::sync::atomic::Ordering;
use std::time::Instant;

use presrs_core::Grid;
use presrs_core::online::OnlineProfile;
use presrs_core::pipeline::TrainedModel;
use presrs_io::frame_protocol::{DEFAULT_MAX_PAYLOAD_BYTES, FrameError, FrameReader};
use presrs_io::mcap::BagFrames;
use presrs_io::tekscan::TekscanStream;

use super::shutdown::ShutdownHandle;
use presrs::error::Result;
use presrs::session::{
    ConnectionNotice, ConnectionSummary, Input, JsonLines, NoObserver, Observers, SessionObserver,
    run_frames,
};

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
    run_connection_observed(
        model,
        profile,
        input,
        output,
        options,
        notify,
        &mut NoObserver,
    )
}

/// [`run_connection`] with an `observer` that sees every frame read and every event, before the
/// output does (a bag being recorded, a live viewer).
pub fn run_connection_observed<R: BufRead>(
    model: &TrainedModel,
    profile: &OnlineProfile,
    input: R,
    output: &mut dyn Write,
    options: &ConnectionOptions,
    notify: &dyn Fn(&ConnectionNotice),
    observer: &mut dyn SessionObserver,
) -> Result<ConnectionSummary> {
    // A closed output (`presrs stream | head`): nobody reads the decisions any more, so the connection
    // ends as if the input had (a live input may never end by itself).
    let mut lines = JsonLines::new(output);
    let closed = lines.closed_flag();
    let mut observers = Observers::<&mut dyn SessionObserver>(vec![observer, &mut lines]);
    // After a stop, what is left of the input is not judged: the end of a cut frame is the end.
    let until_stopped = |input: Input| match (&options.stop, input) {
        _ if closed.load(Ordering::Relaxed) => Input::End,
        (Some(stop), Input::Skipped(_) | Input::Fatal(_)) if stop.is_stopped() => Input::End,
        (_, input) => input,
    };
    match options.format {
        InputFormat::Tekscan => {
            let mut source = tekscan_source(input, &options.name, options.frame_period_s);
            let next = |values: &mut Vec<f64>, present: &mut Vec<bool>| {
                until_stopped(source(values, present))
            };
            run_frames(model, profile, next, &mut observers, notify)
        }
        InputFormat::Binary => {
            let mut source = binary_source(input, &options.name, options.max_frame_bytes);
            let next = |values: &mut Vec<f64>, present: &mut Vec<bool>| {
                until_stopped(source(values, present))
            };
            run_frames(model, profile, next, &mut observers, notify)
        }
        InputFormat::Mcap => {
            let mut source = mcap_source(input, &options.name, options.topic.as_deref());
            let next = |values: &mut Vec<f64>, present: &mut Vec<bool>| {
                until_stopped(source(values, present))
            };
            run_frames(model, profile, next, &mut observers, notify)
        }
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
