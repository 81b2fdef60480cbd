//! What the node counts, and the `/diagnostics` message made of it.

use std::time::Duration;

use presrs::session::SessionEvent;

use crate::messages::{DiagnosticArray, DiagnosticStatus, Header, KeyValue, Time};

/// The node's counters: the input as it came, and the events of its session.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NodeCounters {
    /// Messages taken from the input topic.
    pub received: u64,
    /// Messages that could not be decoded as frames (an unsupported encoding, a short message):
    /// each is also an `error` event.
    pub undecodable: u64,
    /// Frames lost before the node took them: gaps in their publishers' sequence numbers (a burst
    /// faster than the node, which the input QoS history could not hold, or lost on the way).
    pub dropped: u64,
    /// Frames each publisher had sent before the first one the node took from it: published before
    /// it matched the node (never meant for it), or lost in a burst before the node took one. DDS
    /// does not say which (docs/ros2.md), so they are not in `dropped`.
    pub before_first: u64,
    /// Outputs that could not be published.
    pub publish_failures: u64,
    pub touchdowns: u64,
    pub decisions: u64,
    /// `error` events (rejected frames, failed classifications, a fatal input).
    pub errors: u64,
    /// The last `error` event's message.
    pub last_error: Option<String>,
    /// Publishers seen on the input (a publisher restarting is a new one).
    pub publishers: u64,
}

impl NodeCounters {
    /// Counts one event of the session.
    pub fn note_event(&mut self, event: &SessionEvent) {
        match event {
            SessionEvent::Touchdown(_) => self.touchdowns += 1,
            SessionEvent::Classification(_) => self.decisions += 1,
            SessionEvent::Error(error) => {
                self.errors += 1;
                self.last_error = Some(error.message.clone());
            }
            SessionEvent::Liftoff(_) | SessionEvent::End(_) => {}
        }
    }
}

/// One `/diagnostics` message: `now` the counters, `before` them at the last one (`period` ago).
#[derive(Debug)]
pub struct DiagnosticsReport<'a> {
    pub node: &'a str,
    pub input: &'a str,
    pub now: &'a NodeCounters,
    pub before: &'a NodeCounters,
    pub period: Duration,
    pub stamp: Time,
    /// The session has ended (the final message).
    pub ended: bool,
}

impl DiagnosticsReport<'_> {
    /// ERROR when an error came since the last message, WARN when frames were dropped, else OK.
    pub fn level(&self) -> u8 {
        if self.now.errors > self.before.errors {
            DiagnosticStatus::ERROR
        } else if self.now.dropped > self.before.dropped
            || self.now.publish_failures > self.before.publish_failures
        {
            DiagnosticStatus::WARN
        } else {
            DiagnosticStatus::OK
        }
    }

    /// The message.
    pub fn message(&self) -> DiagnosticArray {
        let (now, before) = (self.now, self.before);
        let level = self.level();
        let text = match level {
            DiagnosticStatus::ERROR => now.last_error.clone().unwrap_or_default(),
            DiagnosticStatus::WARN => format!(
                "{} frames dropped since the last report",
                now.dropped - before.dropped
            ),
            _ if self.ended => "ended".to_owned(),
            _ => "running".to_owned(),
        };
        let rate = (now.received - before.received) as f64 / self.period.as_secs_f64().max(1e-9);
        let values = [
            ("input_rate_hz", format!("{rate:.1}")),
            ("frames_received", now.received.to_string()),
            ("frames_dropped", now.dropped.to_string()),
            ("frames_before_first_taken", now.before_first.to_string()),
            ("frames_rejected_undecodable", now.undecodable.to_string()),
            ("stances", now.touchdowns.to_string()),
            ("decisions", now.decisions.to_string()),
            ("errors", now.errors.to_string()),
            ("publish_failures", now.publish_failures.to_string()),
            ("publishers_seen", now.publishers.to_string()),
            ("last_error", now.last_error.clone().unwrap_or_default()),
            (
                "state",
                if self.ended { "ended" } else { "running" }.to_owned(),
            ),
        ];
        DiagnosticArray {
            header: Header {
                stamp: self.stamp,
                frame_id: String::new(),
            },
            status: vec![DiagnosticStatus {
                level,
                name: format!("presrs: {}", self.node),
                message: text,
                hardware_id: self.input.to_owned(),
                values: values
                    .into_iter()
                    .map(|(key, value)| KeyValue {
                        key: key.to_owned(),
                        value,
                    })
                    .collect(),
            }],
        }
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;

    fn report<'a>(now: &'a NodeCounters, before: &'a NodeCounters) -> DiagnosticsReport<'a> {
        DiagnosticsReport {
            node: "/presrs",
            input: "/foot/pressure",
            now,
            before,
            period: Duration::from_secs(2),
            stamp: Time::ZERO,
            ended: false,
        }
    }

    #[test]
    fn an_error_since_the_last_report_is_an_error_status_with_its_message() {
        let before = NodeCounters::default();
        let mut now = before.clone();
        now.received = 200;
        now.note_event(&SessionEvent::error("input frame 3 rejected: x", false));
        let message = report(&now, &before).message();
        let status = &message.status[0];
        assert_eq!(status.level, DiagnosticStatus::ERROR);
        assert_eq!(status.message, "input frame 3 rejected: x");
        let rate = status
            .values
            .iter()
            .find(|kv| kv.key == "input_rate_hz")
            .unwrap();
        assert_eq!(rate.value, "100.0");
        // The next report, without a new error, is OK again; the counts stay.
        let later = report(&now, &now).message();
        assert_eq!(later.status[0].level, DiagnosticStatus::OK);
    }

    #[test]
    fn dropped_frames_are_a_warning() {
        let before = NodeCounters::default();
        let now = NodeCounters {
            dropped: 7,
            ..NodeCounters::default()
        };
        let message = report(&now, &before).message();
        assert_eq!(message.status[0].level, DiagnosticStatus::WARN);
        assert!(message.status[0].message.contains("7 frames dropped"));
    }
}
