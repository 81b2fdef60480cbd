//! `presrs replay`: a recording sent to a `presrs stream --listen` server as a live stream, in the binary
//! protocol of `docs/stream-protocol.md` (dtype: the smallest that holds the recording exactly), at a
//! rate on an absolute schedule (no drift) or as fast as possible; the server's lines come back as they
//! arrive.

use std::io::{BufRead, BufReader, Write};
use std::net::{Shutdown, SocketAddr, TcpStream};
use std::str::FromStr;
use std::sync::mpsc::{Receiver, sync_channel};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use presrs_core::Grid;
use presrs_core::Recording;
use presrs_io::frame_protocol::{Dtype, write_frame};

use presrs::error::{Context, Error, Result};

/// Frames per second, or as fast as possible.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Rate {
    Hz(f64),
    Max,
}

impl FromStr for Rate {
    type Err = String;

    fn from_str(text: &str) -> std::result::Result<Self, String> {
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

/// What was sent.
#[derive(Clone, Copy, Debug)]
pub struct ReplaySummary {
    pub frames: usize,
    pub grid: Grid,
    pub dtype: Dtype,
    /// Seconds from the first frame to the last one flushed.
    pub sent_s: f64,
}

/// A replay under way: the server's lines arrive on `lines` (bounded: a slow reader slows the
/// connection, and with it the server's queue for us, which then drops, not us) until the server
/// closes the connection; [`finish`](Self::finish) waits for the sending.
#[derive(Debug)]
pub struct Replay {
    pub lines: Receiver<String>,
    sender: JoinHandle<Result<ReplaySummary>>,
}

impl Replay {
    /// Connects to `addr` (within 5 s) and starts sending `recording` at `rate` on a thread; the
    /// connection gives up when the server is silent for `timeout`.
    pub fn start(
        recording: Recording,
        addr: SocketAddr,
        rate: Rate,
        timeout: Duration,
    ) -> Result<Self> {
        let stream = TcpStream::connect_timeout(&addr, Duration::from_secs(5))
            .map_err(|err| Error::system(format!("cannot connect to {addr}"), err))?;
        let _ = stream.set_nodelay(true);
        stream.set_read_timeout(Some(timeout.max(Duration::from_millis(1))))?;
        let (lines_tx, lines) = sync_channel::<String>(4096);
        let reader_stream = stream.try_clone()?;
        let reader = std::thread::spawn(move || -> std::io::Result<()> {
            for line in BufReader::new(reader_stream).lines() {
                if lines_tx.send(line?).is_err() {
                    break;
                }
            }
            Ok(())
        });
        let sender = std::thread::spawn(move || {
            let sent = send_frames(&recording, &stream, addr, rate);
            // Whatever happened, the server learns that no more frames come (and, after a failure,
            // the reader stops waiting for answers).
            let how = if sent.is_ok() {
                Shutdown::Write
            } else {
                Shutdown::Both
            };
            let shut = stream.shutdown(how);
            let sent_s = sent?;
            shut?;
            match reader.join() {
                Ok(Ok(())) => {}
                Ok(Err(err)) => {
                    return Err(Error::system(
                        format!("reading the server's answers from {addr}"),
                        err,
                    ));
                }
                Err(_) => return Err(Error::data("the reader thread failed")),
            }
            Ok(ReplaySummary {
                frames: recording.frame_count(),
                grid: recording.grid(),
                dtype: Dtype::smallest_exact(recording.data()),
                sent_s,
            })
        });
        Ok(Self { lines, sender })
    }

    /// Waits for the sending (and the server's last line) to end.
    pub fn finish(self) -> Result<ReplaySummary> {
        self.sender
            .join()
            .unwrap_or_else(|_| Err(Error::data("the sending thread failed")))
    }
}

/// Sends every frame on schedule; returns the seconds it took.
fn send_frames(
    recording: &Recording,
    stream: &TcpStream,
    addr: SocketAddr,
    rate: Rate,
) -> Result<f64> {
    let grid = recording.grid();
    let dtype = Dtype::smallest_exact(recording.data());
    let period_us = match rate {
        Rate::Hz(hz) => 1e6 / hz,
        Rate::Max => recording.frame_period_s().unwrap_or(0.01) * 1e6,
    };
    let mut writer = std::io::BufWriter::new(stream.try_clone()?);
    let mut scratch = Vec::new();
    let start = Instant::now();
    for (index, frame) in recording.frames().enumerate() {
        if let Rate::Hz(hz) = rate {
            let due = start + Duration::from_secs_f64(index as f64 / hz);
            let now = Instant::now();
            if due > now {
                std::thread::sleep(due - now);
            }
        }
        let timestamp_us = (index as f64 * period_us).round() as u64;
        let (rows, cols) = (grid.rows, grid.cols);
        write_frame(
            &mut writer,
            &mut scratch,
            rows,
            cols,
            dtype,
            timestamp_us,
            frame.values(),
        )
        .with_context(|| format!("cannot send frame {index} to {addr}"))?;
        if matches!(rate, Rate::Hz(_)) {
            writer.flush()?;
        }
    }
    writer.flush()?;
    Ok(start.elapsed().as_secs_f64())
}
