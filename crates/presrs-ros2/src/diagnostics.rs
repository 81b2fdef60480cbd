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
    /// it matched the node (never meant for it), after that but before the node had discovered it
    /// (RustDDS drops the frames of a writer it does not know yet; a reliable publisher resends
    /// them), or lost in a burst before the node took one. DDS does not say which (docs/ros2.md),
    /// so they are not in `dropped`.
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
    /// Messages rejected (undecodable, another size, non-finite values: each an `error` event
    /// about one frame, naming no stance), for the rejected share.
    pub rejected: u64,
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
                // An error about one input frame (a fatal one stops the input; a stance's decision
                // that failed names its stance).
                if !error.fatal && error.stance.is_none() {
                    self.rejected += 1;
                }
            }
            SessionEvent::Liftoff(_) | SessionEvent::End(_) => {}
        }
    }
}

/// No frame for this long after frames came is a warning (the first report after it says so).
pub const SILENCE_WARN: Duration = Duration::from_secs(1);
/// No frame for this long after frames came is an error.
pub const SILENCE_ERROR: Duration = Duration::from_secs(5);
/// A share of rejected frames above this is a warning...
pub const REJECTED_WARN: f64 = 0.01;
/// ...and above this an error.
pub const REJECTED_ERROR: f64 = 0.10;
/// The share of rejected frames is taken over this many reports (10 s at the default period); the
/// final report takes the whole run.
pub const REJECTED_WINDOW: usize = 10;

/// One thing a report says about the input or the graph, at its level.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Finding {
    /// [`DiagnosticStatus::WARN`] or [`DiagnosticStatus::ERROR`].
    pub level: u8,
    /// What it is about, the same from report to report while it lasts (`silence`, `rejected`,
    /// `publisher <guid>`, `name <participant>`, ...): stderr says each once, when it comes or grows.
    pub key: String,
    pub text: String,
}

impl Finding {
    pub fn warn(key: impl Into<String>, text: impl Into<String>) -> Self {
        Self {
            level: DiagnosticStatus::WARN,
            key: key.into(),
            text: text.into(),
        }
    }

    pub fn error(key: impl Into<String>, text: impl Into<String>) -> Self {
        Self {
            level: DiagnosticStatus::ERROR,
            key: key.into(),
            text: text.into(),
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
    /// The counters at the start of the rejected frames' window ([`REJECTED_WINDOW`] reports ago;
    /// all zero for the whole run).
    pub window_start: &'a NodeCounters,
    pub period: Duration,
    /// How long since the last message was taken (`None` before the first).
    pub silence: Option<Duration>,
    /// What discovery shows that the node cannot receive or that clashes with it
    /// (`crate::watch::GraphWatch`).
    pub graph: &'a [Finding],
    pub stamp: Time,
    /// The session has ended (the final message).
    pub ended: bool,
}

impl DiagnosticsReport<'_> {
    /// What this report finds wrong: an error since the last report (ERROR, its message), the
    /// input silent ([`SILENCE_WARN`], [`SILENCE_ERROR`]), too many frames rejected
    /// ([`REJECTED_WARN`], [`REJECTED_ERROR`]), frames dropped or outputs not published since the
    /// last report (WARN), and the graph's findings.
    pub fn findings(&self) -> Vec<Finding> {
        let (now, before) = (self.now, self.before);
        let mut found = Vec::new();
        if now.errors > before.errors {
            found.push(Finding::error(
                "error",
                now.last_error.clone().unwrap_or_default(),
            ));
        }
        found.extend(self.silence_finding());
        found.extend(self.rejected_finding());
        if now.dropped > before.dropped {
            let dropped = now.dropped - before.dropped;
            found.push(Finding::warn(
                "dropped",
                format!("{dropped} frames dropped since the last report"),
            ));
        }
        if now.publish_failures > before.publish_failures {
            let failed = now.publish_failures - before.publish_failures;
            found.push(Finding::warn(
                "publish",
                format!("{failed} outputs could not be published since the last report"),
            ));
        }
        found.extend(self.graph.iter().cloned());
        found
    }

    /// The input silent since frames came (not judged in the final report: the node is ending).
    fn silence_finding(&self) -> Option<Finding> {
        if self.ended {
            return None;
        }
        let silence = self.silence.filter(|s| *s >= SILENCE_WARN)?;
        let text = format!(
            "no frame on {} for {:.1} s (after {} received)",
            self.input,
            silence.as_secs_f64(),
            self.now.received
        );
        Some(if silence >= SILENCE_ERROR {
            Finding::error("silence", text)
        } else {
            Finding::warn("silence", text)
        })
    }

    /// The share of the messages of the window that were rejected.
    fn rejected_finding(&self) -> Option<Finding> {
        let (now, start) = (self.now, self.window_start);
        let received = now.received.saturating_sub(start.received);
        let rejected = now.rejected.saturating_sub(start.rejected);
        if received == 0 || rejected == 0 {
            return None;
        }
        let share = rejected as f64 / received as f64;
        let over = if start.received == 0 && start.rejected == 0 {
            "since the start".to_owned()
        } else {
            format!("in the last {REJECTED_WINDOW} reports")
        };
        let text = format!(
            "{rejected} of {received} messages on {} rejected {over} ({:.1} %)",
            self.input,
            100.0 * share
        );
        if share > REJECTED_ERROR {
            Some(Finding::error("rejected", text))
        } else if share > REJECTED_WARN {
            Some(Finding::warn("rejected", text))
        } else {
            None
        }
    }

    /// The level: the worst finding's, OK without any.
    pub fn level(&self) -> u8 {
        level_of(&self.findings())
    }

    /// The message.
    pub fn message(&self) -> DiagnosticArray {
        let (now, before) = (self.now, self.before);
        let findings = self.findings();
        let level = level_of(&findings);
        let text = if level == DiagnosticStatus::OK {
            if self.ended {
                "ended".to_owned()
            } else if now.received == 0 {
                format!("waiting for frames on {}", self.input)
            } else {
                "running".to_owned()
            }
        } else {
            // The worst findings, the error since the last report first.
            let worst: Vec<&str> = findings
                .iter()
                .filter(|f| f.level == level)
                .map(|f| f.text.as_str())
                .collect();
            worst.join("; ")
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
            // The input's health (docs/ros2.md, "Diagnostics").
            ("frames_rejected", now.rejected.to_string()),
            (
                "seconds_since_last_frame",
                self.silence
                    .map_or_else(String::new, |s| format!("{:.1}", s.as_secs_f64())),
            ),
            (
                "problems",
                findings
                    .iter()
                    .map(|f| f.text.as_str())
                    .collect::<Vec<_>>()
                    .join("; "),
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

/// The worst level of `findings` (OK without any).
pub fn level_of(findings: &[Finding]) -> u8 {
    findings
        .iter()
        .map(|f| f.level)
        .max()
        .unwrap_or(DiagnosticStatus::OK)
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
            window_start: before,
            period: Duration::from_secs(2),
            silence: Some(Duration::from_millis(10)),
            graph: &[],
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
