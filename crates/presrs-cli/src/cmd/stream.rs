//! `presrs stream`: online terrain classification of a live frame stream — the arguments, the call
//! into [`presrs::stream`] (which holds the workflow: sessions, the server, the JSON events), and what
//! goes to stderr.
//!
//! Input: TekScan ASCII frames on stdin as they are written (`--format tekscan`, the default), binary
//! frames on stdin (`--format binary`), or binary frames from TCP clients on a loopback address
//! (`--listen 127.0.0.1:PORT`, several clients at once; protocol in `docs/stream-protocol.md`). Output:
//! JSON lines to stdout, or back to each client. A finite input (stdin) with any rejected frame or error
//! exits with code 1 once it has been read to its end; the server (`--listen`) logs each connection's
//! summary and keeps serving.

use std::io::Write;
use std::net::SocketAddr;
use std::path::PathBuf;
use std::time::Duration;

use presrs::stream::{
    ConnectionSummary, InputFormat, ProfileOverrides, ServerNotice, ServerOptions, SessionNotice,
    SessionOptions, StreamServer, resolve_profile, run_session,
};
use presrs_io::frame_protocol::DEFAULT_MAX_PAYLOAD_BYTES;
use presrs_io::model_file::load_model;
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

impl From<StreamFormat> for InputFormat {
    fn from(format: StreamFormat) -> Self {
        match format {
            StreamFormat::Tekscan => Self::Tekscan,
            StreamFormat::Binary => Self::Binary,
        }
    }
}

impl StreamArgs {
    fn overrides(&self) -> ProfileOverrides {
        ProfileOverrides {
            sample_offset: self.sample_offset,
            fuse: self.fuse.clone(),
            gait: self.gait.clone(),
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
    let file = load_model(&args.model)?;
    let profile = resolve_profile(
        args.profile.as_deref(),
        args.calibrate.as_deref(),
        file.online.as_ref(),
        &args.overrides(),
    )?;
    match args.listen {
        None => run_stdin(args, &file.model, &profile, out),
        Some(addr) => {
            let server = StreamServer::bind(addr, file.model, profile, args.server_options())?;
            let local = server.local_addr();
            writeln!(
                out,
                "{}",
                json!({"event": "listening", "addr": local.to_string()})
            )?;
            out.flush()?;
            stderr_line!("presrs stream: listening on {local}");
            server.serve(&print_server_notice)?;
            Ok(())
        }
    }
}

/// One session on stdin; an error (after the summary) when any frame was rejected or any error came.
fn run_stdin(
    args: &StreamArgs,
    model: &presrs::core::TrainedModel,
    profile: &presrs::core::online::OnlineProfile,
    out: &mut dyn Write,
) -> anyhow::Result<()> {
    let options = SessionOptions {
        format: args.format.into(),
        name: "stdin".to_owned(),
        max_frame_bytes: args.max_frame_bytes,
    };
    let log = |notice: &SessionNotice| stderr_line!("presrs stream: {}", notice_text(notice));
    let summary = run_session(model, profile, std::io::stdin().lock(), out, &options, &log)?;
    let name = &options.name;
    stderr_line!("presrs stream: {}", summary_text(name, &summary));
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

/// The stderr line of what the server saw (each about a client is named by its address).
fn print_server_notice(notice: &ServerNotice<'_>) {
    match notice {
        ServerNotice::AcceptFailed(err) => stderr_line!("presrs stream: accept failed: {err}"),
        ServerNotice::Refused { peer, max_clients } => {
            stderr_line!("presrs stream: {peer}: refused, {max_clients} clients already connected")
        }
        ServerNotice::Connected { peer } => stderr_line!("presrs stream: {peer}: connected"),
        ServerNotice::Session { peer, notice } => {
            stderr_line!("presrs stream: {peer}: {}", notice_text(notice));
        }
        ServerNotice::Ended { peer, summary } => {
            stderr_line!("presrs stream: {}", summary_text(peer, summary));
        }
        ServerNotice::Failed { peer, error } => {
            stderr_line!("presrs stream: {peer}: {}", chain_text(*error));
        }
        _ => {}
    }
}

/// A session's notice as the stderr line says it.
fn notice_text(notice: &SessionNotice) -> String {
    match notice {
        SessionNotice::Error(message) => message.clone(),
        SessionNotice::ErrorsMuted => "further errors are counted, not logged".to_owned(),
        SessionNotice::WarmupDone { frames } => format!(
            "warm-up calibration done on the first {frames} frames: stances before frame {frames} were \
             not classified (give --calibrate MANIFEST or --profile, or a model with an online profile, to \
             classify from the first frame)"
        ),
        SessionNotice::WarmupUnfinished { frames } => format!(
            "the stream ended during the warm-up calibration ({frames} frames): no stance was classified \
             (give --calibrate MANIFEST or --profile, or a model with an online profile, to classify from \
             the first frame)"
        ),
        _ => format!("{notice:?}"),
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

/// An error and its causes in one line, skipping causes whose text is already there.
fn chain_text(error: &(dyn std::error::Error + 'static)) -> String {
    let mut text = String::new();
    let mut cause = Some(error);
    while let Some(err) = cause {
        let part = err.to_string();
        if !text.contains(&part) {
            if !text.is_empty() {
                text.push_str(": ");
            }
            text.push_str(&part);
        }
        cause = err.source();
    }
    text
}
