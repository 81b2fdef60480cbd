//! `presrs view FILE`: a recording replayed at its frame rate into a live view, through the online
//! classifier when a model is given.

use std::io::{BufReader, Read, Write};
use std::time::{Duration, Instant};

use presrs_core::Recording;
use presrs_core::online::OnlineProfile;
use presrs_core::pipeline::TrainedModel;
use presrs_io::frame_protocol::{DEFAULT_MAX_PAYLOAD_BYTES, Dtype, encode_frame};

use super::hub::LiveHub;
use crate::{ConnectionOptions, InputFormat, ShutdownHandle, run_connection_observed};
use presrs::error::{Error, Result};
use presrs::session::{ConnectionNotice, ConnectionSummary, SessionObserver};

/// How a recording is replayed.
#[derive(Clone, Debug, PartialEq)]
pub struct ReplayOptions {
    /// Seconds between frames [default: the recording's, else 0.01].
    pub frame_period_s: Option<f64>,
    /// Faster (> 1) or slower than real time.
    pub speed: f64,
    /// Ends the replay early (the frames sent so far are classified, with an `end` line).
    pub stop: Option<ShutdownHandle>,
}

impl Default for ReplayOptions {
    fn default() -> Self {
        Self {
            frame_period_s: None,
            speed: 1.0,
            stop: None,
        }
    }
}

/// The period a recording is replayed at, in seconds (speed applied).
pub fn replay_period_s(recording: &Recording, options: &ReplayOptions) -> Result<f64> {
    let period = options
        .frame_period_s
        .or(recording.frame_period_s())
        .unwrap_or(0.01);
    let speed = options.speed;
    if !(period.is_finite() && period > 0.0 && speed.is_finite() && speed > 0.0) {
        return Err(Error::invalid(format!(
            "cannot replay at a frame period of {period} s and a speed of {speed}: both must be above 0"
        )));
    }
    Ok(period / speed)
}

/// Replays `recording` into `hub` at its frame period: with `model`, through the online classifier as
/// `presrs stream` runs it (its JSON lines also written to `output`; the summary returned), else only
/// the frames. Returns when the recording has been replayed or the replay is stopped.
pub fn replay_recording(
    recording: &Recording,
    name: &str,
    model: Option<(&TrainedModel, &OnlineProfile)>,
    hub: &LiveHub,
    output: &mut dyn Write,
    options: &ReplayOptions,
    notify: &dyn Fn(&ConnectionNotice),
) -> Result<Option<ConnectionSummary>> {
    let period = Duration::from_secs_f64(replay_period_s(recording, options)?);
    let mut tap = hub.tap();
    let Some((model, profile)) = model else {
        let schedule = Schedule::new(period, options.stop.clone());
        for (index, frame) in recording.frames().enumerate() {
            if !schedule.wait(index) {
                break;
            }
            tap.frame(
                index as u64,
                frame.grid(),
                frame.values(),
                frame.present(),
                None,
            );
        }
        return Ok(None);
    };
    let paced = PacedFrames {
        recording,
        dtype: Dtype::smallest_exact(recording.data()),
        schedule: Schedule::new(period, options.stop.clone()),
        next: 0,
        buf: Vec::new(),
        at: 0,
    };
    let grid = recording.grid();
    let connection = ConnectionOptions {
        format: InputFormat::Binary,
        name: name.to_owned(),
        max_frame_bytes: DEFAULT_MAX_PAYLOAD_BYTES.max(grid.len() * 8 + 64),
        stop: options.stop.clone(),
        topic: None,
        frame_period_s: None,
    };
    let summary = run_connection_observed(
        model,
        profile,
        BufReader::new(paced),
        output,
        &connection,
        notify,
        &mut tap,
    )?;
    Ok(Some(summary))
}

/// Frame `i` is due at `start + i * period`: an absolute schedule, no drift.
struct Schedule {
    start: Instant,
    period: Duration,
    stop: Option<ShutdownHandle>,
}

impl Schedule {
    fn new(period: Duration, stop: Option<ShutdownHandle>) -> Self {
        Self {
            start: Instant::now(),
            period,
            stop,
        }
    }

    fn stopped(&self) -> bool {
        self.stop.as_ref().is_some_and(ShutdownHandle::is_stopped)
    }

    /// Sleeps until frame `index` is due; false when stopped (looked at every 50 ms).
    fn wait(&self, index: usize) -> bool {
        let due = self.start + self.period.mul_f64(index as f64);
        loop {
            if self.stopped() {
                return false;
            }
            let now = Instant::now();
            if now >= due {
                return true;
            }
            std::thread::sleep((due - now).min(Duration::from_millis(50)));
        }
    }
}

/// A recording as a paced binary-protocol byte stream (what `presrs replay` sends), so that the
/// replay runs the very connection `presrs stream` runs.
struct PacedFrames<'a> {
    recording: &'a Recording,
    dtype: Dtype,
    schedule: Schedule,
    next: usize,
    buf: Vec<u8>,
    at: usize,
}

impl Read for PacedFrames<'_> {
    fn read(&mut self, out: &mut [u8]) -> std::io::Result<usize> {
        if self.at == self.buf.len() {
            let Some(frame) = self.recording.frame(self.next) else {
                return Ok(0);
            };
            if !self.schedule.wait(self.next) {
                return Ok(0);
            }
            let grid = frame.grid();
            let timestamp_us = self.schedule.period.mul_f64(self.next as f64).as_micros() as u64;
            encode_frame(
                &mut self.buf,
                grid.rows,
                grid.cols,
                self.dtype,
                timestamp_us,
                frame.values(),
            )?;
            self.at = 0;
            self.next += 1;
        }
        let n = out.len().min(self.buf.len() - self.at);
        out[..n].copy_from_slice(&self.buf[self.at..self.at + n]);
        self.at += n;
        Ok(n)
    }
}
