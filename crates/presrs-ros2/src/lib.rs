//! presrs as a ROS 2 node: pressure images in, terrain decisions out, over DDS.
//!
//! Built on `ros2-client` (pure Rust over RustDDS: no ROS installation to build or run). The node
//! subscribes to a pressure topic (`sensor_msgs/msg/Image` mono8/mono16/16UC1/32FC1 in either byte
//! order, or a 2-D `std_msgs/msg/Float32MultiArray` / `UInt16MultiArray`), decodes each message with
//! the bag reader's own decoder (`presrs_io::mcap::decode_frame`, through [`raw`]), and runs the same
//! per-frame session as `presrs stream` ([`presrs::session::run_frames`]). Every JSON event goes out
//! on a `std_msgs/msg/String` topic as is, decisions and stance events as typed messages
//! (`ros/presrs_msgs`, [`messages`]), the recommended gait on its own topic, and the counters on
//! `/diagnostics`.
//!
//! Order of use: [`NodeOptions`] (checked: ROS 2 names, domain id), load the model, [`NodeGraph::join`],
//! then [`run_node`] until the [`NodeStop`] handle is called. See `docs/ros2.md`.

pub mod diagnostics;
pub mod error;
pub mod graph;
pub mod messages;
pub mod names;
pub mod node;
pub mod options;
pub mod raw;
pub mod report;
pub mod watch;

pub use diagnostics::NodeCounters;
pub use error::{Result, Ros2Error};
pub use graph::{NodeGraph, NodeStop};
pub use node::{NodeSummary, run_node};
pub use options::{
    InputQos, NodeOptions, OutputTopics, domain_id, input_type, localhost_only_from_env,
};
pub use report::{joined_event, summary_text};
