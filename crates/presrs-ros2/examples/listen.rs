//! Spike: a ros2-client node on a domain that prints the frames it receives on a topic.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::time::{Duration, Instant};

use presrs_io::mcap::{FrameType, decode_frame};
use presrs_ros2::raw::{RawAdapter, RawCdr};
use ros2_client::dds::rustdds::mio1::{Events, Interest, Poll, Token};
use ros2_client::dds::rustdds::{DomainParticipantBuilder, QosPolicies};
use ros2_client::{Context, MessageTypeName, Name, NodeName, NodeOptions, QosProfile};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let domain: u16 = args[1].parse().unwrap();
    let topic_name = &args[2];
    let seconds: u64 = args[3].parse().unwrap();
    // Loopback only: nothing leaves this machine.
    let participant = DomainParticipantBuilder::new(domain)
        .with_only_networks([std::net::IpAddr::from([127, 0, 0, 1])])
        .build()
        .unwrap();
    let context = Context::from_domain_participant(participant).unwrap();
    let mut node = context
        .new_node(
            NodeName::new("/", "presrs_spike").unwrap(),
            NodeOptions::new(),
        )
        .unwrap();
    let qos = QosProfile::subscription_default();
    let topic = node
        .create_topic(
            &Name::parse(topic_name).unwrap(),
            MessageTypeName::new("sensor_msgs", "Image"),
            &qos,
        )
        .unwrap();
    let dds_qos = QosPolicies::from(&qos);
    let subscriber = context
        .domain_participant()
        .create_subscriber(&dds_qos)
        .unwrap();
    let mut reader = subscriber
        .create_simple_datareader_no_key::<RawCdr, RawAdapter>(&topic, Some(dds_qos))
        .unwrap();
    let mut poll = Poll::new().unwrap();
    poll.registry()
        .register(&mut reader, Token(1), Interest::READABLE)
        .unwrap();
    let mut events = Events::with_capacity(8);
    let end = Instant::now() + Duration::from_secs(seconds);
    let mut values = Vec::new();
    let mut count = 0;
    eprintln!("listening");
    while Instant::now() < end {
        poll.poll(&mut events, Some(Duration::from_millis(100)))
            .unwrap();
        while let Some(sample) = reader.try_take_one().unwrap() {
            let decoded = decode_frame(FrameType::Image, &sample.sample.0, &mut values);
            count += 1;
            println!(
                "{count} seq {:?} {:?}",
                i64::from(sample.sequence_number),
                decoded.map(|(g, s)| (g, s))
            );
        }
    }
}
