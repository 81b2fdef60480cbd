//! Joining the ROS 2 graph: the DDS participant, the node, the input reader and the publishers.

use std::net::{IpAddr, Ipv4Addr};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use ros2_client::dds::rustdds::mio1::{Interest, Poll, Token, Waker};
use ros2_client::dds::rustdds::no_key::SimpleDataReader;
use ros2_client::dds::rustdds::{DomainParticipantBuilder, QosPolicies};
use ros2_client::{Context, MessageTypeName, Name, Node, NodeName, Publisher, QosProfile};
use serde::Serialize;

use crate::error::{Result, Ros2Error};
use crate::messages::{DiagnosticArray, StanceEvent, StringMsg, TerrainDecision};
use crate::names::resolve_topic;
use crate::options::{NodeOptions, output_qos, ros_type};
use crate::raw::{RawAdapter, RawCdr};
use crate::watch::GraphWatch;

/// The poll token of the input reader.
pub(crate) const INPUT: Token = Token(1);
/// The poll token of the stop waker.
pub(crate) const STOP: Token = Token(2);

/// Reliable outputs keep this many messages for a slow subscriber.
const OUTPUT_DEPTH: usize = 100;

/// The publishers of the node's outputs.
pub(crate) struct Outputs {
    pub decisions: Publisher<TerrainDecision>,
    pub stances: Publisher<StanceEvent>,
    pub events: Publisher<StringMsg>,
    pub gait: Publisher<StringMsg>,
    pub diagnostics: Publisher<DiagnosticArray>,
}

/// A node in the ROS 2 graph: what it reads, what it publishes, and how it is woken.
pub struct NodeGraph {
    // Kept alive: dropping the node or the context leaves the graph.
    pub(crate) _context: Context,
    pub(crate) node: Node,
    pub(crate) reader: SimpleDataReader<RawCdr, RawAdapter>,
    pub(crate) outputs: Outputs,
    pub(crate) poll: Poll,
    pub(crate) stop: NodeStop,
    pub(crate) options: NodeOptions,
    /// The input topic, resolved against the namespace (`/robot/left/pressure`).
    pub(crate) input_topic: String,
    /// What discovery shows about the input's publishers and the node's name.
    pub(crate) watch: GraphWatch,
}

impl std::fmt::Debug for NodeGraph {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "NodeGraph({})", self.node.fully_qualified_name())
    }
}

/// Stops a running node from another thread (a signal handler): its session ends as if the input had,
/// with the final `end` event and diagnostics.
#[derive(Clone, Debug)]
pub struct NodeStop {
    flag: Arc<AtomicBool>,
    waker: Arc<Waker>,
}

impl NodeStop {
    /// Asks the node to stop.
    pub fn stop(&self) {
        self.flag.store(true, Ordering::SeqCst);
        // A failed wake only delays the stop to the next poll timeout.
        let _ = self.waker.wake();
    }

    /// Whether [`stop`](Self::stop) was called.
    pub fn is_stopped(&self) -> bool {
        self.flag.load(Ordering::SeqCst)
    }
}

impl NodeGraph {
    /// Checks `options` and joins the graph: nothing is announced on the network before the names,
    /// the domain id and the QoS are known to be valid.
    pub fn join(options: &NodeOptions) -> Result<Self> {
        options.check()?;
        let mut builder = DomainParticipantBuilder::new(options.domain_id);
        if options.localhost_only {
            builder = builder.with_only_networks([IpAddr::V4(Ipv4Addr::LOCALHOST)]);
        }
        let participant = builder
            .build()
            .map_err(|e| Ros2Error::dds("create the DDS participant", e))?;
        let context = Context::from_domain_participant(participant)
            .map_err(|e| Ros2Error::dds("create the ROS 2 context", e))?;
        let node_name = NodeName::new(&options.namespace, &options.name)
            .map_err(|e| Ros2Error::dds("name the node", e))?;
        let mut node = context
            .new_node(node_name, ros2_client::NodeOptions::new())
            .map_err(|e| Ros2Error::dds("create the node", e))?;
        let reader = input_reader(&context, &node, options)?;
        let input_topic = resolve_topic(node.namespace(), &options.input);
        let (package, type_name) = ros_type(options.input_type);
        let watch = GraphWatch::new(
            context.domain_participant(),
            node.fully_qualified_name(),
            input_topic.clone(),
            MessageTypeName::new(package, type_name).dds_msg_type(),
            reader.qos().clone(),
        )?;
        let outputs = Outputs {
            decisions: publisher(
                &mut node,
                &options.outputs.decisions,
                ("presrs_msgs", "TerrainDecision"),
            )?,
            stances: publisher(
                &mut node,
                &options.outputs.stances,
                ("presrs_msgs", "StanceEvent"),
            )?,
            events: publisher(&mut node, &options.outputs.events, ("std_msgs", "String"))?,
            gait: publisher(&mut node, &options.outputs.gait, ("std_msgs", "String"))?,
            diagnostics: publisher(
                &mut node,
                &options.outputs.diagnostics,
                ("diagnostic_msgs", "DiagnosticArray"),
            )?,
        };
        let poll = Poll::new().map_err(|e| Ros2Error::dds("create the poll", e))?;
        let mut graph_reader = reader;
        poll.registry()
            .register(&mut graph_reader, INPUT, Interest::READABLE)
            .map_err(|e| Ros2Error::dds("watch the input", e))?;
        let waker = Waker::new(poll.registry(), STOP)
            .map_err(|e| Ros2Error::dds("create the stop waker", e))?;
        Ok(Self {
            _context: context,
            node,
            reader: graph_reader,
            outputs,
            poll,
            stop: NodeStop {
                flag: Arc::new(AtomicBool::new(false)),
                waker: Arc::new(waker),
            },
            options: options.clone(),
            input_topic,
            watch,
        })
    }

    /// The handle that stops the node from another thread.
    pub fn stop_handle(&self) -> NodeStop {
        self.stop.clone()
    }

    /// The node's fully qualified name (`/namespace/name`).
    pub fn fully_qualified_name(&self) -> String {
        self.node.fully_qualified_name()
    }

    /// The input topic, resolved against the node's namespace.
    pub fn input_topic(&self) -> &str {
        &self.input_topic
    }
}

/// A topic of the node, `name` resolved against its namespace.
fn topic(
    node: &Node,
    name: &str,
    (package, type_name): (&str, &str),
    qos: &QosProfile,
) -> Result<ros2_client::dds::rustdds::Topic> {
    // Resolved here: ros2-client puts a relative name in the root namespace as `rt//name`.
    let name = &resolve_topic(node.namespace(), name);
    let parsed =
        Name::parse(name).map_err(|e| Ros2Error::dds(format!("name the topic {name}"), e))?;
    node.create_topic(&parsed, MessageTypeName::new(package, type_name), qos)
        .map_err(|e| Ros2Error::dds(format!("create the topic {name}"), e))
}

/// The input reader: raw CDR, decoded by `presrs_io::mcap`, with the input QoS.
fn input_reader(
    context: &Context,
    node: &Node,
    options: &NodeOptions,
) -> Result<SimpleDataReader<RawCdr, RawAdapter>> {
    let qos = options.input_qos.profile();
    let topic = topic(node, &options.input, ros_type(options.input_type), &qos)?;
    let dds_qos = QosPolicies::from(&qos);
    let subscriber = context
        .domain_participant()
        .create_subscriber(&dds_qos)
        .map_err(|e| Ros2Error::dds("create the subscriber", e))?;
    subscriber
        .create_simple_datareader_no_key::<RawCdr, RawAdapter>(&topic, Some(dds_qos))
        .map_err(|e| Ros2Error::dds(format!("subscribe to {}", options.input), e))
}

/// A reliable publisher of `M` on `name`.
fn publisher<M: Serialize>(
    node: &mut Node,
    name: &str,
    type_name: (&str, &str),
) -> Result<Publisher<M>> {
    let qos = output_qos(OUTPUT_DEPTH);
    let topic = topic(node, name, type_name, &qos)?;
    node.create_publisher(&topic, Some(qos))
        .map_err(|e| Ros2Error::dds(format!("publish on {name}"), e))
}
