//! What discovery shows about the node's input and name: publishers on the input topic that the node
//! cannot receive (another message type, or a QoS that does not match its reader's), and other nodes
//! of the same fully qualified name. Each is a [`Finding`] of the node's `/diagnostics`; DDS itself
//! says nothing of them to either side's user.

use std::collections::{BTreeMap, BTreeSet};

use ros2_client::Gid;
use ros2_client::dds::rustdds::no_key::SimpleDataReader;
use ros2_client::dds::rustdds::policy::{Durability, History, Reliability};
use ros2_client::dds::rustdds::{
    CDRDeserializerAdapter, DomainParticipant, Duration as DdsDuration, GUID, QosPolicies,
    QosPolicyBuilder, RTPSEntity, TopicKind,
};
use ros2_client::entities_info::ParticipantEntitiesInfo;

use crate::diagnostics::Finding;
use crate::error::{Result, Ros2Error};
use crate::messages::DiagnosticStatus;

/// ROS 2's topic of node names (`rmw_dds_common`), and its type.
const ROS_DISCOVERY_TOPIC: &str = "ros_discovery_info";
const ROS_DISCOVERY_TYPE: &str = "rmw_dds_common::msg::dds_::ParticipantEntitiesInfo_";

/// A publisher on the input topic, as discovery describes it.
#[derive(Clone, Debug)]
pub struct SeenPublisher {
    /// Its DDS endpoint GUID, as text (a key of its finding).
    pub id: String,
    /// Its DDS type name (`sensor_msgs::msg::dds_::Image_`).
    pub type_name: String,
    /// The QoS it offers.
    pub offered: QosPolicies,
}

/// Why the node cannot receive from a publisher, or `None` when it can: another type than
/// `expected_type` (a DDS type name), or an offered QoS that does not match `requested` (the
/// reader's).
pub fn publisher_problem(
    publisher: &SeenPublisher,
    expected_type: &str,
    requested: &QosPolicies,
) -> Option<String> {
    if publisher.type_name != expected_type {
        return Some(format!(
            "publishes {}, the node reads {} (give --input-type, or publish that type)",
            ros_type_name(&publisher.type_name),
            ros_type_name(expected_type)
        ));
    }
    let failed = publisher.offered.compliance_failure_wrt(requested)?;
    Some(
        if requested.is_reliable() && !publisher.offered.is_reliable() {
            "offers best-effort delivery, the node's reader asks reliable (--input-qos reliable): \
             they do not match; use --input-qos sensor-data, or make the publisher reliable"
                .to_owned()
        } else {
            format!("offers a QoS the node's reader cannot match ({failed:?})")
        },
    )
}

/// `pkg/msg/Type` of a DDS type name `pkg::msg::dds_::Type_` (other names as they are).
pub fn ros_type_name(dds: &str) -> String {
    match dds.split("::").collect::<Vec<_>>().as_slice() {
        [package, "msg", "dds_", name] => {
            format!("{package}/msg/{}", name.strip_suffix('_').unwrap_or(name))
        }
        _ => dds.to_owned(),
    }
}

/// The findings about the input's publishers: one for each the node cannot receive, an ERROR when
/// no publisher on the topic can deliver frames, else a WARN.
pub fn publisher_findings(
    publishers: &[SeenPublisher],
    topic: &str,
    expected_type: &str,
    requested: &QosPolicies,
) -> Vec<Finding> {
    let problems: Vec<(&SeenPublisher, String)> = publishers
        .iter()
        .filter_map(|p| Some((p, publisher_problem(p, expected_type, requested)?)))
        .collect();
    let level = if problems.len() == publishers.len() {
        DiagnosticStatus::ERROR
    } else {
        DiagnosticStatus::WARN
    };
    problems
        .into_iter()
        .map(|(p, why)| Finding {
            level,
            key: format!("publisher {}", p.id),
            text: format!("a publisher on {topic} that the node cannot receive: it {why}"),
        })
        .collect()
}

/// The findings about other participants with a node of the node's name `name` (ROS 2 tools and
/// parameters cannot tell such nodes apart).
pub fn same_name_findings(
    own: Gid,
    name: &str,
    participants: &BTreeMap<Gid, Vec<String>>,
) -> Vec<Finding> {
    participants
        .iter()
        .filter(|(gid, nodes)| **gid != own && nodes.iter().any(|n| n == name))
        .map(|(gid, _)| {
            Finding::warn(
                format!("name {gid:?}"),
                format!(
                    "another node named {name} is in the graph (participant {gid:?}): ROS 2 \
                     tools cannot tell the two apart; give each its own --name or --namespace"
                ),
            )
        })
        .collect()
}

/// Watches discovery for the node: the input topic's publishers, and ROS 2's node names.
pub(crate) struct GraphWatch {
    participant: DomainParticipant,
    own: Gid,
    node_name: String,
    /// The input topic's ROS name and DDS name (`rt/...`).
    topic: (String, String),
    expected_type: String,
    requested: QosPolicies,
    names: SimpleDataReader<ParticipantEntitiesInfo>,
    /// The node names each other participant announced last.
    participants: BTreeMap<Gid, Vec<String>>,
}

impl GraphWatch {
    /// A watch for node `node_name` reading `topic` (resolved) of DDS type `expected_type` with
    /// the reader's QoS `requested`.
    pub(crate) fn new(
        participant: DomainParticipant,
        node_name: String,
        topic: String,
        expected_type: String,
        requested: QosPolicies,
    ) -> Result<Self> {
        // Transient local, as ROS 2's nodes publish it: the names announced before the node joined
        // come too.
        let qos = QosPolicyBuilder::new()
            .durability(Durability::TransientLocal)
            .reliability(Reliability::Reliable {
                max_blocking_time: DdsDuration::ZERO,
            })
            .history(History::KeepLast { depth: 1 })
            .build();
        let dds_topic = participant
            .create_topic(
                ROS_DISCOVERY_TOPIC.to_owned(),
                ROS_DISCOVERY_TYPE.to_owned(),
                &qos,
                TopicKind::NoKey,
            )
            .map_err(|e| Ros2Error::dds("create the topic ros_discovery_info", e))?;
        let names = participant
            .create_subscriber(&qos)
            .and_then(|s| {
                s.create_simple_datareader_no_key::<
                    ParticipantEntitiesInfo,
                    CDRDeserializerAdapter<ParticipantEntitiesInfo>,
                >(&dds_topic, Some(qos.clone()))
            })
            .map_err(|e| Ros2Error::dds("read ros_discovery_info", e))?;
        let own = Gid::from(participant.guid());
        let dds_name = format!("rt{topic}");
        Ok(Self {
            participant,
            own,
            node_name,
            topic: (topic, dds_name),
            expected_type,
            requested,
            names,
            participants: BTreeMap::new(),
        })
    }

    /// What discovery shows now.
    pub(crate) fn findings(&mut self) -> Vec<Finding> {
        while let Ok(Some(info)) = self.names.try_take_one() {
            let info = info.into_value();
            let names = info.nodes().iter().map(|n| n.fully_qualified_name());
            self.participants.insert(info.gid(), names.collect());
        }
        let writers = self.participant.discovered_writers();
        // Only participants still in the graph (one that died without a word left its names).
        let alive: BTreeSet<_> = writers
            .iter()
            .map(|w| w.writer_proxy.remote_writer_guid.prefix)
            .collect();
        self.participants
            .retain(|gid, _| alive.contains(&GUID::from(*gid).prefix));
        let publishers: Vec<SeenPublisher> = writers
            .into_iter()
            .filter(|w| w.publication_topic_data.topic_name == self.topic.1)
            .map(|w| SeenPublisher {
                id: guid_text(w.writer_proxy.remote_writer_guid),
                type_name: w.publication_topic_data.type_name.clone(),
                offered: w.publication_topic_data.qos(),
            })
            .collect();
        let mut found = publisher_findings(
            &publishers,
            &self.topic.0,
            &self.expected_type,
            &self.requested,
        );
        found.extend(same_name_findings(
            self.own,
            &self.node_name,
            &self.participants,
        ));
        found
    }
}

fn guid_text(guid: GUID) -> String {
    format!("{guid:?}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dds_type_names_read_as_ros_names() {
        assert_eq!(
            ros_type_name("sensor_msgs::msg::dds_::Image_"),
            "sensor_msgs/msg/Image"
        );
        assert_eq!(ros_type_name("Odd"), "Odd");
    }
}
