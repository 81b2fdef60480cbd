//! `presrs stream`: online terrain classification of a live frame stream.
//!
//! Input: TekScan ASCII frames on stdin as they are written (`--format tekscan`, the default), binary
//! frames on stdin (`--format binary`), or binary frames from TCP clients on a loopback address
//! (`--listen 127.0.0.1:PORT`, several clients at once; protocol in `docs/stream-protocol.md`). Output:
//! JSON lines (touchdown, classification, lift-off, error, end) to stdout, or back to each client.
//!
//! A bad frame (unreadable, non-finite, or of a size the model cannot use) is rejected with an `error`
//! event and the stream goes on; the `end` event and the summary on stderr count it among
//! `rejected_frames` and `errors`. A finite input (stdin) with any rejected frame or error exits with
//! code 1 once it has been read to its end; the server (`--listen`) logs each connection's summary and
//! keeps serving.
//!
//! Without a calibration (from `--profile`, `--calibrate` or the model file) the detector calibrates on
//! the stream's first frames (the warm-up, [`OnlineParams::warmup_frames`](presrs_core::online::OnlineParams));
//! stances in them are not classified, and a line on stderr says so when the warm-up ends.
//!
//! Each connection has its own causal detector and classifier session (`presrs_core::online`); the
//! model is shared read-only. Faults never panic and never grow memory without bound: frame sizes are
//! capped before reading, output to a client goes through a bounded queue (overflow is dropped and
//! counted), the number of clients is capped, idle connections are closed.

use std::io::{BufRead, BufWriter, Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::mpsc::{Receiver, SyncSender, TrySendError, sync_channel};
use std::time::{Duration, Instant};

use anyhow::Context;
use presrs_core::online::{
    DecisionKind, OnlineClassifier, OnlineEvent, OnlineProfile, OnlineStats, Step,
};
use presrs_core::pipeline::TrainedModel;
use presrs_core::stance::ValidSegmentParams;
use presrs_core::{FrameView, Grid};
use presrs_io::frame_protocol::{DEFAULT_MAX_PAYLOAD_BYTES, FrameError, FrameReader};
use presrs_io::model_file::{ModelFile, load_model};
use presrs_io::tekscan_stream::TekscanStream;
use serde_json::json;

/// Input format on stdin.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum StreamFormat {
    /// TekScan ASCII movie text, frame by frame.
    Tekscan,
    /// The binary frame protocol of docs/stream-protocol.md.
    Binary,
}

/// Classify a live stream of pressure frames online.
///
/// Bad frames are rejected (an error event each) and the stream goes on; reading stdin, the exit code is
/// 1 when any frame was rejected or any error occurred (after the whole input, and the summary on
/// stderr), 0 otherwise. Without a calibration the first frames (128) calibrate the detector: stances in
/// them are not classified (stderr says how many frames it took).
#[derive(Debug, clap::Args)]
pub struct StreamArgs {
    /// Model file from `presrs train`.
    #[arg(long)]
    pub model: PathBuf,
    /// Listen for binary-protocol clients on this loopback address (e.g. 127.0.0.1:7700; port 0 picks
    /// one, printed as the first JSON line) instead of reading stdin. A connection's errors end at most
    /// that connection; the server keeps serving.
    #[arg(long, value_name = "IP:PORT", value_parser = super::usage::loopback_addr)]
    pub listen: Option<SocketAddr>,
    /// Format of stdin.
    #[arg(long, value_enum, default_value = "tekscan")]
    pub format: StreamFormat,
    /// Online profile JSON (detector settings, calibration, terrain-to-gait table) [default: the model
    /// file's, else learned from --calibrate, else warm-up calibration with k = 6].
    #[arg(long)]
    pub profile: Option<PathBuf>,
    /// Learn calibration and sample offset k from the recordings of this manifest (e.g. the training
    /// manifest).
    #[arg(long)]
    pub calibrate: Option<PathBuf>,
    /// Classify the K-th frame after touchdown (overrides the profile).
    #[arg(long)]
    pub sample_offset: Option<usize>,
    /// Also fuse the posteriors of these frame offsets after touchdown, comma separated (e.g. 4,5,6,7,8).
    #[arg(long, value_delimiter = ',')]
    pub fuse: Vec<usize>,
    /// Recommended gait per terrain, TERRAIN=GAIT, comma separated (added to the profile's table).
    #[arg(long, value_delimiter = ',', value_name = "TERRAIN=GAIT",
          value_parser = |t: &str| super::usage::name_value(t, "TERRAIN=GAIT"))]
    pub gait: Vec<(String, String)>,
    /// Most simultaneous clients.
    #[arg(long, default_value_t = 16, value_parser = super::usage::positive_count)]
    pub max_clients: usize,
    /// Largest frame payload accepted, bytes.
    #[arg(long, default_value_t = DEFAULT_MAX_PAYLOAD_BYTES, value_parser = super::usage::positive_count)]
    pub max_frame_bytes: usize,
    /// Output lines queued per client before further ones are dropped (and counted).
    #[arg(long, default_value_t = 256, value_parser = super::usage::positive_count)]
    pub queue: usize,
    /// Close a connection idle for this many seconds.
    #[arg(long, default_value_t = 30.0, value_parser = super::usage::positive_seconds)]
    pub idle_timeout: f64,
    /// Exit after this many connections have ended (demos and tests) [default: serve forever].
    #[arg(long)]
    pub exit_after: Option<usize>,
}

/// The profile to run with: file, model, calibration manifest or defaults, then the overrides.
pub fn resolve_profile(args: &StreamArgs, file: &ModelFile) -> anyhow::Result<OnlineProfile> {
    let mut profile = if let Some(path) = &args.profile {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("cannot read the profile {}", path.display()))?;
        serde_json::from_str(&text)
            .with_context(|| format!("invalid online profile {}", path.display()))?
    } else if let Some(path) = &args.calibrate {
        presrs::train::learn_online_profile(path)?
    } else if let Some(online) = &file.online {
        online.clone()
    } else {
        OnlineProfile::default()
    };
    if let Some(k) = args.sample_offset {
        profile.params.sample_offset = k;
    }
    if !args.fuse.is_empty() {
        profile.params.fusion_offsets.clone_from(&args.fuse);
    }
    for (terrain, gait) in &args.gait {
        profile.gait_table.insert(terrain.clone(), gait.clone());
    }
    Ok(profile)
}

/// One frame source: fills `values`/`present`, returns what came.
enum Input {
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

/// What one connection did.
#[derive(Clone, Copy, Debug, Default)]
pub struct ConnectionSummary {
    /// The classifier's counters; its `rejected_frames` counts only the frames it refused itself.
    pub stats: OnlineStats,
    /// Every frame that came and was not used: unreadable (skipped by the reader), of a size the model
    /// cannot use, or refused by the classifier (another size than the first frame, non-finite values).
    /// Each is also an error.
    pub rejected_frames: u64,
    /// Error events: the rejected frames, classifications that failed and a fatal fault.
    pub errors: u64,
    pub dropped_events: u64,
    pub fatal: bool,
    /// Frames the warm-up calibration used (0 with a calibration given); stances in them were not
    /// classified.
    pub warmup_frames: u64,
}

impl ConnectionSummary {
    /// Whether anything went wrong on the connection (a rejected frame or an error).
    pub fn had_errors(&self) -> bool {
        self.errors > 0 || self.rejected_frames > 0 || self.fatal
    }
}

/// Why `grid` frames cannot be classified by `model` (its crop does not give the grid it was trained
/// on), or `None` when they can.
fn unusable_for_model(model: &TrainedModel, grid: Grid) -> Option<String> {
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

/// Runs the online classifier over `next` until it ends, handing every JSON line to `emit` (which
/// returns false when it had to drop the line).
fn run_connection(
    model: &TrainedModel,
    profile: &OnlineProfile,
    mut next: impl FnMut(&mut Vec<f64>, &mut Vec<bool>) -> Input,
    emit: &mut dyn FnMut(String) -> bool,
    log: &dyn Fn(&str),
) -> anyhow::Result<ConnectionSummary> {
    let mut classifier = OnlineClassifier::new(
        model,
        &ValidSegmentParams::default(),
        &profile.params,
        profile.calibration,
    )?;
    let mut summary = ConnectionSummary::default();
    let (mut values, mut present) = (Vec::new(), Vec::new());
    // Frames as they came (rejected ones included), for the messages; event frame indices count only
    // the accepted ones.
    let mut received = 0u64;
    let mut warming_up = classifier.segmenter().warming_up();
    let mut logged = 0u64;
    let mut report = |summary: &mut ConnectionSummary, message: &str, fatal: bool| {
        summary.errors += 1;
        if logged < 10 {
            log(message);
        } else if logged == 10 {
            log("further errors are counted, not logged");
        }
        logged += 1;
        json!({"event": "error", "message": message, "fatal": fatal}).to_string()
    };
    loop {
        match next(&mut values, &mut present) {
            Input::Frame {
                grid,
                has_mask,
                timestamp_us,
                arrival,
            } => {
                let index = received;
                received += 1;
                let mask = has_mask.then_some(present.as_slice());
                let frames_before = classifier.stats().frames;
                let pushed = match unusable_for_model(model, grid) {
                    Some(why) => Err(why),
                    None => match FrameView::new(grid, &values, mask)
                        .and_then(|view| classifier.push(&view).map(|step| (step, Instant::now())))
                    {
                        Ok((step, decided)) => {
                            // A frame taken but not classified is an `error` line (event_lines) and
                            // one of the connection's errors.
                            let failed = step
                                .events
                                .iter()
                                .filter(|event| matches!(event, OnlineEvent::Failed(_)))
                                .count();
                            summary.errors += failed as u64;
                            let latency_us = decided.duration_since(arrival).as_secs_f64() * 1e6;
                            for line in event_lines(&step, model, profile, latency_us, timestamp_us)
                            {
                                if !emit(line) {
                                    summary.dropped_events += 1;
                                }
                            }
                            Ok(())
                        }
                        Err(err) => Err(err.to_string()),
                    },
                };
                let message = match pushed {
                    Ok(()) => None,
                    // Not taken: the classifier's frame count did not move.
                    Err(err) if classifier.stats().frames == frames_before => {
                        summary.rejected_frames += 1;
                        Some(format!("input frame {index} rejected: {err}"))
                    }
                    // Taken (frame `frames_before` of the stream), then not classified.
                    Err(err) => Some(format!(
                        "input frame {index} (frame {frames_before}): classification failed: {err}"
                    )),
                };
                if let Some(message) = message {
                    let line = report(&mut summary, &message, false);
                    if !emit(line) {
                        summary.dropped_events += 1;
                    }
                }
                if warming_up && !classifier.segmenter().warming_up() {
                    warming_up = false;
                    summary.warmup_frames = classifier.stats().frames;
                    log(&warmup_note(summary.warmup_frames, false));
                }
            }
            Input::Skipped(message) => {
                received += 1;
                summary.rejected_frames += 1;
                let line = report(&mut summary, &message, false);
                if !emit(line) {
                    summary.dropped_events += 1;
                }
            }
            Input::Fatal(message) => {
                summary.fatal = true;
                let line = report(&mut summary, &message, true);
                if !emit(line) {
                    summary.dropped_events += 1;
                }
                break;
            }
            Input::End => break,
        }
    }
    let step = classifier.finish()?;
    for line in event_lines(&step, model, profile, 0.0, None) {
        if !emit(line) {
            summary.dropped_events += 1;
        }
    }
    summary.stats = classifier.stats();
    let s = summary.stats;
    if warming_up && s.frames > 0 {
        summary.warmup_frames = s.frames;
        log(&warmup_note(s.frames, true));
    }
    let end = json!({
        "event": "end",
        "frames": s.frames,
        "stances": s.stances,
        "decisions": s.decisions,
        "fused_decisions": s.fused_decisions,
        "rejected_frames": summary.rejected_frames,
        "errors": summary.errors,
        "dropped_events": summary.dropped_events,
    });
    if !emit(end.to_string()) {
        summary.dropped_events += 1;
    }
    Ok(summary)
}

/// The stderr note that the warm-up calibration ended (`at_end`: with the stream, which was no longer).
fn warmup_note(frames: u64, at_end: bool) -> String {
    if at_end {
        format!(
            "the stream ended during the warm-up calibration ({frames} frames): no stance was classified \
             (give --calibrate MANIFEST or --profile, or a model with an online profile, to classify from \
             the first frame)"
        )
    } else {
        format!(
            "warm-up calibration done on the first {frames} frames: stances before frame {frames} were \
             not classified (give --calibrate MANIFEST or --profile, or a model with an online profile, to \
             classify from the first frame)"
        )
    }
}

/// The JSON lines of one step.
fn event_lines(
    step: &Step<'_>,
    model: &TrainedModel,
    profile: &OnlineProfile,
    latency_us: f64,
    timestamp_us: Option<u64>,
) -> Vec<String> {
    let names = model.class_names();
    step.events
        .iter()
        .map(|event| match event {
            OnlineEvent::Touchdown(td) => json!({
                "event": "touchdown",
                "stance": td.stance_id,
                "touchdown_frame": td.touchdown_frame,
                "frame": td.frame,
                "partial": td.partial,
            }),
            OnlineEvent::Decision(d) => {
                let label = names.get(d.class).map_or("?", String::as_str);
                let posteriors: serde_json::Map<String, serde_json::Value> = names
                    .iter()
                    .zip(step.posteriors(d))
                    .map(|(name, &p)| (name.clone(), json!(p)))
                    .collect();
                json!({
                    "event": "classification",
                    "kind": match d.kind { DecisionKind::Single => "single", DecisionKind::Fused => "fused" },
                    "stance": d.stance_id,
                    "label": label,
                    "class": d.class,
                    "confidence": d.confidence,
                    "posteriors": posteriors,
                    "sample_frame": d.sample_frame,
                    "frame": d.frame,
                    "frames_used": d.frames_used,
                    "touchdown_frame": d.touchdown_frame,
                    "latency_us": (latency_us * 10.0).round() / 10.0,
                    "timestamp_us": timestamp_us,
                    "gait": profile.gait_table.get(label),
                })
            }
            OnlineEvent::Failed(f) => json!({
                "event": "error",
                "message": format!(
                    "stance {}: frame {} could not be classified ({} decision): {}",
                    f.stance_id,
                    f.sample_frame,
                    match f.kind { DecisionKind::Single => "single", DecisionKind::Fused => "fused" },
                    step.error(f).map_or_else(|| "unknown error".to_owned(), ToString::to_string)
                ),
                "fatal": false,
                "stance": f.stance_id,
                "frame": f.frame,
            }),
            OnlineEvent::Liftoff(lo) => json!({
                "event": "liftoff",
                "stance": lo.stance_id,
                "touchdown_frame": lo.stance.start,
                "end_frame": lo.stance.end(),
                "len": lo.stance.len,
                "peak_frame": lo.stance.peak_frame,
                "peak_load": lo.stance.peak_load,
                "partial": lo.stance.partial,
                "sampled": lo.sampled,
                "frame": lo.frame,
            }),
        })
        .map(|value| value.to_string())
        .collect()
}

/// A binary-protocol source over any reader.
fn binary_source<R: Read>(
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

/// A TekScan ASCII source over a buffered reader.
fn tekscan_source<R: BufRead>(
    reader: R,
    name: &str,
) -> impl FnMut(&mut Vec<f64>, &mut Vec<bool>) -> Input {
    let mut stream = TekscanStream::new(reader, name);
    let mut failures = 0usize;
    move |values, present| match stream.next_frame(values, present) {
        Ok(Some(frame)) => {
            failures = 0;
            match stream.header() {
                Some(header) => Input::Frame {
                    grid: header.grid,
                    has_mask: frame.has_absent,
                    timestamp_us: None,
                    arrival: Instant::now(),
                },
                None => Input::Fatal("no header".to_owned()),
            }
        }
        Ok(None) => Input::End,
        Err(err) if stream.header().is_none() => Input::Fatal(err.to_string()),
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

pub fn run(args: &StreamArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    let file = load_model(&args.model)?;
    let profile = resolve_profile(args, &file)?;
    let model = &file.model;
    let log = |message: &str| stderr_line!("presrs stream: {message}");
    match &args.listen {
        None => {
            let stdin = std::io::stdin();
            let name = "stdin";
            let mut emit = |line: String| -> bool {
                // stdout closed (`| head`): the caller's problem, not ours; the lines are dropped.
                writeln!(out, "{line}").and_then(|()| out.flush()).is_ok()
            };
            let summary = match args.format {
                StreamFormat::Tekscan => run_connection(
                    model,
                    &profile,
                    tekscan_source(stdin.lock(), name),
                    &mut emit,
                    &log,
                )?,
                StreamFormat::Binary => run_connection(
                    model,
                    &profile,
                    binary_source(stdin.lock(), name, args.max_frame_bytes),
                    &mut emit,
                    &log,
                )?,
            };
            log(&summary_text(name, &summary));
            if summary.fatal {
                anyhow::bail!("the input stream ended with an error (see above)");
            }
            if summary.had_errors() {
                anyhow::bail!(
                    "{name}: {} rejected frame(s), {} error(s) in the input (see the error events)",
                    summary.rejected_frames,
                    summary.errors
                );
            }
            Ok(())
        }
        Some(addr) => serve(args, *addr, model, &profile, out),
    }
}

fn summary_text(name: &str, s: &ConnectionSummary) -> String {
    format!(
        "{name}: {} frames, {} stances, {} decisions ({} fused), {} rejected frames, {} errors, {} dropped events",
        s.stats.frames,
        s.stats.stances,
        s.stats.decisions,
        s.stats.fused_decisions,
        s.rejected_frames,
        s.errors,
        s.dropped_events
    )
}

/// The TCP server (see the module docs).
fn serve(
    args: &StreamArgs,
    addr: SocketAddr,
    model: &TrainedModel,
    profile: &OnlineProfile,
    out: &mut dyn Write,
) -> anyhow::Result<()> {
    // `--listen` accepts loopback addresses only (checked when parsed); checked again here, where it
    // matters.
    anyhow::ensure!(
        addr.ip().is_loopback(),
        "--listen {addr}: only loopback addresses are served (127.0.0.1 or [::1])"
    );
    let listener = TcpListener::bind(addr).with_context(|| format!("cannot listen on {addr}"))?;
    let local = listener.local_addr()?;
    listener.set_nonblocking(true)?;
    writeln!(
        out,
        "{}",
        json!({"event": "listening", "addr": local.to_string()})
    )?;
    out.flush()?;
    stderr_line!("presrs stream: listening on {local}");
    let active = AtomicUsize::new(0);
    let ended = AtomicUsize::new(0);
    let idle = Duration::from_secs_f64(args.idle_timeout.max(0.001));
    std::thread::scope(|scope| -> anyhow::Result<()> {
        loop {
            if args
                .exit_after
                .is_some_and(|n| ended.load(Ordering::SeqCst) >= n)
            {
                break;
            }
            let (stream, peer) = match listener.accept() {
                Ok(conn) => conn,
                Err(err) if err.kind() == std::io::ErrorKind::WouldBlock => {
                    std::thread::sleep(Duration::from_millis(5));
                    continue;
                }
                Err(err) => {
                    stderr_line!("presrs stream: accept failed: {err}");
                    std::thread::sleep(Duration::from_millis(50));
                    continue;
                }
            };
            if active.load(Ordering::SeqCst) >= args.max_clients {
                stderr_line!(
                    "presrs stream: {peer}: refused, {} clients already connected",
                    args.max_clients
                );
                let mut stream = stream;
                let line = json!({"event": "error", "fatal": true,
                    "message": format!("server full ({} clients)", args.max_clients)});
                let _ = stream.set_nonblocking(false);
                let _ = writeln!(stream, "{line}");
                ended.fetch_add(1, Ordering::SeqCst);
                continue;
            }
            active.fetch_add(1, Ordering::SeqCst);
            let (active, ended) = (&active, &ended);
            scope.spawn(move || {
                let name = peer.to_string();
                match handle_client(stream, &name, args, model, profile, idle) {
                    Ok(summary) => stderr_line!("presrs stream: {}", summary_text(&name, &summary)),
                    Err(err) => stderr_line!("presrs stream: {name}: {err:#}"),
                }
                active.fetch_sub(1, Ordering::SeqCst);
                ended.fetch_add(1, Ordering::SeqCst);
            });
        }
        Ok(())
    })?;
    Ok(())
}

/// A bounded queue of output lines to a writer thread: `send` never blocks; when the queue is full the
/// line is dropped and counted.
pub struct BoundedOutput {
    sender: Option<SyncSender<String>>,
    dropped: std::sync::Arc<AtomicU64>,
}

impl BoundedOutput {
    /// Starts the writer thread on `sink` with `capacity` queued lines. Write errors stop the output
    /// (later lines are dropped and counted). Returns the queue and the writer's handle.
    pub fn start<W: Write + Send + 'static>(
        sink: W,
        capacity: usize,
    ) -> (Self, std::thread::JoinHandle<()>) {
        let (sender, receiver) = sync_channel::<String>(capacity.max(1));
        let dropped = std::sync::Arc::new(AtomicU64::new(0));
        let counter = dropped.clone();
        let handle = std::thread::spawn(move || write_lines(sink, receiver, &counter));
        (
            Self {
                sender: Some(sender),
                dropped,
            },
            handle,
        )
    }

    /// Queues a line; false if it was dropped.
    pub fn send(&self, line: String) -> bool {
        let Some(sender) = &self.sender else {
            return false;
        };
        match sender.try_send(line) {
            Ok(()) => true,
            Err(TrySendError::Full(_) | TrySendError::Disconnected(_)) => {
                self.dropped.fetch_add(1, Ordering::Relaxed);
                false
            }
        }
    }

    /// Lines dropped so far (queue full, or output failed).
    pub fn dropped(&self) -> u64 {
        self.dropped.load(Ordering::Relaxed)
    }

    /// Closes the queue; the writer drains it and ends.
    pub fn close(&mut self) {
        self.sender = None;
    }
}

impl std::fmt::Debug for BoundedOutput {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BoundedOutput")
            .field("dropped", &self.dropped())
            .finish()
    }
}

fn write_lines<W: Write>(sink: W, receiver: Receiver<String>, dropped: &AtomicU64) {
    let mut sink = BufWriter::new(sink);
    let mut failed = false;
    while let Ok(line) = receiver.recv() {
        if failed {
            dropped.fetch_add(1, Ordering::Relaxed);
            continue;
        }
        // Each line goes out at once: a robot waits for its decision.
        let written = writeln!(sink, "{line}").and_then(|()| sink.flush());
        if written.is_err() {
            failed = true;
            dropped.fetch_add(1, Ordering::Relaxed);
        }
    }
    let _ = sink.flush();
}

fn handle_client(
    stream: TcpStream,
    name: &str,
    args: &StreamArgs,
    model: &TrainedModel,
    profile: &OnlineProfile,
    idle: Duration,
) -> anyhow::Result<ConnectionSummary> {
    stream.set_nonblocking(false)?;
    stream.set_read_timeout(Some(idle))?;
    stream.set_write_timeout(Some(idle))?;
    let _ = stream.set_nodelay(true);
    stderr_line!("presrs stream: {name}: connected");
    let (mut output, writer) = BoundedOutput::start(stream.try_clone()?, args.queue);
    let reader = std::io::BufReader::with_capacity(64 * 1024, stream.try_clone()?);
    // Named: with several clients, a message says whose stream it is about.
    let log = |message: &str| stderr_line!("presrs stream: {name}: {message}");
    let mut emit = |line: String| output.send(line);
    let result = run_connection(
        model,
        profile,
        binary_source(reader, name, args.max_frame_bytes),
        &mut emit,
        &log,
    );
    let dropped_in_writer = output.dropped();
    output.close();
    let _ = writer.join();
    let _ = stream.shutdown(std::net::Shutdown::Both);
    let mut summary = result?;
    summary.dropped_events = summary.dropped_events.max(dropped_in_writer);
    Ok(summary)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    /// A sink that accepts nothing until released: a client that does not read.
    struct Stalled(std::sync::mpsc::Receiver<()>, Vec<u8>);

    impl Write for Stalled {
        fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
            let _ = self.0.recv();
            self.1.extend_from_slice(buf);
            Ok(buf.len())
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn a_slow_consumer_gets_drops_not_unbounded_memory() {
        let (release, gate) = std::sync::mpsc::channel();
        let (mut output, writer) = BoundedOutput::start(Stalled(gate, Vec::new()), 4);
        let mut accepted = 0;
        for i in 0..1000 {
            if output.send(format!("line {i}")) {
                accepted += 1;
            }
        }
        // At most the queue plus the line being written got through; the rest was dropped at once.
        assert!(accepted <= 6, "{accepted}");
        assert_eq!(output.dropped(), 1000 - accepted);
        drop(release);
        output.close();
        writer.join().unwrap();
    }
}
