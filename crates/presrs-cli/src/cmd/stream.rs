//! `presrs stream`: online terrain classification of a live frame stream — the arguments, the call
//! into [`presrs_stream`] (the transports: the server, the stdin connection) around [`presrs::session`] (the session and its events), and what
//! goes to stderr.
//!
//! Input: TekScan ASCII frames on stdin as they are written (`--format tekscan`, the default), binary
//! frames on stdin (`--format binary`), or binary frames from TCP clients on a loopback address
//! (`--listen 127.0.0.1:PORT`, several clients at once; protocol in `docs/stream-protocol.md`). Output:
//! JSON lines to stdout, or back to each client. A finite input (stdin) with any rejected frame or error
//! exits with code 1 once it has been read to its end; the server (`--listen`) logs each connection's
//! summary and keeps serving. `--http ADDR` also serves the live view in the browser
//! ([`presrs_stream::live`]; [`HttpArgs`] is shared with `presrs view`).
//!
//! SIGINT and SIGTERM end the run cleanly: on stdin the input is taken as ended (the session writes its
//! `end` line), the server stops (each connection gets its `end` line, then a `stopped` line on stdout);
//! a second signal ends the process at once.

use presrs_core::online::DecideAt;
use std::io::Write;
use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

use presrs::session::{
    ConnectionNotice, NoObserver, Observers, ProfileOverrides, SessionObserver, resolve_profile,
};
use presrs_io::frame_protocol::DEFAULT_MAX_PAYLOAD_BYTES;
use presrs_io::model_file::load_model;
use presrs_stream::live::{LiveHub, LiveInfo, LiveOptions, LiveServer};
use presrs_stream::stoppable_input::StoppableInput;
use presrs_stream::{
    BagRecorder, BagReport, ConnectionBags, ConnectionOptions, InputFormat, ServerNotice,
    ServerOptions, ShutdownHandle, StopSignals, StreamServer, run_connection_observed,
};

use crate::printer::stream_log::{
    input_failure, listening_event, notice_text, server_notice_text, stopped_event, summary_text,
};

/// Input format on stdin.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum StreamFormat {
    /// TekScan ASCII movie text, frame by frame.
    Tekscan,
    /// The binary frame protocol of docs/stream-protocol.md.
    Binary,
    /// An MCAP file (a ROS 2 bag): the frames of --topic, message by message.
    Mcap,
}

/// Classify a live stream of pressure frames online.
///
/// Bad frames are rejected (an error event each) and the stream goes on, but a stream whose first frame
/// has a size the model cannot use stops at once (one error); reading stdin, the exit code is
/// 1 when any frame was rejected or any error occurred (after the whole input, and the summary on
/// stderr), 0 otherwise. Without a calibration the first frames (128) calibrate the detector: stances in
/// them are not classified (stderr says how many frames it took). Several TekScan files one after
/// another on stdin are one stream when their frames have the same size. SIGINT or SIGTERM ends the run
/// cleanly, with the final `end` line (and, with --listen, a `stopped` line).
#[derive(Debug, clap::Args)]
pub struct StreamArgs {
    /// Model file from `presrs train`.
    #[arg(long)]
    pub model: PathBuf,
    #[command(flatten)]
    pub novelty: super::common::NoveltyArgs,
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
    /// A whole-stance model decides K frames after touchdown, on the stance so far, or at its first
    /// decision point confident enough (`auto`, else at its deadline point) [default: at lift-off]. Only a moment the model was
    /// trained for (`presrs train --decide-at`), or its whole length.
    #[arg(long, value_name = "K|auto")]
    pub decide_at: Option<DecideAt>,
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
    /// With --format tekscan: the frame period in seconds when the header states no SECONDS_PER_FRAME
    /// (the frames' times, in the JSON lines and a --record bag; else untimed, and a bag takes the
    /// wall clock).
    #[arg(long, value_name = "SECONDS", value_parser = crate::args::values::period_seconds)]
    pub frame_period: Option<f64>,
    /// With --format mcap: the topic to read [default: the only topic holding frames].
    #[arg(long, value_name = "NAME")]
    pub topic: Option<String>,
    /// Record the session (stdin; with --listen one bag per connection, OUT-1.mcap, OUT-2.mcap, ... in
    /// the order the clients connected) to this MCAP file: the frames on /presrs/frames
    /// (sensor_msgs/msg/Image), stamped with the input's own frame times (TekScan SECONDS_PER_FRAME or
    /// --frame-period, MCAP stamps, binary timestamps; the wall clock only when it has none: the bag's
    /// `presrs.recording` metadata says which), and every JSON line on /presrs/decisions (JSON, with a
    /// JSON schema); the file appears when the stream ends.
    #[arg(long, value_name = "OUT.mcap")]
    pub record: Option<PathBuf>,
    #[command(flatten)]
    pub http: HttpArgs,
    /// The unit of the frame values, shown on the live view's colour scale (the stream does not say).
    #[arg(long, default_value = "raw", requires = "http")]
    pub units: String,
}

/// The live view in the browser (`presrs stream` and `presrs view`).
#[derive(Debug, clap::Args)]
pub struct HttpArgs {
    /// Serve the live view (the pressure image, the load trace, the terrain, gait and decision log) on
    /// this loopback address, e.g. 127.0.0.1:7800 (port 0 picks one); its URL goes to stderr. With
    /// --listen it shows one client at a time.
    #[arg(long, value_name = "IP:PORT", value_parser = super::usage::loopback_addr)]
    pub http: Option<SocketAddr>,
    /// Most frames a second sent to each viewer of the live view.
    #[arg(long, default_value_t = 30.0, value_parser = super::usage::positive_number)]
    pub http_fps: f64,
    /// Most viewers of the live view at once.
    #[arg(long, default_value_t = 16, value_parser = super::usage::positive_count)]
    pub http_viewers: usize,
}

impl HttpArgs {
    /// Starts the live view on `addr` (printing its URL), or nothing without one.
    pub fn start(
        &self,
        addr: Option<SocketAddr>,
        info: LiveInfo,
        command: &str,
    ) -> anyhow::Result<Option<(LiveHub, LiveServer)>> {
        let Some(addr) = addr else {
            return Ok(None);
        };
        let hub = LiveHub::new(info);
        let options = LiveOptions {
            max_fps: self.http_fps,
            max_viewers: self.http_viewers,
            ..LiveOptions::default()
        };
        let server = LiveServer::start(addr, hub.clone(), options)?;
        stderr_line!("presrs {command}: live view: {}", server.url());
        Ok(Some((hub, server)))
    }
}

impl From<StreamFormat> for InputFormat {
    fn from(format: StreamFormat) -> Self {
        match format {
            StreamFormat::Tekscan => Self::Tekscan,
            StreamFormat::Binary => Self::Binary,
            StreamFormat::Mcap => Self::Mcap,
        }
    }
}

impl StreamArgs {
    fn overrides(&self) -> ProfileOverrides {
        ProfileOverrides {
            sample_offset: self.sample_offset,
            fuse: self.fuse.clone(),
            gait: self.gait.clone(),
            decide_at: self.decide_at,
        }
    }

    fn server_options(&self) -> ServerOptions {
        ServerOptions {
            max_clients: self.max_clients,
            max_frame_bytes: self.max_frame_bytes,
            queue: self.queue,
            idle_timeout: Duration::from_secs_f64(self.idle_timeout.max(0.001)),
            exit_after: self.exit_after,
        }
    }
}

pub fn run(args: &StreamArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    args.record
        .as_deref()
        .map(presrs_io::output_path::check_output_file)
        .transpose()?;
    let file = args.novelty.apply(load_model(&args.model)?);
    presrs::session::check_overrides(&file.model, &args.overrides())
        .map_err(|err| super::usage::UsageError::error("stream", err))?;
    let profile = resolve_profile(
        args.profile.as_deref(),
        args.calibrate.as_deref(),
        file.online.as_ref(),
        &args.overrides(),
    )?;
    presrs::session::check_profile(&file.model, &profile)?;
    let signals = StopSignals::register()?;
    let info = LiveInfo {
        source: if args.listen.is_some() {
            "no client yet"
        } else {
            "stdin"
        }
        .to_owned(),
        units: args.units.clone(),
        classes: file.model.class_names().to_vec(),
    };
    let live = args.http.start(args.http.http, info, "stream")?;
    match args.listen {
        None => {
            let mut tap = live.as_ref().map(|(hub, _)| hub.tap());
            let tap: &mut dyn SessionObserver = match tap.as_mut() {
                Some(tap) => tap,
                None => &mut NoObserver,
            };
            run_stdin(args, &file.model, &profile, signals, tap, out)
        }
        Some(addr) => {
            let mut server = StreamServer::bind(addr, file.model, profile, args.server_options())?;
            let hub = live.as_ref().map(|(hub, _)| hub.clone());
            let bags = (args.record.as_deref()).map(|path| ConnectionBags::new(path, bag_report()));
            if hub.is_some() || bags.is_some() {
                server = server.with_observers(Arc::new(move |peer: &str| {
                    let mut taps: Vec<Box<dyn SessionObserver + Send>> = Vec::new();
                    if let Some(hub) = &hub {
                        taps.push(Box::new(hub.exclusive_tap(peer)));
                    }
                    taps.extend(bags.as_ref().map(|bags| bags.observer(peer)));
                    Box::new(Observers(taps))
                }));
            }
            let local = server.local_addr();
            writeln!(out, "{}", listening_event(local))?;
            out.flush()?;
            stderr_line!("presrs stream: listening on {local}");
            let stop = server.shutdown_handle();
            let signal_thread = signals.on_first(move || stop.stop());
            let served = server.serve(&print_server_notice)?;
            if let Some(signal) = signal_thread.close() {
                stderr_line!("presrs stream: stopped by {signal}");
                writeln!(out, "{}", stopped_event(signal, &served))?;
            }
            Ok(())
        }
    }
}

/// One connection on stdin; an error (after the summary) when any frame was rejected or any error came.
fn run_stdin(
    args: &StreamArgs,
    model: &presrs::core::TrainedModel,
    profile: &presrs::core::online::OnlineProfile,
    signals: StopSignals,
    tap: &mut dyn SessionObserver,
    out: &mut dyn Write,
) -> anyhow::Result<()> {
    let stop = ShutdownHandle::default();
    let options = ConnectionOptions {
        format: args.format.into(),
        name: "stdin".to_owned(),
        max_frame_bytes: args.max_frame_bytes,
        stop: Some(stop.clone()),
        topic: args.topic.clone(),
        frame_period_s: args.frame_period,
    };
    let log = |notice: &ConnectionNotice| stderr_line!("presrs stream: {}", notice_text(notice));
    let (input, end_input) = StoppableInput::start(|| std::io::stdin().lock());
    let signal_thread = signals.on_first(move || {
        // The flag first: the session must know the end it is about to read is a stop.
        stop.stop();
        end_input.stop();
    });
    let input = std::io::BufReader::with_capacity(64 * 1024, input);
    let summary = match &args.record {
        None => run_connection_observed(model, profile, input, out, &options, &log, tap)?,
        Some(path) => {
            let mut bag = BagRecorder::create(path)?;
            let summary = {
                let mut taps: Observers<&mut dyn SessionObserver> = Observers(vec![tap, &mut bag]);
                run_connection_observed(model, profile, input, out, &options, &log, &mut taps)?
            };
            let recorded = bag.finish()?;
            stderr_line!("presrs stream: {}", recorded.text());
            summary
        }
    };
    let name = &options.name;
    if let Some(signal) = signal_thread.close() {
        stderr_line!("presrs stream: stopped by {signal}: the input read so far was classified");
    }
    stderr_line!("presrs stream: {}", summary_text(name, &summary));
    match input_failure(name, &summary) {
        Some(failure) => Err(anyhow::anyhow!(failure)),
        None => Ok(()),
    }
}

/// Each connection's bag, said on stderr when its connection ends.
fn bag_report() -> BagReport {
    Arc::new(|peer: &str, recorded| match recorded {
        Ok(bag) => stderr_line!("presrs stream: {peer}: {}", bag.text()),
        Err(err) => stderr_line!("presrs stream: {peer}: no bag: {err}"),
    })
}

/// The stderr line of what the server saw.
fn print_server_notice(notice: &ServerNotice<'_>) {
    stderr_line!("presrs stream: {}", server_notice_text(notice));
}
