//! The per-frame session every online face runs: frames from a source through the causal classifier,
//! typed events to an observer, the error policy and the counters. `presrs stream` (stdin and TCP),
//! the live view's replay, the ROS 2 node and the gait loop differ only in where frames come from and
//! what sees the events.

use std::time::Instant;

use presrs_core::online::{OnlineClassifier, OnlineEvent, OnlineProfile};
use presrs_core::pipeline::TrainedModel;
use presrs_core::sample::SampleKind;
use presrs_core::{FrameView, Grid};

use super::events::{EventTiming, SessionEvent, step_events};
use super::gaps::FrameGaps;
use super::observer::SessionObserver;
use super::summary::ConnectionSummary;
use crate::error::Result;

/// What a connection tells the person watching it, as it happens.
#[derive(Clone, Debug, PartialEq, Eq)]
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
    observer: &'a mut dyn SessionObserver,
    notify: &'a dyn Fn(&ConnectionNotice),
    /// Errors reported so far (the first few are noticed).
    reported: u64,
    /// Frames missing between the accepted ones, from their times.
    gaps: FrameGaps,
}

impl Connection<'_, '_> {
    fn emit(&mut self, event: &SessionEvent) {
        if !self.observer.event(event) {
            self.summary.dropped_events += 1;
        }
    }

    /// Emits the events of a step, each decision and lift-off with the frames missing in its stance.
    fn emit_step(&mut self, mut events: Vec<SessionEvent>) {
        for event in &mut events {
            self.gaps.mark(event);
            self.emit(event);
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
        self.emit(&SessionEvent::error(message, fatal));
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
        self.observer
            .frame(index, grid, frame.0, frame.1, timestamp_us);
        let frames_before = self.classifier.stats().frames;
        let pushed = match unusable_for_model(self.model, grid) {
            Some(why) if frames_before == 0 => {
                self.summary.rejected_frames += 1;
                self.summary.fatal = true;
                let message = match self.model.sample() {
                    SampleKind::Series { .. } => format!(
                        "input frame {index} rejected: {why}; the stream stops (this model \
                         classifies series, channels x time, not the frames of a sensor)"
                    ),
                    _ => format!(
                        "input frame {index} rejected: {why}; the stream stops (its frames come \
                         from a sensor this model was not trained on)"
                    ),
                };
                self.error(&message, true);
                return false;
            }
            Some(why) => Err(why),
            None => match FrameView::new(grid, frame.0, frame.1)
                .and_then(|view| self.classifier.push(&view))
            {
                Ok(step) => {
                    let latency_us = arrival.elapsed().as_secs_f64() * 1e6;
                    // Before the step's events: a decision on this frame counts a gap just before it.
                    self.gaps.frame(frames_before, timestamp_us);
                    // A frame taken but not classified is an `error` event (step_events) and one of
                    // the connection's errors.
                    let failed = step
                        .events
                        .iter()
                        .filter(|event| matches!(event, OnlineEvent::Failed(_)))
                        .count();
                    let timing = EventTiming {
                        latency_us,
                        timestamp_us,
                    };
                    let events = step_events(&step, self.model, self.profile, timing);
                    self.summary.errors += failed as u64;
                    self.emit_step(events);
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
                self.gaps.frame(frames_before, timestamp_us);
                format!("input frame {index} (frame {frames_before}): classification failed: {err}")
            }
        };
        self.error(&message, false);
        true
    }
}

/// Runs one session: the online classifier over `next` until it returns [`Input::End`] or
/// [`Input::Fatal`], every frame and typed event to `observer` (an event it could not take is counted
/// as dropped), notices to `notify`. Every online face runs this: the stream's connections, the ROS 2
/// node, Python's replay of a recording.
pub fn run_frames(
    model: &TrainedModel,
    profile: &OnlineProfile,
    mut next: impl FnMut(&mut Vec<f64>, &mut Vec<bool>) -> Input,
    observer: &mut dyn SessionObserver,
    notify: &dyn Fn(&ConnectionNotice),
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
        observer,
        notify,
        reported: 0,
        gaps: FrameGaps::default(),
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
    let step = conn.classifier.finish()?;
    let events = step_events(&step, conn.model, conn.profile, EventTiming::default());
    conn.emit_step(events);
    conn.summary.stats = conn.classifier.stats();
    let frames = conn.summary.stats.frames;
    if warming_up && frames > 0 {
        conn.summary.warmup_frames = frames;
        conn.summary.warmup_unfinished = true;
        (conn.notify)(&ConnectionNotice::WarmupUnfinished { frames });
    }
    let end = SessionEvent::end(&conn.summary);
    conn.emit(&end);
    Ok(conn.summary)
}

/// Why `grid` frames cannot be classified by `model` (its crop does not give the grid it was trained
/// on), or `None` when they can. A whole-stance model classifies the stance's summary, whose channels
/// any sensor's frames give: it takes the sensor it was trained on when it says which (older models
/// take any; the online classifier checks that one stream keeps one size).
fn unusable_for_model(model: &TrainedModel, grid: Grid) -> Option<String> {
    if matches!(model.sample(), SampleKind::Stance { .. }) {
        return model.check_sensor(grid).err().map(|err| err.to_string());
    }
    if let SampleKind::Series { .. } = model.sample() {
        let takes = model.sensor().unwrap_or(model.image_grid());
        return (model.check_sensor(grid).is_err()
            || model.crop().output_grid(grid).ok() != Some(model.image_grid()))
        .then(|| {
            format!(
                "a {grid} frame, but this model classifies series of {} channels x {} time steps \
                 (it was trained on series samples, one 2-D array each)",
                takes.rows, takes.cols
            )
        });
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
