//! `presrs replay`: send a recording to `presrs stream --listen` as a live stream (demos and tests).
//!
//! The sending is [`presrs_stream::replay`]'s: frames in the binary protocol of `docs/stream-protocol.md`, at
//! `--rate` frames per second on an absolute schedule or as fast as possible (`max`). The server's JSON
//! lines are printed to stdout as they arrive; a summary goes to stderr.

use std::io::Write;
use std::net::SocketAddr;
use std::path::PathBuf;
use std::time::Duration;

use presrs_stream::replay::{Rate, Replay};

/// Send a recording as a live frame stream to `presrs stream --listen`.
#[derive(Debug, clap::Args)]
pub struct ReplayArgs {
    /// Recording to send (TekScan ASCII, .npy, PNG, text matrix or MCAP: the only topic of a bag that
    /// holds frames).
    pub file: PathBuf,
    /// The server's address, e.g. 127.0.0.1:7700.
    #[arg(long, value_name = "IP:PORT", value_parser = super::usage::socket_addr)]
    pub connect: SocketAddr,
    /// Frames per second, or `max`.
    #[arg(long, default_value = "100")]
    pub rate: Rate,
    /// Give up if the server does not answer within this many seconds after the last frame.
    #[arg(long, default_value_t = 30.0, value_parser = super::usage::positive_seconds)]
    pub timeout: f64,
}

pub fn run(args: &ReplayArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    let recording = presrs_io::read_recording(&args.file)?;
    let timeout = Duration::from_secs_f64(args.timeout);
    let replay = Replay::start(recording, args.connect, args.rate, timeout)?;
    let mut printed = 0usize;
    for line in replay.lines.iter() {
        writeln!(out, "{line}")?;
        printed += 1;
    }
    let sent = replay.finish()?;
    stderr_line!(
        "presrs replay: sent {} frames ({}, {:?}) in {:.3} s ({:.0} frames/s); {printed} lines received",
        sent.frames,
        sent.grid,
        sent.dtype,
        sent.sent_s,
        sent.frames as f64 / sent.sent_s.max(1e-9),
    );
    Ok(())
}
