//! The messages the node publishes, as serde types in the field order of their `.msg` files (CDR is
//! positional), and the typed messages made from the stream's JSON events.
//!
//! `presrs_msgs/msg/TerrainDecision` and `StanceEvent` are defined in `ros/presrs_msgs/msg/`; the rest
//! are ROS 2's own. `builtin_interfaces/msg/Time` is ros2-client's [`Time`] (it goes over the wire as
//! `sec: i32, nanosec: u32`, a `nanosec` of a second or more folded into `sec`); the others are written
//! here because neither ros2-client nor its dependencies define them (`std_msgs/msg/Header`,
//! `std_msgs/msg/String`, `diagnostic_msgs/msg/KeyValue`, `DiagnosticStatus`, `DiagnosticArray`).

use presrs_io::mcap::Stamp;
pub use ros2_client::builtin_interfaces::Time;
use serde::{Deserialize, Serialize};
use serde_json::Value;

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
}

impl TerrainDecision {
    pub const DECIDED_AT_NONE: u8 = 0;
    pub const DECIDED_AT_LIFTOFF: u8 = 1;
    pub const DECIDED_AT_OFFSET: u8 = 2;
    pub const DECIDED_AT_LENGTH: u8 = 3;

    /// The constant of a JSON event's `decided_at` (absent: [`TerrainDecision::DECIDED_AT_NONE`]).
    fn decided_at_of(name: Option<&str>) -> u8 {
        match name {
            Some("liftoff") => Self::DECIDED_AT_LIFTOFF,
            Some("offset") => Self::DECIDED_AT_OFFSET,
            Some("length") => Self::DECIDED_AT_LENGTH,
            _ => Self::DECIDED_AT_NONE,
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

fn u64_of(event: &Value, key: &str) -> u64 {
    event[key].as_u64().unwrap_or(0)
}

fn stamp_at(stamps: &dyn FrameStamps, event: &Value, key: &str) -> Time {
    event[key]
        .as_u64()
        .and_then(|index| stamps.stamp_of(index))
        .unwrap_or(Time::ZERO)
}

/// The typed decision of a `classification` event; `class_names` the model's, in its order.
pub fn decision_message(
    event: &Value,
    class_names: &[String],
    stamps: &dyn FrameStamps,
    frame_id: &str,
) -> TerrainDecision {
    let posteriors = class_names
        .iter()
        .map(|name| event["posteriors"][name].as_f64().unwrap_or(f64::NAN))
        .collect();
    TerrainDecision {
        header: Header {
            stamp: stamp_at(stamps, event, "sample_frame"),
            frame_id: frame_id.to_owned(),
        },
        stance: u64_of(event, "stance"),
        kind: event["kind"].as_str().unwrap_or_default().to_owned(),
        label: event["label"].as_str().unwrap_or_default().to_owned(),
        class_index: u64_of(event, "class") as u32,
        class_names: class_names.to_vec(),
        confidence: event["confidence"].as_f64().unwrap_or(f64::NAN),
        posteriors,
        touchdown_frame: u64_of(event, "touchdown_frame"),
        sample_frame: u64_of(event, "sample_frame"),
        frame: u64_of(event, "frame"),
        frames_used: u64_of(event, "frames_used") as u32,
        decided_at: TerrainDecision::decided_at_of(event["decided_at"].as_str()),
        decided_at_frame: u64_of(event, "decided_at_frame"),
        decided_at_stamp: stamp_at(stamps, event, "decided_at_frame"),
        cut: event["cut"].as_bool().unwrap_or(false),
        touchdown_stamp: stamp_at(stamps, event, "touchdown_frame"),
        liftoff_stamp: stamp_at(stamps, event, "end_frame"),
        gait: event["gait"].as_str().unwrap_or_default().to_owned(),
        latency_us: event["latency_us"].as_f64().unwrap_or(0.0),
    }
}

/// The typed stance event of a `touchdown` or `liftoff` event (`None` for other events).
pub fn stance_message(
    event: &Value,
    stamps: &dyn FrameStamps,
    frame_id: &str,
) -> Option<StanceEvent> {
    let kind = match event["event"].as_str()? {
        "touchdown" => StanceEvent::TOUCHDOWN,
        "liftoff" => StanceEvent::LIFTOFF,
        _ => return None,
    };
    Some(StanceEvent {
        header: Header {
            stamp: stamp_at(stamps, event, "frame"),
            frame_id: frame_id.to_owned(),
        },
        event: kind,
        stance: u64_of(event, "stance"),
        touchdown_frame: u64_of(event, "touchdown_frame"),
        end_frame: u64_of(event, "end_frame"),
        frame: u64_of(event, "frame"),
        partial: event["partial"].as_bool().unwrap_or(false),
        peak_frame: u64_of(event, "peak_frame"),
        peak_load: event["peak_load"].as_f64().unwrap_or(0.0),
        sampled: event["sampled"].as_bool().unwrap_or(false),
        touchdown_stamp: stamp_at(stamps, event, "touchdown_frame"),
        liftoff_stamp: stamp_at(stamps, event, "end_frame"),
    })
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;
    use serde_json::json;

    struct Tenths;
    impl FrameStamps for Tenths {
        fn stamp_of(&self, index: u64) -> Option<Time> {
            Some(Time::new(
                (index / 10) as i32,
                (index % 10) as u32 * 100_000_000,
            ))
        }
    }

    #[test]
    fn a_classification_event_becomes_a_decision_with_the_frames_stamps() {
        let names = vec!["grass".to_owned(), "sand".to_owned()];
        let event = json!({"event": "classification", "kind": "single", "stance": 3, "label": "sand",
            "class": 1, "confidence": 0.75, "posteriors": {"grass": 0.25, "sand": 0.75},
            "sample_frame": 26, "frame": 26, "frames_used": 1, "touchdown_frame": 20,
            "latency_us": 12.5, "timestamp_us": 2_600_000, "gait": "walk"});
        let d = decision_message(&event, &names, &Tenths, "foot");
        assert_eq!((d.label.as_str(), d.class_index, d.stance), ("sand", 1, 3));
        assert_eq!(d.posteriors, [0.25, 0.75]);
        assert_eq!(d.header.stamp, Time::new(2, 600_000_000));
        assert_eq!(d.touchdown_stamp, Time::new(2, 0));
        assert_eq!(d.liftoff_stamp, Time::ZERO);
        assert_eq!(d.decided_at, TerrainDecision::DECIDED_AT_NONE);
        assert_eq!((d.decided_at_frame, d.decided_at_stamp), (0, Time::ZERO));
        assert_eq!(
            (d.gait.as_str(), d.header.frame_id.as_str()),
            ("walk", "foot")
        );
    }

    #[test]
    fn a_whole_stance_decision_says_what_it_waited_for_and_when() {
        let names = vec!["fast".to_owned(), "slow".to_owned()];
        for (name, constant) in [
            ("liftoff", TerrainDecision::DECIDED_AT_LIFTOFF),
            ("offset", TerrainDecision::DECIDED_AT_OFFSET),
            ("length", TerrainDecision::DECIDED_AT_LENGTH),
        ] {
            let event = json!({"event": "classification", "kind": "stance", "stance": 0,
                "label": "slow", "class": 1, "confidence": 0.5,
                "posteriors": {"fast": 0.5, "slow": 0.5}, "sample_frame": 33, "frame": 35,
                "frames_used": 24, "touchdown_frame": 10, "decided_at": name,
                "decided_at_frame": 34, "cut": name == "length"});
            let d = decision_message(&event, &names, &Tenths, "foot");
            assert_eq!(d.decided_at, constant, "{name}");
            assert_eq!(d.decided_at_frame, 34);
            assert_eq!(d.decided_at_stamp, Time::new(3, 400_000_000));
            assert_eq!(d.cut, name == "length");
        }
    }

    #[test]
    fn touchdown_and_liftoff_become_stance_events_and_others_none() {
        let liftoff = json!({"event": "liftoff", "stance": 1, "touchdown_frame": 10, "end_frame": 19,
            "len": 10, "peak_frame": 14, "peak_load": 5.5, "partial": false, "sampled": true,
            "frame": 21});
        let s = stance_message(&liftoff, &Tenths, "").unwrap();
        assert_eq!(
            (s.event, s.end_frame, s.frame, s.peak_frame),
            (StanceEvent::LIFTOFF, 19, 21, 14)
        );
        assert_eq!(s.liftoff_stamp, Time::new(1, 900_000_000));
        assert!(stance_message(&json!({"event": "end"}), &Tenths, "").is_none());
    }
}
