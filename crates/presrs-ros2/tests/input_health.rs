//! What the node says about an input it cannot receive, one that stops, one whose frames are
//! rejected, and a name another node has: `/diagnostics` levels and texts from the node's counters
//! and discovery's data (the same findings go to stderr). The wire itself is tested against Cyclone
//! DDS in `tests/ros2/test_node.py`.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::collections::BTreeMap;
use std::time::Duration;

use presrs::session::SessionEvent;
use presrs_ros2::diagnostics::{
    DiagnosticsReport, Finding, NodeCounters, SILENCE_ERROR, SILENCE_WARN,
};
use presrs_ros2::messages::{DiagnosticStatus, Time};
use presrs_ros2::watch::{SeenPublisher, publisher_findings, same_name_findings};
use presrs_ros2::{InputQos, NodeGraph, NodeOptions};
use ros2_client::Gid;
use ros2_client::dds::rustdds::QosPolicies;

const OK: u8 = DiagnosticStatus::OK;
const WARN: u8 = DiagnosticStatus::WARN;
const ERROR: u8 = DiagnosticStatus::ERROR;

fn report<'a>(
    now: &'a NodeCounters,
    before: &'a NodeCounters,
    silence: Option<Duration>,
    graph: &'a [Finding],
    ended: bool,
) -> DiagnosticsReport<'a> {
    DiagnosticsReport {
        node: "/presrs",
        input: "/foot/pressure",
        now,
        before,
        window_start: before,
        period: Duration::from_secs(1),
        silence,
        graph,
        stamp: Time::ZERO,
        ended,
    }
}

fn running(received: u64) -> NodeCounters {
    NodeCounters {
        received,
        ..NodeCounters::default()
    }
}

#[test]
fn an_input_that_stops_is_a_warning_after_1_s_and_an_error_after_5_s() {
    let before = running(100);
    let now = running(150);
    let level = |silence| report(&now, &before, Some(silence), &[], false).level();
    assert_eq!(level(Duration::from_millis(200)), OK);
    assert_eq!(SILENCE_WARN, Duration::from_secs(1));
    assert_eq!(level(SILENCE_WARN), WARN);
    assert_eq!(level(Duration::from_millis(4900)), WARN);
    assert_eq!(SILENCE_ERROR, Duration::from_secs(5));
    assert_eq!(level(SILENCE_ERROR), ERROR);
    let status = &report(&now, &now, Some(Duration::from_secs(2)), &[], false)
        .message()
        .status[0];
    assert_eq!(status.level, WARN);
    assert!(
        status
            .message
            .contains("no frame on /foot/pressure for 2.0 s"),
        "{}",
        status.message
    );
    let value = |key| {
        status
            .values
            .iter()
            .find(|kv| kv.key == key)
            .unwrap()
            .value
            .clone()
    };
    assert_eq!(value("seconds_since_last_frame"), "2.0");
    assert_eq!(value("input_rate_hz"), "0.0");
}

#[test]
fn before_the_first_frame_the_node_is_waiting_not_silent() {
    let none = NodeCounters::default();
    let status = &report(&none, &none, None, &[], false).message().status[0];
    assert_eq!(status.level, OK);
    assert_eq!(status.message, "waiting for frames on /foot/pressure");
}

fn with_rejections(received: u64, rejected: u64) -> NodeCounters {
    let mut counters = running(received);
    for i in 0..rejected {
        counters.note_event(&SessionEvent::error(
            format!("input frame {i} rejected: a 10x10 frame"),
            false,
        ));
    }
    counters
}

#[test]
fn the_share_of_rejected_frames_is_a_warning_above_1_percent_and_an_error_above_10() {
    let start = NodeCounters::default();
    // Judged over the window (here the whole run, as the final report does), not only since the
    // last report: an error since the last report is an ERROR already.
    let last = |c: &NodeCounters| {
        let mut at_last_report = c.clone();
        at_last_report.received -= 1;
        at_last_report
    };
    for (received, rejected, level) in [(1000, 5, OK), (1000, 50, WARN), (1000, 200, ERROR)] {
        let now = with_rejections(received, rejected);
        let before = last(&now);
        let r = DiagnosticsReport {
            window_start: &start,
            ..report(&now, &before, Some(Duration::ZERO), &[], false)
        };
        assert_eq!(r.level(), level, "{rejected} of {received}");
    }
}

#[test]
fn a_run_of_rejected_frames_does_not_end_ok() {
    // 200 frames, every one rejected; the final report comes when no error came since the last one.
    let now = with_rejections(200, 200);
    let start = NodeCounters::default();
    let r = DiagnosticsReport {
        window_start: &start,
        ..report(&now, &now, Some(Duration::from_millis(100)), &[], true)
    };
    let status = &r.message().status[0];
    assert_eq!(status.level, ERROR, "{}", status.message);
    assert!(
        status
            .message
            .contains("200 of 200 messages on /foot/pressure rejected since the start (100.0 %)"),
        "{}",
        status.message
    );
    // A failed classification names its stance and a fatal error stops the input: not rejections.
    let mut counters = NodeCounters::default();
    counters.note_event(&SessionEvent::error("the sensor is another", true));
    assert_eq!(counters.rejected, 0);
}

fn qos(input: InputQos) -> QosPolicies {
    QosPolicies::from(&input.profile())
}

const IMAGE: &str = "sensor_msgs::msg::dds_::Image_";

fn seen(id: &str, type_name: &str, offered: InputQos) -> SeenPublisher {
    SeenPublisher {
        id: id.to_owned(),
        type_name: type_name.to_owned(),
        offered: qos(offered),
    }
}

#[test]
fn a_publisher_the_node_cannot_receive_is_an_error_and_says_why() {
    let reliable = InputQos::Reliable { depth: 10 };
    let best_effort = InputQos::SensorData { depth: 5 };
    // A best-effort publisher and a reliable reader do not match.
    let found = publisher_findings(
        &[seen("w1", IMAGE, best_effort)],
        "/foot/pressure",
        IMAGE,
        &qos(reliable),
    );
    assert_eq!(found.len(), 1);
    assert_eq!(found[0].level, ERROR);
    assert!(found[0].text.contains("best-effort"), "{}", found[0].text);
    assert!(found[0].text.contains("--input-qos"), "{}", found[0].text);
    // Another type on the topic.
    let found = publisher_findings(
        &[seen("w2", "std_msgs::msg::dds_::String_", best_effort)],
        "/foot/pressure",
        IMAGE,
        &qos(best_effort),
    );
    assert_eq!(found[0].level, ERROR);
    assert!(
        found[0]
            .text
            .contains("publishes std_msgs/msg/String, the node reads sensor_msgs/msg/Image"),
        "{}",
        found[0].text
    );
    // Beside a publisher the node receives, a stray one is a warning.
    let found = publisher_findings(
        &[
            seen("w1", IMAGE, best_effort),
            seen("w2", "std_msgs::msg::dds_::String_", best_effort),
        ],
        "/foot/pressure",
        IMAGE,
        &qos(best_effort),
    );
    assert_eq!(
        found.iter().map(|f| f.level).collect::<Vec<_>>(),
        [WARN],
        "{found:?}"
    );
    // A reliable publisher serves a best-effort reader: nothing to say.
    let found = publisher_findings(
        &[seen("w1", IMAGE, reliable)],
        "/foot/pressure",
        IMAGE,
        &qos(best_effort),
    );
    assert!(found.is_empty(), "{found:?}");
}

#[test]
fn a_graph_finding_sets_the_level_and_the_message() {
    let now = running(0);
    let graph = [Finding::error(
        "publisher w1",
        "a publisher on /foot/pressure ...",
    )];
    let status = &report(&now, &now, None, &graph, false).message().status[0];
    assert_eq!(status.level, ERROR);
    assert_eq!(status.message, "a publisher on /foot/pressure ...");
}

#[test]
fn another_node_of_the_same_name_is_a_warning() {
    let own = Gid::from([1u8; 16]);
    let other = Gid::from([2u8; 16]);
    let mut participants = BTreeMap::new();
    participants.insert(own, vec!["/presrs".to_owned()]);
    participants.insert(other, vec!["/robot/presrs".to_owned()]);
    assert!(same_name_findings(own, "/presrs", &participants).is_empty());
    participants.insert(other, vec!["/talker".to_owned(), "/presrs".to_owned()]);
    let found = same_name_findings(own, "/presrs", &participants);
    assert_eq!(found.len(), 1);
    assert_eq!(found[0].level, WARN);
    assert!(
        found[0]
            .text
            .contains("another node named /presrs is in the graph"),
        "{}",
        found[0].text
    );
}

#[test]
fn the_joined_line_names_the_input_as_resolved() {
    let domain = 100 + (std::process::id() % 100) as u16;
    let mut options = NodeOptions::new("pressure", domain);
    options.namespace = "/robot/left".to_owned();
    options.localhost_only = true;
    let graph = NodeGraph::join(&options).unwrap();
    let joined = presrs_ros2::joined_event(&graph);
    assert_eq!(joined["input"], "/robot/left/pressure");
    assert_eq!(joined["node"], "/robot/left/presrs");
    let mut absolute = NodeOptions::new("/foot/pressure", domain);
    absolute.namespace = "/robot".to_owned();
    absolute.name = "other".to_owned();
    absolute.localhost_only = true;
    let graph = NodeGraph::join(&absolute).unwrap();
    assert_eq!(presrs_ros2::joined_event(&graph)["input"], "/foot/pressure");
}

#[test]
fn the_summary_counts_frames_processed_and_decisions_made_apart() {
    use presrs::core::online::OnlineStats;
    use presrs::session::ConnectionSummary;
    use presrs_ros2::NodeSummary;

    let summary = NodeSummary {
        session: ConnectionSummary {
            stats: OnlineStats {
                frames: 517,
                stances: 6,
                decisions: 6,
                fused_decisions: 0,
                rejected_frames: 0,
            },
            ..ConnectionSummary::default()
        },
        counters: running(517),
        input: "/robot/left/pressure".to_owned(),
    };
    let text = presrs_ros2::summary_text(&summary.input, &summary);
    assert!(
        text.starts_with(
            "/robot/left/pressure: 517 messages received, 517 frames processed, 6 stances, 6 \
             decisions made (0 fused)"
        ),
        "{text}"
    );
    assert!(!text.contains("classified"), "{text}");
}
