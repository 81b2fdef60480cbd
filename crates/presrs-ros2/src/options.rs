//! What the node is told: its name, domain, topics and QoS; checked before it joins the graph.

use std::time::Duration;

use presrs_io::mcap::FrameType;
use ros2_client::QosProfile;
use ros2_client::qos::{Durability, History, Reliability, WhenFull};

use crate::error::{Result, Ros2Error};
use crate::names::{check_namespace, check_node_name, check_topic_name};

/// Largest ROS 2 domain id (the DDS port mapping leaves no room above it).
pub const MAX_DOMAIN_ID: u16 = 232;

/// The QoS of the input subscription.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InputQos {
    /// ROS 2's sensor-data profile: best effort, keep the last `depth` frames (a frame not taken in
    /// time is replaced by a newer one; the node counts it as dropped).
    SensorData { depth: usize },
    /// Reliable, keep the last `depth` frames: a publisher resends what was lost on the way.
    Reliable { depth: usize },
}

impl InputQos {
    /// ROS 2's sensor-data default depth (`rclcpp::SensorDataQoS`).
    pub const SENSOR_DATA_DEPTH: usize = 5;
    /// The reliable profile keeps a burst of this many frames.
    pub const RELIABLE_DEPTH: usize = 1000;

    /// The profile of `name` (`sensor-data` or `reliable`) with `depth` frames kept (`None`: the
    /// profile's default).
    pub fn named(name: &str, depth: Option<usize>) -> Result<Self> {
        if depth == Some(0) {
            return Err(Ros2Error::Setting(
                "the input QoS depth is 0: keep at least 1 frame".to_owned(),
            ));
        }
        match name {
            "sensor-data" | "best-effort" => Ok(Self::SensorData {
                depth: depth.unwrap_or(Self::SENSOR_DATA_DEPTH),
            }),
            "reliable" => Ok(Self::Reliable {
                depth: depth.unwrap_or(Self::RELIABLE_DEPTH),
            }),
            other => Err(Ros2Error::Setting(format!(
                "unknown input QoS {other:?}: expected sensor-data or reliable"
            ))),
        }
    }

    /// The ROS 2 QoS profile.
    pub fn profile(self) -> QosProfile {
        let (reliability, depth) = match self {
            Self::SensorData { depth } => (Reliability::BestEffort, depth),
            Self::Reliable { depth } => (
                Reliability::Reliable {
                    when_full: WhenFull::DEFAULT,
                },
                depth,
            ),
        };
        QosProfile::subscription_default()
            .reliability(reliability)
            .durability(Durability::Volatile)
            .history(History::KeepLast { depth })
    }
}

/// The QoS of the outputs: reliable, keep the last `depth` messages (a subscriber that falls behind
/// by more loses the oldest).
pub fn output_qos(depth: usize) -> QosProfile {
    QosProfile::publisher_default()
        .reliability(Reliability::Reliable {
            when_full: WhenFull::DEFAULT,
        })
        .durability(Durability::Volatile)
        .history(History::KeepLast { depth })
}

/// The topics the node publishes on (relative names are in the node's namespace).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct OutputTopics {
    /// `presrs_msgs/msg/TerrainDecision`.
    pub decisions: String,
    /// `presrs_msgs/msg/StanceEvent`.
    pub stances: String,
    /// `std_msgs/msg/String`: the JSON events of `presrs stream`, one a message.
    pub events: String,
    /// `std_msgs/msg/String`: the recommended gait of each decision that has one.
    pub gait: String,
    /// `diagnostic_msgs/msg/DiagnosticArray`.
    pub diagnostics: String,
}

impl Default for OutputTopics {
    fn default() -> Self {
        Self {
            decisions: "presrs/decisions".to_owned(),
            stances: "presrs/stance_events".to_owned(),
            events: "presrs/events".to_owned(),
            gait: "presrs/gait".to_owned(),
            diagnostics: "/diagnostics".to_owned(),
        }
    }
}

/// Everything the node needs besides the model.
#[derive(Clone, Debug, PartialEq)]
pub struct NodeOptions {
    pub name: String,
    pub namespace: String,
    pub domain_id: u16,
    /// The pressure topic.
    pub input: String,
    /// Its message type.
    pub input_type: FrameType,
    pub input_qos: InputQos,
    pub outputs: OutputTopics,
    /// Discovery and traffic on the loopback interface only (tests, a robot's single computer).
    pub localhost_only: bool,
    /// How often `/diagnostics` is published.
    pub diagnostics_period: Duration,
    /// How long the node waits at its end for subscribers to take its last messages.
    pub linger: Duration,
}

impl NodeOptions {
    /// The defaults for input `input` on domain `domain_id`.
    pub fn new(input: &str, domain_id: u16) -> Self {
        Self {
            name: "presrs".to_owned(),
            namespace: "/".to_owned(),
            domain_id,
            input: input.to_owned(),
            input_type: FrameType::Image,
            input_qos: InputQos::SensorData {
                depth: InputQos::SENSOR_DATA_DEPTH,
            },
            outputs: OutputTopics::default(),
            localhost_only: false,
            diagnostics_period: Duration::from_secs(1),
            linger: Duration::from_millis(500),
        }
    }

    /// Checks every name against ROS 2's rules and the domain id against its range.
    pub fn check(&self) -> Result<()> {
        check_node_name(&self.name)?;
        check_namespace(&self.namespace)?;
        let o = &self.outputs;
        [
            &self.input,
            &o.decisions,
            &o.stances,
            &o.events,
            &o.gait,
            &o.diagnostics,
        ]
        .into_iter()
        .try_for_each(|topic| check_topic_name(topic))?;
        if self.domain_id > MAX_DOMAIN_ID {
            return Err(Ros2Error::DomainId {
                value: self.domain_id.to_string(),
                source_name: "the node's options",
                max: MAX_DOMAIN_ID,
            });
        }
        Ok(())
    }
}

/// The input message type named `name`: `sensor_msgs/msg/Image`, `std_msgs/msg/Float32MultiArray` or
/// `std_msgs/msg/UInt16MultiArray` (also without `/msg`, or `image`, `float32`, `uint16`).
pub fn input_type(name: &str) -> Result<FrameType> {
    match name {
        "image" => Ok(FrameType::Image),
        "float32" => Ok(FrameType::Float32MultiArray),
        "uint16" => Ok(FrameType::UInt16MultiArray),
        other => FrameType::of_schema(other).ok_or_else(|| {
            Ros2Error::Setting(format!(
                "unknown input type {other:?}: expected sensor_msgs/msg/Image, \
                 std_msgs/msg/Float32MultiArray or std_msgs/msg/UInt16MultiArray"
            ))
        }),
    }
}

/// The ROS 2 package and type name of a frame type.
pub fn ros_type(kind: FrameType) -> (&'static str, &'static str) {
    match kind {
        FrameType::Image => ("sensor_msgs", "Image"),
        FrameType::Float32MultiArray => ("std_msgs", "Float32MultiArray"),
        FrameType::UInt16MultiArray => ("std_msgs", "UInt16MultiArray"),
    }
}

/// The domain id: `explicit` (the command line) if given, else `ROS_DOMAIN_ID` from `env` if set and
/// not empty, else 0, as ROS 2 does.
pub fn domain_id(explicit: Option<u16>, env: Option<&str>) -> Result<u16> {
    let (value, source_name) = match (explicit, env.map(str::trim)) {
        (Some(id), _) => (id.to_string(), "the node's options"),
        (None, Some(text)) if !text.is_empty() => (text.to_owned(), "ROS_DOMAIN_ID"),
        (None, _) => return Ok(0),
    };
    value
        .parse::<u16>()
        .ok()
        .filter(|&id| id <= MAX_DOMAIN_ID)
        .ok_or(Ros2Error::DomainId {
            value,
            source_name,
            max: MAX_DOMAIN_ID,
        })
}

/// Whether ROS 2's environment asks for localhost-only discovery: `ROS_LOCALHOST_ONLY=1` (Humble) or
/// `ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST` (Jazzy on), as read by `var`.
pub fn localhost_only_from_env(var: impl Fn(&str) -> Option<String>) -> bool {
    var("ROS_LOCALHOST_ONLY").is_some_and(|v| v.trim() == "1")
        || var("ROS_AUTOMATIC_DISCOVERY_RANGE").is_some_and(|v| v.trim() == "LOCALHOST")
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;

    #[test]
    fn the_domain_id_comes_from_the_option_then_the_environment_then_0() {
        assert_eq!(domain_id(Some(7), Some("9")).unwrap(), 7);
        assert_eq!(domain_id(None, Some(" 9 ")).unwrap(), 9);
        assert_eq!(domain_id(None, Some("")).unwrap(), 0);
        assert_eq!(domain_id(None, None).unwrap(), 0);
        let err = domain_id(None, Some("300")).unwrap_err().to_string();
        assert!(
            err.contains("ROS_DOMAIN_ID") && err.contains("300"),
            "{err}"
        );
        assert!(domain_id(None, Some("x")).is_err());
        assert!(domain_id(Some(233), None).is_err());
    }

    #[test]
    fn options_with_a_bad_name_are_refused() {
        let mut options = NodeOptions::new("/foot/pressure", 0);
        assert!(options.check().is_ok());
        options.namespace = "robot".to_owned();
        assert!(
            options
                .check()
                .unwrap_err()
                .to_string()
                .contains("namespace")
        );
        options.namespace = "/robot".to_owned();
        options.outputs.gait = "gait//cmd".to_owned();
        assert!(
            options
                .check()
                .unwrap_err()
                .to_string()
                .contains("topic name")
        );
    }

    #[test]
    fn input_qos_profiles_and_types_by_name() {
        assert_eq!(
            InputQos::named("sensor-data", None).unwrap(),
            InputQos::SensorData { depth: 5 }
        );
        assert_eq!(
            InputQos::named("reliable", Some(10)).unwrap(),
            InputQos::Reliable { depth: 10 }
        );
        assert!(InputQos::named("reliable", Some(0)).is_err());
        assert!(InputQos::named("fast", None).is_err());
        assert_eq!(
            input_type("std_msgs/msg/UInt16MultiArray").unwrap(),
            FrameType::UInt16MultiArray
        );
        assert_eq!(input_type("image").unwrap(), FrameType::Image);
        assert!(input_type("sensor_msgs/msg/CompressedImage").is_err());
        let env = |k: &str| (k == "ROS_AUTOMATIC_DISCOVERY_RANGE").then(|| "LOCALHOST".to_owned());
        assert!(localhost_only_from_env(env));
        assert!(!localhost_only_from_env(|_| None));
    }
}
