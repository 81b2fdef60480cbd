//! `presrs view FILE`: replay a recording into the live view in the browser, at its frame rate, through
//! the online classifier when a model is given ([`presrs_stream::live::replay_recording`]).

use std::io::Write;
use std::net::SocketAddr;
use std::path::PathBuf;

use presrs::session::{ConnectionNotice, ProfileOverrides, resolve_profile};
use presrs_io::model_file::load_model;
use presrs_stream::ShutdownHandle;
use presrs_stream::live::{LiveInfo, ReplayOptions, replay_period_s, replay_recording};

use super::stream::HttpArgs;
use crate::printer::stream_log::{notice_text, summary_text};

/// Where `presrs view` serves without `--http`.
const DEFAULT_ADDR: SocketAddr = SocketAddr::V4(std::net::SocketAddrV4::new(
    std::net::Ipv4Addr::LOCALHOST,
    7800,
));

/// Replay a recording in the live view in the browser (the pressure image, the load trace and, with a
/// model, the terrain, gait and decision log).
///
/// Served on --http (default 127.0.0.1:7800); the URL goes to stderr; with a model the JSON lines of `presrs stream` go to stdout. SIGINT or
/// SIGTERM ends the replay (and --hold).
#[derive(Debug, clap::Args)]
#[command(after_help = "Examples:
  presrs view sim/recordings/grass_G2_000.asf
  presrs view my-walk.asf --model g2.model.json --speed 0.5 --hold")]
pub struct ViewArgs {
    /// Recording to replay (TekScan ASCII, .npy, PNG, text matrix or MCAP: the only topic of a bag that
    /// holds frames).
    pub file: PathBuf,
    /// Classify the frames online with this model (its online profile, else warm-up calibration).
    #[arg(long)]
    pub model: Option<PathBuf>,
    #[command(flatten)]
    pub novelty: super::common::NoveltyArgs,
    /// Online profile JSON (overrides the model file's).
    #[arg(long, requires = "model")]
    pub profile: Option<PathBuf>,
    /// Learn calibration and sample offset from the recordings of this manifest.
    #[arg(long, requires = "model")]
    pub calibrate: Option<PathBuf>,
    #[command(flatten)]
    pub http: HttpArgs,
    /// Replay faster (> 1) or slower (< 1) than real time.
    #[arg(long, default_value_t = 1.0, value_parser = super::usage::positive_number)]
    pub speed: f64,
    /// Seconds between frames [default: the recording's, else 0.01].
    #[arg(long, value_parser = super::usage::positive_number)]
    pub frame_period: Option<f64>,
    /// Wait before the first frame, seconds (time to open the page).
    #[arg(long, default_value_t = 0.0, value_parser = crate::args::values::non_negative_seconds)]
    pub delay: f64,
    /// Keep serving after the last frame until SIGINT or SIGTERM.
    #[arg(long)]
    pub hold: bool,
}

pub fn run(args: &ViewArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    let recording = presrs_io::read_recording(&args.file)?;
    let model = args
        .model
        .as_deref()
        .map(load_model)
        .transpose()?
        .map(|file| args.novelty.apply(file));
    let profile = model
        .as_ref()
        .map(|file| {
            resolve_profile(
                args.profile.as_deref(),
                args.calibrate.as_deref(),
                file.online.as_ref(),
                &ProfileOverrides::default(),
            )
        })
        .transpose()?;
    let name = args.file.display().to_string();
    let options = ReplayOptions {
        frame_period_s: args.frame_period,
        speed: args.speed,
        stop: Some(ShutdownHandle::default()),
    };
    let period = replay_period_s(&recording, &options)?;
    let info = LiveInfo {
        source: name.clone(),
        units: recording.meta.units_or_raw().to_string(),
        classes: model
            .as_ref()
            .map(|file| file.model.class_names().to_vec())
            .unwrap_or_default(),
    };
    let addr = args.http.http.unwrap_or(DEFAULT_ADDR);
    let Some((hub, server)) = args.http.start(Some(addr), info, "view")? else {
        anyhow::bail!("no address to serve the live view on");
    };
    let signals = presrs_stream::StopSignals::register()?;
    let stop = options.stop.clone().unwrap_or_default();
    let stopper = stop.clone();
    let signal_thread = signals.on_first(move || stopper.stop());
    stderr_line!(
        "presrs view: {} frames of {} at {:.1} frames/s{}",
        recording.frame_count(),
        recording.grid(),
        1.0 / period,
        if model.is_some() {
            ", classified online"
        } else {
            ""
        }
    );
    if args.delay > 0.0 {
        std::thread::sleep(std::time::Duration::from_secs_f64(args.delay.min(3600.0)));
    }
    let log = |notice: &ConnectionNotice| stderr_line!("presrs view: {}", notice_text(notice));
    let classify = model
        .as_ref()
        .zip(profile.as_ref())
        .map(|(file, profile)| (&file.model, profile));
    let summary = replay_recording(&recording, &name, classify, &hub, out, &options, &log)?;
    out.flush()?;
    match &summary {
        Some(summary) => stderr_line!("presrs view: {}", summary_text(&name, summary)),
        None => stderr_line!("presrs view: {} frames shown", hub.frames_seen()),
    }
    if args.hold && !stop.is_stopped() {
        stderr_line!("presrs view: the replay ended; serving until SIGINT");
        while !stop.is_stopped() {
            std::thread::sleep(std::time::Duration::from_millis(50));
        }
    }
    if let Some(signal) = signal_thread.close() {
        stderr_line!("presrs view: stopped by {signal}");
    }
    server.stop();
    Ok(())
}
