//! The node's messages come from the session's typed events: a real session (a trained model, a
//! synthetic walk) is run, and every `TerrainDecision` and `StanceEvent` the node would publish is
//! checked against the JSON line of the same event, which serde writes independently of the message.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use presrs::session::Input;
use presrs::session::{SessionEvent, SessionObserver, run_frames};
use presrs_core::online::{Calibration, OnlineProfile};
use presrs_core::testing::{bench_fixture, synthetic_stream};
use presrs_ros2::messages::{FrameStamps, StanceEvent, Time, decision_message, stance_message};
use rand::SeedableRng;
use serde_json::Value;

/// Frame `i` stamped `i` seconds and `i` ms.
struct Seconds;
impl FrameStamps for Seconds {
    fn stamp_of(&self, index: u64) -> Option<Time> {
        Some(Time::new(index as i32, index as u32 * 1_000_000))
    }
}

#[derive(Default)]
struct Kept(Vec<SessionEvent>);
impl SessionObserver for Kept {
    fn event(&mut self, event: &SessionEvent) -> bool {
        self.0.push(event.clone());
        true
    }
}

fn session_events() -> Vec<SessionEvent> {
    let (model, _) = bench_fixture(3, 0).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(4);
    let frames = synthetic_stream(8, &mut rng);
    let load_range = frames
        .iter()
        .map(|f| f.values().iter().sum::<f64>())
        .fold(0.0, f64::max);
    let mut profile = OnlineProfile {
        calibration: Some(Calibration {
            baseline: 0.0,
            noise: 1.0,
            load_range,
        }),
        ..OnlineProfile::default()
    };
    profile
        .gait_table
        .insert(model.class_names()[0].clone(), "G2".into());
    let mut next_frame = frames.iter();
    let next = |values: &mut Vec<f64>, _: &mut Vec<bool>| match next_frame.next() {
        Some(frame) => {
            values.clear();
            values.extend_from_slice(frame.values());
            Input::Frame {
                grid: frame.grid(),
                has_mask: false,
                timestamp_us: None,
                arrival: std::time::Instant::now(),
            }
        }
        None => Input::End,
    };
    let mut kept = Kept::default();
    run_frames(&model, &profile, next, &mut kept, &|_| {}).unwrap();
    kept.0
}

fn stamp(line: &Value, key: &str) -> Time {
    Seconds.stamp_of(line[key].as_u64().unwrap()).unwrap()
}

#[test]
fn every_decision_message_holds_the_values_of_its_event_line() {
    let events = session_events();
    let mut decisions = 0;
    for event in &events {
        let line: Value = serde_json::from_str(&event.to_line()).unwrap();
        let SessionEvent::Classification(decision) = event else {
            continue;
        };
        decisions += 1;
        let msg = decision_message(decision, &Seconds, "foot");
        assert_eq!(line["event"], "classification");
        assert_eq!(msg.label, line["label"].as_str().unwrap());
        assert_eq!(msg.kind, line["kind"].as_str().unwrap());
        assert_eq!(u64::from(msg.class_index), line["class"].as_u64().unwrap());
        assert_eq!(msg.confidence, line["confidence"].as_f64().unwrap());
        assert_eq!(msg.stance, line["stance"].as_u64().unwrap());
        assert_eq!(msg.sample_frame, line["sample_frame"].as_u64().unwrap());
        assert_eq!(
            msg.touchdown_frame,
            line["touchdown_frame"].as_u64().unwrap()
        );
        assert_eq!(msg.frame, line["frame"].as_u64().unwrap());
        assert_eq!(
            u64::from(msg.frames_used),
            line["frames_used"].as_u64().unwrap()
        );
        assert_eq!(msg.latency_us, line["latency_us"].as_f64().unwrap());
        assert_eq!(msg.gait, line["gait"].as_str().unwrap_or_default());
        assert_eq!(msg.header.stamp, stamp(&line, "sample_frame"));
        assert_eq!(msg.touchdown_stamp, stamp(&line, "touchdown_frame"));
        assert_eq!(msg.class_names.len(), 4);
        for (name, p) in msg.class_names.iter().zip(&msg.posteriors) {
            assert_eq!(*p, line["posteriors"][name].as_f64().unwrap(), "{name}");
        }
        assert_eq!(
            msg.decided_at, 0,
            "a one-frame model's decision waited for nothing"
        );
        assert_eq!(
            u64::from(msg.gap_frames),
            line["gap_frames"].as_u64().unwrap_or(0)
        );
    }
    assert!(decisions >= 6, "{decisions} decisions in 8 stances");
}

#[test]
fn every_stance_message_holds_the_values_of_its_event_line() {
    let events = session_events();
    let (mut touchdowns, mut liftoffs) = (0, 0);
    for event in &events {
        let line: Value = serde_json::from_str(&event.to_line()).unwrap();
        let Some(msg) = stance_message(event, &Seconds, "foot") else {
            assert!(!matches!(
                event,
                SessionEvent::Touchdown(_) | SessionEvent::Liftoff(_)
            ));
            continue;
        };
        assert_eq!(msg.stance, line["stance"].as_u64().unwrap());
        assert_eq!(
            msg.touchdown_frame,
            line["touchdown_frame"].as_u64().unwrap()
        );
        assert_eq!(msg.frame, line["frame"].as_u64().unwrap());
        assert_eq!(msg.partial, line["partial"].as_bool().unwrap());
        assert_eq!(msg.header.stamp, stamp(&line, "frame"));
        if msg.event == StanceEvent::LIFTOFF {
            liftoffs += 1;
            assert_eq!(line["event"], "liftoff");
            assert_eq!(msg.end_frame, line["end_frame"].as_u64().unwrap());
            assert_eq!(msg.peak_frame, line["peak_frame"].as_u64().unwrap());
            assert_eq!(msg.peak_load, line["peak_load"].as_f64().unwrap());
            assert_eq!(msg.sampled, line["sampled"].as_bool().unwrap());
            assert_eq!(msg.liftoff_stamp, stamp(&line, "end_frame"));
            assert_eq!(
                u64::from(msg.gap_frames),
                line["gap_frames"].as_u64().unwrap_or(0)
            );
        } else {
            touchdowns += 1;
            assert_eq!(line["event"], "touchdown");
        }
    }
    assert!(touchdowns >= 6 && liftoffs >= 6, "{touchdowns} {liftoffs}");
}
