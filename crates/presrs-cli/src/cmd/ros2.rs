//! `presrs ros2`: the ROS 2 node ([`presrs_ros2`]): arguments, the call, what goes to stdout and stderr.

use std::io::Write;
use std::path::PathBuf;

use presrs::stream::{ProfileOverrides, StopSignals, resolve_profile};
use presrs_ros2::{InputQos, NodeGraph, NodeOptions, run_node};

/// Run as a ROS 2 node: pressure frames from a topic in, terrain decisions out (docs/ros2.md).
///
/// Publishes presrs_msgs/TerrainDecision on presrs/decisions, presrs_msgs/StanceEvent on
/// presrs/stance_events, the JSON events of `presrs stream` (also printed on stdout) on presrs/events,
/// the recommended gait on presrs/gait, and /diagnostics. SIGINT or SIGTERM ends it cleanly; the exit
/// code is 1 only when the input could not go on (frames of a size the model cannot use).
#[derive(Debug, clap::Args)]
pub struct Ros2Args {
    /// Model file from `presrs train` (read before the node joins the graph).
    #[arg(long)]
    pub model: PathBuf,
    /// The pressure topic (relative names are in the namespace).
    #[arg(long, value_name = "TOPIC")]
    pub input: String,
    /// Its type: sensor_msgs/msg/Image, std_msgs/msg/Float32MultiArray or UInt16MultiArray.
    #[arg(long, default_value = "sensor_msgs/msg/Image", value_parser = |t: &str| presrs_ros2::input_type(t).map_err(|e| e.to_string()))]
    pub input_type: presrs_io::mcap::FrameType,
    /// Input QoS: sensor-data (best effort, keep last --input-depth, default 5) or reliable (default 1000).
    #[arg(long, default_value = "sensor-data", value_name = "PROFILE")]
    pub input_qos: String,
    #[arg(long, value_name = "N", help = "Frames the input QoS history keeps")]
    pub input_depth: Option<usize>,
    #[arg(long, help = "ROS 2 domain id [default: ROS_DOMAIN_ID, else 0]")]
    pub domain_id: Option<u16>,
    #[arg(long, default_value = "presrs", help = "Node name")]
    pub name: String,
    #[arg(long, default_value = "/", help = "Node namespace")]
    pub namespace: String,
    /// Discovery and traffic on the loopback interface only (also ROS_LOCALHOST_ONLY=1 or
    /// ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST).
    #[arg(long)]
    pub localhost_only: bool,
    #[arg(long, help = "Online profile JSON [default: the model file's]")]
    pub profile: Option<PathBuf>,
    #[arg(long, value_delimiter = ',', value_name = "TERRAIN=GAIT", help = "Recommended gait per terrain (added to the profile's table)",
          value_parser = |t: &str| super::usage::name_value(t, "TERRAIN=GAIT"))]
    pub gait: Vec<(String, String)>,
}

pub fn run(args: &Ros2Args, out: &mut dyn Write) -> anyhow::Result<()> {
    let var = |key: &str| std::env::var(key).ok();
    let mut options = NodeOptions::new(
        &args.input,
        presrs_ros2::domain_id(args.domain_id, var("ROS_DOMAIN_ID").as_deref())?,
    );
    (options.name, options.namespace) = (args.name.clone(), args.namespace.clone());
    options.input_type = args.input_type;
    options.input_qos = InputQos::named(&args.input_qos, args.input_depth)?;
    options.localhost_only = args.localhost_only || presrs_ros2::localhost_only_from_env(var);
    options.check()?;
    let file = presrs_io::model_file::load_model(&args.model)?;
    let overrides = ProfileOverrides {
        gait: args.gait.clone(),
        ..ProfileOverrides::default()
    };
    let profile = resolve_profile(
        args.profile.as_deref(),
        None,
        file.online.as_ref(),
        &overrides,
    )?;
    let signals = StopSignals::register()?;
    let graph = NodeGraph::join(&options)?;
    writeln!(out, "{}", presrs_ros2::joined_event(&graph))?;
    out.flush()?;
    let stop = graph.stop_handle();
    let signal_thread = signals.on_first(move || stop.stop());
    let log = |notice: &_| stderr_line!("presrs ros2: {}", presrs::stream_log::notice_text(notice));
    let mut print = |line: &str| drop(writeln!(out, "{line}").and_then(|()| out.flush()));
    let summary = run_node(graph, &file.model, &profile, &mut print, &log)?;
    if let Some(signal) = signal_thread.close() {
        stderr_line!("presrs ros2: stopped by {signal}");
    }
    stderr_line!(
        "presrs ros2: {}",
        presrs_ros2::summary_text(&options.input, &summary)
    );
    anyhow::ensure!(
        !summary.session.fatal,
        "the input could not go on (see the error event)"
    );
    Ok(())
}
