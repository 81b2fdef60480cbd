//! `presrs replay`: send a recording to `presrs stream --listen` as a live stream (demos and tests).
//!
//! Frames go out in the binary protocol of `docs/stream-protocol.md` (dtype: the smallest that holds the
//! recording exactly), at `--rate` frames per second on an absolute schedule (no drift) or as fast as
//! possible (`max`). The server's JSON lines are printed to stdout as they arrive; a summary goes to
//! stderr.

use std::io::{BufRead, BufReader, Write};
use std::net::{Shutdown, SocketAddr, TcpStream};
use std::path::PathBuf;
use std::str::FromStr;
use std::sync::mpsc::sync_channel;
use std::time::{Duration, Instant};

use anyhow::Context;
use presrs_io::frame_protocol::{Dtype, write_frame};

/// Frames per second, or as fast as possible.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Rate {
    Hz(f64),
    Max,
}

impl FromStr for Rate {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, String> {
        if text.eq_ignore_ascii_case("max") {
            return Ok(Self::Max);
        }
        match text.parse::<f64>() {
            Ok(hz) if hz.is_finite() && hz > 0.0 => Ok(Self::Hz(hz)),
            _ => Err(format!(
                "expected frames per second (> 0) or `max`, got {text:?}"
            )),
        }
    }
}

/// Send a recording as a live frame stream to `presrs stream --listen`.
#[derive(Debug, clap::Args)]
pub struct ReplayArgs {
    /// Recording to send (TekScan, NPY, PNG or text matrix).
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
    let addr = args.connect;
    let stream = TcpStream::connect_timeout(&addr, Duration::from_secs(5))
        .with_context(|| format!("cannot connect to {addr}"))?;
    let _ = stream.set_nodelay(true);
    stream.set_read_timeout(Some(Duration::from_secs_f64(args.timeout.max(0.001))))?;
    let grid = recording.grid();
    let dtype = Dtype::smallest_exact(recording.data());
    let period_us = match args.rate {
        Rate::Hz(hz) => 1e6 / hz,
        Rate::Max => recording.frame_period_s().unwrap_or(0.01) * 1e6,
    };

    // The server's lines, read on their own thread (bounded: a slow terminal slows the reader, and
    // with it the server's queue for us, which then drops, not us).
    let (lines_tx, lines_rx) = sync_channel::<String>(4096);
    let reader_stream = stream.try_clone()?;
    let reader = std::thread::spawn(move || -> std::io::Result<()> {
        for line in BufReader::new(reader_stream).lines() {
            if lines_tx.send(line?).is_err() {
                break;
            }
        }
        Ok(())
    });

    let mut writer = std::io::BufWriter::new(stream.try_clone()?);
    let mut scratch = Vec::new();
    let start = Instant::now();
    let mut printed = 0usize;
    for (index, frame) in recording.frames().enumerate() {
        if let Rate::Hz(hz) = args.rate {
            let due = start + Duration::from_secs_f64(index as f64 / hz);
            let now = Instant::now();
            if due > now {
                std::thread::sleep(due - now);
            }
        }
        let timestamp_us = (index as f64 * period_us).round() as u64;
        write_frame(
            &mut writer,
            &mut scratch,
            grid.rows,
            grid.cols,
            dtype,
            timestamp_us,
            frame.values(),
        )
        .with_context(|| format!("cannot send frame {index} to {addr}"))?;
        if matches!(args.rate, Rate::Hz(_)) {
            writer.flush()?;
        }
        while let Ok(line) = lines_rx.try_recv() {
            writeln!(out, "{line}")?;
            printed += 1;
        }
    }
    writer.flush()?;
    let sent_s = start.elapsed().as_secs_f64();
    stream.shutdown(Shutdown::Write)?;
    for line in lines_rx.iter() {
        writeln!(out, "{line}")?;
        printed += 1;
    }
    match reader.join() {
        Ok(Ok(())) => {}
        Ok(Err(err)) => anyhow::bail!("reading the server's answers from {addr}: {err}"),
        Err(_) => anyhow::bail!("the reader thread failed"),
    }
    stderr_line!(
        "presrs replay: sent {} frames ({grid}, {dtype:?}) in {sent_s:.3} s ({:.0} frames/s); {printed} lines received",
        recording.frame_count(),
        recording.frame_count() as f64 / sent_s.max(1e-9),
    );
    Ok(())
}
