//! The node's loop: frames from the input topic through the library's per-frame session
//! ([`presrs::session::run_frames`]: the same classifier, error policy and events as
//! `presrs stream`), every typed event out as a typed message, a JSON string, and the gait command.

use std::cell::RefCell;
use std::collections::{HashMap, VecDeque};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use presrs::session::{
    ConnectionNotice, ConnectionSummary, Input, SessionEvent, SessionObserver, run_frames,
};
use presrs_core::Grid;
use presrs_core::online::OnlineProfile;
use presrs_core::pipeline::TrainedModel;
use presrs_io::mcap::{FrameType, Stamp, decode_frame};
use ros2_client::dds::rustdds::GUID;
use ros2_client::dds::rustdds::mio1::Events;
use ros2_client::dds::rustdds::no_key::DeserializedCacheChange;

use crate::diagnostics::{DiagnosticsReport, Finding, NodeCounters, REJECTED_WINDOW};
use crate::error::Result;
use crate::graph::{NodeGraph, Outputs};
use crate::messages::{
    DiagnosticStatus, FrameStamps, StringMsg, Time, decision_message, stance_message, time_of,
};
use crate::raw::RawCdr;
use crate::watch::GraphWatch;

/// The node waits for frames at most this long before it looks at its stop flag again.
const IDLE_POLL: Duration = Duration::from_millis(100);

/// Frame stamps kept for the events that name earlier frames (a stance far longer than this many
/// frames gets zero stamps for its touchdown).
const STAMPS_KEPT: usize = 1 << 16;

/// What a node did, when it ends.
#[derive(Clone, Debug)]
pub struct NodeSummary {
    /// The session's summary (as `presrs stream` reports it in its `end` event).
    pub session: ConnectionSummary,
    /// The node's own counters (the input as it came, dropped frames, publish failures).
    pub counters: NodeCounters,
    /// The input topic, resolved against the node's namespace.
    pub input: String,
}

/// The stamps of the accepted frames, by their index in the session.
#[derive(Debug, Default)]
struct StampBook {
    first: u64,
    stamps: VecDeque<Time>,
}

impl StampBook {
    fn push(&mut self, stamp: Time) {
        if self.stamps.len() == STAMPS_KEPT {
            self.stamps.pop_front();
            self.first += 1;
        }
        self.stamps.push_back(stamp);
    }
}

impl FrameStamps for StampBook {
    fn stamp_of(&self, index: u64) -> Option<Time> {
        let offset = usize::try_from(index.checked_sub(self.first)?).ok()?;
        self.stamps.get(offset).copied()
    }
}

/// The loop's state, shared by the frame source and the event sink (never at the same time).
struct LoopState {
    counters: NodeCounters,
    at_last_report: NodeCounters,
    last_report: Instant,
    /// The counters at the last reports, oldest first (the rejected share's window).
    at_reports: VecDeque<NodeCounters>,
    /// When the last message was taken.
    last_taken: Option<Instant>,
    /// The findings said on stderr, by key, at the level said (each is said when it comes or
    /// grows, not at every report).
    said: HashMap<String, u8>,
    stamps: StampBook,
    /// The last sequence number of each input publisher.
    sequences: HashMap<GUID, i64>,
    /// The size of the session's first frame: the session takes only frames of that size, so only
    /// they get an index (and a stamp) in it.
    first_grid: Option<Grid>,
}

impl LoopState {
    /// One message of the input: its frame into `values`, or why it was rejected.
    fn take(
        &mut self,
        sample: DeserializedCacheChange<RawCdr>,
        kind: FrameType,
        topic: &str,
        values: &mut Vec<f64>,
    ) -> Input {
        let arrival = Instant::now();
        self.last_taken = Some(arrival);
        let sequence = i64::from(sample.sequence_number);
        match self.sequences.insert(sample.writer_guid, sequence) {
            Some(last) if sequence > last + 1 => {
                self.counters.dropped += (sequence - last - 1) as u64
            }
            Some(_) => {}
            None => {
                self.counters.publishers += 1;
                // A writer numbers its samples from 1: those before the first one taken were
                // published before it matched the node, before the node had discovered it, or
                // lost before the node took one; DDS (RustDDS: no SAMPLE_LOST status) cannot tell
                // which, so they are not `dropped`.
                self.counters.before_first += u64::try_from(sequence - 1).unwrap_or(0);
            }
        }
        let index = self.counters.received;
        self.counters.received += 1;
        match decode_frame(kind, &sample.sample.0, values) {
            Ok((grid, stamp)) => {
                // Header stamps as given (a bag's first frame may be at 0); arrays have none.
                let stamp = stamp.unwrap_or_else(wall_clock);
                if *self.first_grid.get_or_insert(grid) == grid {
                    self.stamps.push(time_of(stamp));
                }
                Input::Frame {
                    grid,
                    has_mask: false,
                    timestamp_us: stamp.nanos().map(|ns| ns / 1000),
                    arrival,
                }
            }
            Err(why) => {
                self.counters.undecodable += 1;
                Input::Skipped(format!("{topic}: message {index} rejected: {why}"))
            }
        }
    }
}

impl LoopState {
    fn new() -> Self {
        Self {
            counters: NodeCounters::default(),
            at_last_report: NodeCounters::default(),
            last_report: Instant::now(),
            at_reports: VecDeque::new(),
            last_taken: None,
            said: HashMap::new(),
            stamps: StampBook::default(),
            sequences: HashMap::new(),
            first_grid: None,
        }
    }

    /// Publishes `/diagnostics` for node `names.0` reading `names.1`: the counters, what changed
    /// since the last report, and what `graph` shows; the findings not said yet go to `warn`.
    fn report(
        &mut self,
        outputs: &Outputs,
        names: (&str, &str),
        graph: &[Finding],
        ended: bool,
        warn: &dyn Fn(&str),
    ) {
        let whole_run = NodeCounters::default();
        let report = DiagnosticsReport {
            node: names.0,
            input: names.1,
            now: &self.counters,
            before: &self.at_last_report,
            // The final report judges the whole run's rejected share.
            window_start: if ended {
                &whole_run
            } else {
                self.at_reports.front().unwrap_or(&whole_run)
            },
            period: self.last_report.elapsed(),
            silence: self.last_taken.map(|t| t.elapsed()),
            graph,
            stamp: time_of(wall_clock()),
            ended,
        };
        let findings = report.findings();
        let message = report.message();
        self.say(&findings, warn);
        if outputs.diagnostics.publish(message).is_err() {
            self.counters.publish_failures += 1;
        }
        self.at_last_report = self.counters.clone();
        if self.at_reports.len() == REJECTED_WINDOW {
            self.at_reports.pop_front();
        }
        self.at_reports.push_back(self.counters.clone());
        self.last_report = Instant::now();
    }

    /// Says on stderr each finding that is new or worse than when it was last said; the session's
    /// own errors and the counts stderr's summary gives are not repeated.
    fn say(&mut self, findings: &[Finding], warn: &dyn Fn(&str)) {
        let quiet = ["error", "dropped", "publish"];
        let mut now = HashMap::new();
        for finding in findings.iter().filter(|f| !quiet.contains(&f.key.as_str())) {
            if self
                .said
                .get(&finding.key)
                .is_none_or(|&l| l < finding.level)
            {
                let level = if finding.level == DiagnosticStatus::ERROR {
                    "error"
                } else {
                    "warning"
                };
                warn(&format!("{level}: {}", finding.text));
            }
            let said = self.said.get(&finding.key).copied().unwrap_or(0);
            now.insert(finding.key.clone(), said.max(finding.level));
        }
        // A finding gone and back is said again.
        self.said = now;
    }
}

fn wall_clock() -> Stamp {
    let nanos = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| u64::try_from(d.as_nanos()).unwrap_or(u64::MAX));
    Stamp::from_nanos(nanos)
}

/// Runs the node until its stop handle is called (a signal), or its input cannot go on (a fatal
/// error, as in `presrs stream`): every JSON event also goes to `on_line`, the session's notices to
/// `notify`, what the node finds wrong with its input or the graph (`/diagnostics` WARN and ERROR
/// findings: docs/ros2.md) to `warn`, once each as it comes. Publishes the final diagnostics, then
/// waits `linger` for subscribers to take the last messages.
pub fn run_node(
    graph: NodeGraph,
    model: &TrainedModel,
    profile: &OnlineProfile,
    on_line: &mut dyn FnMut(&str),
    notify: &dyn Fn(&ConnectionNotice),
    warn: &dyn Fn(&str),
) -> Result<NodeSummary> {
    let NodeGraph {
        _context,
        node,
        reader,
        outputs,
        mut poll,
        stop,
        options,
        input_topic,
        watch,
    } = graph;
    let name = node.fully_qualified_name();
    let state = RefCell::new(LoopState::new());
    let watch = RefCell::new(watch);
    let report = |state: &mut LoopState, watch: &mut GraphWatch, ended: bool| {
        let graph = watch.findings();
        state.report(&outputs, (&name, &input_topic), &graph, ended, warn);
    };
    let mut events = Events::with_capacity(16);
    let next = |values: &mut Vec<f64>, _present: &mut Vec<bool>| loop {
        if stop.is_stopped() {
            return Input::End;
        }
        {
            let mut s = state.borrow_mut();
            if s.last_report.elapsed() >= options.diagnostics_period {
                report(&mut s, &mut watch.borrow_mut(), false);
            }
        }
        match reader.try_take_one() {
            Ok(Some(sample)) => {
                let mut s = state.borrow_mut();
                return s.take(sample, options.input_type, &input_topic, values);
            }
            Ok(None) => {
                let due = options
                    .diagnostics_period
                    .saturating_sub(state.borrow().last_report.elapsed());
                // An interrupted poll (a signal) is looked at like a wake-up.
                let _ = poll.poll(&mut events, Some(due.min(IDLE_POLL)));
                reader.drain_read_notifications();
            }
            Err(err) => {
                let mut s = state.borrow_mut();
                s.counters.undecodable += 1;
                return Input::Skipped(format!("{input_topic}: cannot read a message: {err:?}"));
            }
        }
    };
    let mut publisher = Publisher {
        state: &state,
        outputs: &outputs,
        frame_id: &options.name,
        on_line,
    };
    let session = run_frames(model, profile, next, &mut publisher, notify)?;
    let mut s = state.into_inner();
    report(&mut s, &mut watch.borrow_mut(), true);
    std::thread::sleep(options.linger);
    Ok(NodeSummary {
        session,
        counters: s.counters,
        input: input_topic,
    })
}

/// The session's observer in the node: each event counted, published, and handed to `on_line`.
struct Publisher<'a> {
    state: &'a RefCell<LoopState>,
    outputs: &'a Outputs,
    frame_id: &'a str,
    on_line: &'a mut dyn FnMut(&str),
}

impl SessionObserver for Publisher<'_> {
    fn event(&mut self, event: &SessionEvent) -> bool {
        let mut s = self.state.borrow_mut();
        s.counters.note_event(event);
        let line = event.to_line();
        // On the wire first (a robot waits for it), then stdout (a pipe that may be slow to read).
        let published = publish_event(self.outputs, event, &line, &s.stamps, self.frame_id);
        s.counters.publish_failures += u64::from(!published);
        (self.on_line)(&line);
        published
    }
}

/// Publishes one event: its typed message and gait command when it has them (first: a decision is
/// what a robot waits for), then the JSON string. False when any of them could not be published.
fn publish_event(
    outputs: &Outputs,
    event: &SessionEvent,
    line: &str,
    stamps: &StampBook,
    frame_id: &str,
) -> bool {
    let mut ok = true;
    match event {
        SessionEvent::Classification(decision) => {
            let decision = decision_message(decision, stamps, frame_id);
            let gait = decision.gait.clone();
            ok &= outputs.decisions.publish(decision).is_ok();
            if !gait.is_empty() {
                ok &= outputs.gait.publish(StringMsg { data: gait }).is_ok();
            }
        }
        SessionEvent::Touchdown(_) | SessionEvent::Liftoff(_) => {
            if let Some(stance) = stance_message(event, stamps, frame_id) {
                ok &= outputs.stances.publish(stance).is_ok();
            }
        }
        SessionEvent::Error(_) | SessionEvent::End(_) => {}
    }
    let data = line.to_owned();
    ok &= outputs.events.publish(StringMsg { data }).is_ok();
    ok
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_stamp_book_forgets_the_oldest_frames_only() {
        let mut book = StampBook::default();
        for i in 0..(STAMPS_KEPT as u64 + 3) {
            book.push(Time::new(i as i32, 0));
        }
        assert_eq!(book.stamp_of(0), None);
        assert_eq!(book.stamp_of(2), None);
        assert_eq!(book.stamp_of(3), Some(Time::new(3, 0)));
        let last = STAMPS_KEPT as u64 + 2;
        assert_eq!(book.stamp_of(last), Some(Time::new(last as i32, 0)));
        assert_eq!(book.stamp_of(last + 1), None);
    }
}
