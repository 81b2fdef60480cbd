//! The messages the node publishes, as serde types in the field order of their `.msg` files (CDR is
//! positional), and the typed messages made from the session's typed events
//! ([`presrs::session::SessionEvent`]).
//!
//! `presrs_msgs/msg/TerrainDecision` and `StanceEvent` are defined in `ros/presrs_msgs/msg/`; the rest
//! are ROS 2's own. `builtin_interfaces/msg/Time` is ros2-client's [`Time`] (it goes over the wire as
//! `sec: i32, nanosec: u32`, a `nanosec` of a second or more folded into `sec`); the others are written
//! here because neither ros2-client nor its dependencies define them (`std_msgs/msg/Header`,
//! `std_msgs/msg/String`, `diagnostic_msgs/msg/KeyValue`, `DiagnosticStatus`, `DiagnosticArray`).

use presrs::session::{Classification, DecisionPoint, SessionEvent};
use presrs_io::mcap::Stamp;
pub use ros2_client::builtin_interfaces::Time;
use serde::{Deserialize, Serialize};

/// The `builtin_interfaces/msg/Time` of a frame's header stamp.
pub fn time_of(stamp: Stamp) -> Time {
    Time::new(stamp.sec, stamp.nanosec)
}

#[cfg(test)]
mod time_tests {
    use super::*;
    use ros2_client::dds::rustdds::RepresentationIdentifier;
    use ros2_client::dds::rustdds::serialization::to_writer_with_rep_id;

    /// The `.msg` file's layout, field for field.
    #[derive(Serialize)]
    struct MsgTime {
        sec: i32,
        nanosec: u32,
    }

    fn cdr(value: &impl Serialize) -> Vec<u8> {
        let mut bytes = Vec::new();
        to_writer_with_rep_id(&mut bytes, value, RepresentationIdentifier::CDR_LE).unwrap();
        bytes
    }

    #[test]
    fn ros2_clients_time_is_the_msg_files_time_on_the_wire() {
        for (sec, nanosec) in [
            (0, 0),
            (2, 600_000_000),
            (-1, 500_000_000),
            (i32::MAX, 999_999_999),
        ] {
            let stamp = Stamp { sec, nanosec };
            assert_eq!(
                cdr(&time_of(stamp)),
                cdr(&MsgTime { sec, nanosec }),
                "{stamp:?}"
            );
        }
        // A stamp's nanoseconds of a second or more go into its seconds.
        let folded = time_of(Stamp {
            sec: 1,
            nanosec: 1_500_000_000,
        });
        assert_eq!(
            cdr(&folded),
            cdr(&MsgTime {
                sec: 2,
                nanosec: 500_000_000
            })
        );
    }
}

/// `std_msgs/msg/Header`.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Header {
    pub stamp: Time,
    pub frame_id: String,
}

/// `std_msgs/msg/String`.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct StringMsg {
    pub data: String,
}

/// `diagnostic_msgs/msg/KeyValue`.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct KeyValue {
    pub key: String,
    pub value: String,
}

/// `diagnostic_msgs/msg/DiagnosticStatus`.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct DiagnosticStatus {
    /// [`DiagnosticStatus::OK`], [`WARN`](DiagnosticStatus::WARN), [`ERROR`](DiagnosticStatus::ERROR).
    pub level: u8,
    pub name: String,
    pub message: String,
    pub hardware_id: String,
    pub values: Vec<KeyValue>,
}

impl DiagnosticStatus {
    pub const OK: u8 = 0;
    pub const WARN: u8 = 1;
    pub const ERROR: u8 = 2;
}

/// `diagnostic_msgs/msg/DiagnosticArray`.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct DiagnosticArray {
    pub header: Header,
    pub status: Vec<DiagnosticStatus>,
}

/// `presrs_msgs/msg/TerrainDecision` (`ros/presrs_msgs/msg/TerrainDecision.msg`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TerrainDecision {
    pub header: Header,
    pub stance: u64,
    pub kind: String,
    pub label: String,
    pub class_index: u32,
    pub class_names: Vec<String>,
    pub confidence: f64,
    pub posteriors: Vec<f64>,
    pub touchdown_frame: u64,
    pub sample_frame: u64,
    pub frame: u64,
    pub frames_used: u32,
    /// What a whole-stance decision waited for: [`TerrainDecision::DECIDED_AT_LIFTOFF`],
    /// [`DECIDED_AT_OFFSET`](TerrainDecision::DECIDED_AT_OFFSET),
    /// [`DECIDED_AT_LENGTH`](TerrainDecision::DECIDED_AT_LENGTH), or
    /// [`DECIDED_AT_NONE`](TerrainDecision::DECIDED_AT_NONE) for one-frame and fused decisions.
    pub decided_at: u8,
    pub decided_at_frame: u64,
    pub decided_at_stamp: Time,
    pub cut: bool,
    pub touchdown_stamp: Time,
    pub liftoff_stamp: Time,
    pub gait: String,
    pub latency_us: f64,
    /// Early decisions (`--decide-at K` or `auto`): the rule, `fixed` or `auto` (empty without
    /// `--decide-at`); why then (`fixed`, `confident`, `deadline`, `not_confident`,
    /// `ended_first`); the decision
    /// point whose classifier decided (-1: the whole-stance classifier); the frames after touchdown
    /// at which it decided; `auto`'s threshold (0 otherwise).
    pub early_rule: String,
    pub early_reason: String,
    pub early_point: i64,
    pub early_frames: u64,
    pub early_threshold: f64,
    /// Frames missing inside the stance up to the sample frame (the event's `gap_frames`).
    pub gap_frames: u32,
    /// Novelty (a self-contained block: `has_novelty` false and the rest zero without a score).
    pub has_novelty: bool,
    pub unknown: bool,
    pub nearest: String,
    pub novelty: f64,
    pub novelty_threshold: f64,
    pub credibility: f64,
}

impl TerrainDecision {
    pub const DECIDED_AT_NONE: u8 = 0;
    pub const DECIDED_AT_LIFTOFF: u8 = 1;
    pub const DECIDED_AT_OFFSET: u8 = 2;
    pub const DECIDED_AT_LENGTH: u8 = 3;

    /// The constant of a whole-stance decision's point.
    fn decided_at_of(point: DecisionPoint) -> u8 {
        match point {
            DecisionPoint::Liftoff => Self::DECIDED_AT_LIFTOFF,
            DecisionPoint::Offset => Self::DECIDED_AT_OFFSET,
            DecisionPoint::Length => Self::DECIDED_AT_LENGTH,
        }
    }
}

/// `presrs_msgs/msg/StanceEvent` (`ros/presrs_msgs/msg/StanceEvent.msg`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StanceEvent {
    pub header: Header,
    /// [`StanceEvent::TOUCHDOWN`] or [`StanceEvent::LIFTOFF`].
    pub event: u8,
    pub stance: u64,
    pub touchdown_frame: u64,
    pub end_frame: u64,
    pub frame: u64,
    pub partial: bool,
    pub peak_frame: u64,
    pub peak_load: f64,
    pub sampled: bool,
    pub touchdown_stamp: Time,
    pub liftoff_stamp: Time,
    /// Liftoff only: frames missing inside the stance (the event's `gap_frames`).
    pub gap_frames: u32,
}

impl StanceEvent {
    pub const TOUCHDOWN: u8 = 0;
    pub const LIFTOFF: u8 = 1;
}

/// The stamps of the frames the events name (frame indices count the session's accepted frames).
pub trait FrameStamps {
    /// The header stamp of accepted frame `index`, if still known.
    fn stamp_of(&self, index: u64) -> Option<Time>;
}

fn stamp_of(stamps: &dyn FrameStamps, frame: u64) -> Time {
    stamps.stamp_of(frame).unwrap_or(Time::ZERO)
}

/// Saturates an index the message holds in 32 bits (a class index or a frame count never comes near).
fn u32_of(value: impl TryInto<u32>) -> u32 {
    value.try_into().unwrap_or(u32::MAX)
}

/// The typed decision of a `classification` event, field by field from the session's own event.
pub fn decision_message(
    decision: &Classification,
    stamps: &dyn FrameStamps,
    frame_id: &str,
) -> TerrainDecision {
    let whole = decision.whole_stance;
    let early = decision.early;
    let decided_at_frame = whole.map_or(0, |w| w.decided_at_frame);
    // A decision taken at lift-off waited for the lift-off frame; any other came before it.
    let liftoff = whole.filter(|w| w.decided_at == DecisionPoint::Liftoff);
    TerrainDecision {
        header: Header {
            stamp: stamp_of(stamps, decision.sample_frame),
            frame_id: frame_id.to_owned(),
        },
        stance: decision.stance,
        kind: decision.kind.name().to_owned(),
        label: decision.label.clone(),
        class_index: u32_of(decision.class),
        class_names: decision.posteriors.names().map(str::to_owned).collect(),
        confidence: decision.confidence,
        posteriors: decision.posteriors.values().collect(),
        touchdown_frame: decision.touchdown_frame,
        sample_frame: decision.sample_frame,
        frame: decision.frame,
        frames_used: u32_of(decision.frames_used),
        decided_at: whole.map_or(TerrainDecision::DECIDED_AT_NONE, |w| {
            TerrainDecision::decided_at_of(w.decided_at)
        }),
        decided_at_frame,
        decided_at_stamp: whole.map_or(Time::ZERO, |_| stamp_of(stamps, decided_at_frame)),
        cut: whole.is_some_and(|w| w.cut),
        touchdown_stamp: stamp_of(stamps, decision.touchdown_frame),
        liftoff_stamp: liftoff.map_or(Time::ZERO, |w| stamp_of(stamps, w.decided_at_frame)),
        gait: decision.gait.clone().unwrap_or_default(),
        latency_us: decision.latency_us,
        early_rule: early.map_or(String::new(), |e| e.early_rule.name().to_owned()),
        early_reason: early.map_or(String::new(), |e| e.early_reason.name().to_owned()),
        early_point: early
            .and_then(|e| e.early_point)
            .map_or(-1, |k| i64::try_from(k).unwrap_or(i64::MAX)),
        early_frames: early.map_or(0, |e| e.early_frames),
        early_threshold: early.and_then(|e| e.early_threshold).unwrap_or(0.0),
        gap_frames: u32_of(decision.gap_frames),
        has_novelty: decision.novelty.is_some(),
        unknown: decision.novelty.as_ref().is_some_and(|n| n.unknown),
        nearest: decision
            .novelty
            .as_ref()
            .map(|n| n.nearest.clone())
            .unwrap_or_default(),
        novelty: decision.novelty.as_ref().map_or(0.0, |n| n.novelty),
        novelty_threshold: decision
            .novelty
            .as_ref()
            .map_or(0.0, |n| n.novelty_threshold),
        credibility: decision
            .novelty
            .as_ref()
            .map_or(0.0, |n| n.credibility.unwrap_or(1.0)),
    }
}

/// The typed stance event of a `touchdown` or `liftoff` event (`None` for other events).
pub fn stance_message(
    event: &SessionEvent,
    stamps: &dyn FrameStamps,
    frame_id: &str,
) -> Option<StanceEvent> {
    let header = |frame| Header {
        stamp: stamp_of(stamps, frame),
        frame_id: frame_id.to_owned(),
    };
    match event {
        SessionEvent::Touchdown(td) => Some(StanceEvent {
            header: header(td.frame),
            event: StanceEvent::TOUCHDOWN,
            stance: td.stance,
            touchdown_frame: td.touchdown_frame,
            // Not known yet: the stance has not ended.
            end_frame: 0,
            frame: td.frame,
            partial: td.partial,
            peak_frame: 0,
            peak_load: 0.0,
            sampled: false,
            touchdown_stamp: stamp_of(stamps, td.touchdown_frame),
            liftoff_stamp: Time::ZERO,
            gap_frames: 0,
        }),
        SessionEvent::Liftoff(lo) => Some(StanceEvent {
            header: header(lo.frame),
            event: StanceEvent::LIFTOFF,
            stance: lo.stance,
            touchdown_frame: lo.touchdown_frame,
            end_frame: lo.end_frame,
            frame: lo.frame,
            partial: lo.partial,
            peak_frame: lo.peak_frame,
            peak_load: lo.peak_load,
            sampled: lo.sampled,
            touchdown_stamp: stamp_of(stamps, lo.touchdown_frame),
            liftoff_stamp: stamp_of(stamps, lo.end_frame),
            gap_frames: u32_of(lo.gap_frames),
        }),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use presrs::core::online::DecisionKind;
    use presrs::session::{Liftoff, Posteriors, Touchdown, WholeStance};

    use super::*;

    struct Tenths;
    impl FrameStamps for Tenths {
        fn stamp_of(&self, index: u64) -> Option<Time> {
            Some(Time::new(
                (index / 10) as i32,
                (index % 10) as u32 * 100_000_000,
            ))
        }
    }

    fn tenths(index: u64) -> Time {
        Tenths.stamp_of(index).unwrap()
    }

    fn decision(whole_stance: Option<WholeStance>) -> Classification {
        Classification {
            kind: DecisionKind::Single,
            stance: 3,
            label: "sand".to_owned(),
            class: 1,
            confidence: 0.75,
            posteriors: Posteriors(vec![("grass".to_owned(), 0.25), ("sand".to_owned(), 0.75)]),
            sample_frame: 26,
            frame: 26,
            frames_used: 1,
            touchdown_frame: 20,
            latency_us: 12.5,
            timestamp_us: Some(2_600_000),
            gait: Some("walk".to_owned()),
            whole_stance,
            early: None,
            gap_frames: 0,
            novelty: None,
        }
    }

    #[test]
    fn a_decision_says_unknown_with_the_nearest_class_and_the_score() {
        let plain = decision_message(&decision(None), &Tenths, "foot");
        assert!(!plain.has_novelty && !plain.unknown && plain.nearest.is_empty());
        let unknown = Classification {
            label: "unknown".to_owned(),
            novelty: Some(Box::new(presrs::session::NoveltyVerdict {
                unknown: true,
                nearest: "sand".to_owned(),
                novelty: 3.5,
                novelty_threshold: 2.0,
                credibility: Some(0.25),
            })),
            ..decision(None)
        };
        let d = decision_message(&unknown, &Tenths, "foot");
        assert!(d.has_novelty && d.unknown);
        assert_eq!((d.label.as_str(), d.nearest.as_str()), ("unknown", "sand"));
        assert_eq!(
            (d.novelty, d.novelty_threshold, d.credibility, d.class_index),
            (3.5, 2.0, 0.25, 1)
        );
    }

    #[test]
    fn a_classification_event_becomes_a_decision_with_the_frames_stamps() {
        let d = decision_message(&decision(None), &Tenths, "foot");
        assert_eq!((d.label.as_str(), d.class_index, d.stance), ("sand", 1, 3));
        assert_eq!(d.class_names, ["grass", "sand"]);
        assert_eq!(d.posteriors, [0.25, 0.75]);
        assert_eq!(d.kind, "single");
        assert_eq!(d.header.stamp, tenths(26));
        assert_eq!(d.touchdown_stamp, tenths(20));
        assert_eq!(d.liftoff_stamp, Time::ZERO);
        assert_eq!(d.decided_at, TerrainDecision::DECIDED_AT_NONE);
        assert_eq!((d.decided_at_frame, d.decided_at_stamp), (0, Time::ZERO));
        assert_eq!(
            (d.gait.as_str(), d.header.frame_id.as_str(), d.latency_us),
            ("walk", "foot", 12.5)
        );
    }

    #[test]
    fn a_whole_stance_decision_says_what_it_waited_for_and_when() {
        for (point, constant) in [
            (DecisionPoint::Liftoff, TerrainDecision::DECIDED_AT_LIFTOFF),
            (DecisionPoint::Offset, TerrainDecision::DECIDED_AT_OFFSET),
            (DecisionPoint::Length, TerrainDecision::DECIDED_AT_LENGTH),
        ] {
            let whole = WholeStance {
                decided_at: point,
                decided_at_frame: 34,
                cut: point == DecisionPoint::Length,
            };
            let d = decision_message(&decision(Some(whole)), &Tenths, "foot");
            assert_eq!(d.decided_at, constant, "{point:?}");
            assert_eq!(d.decided_at_frame, 34);
            assert_eq!(d.decided_at_stamp, tenths(34));
            assert_eq!(d.cut, point == DecisionPoint::Length);
            // Only a decision at lift-off knows the lift-off's stamp.
            let liftoff = if point == DecisionPoint::Liftoff {
                tenths(34)
            } else {
                Time::ZERO
            };
            assert_eq!(d.liftoff_stamp, liftoff, "{point:?}");
        }
    }

    #[test]
    fn touchdown_and_liftoff_become_stance_events_and_others_none() {
        let liftoff = SessionEvent::Liftoff(Liftoff {
            stance: 1,
            touchdown_frame: 10,
            end_frame: 19,
            len: 10,
            peak_frame: 14,
            peak_load: 5.5,
            partial: false,
            sampled: true,
            frame: 21,
            gap_frames: 2,
        });
        let s = stance_message(&liftoff, &Tenths, "").unwrap();
        assert_eq!(s.gap_frames, 2);
        assert_eq!(
            (s.event, s.end_frame, s.frame, s.peak_frame),
            (StanceEvent::LIFTOFF, 19, 21, 14)
        );
        assert_eq!(s.liftoff_stamp, tenths(19));
        assert_eq!(s.header.stamp, tenths(21));
        let touchdown = SessionEvent::Touchdown(Touchdown {
            stance: 2,
            touchdown_frame: 30,
            frame: 33,
            partial: true,
        });
        let t = stance_message(&touchdown, &Tenths, "").unwrap();
        assert_eq!(
            (t.event, t.stance, t.partial),
            (StanceEvent::TOUCHDOWN, 2, true)
        );
        assert_eq!(
            (t.touchdown_stamp, t.liftoff_stamp),
            (tenths(30), Time::ZERO)
        );
        assert!(stance_message(&SessionEvent::error("x", false), &Tenths, "").is_none());
    }
}
