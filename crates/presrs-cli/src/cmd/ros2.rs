//! `presrs ros2`: the ROS 2 node ([`presrs_ros2`]): its command line, the call, and what goes to stdout
//! (the `joined` line, the JSON events) and stderr (notices, the summary).

use presrs_core::online::DecideAt;
use std::io::Write;
use std::path::PathBuf;

use presrs::session::{ProfileOverrides, resolve_profile};
use presrs_io::mcap::FrameType;
use presrs_ros2::options::MAX_DOMAIN_ID;
use presrs_ros2::{
    InputQos, NodeGraph, NodeOptions, domain_id, input_type, localhost_only_from_env, run_node,
};
use presrs_stream::StopSignals;

use super::usage::UsageError;
use crate::printer::stream_log::notice_text;

/// Run as a ROS 2 node: pressure frames from a topic in, terrain decisions out (docs/ros2.md).
///
/// Publishes presrs_msgs/TerrainDecision on presrs/decisions, presrs_msgs/StanceEvent on
/// presrs/stance_events, the JSON events of `presrs stream` (also printed on stdout, after a `joined`
/// line) on presrs/events, the recommended gait on presrs/gait, and /diagnostics. SIGINT or SIGTERM
/// ends it cleanly; the exit code is 1 only when the input could not go on (frames of a size the
/// model cannot use), or the node could not start.
#[derive(Debug, clap::Args)]
#[command(
    after_help = "Examples (docs/ros2.md: topics, QoS, discovery, a launch file):
  presrs ros2 --model m.json --input /foot/pressure
  presrs ros2 --model m.json --input pressure --namespace /hopper --domain-id 7"
)]
pub struct Ros2Args {
    /// Model file from `presrs train` (read before the node joins the graph).
    #[arg(long)]
    pub model: PathBuf,
    #[command(flatten)]
    pub novelty: super::common::NoveltyArgs,
    /// The pressure topic (a relative name is in the namespace).
    #[arg(long, value_name = "TOPIC")]
    pub input: String,
    /// Its type: sensor_msgs/msg/Image (mono8, mono16, 16UC1, 32FC1), std_msgs/msg/Float32MultiArray
    /// or std_msgs/msg/UInt16MultiArray (2-D layout).
    #[arg(long, default_value = "sensor_msgs/msg/Image", value_name = "TYPE",
          value_parser = |t: &str| input_type(t).map_err(|e| e.to_string()))]
    pub input_type: FrameType,
    /// Input QoS: sensor-data (best effort, keep the last 5 frames) or reliable (keep the last 1000);
    /// --input-depth sets how many.
    #[arg(long, default_value = "sensor-data", value_name = "PROFILE")]
    pub input_qos: String,
    /// Frames the input QoS history keeps [default: the profile's].
    #[arg(long, value_name = "N")]
    pub input_depth: Option<usize>,
    /// ROS 2 domain id, 0 to 232 [default: ROS_DOMAIN_ID, else 0].
    #[arg(long, value_parser = domain_id_arg)]
    pub domain_id: Option<u16>,
    /// Node name.
    #[arg(long, default_value = "presrs")]
    pub name: String,
    /// Node namespace (absolute).
    #[arg(long, default_value = "/")]
    pub namespace: String,
    /// Discovery and traffic on the loopback interface only (also ROS_LOCALHOST_ONLY=1 or
    /// ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST).
    #[arg(long)]
    pub localhost_only: bool,
    /// Online profile JSON (detector settings, calibration, gait table) [default: learned from
    /// --calibrate when given, else the model file's, else warm-up calibration on the first 128
    /// frames].
    #[arg(long)]
    pub profile: Option<PathBuf>,
    /// Learn the calibration and sample offset k from the recordings of this manifest (e.g. the
    /// training manifest), as `presrs stream --calibrate`.
    #[arg(long, value_name = "MANIFEST")]
    pub calibrate: Option<PathBuf>,
    /// Recommended gait per terrain, TERRAIN=GAIT, comma separated (added to the profile's table).
    #[arg(long, value_delimiter = ',', value_name = "TERRAIN=GAIT",
          value_parser = |t: &str| crate::args::values::name_value(t, "TERRAIN=GAIT"))]
    pub gait: Vec<(String, String)>,
    /// A whole-stance model decides K frames after touchdown, on the stance so far, or at its first
    /// confident decision point (`auto`, else at its deadline point) [default: at lift-off], as `presrs stream --decide-at`.
    #[arg(long, value_name = "K|auto")]
    pub decide_at: Option<DecideAt>,
}

impl Ros2Args {
    /// The node's options, the environment read through `var` (`ROS_DOMAIN_ID`, localhost only), and
    /// checked.
    pub fn node_options(
        &self,
        var: impl Fn(&str) -> Option<String>,
    ) -> presrs_ros2::Result<NodeOptions> {
        let domain = domain_id(self.domain_id, var("ROS_DOMAIN_ID").as_deref())?;
        let mut options = NodeOptions::new(&self.input, domain);
        options.name.clone_from(&self.name);
        options.namespace.clone_from(&self.namespace);
        options.input_type = self.input_type;
        options.input_qos = InputQos::named(&self.input_qos, self.input_depth)?;
        options.localhost_only = self.localhost_only || localhost_only_from_env(var);
        options.check()?;
        Ok(options)
    }

    /// The changes to the model's online profile.
    pub fn overrides(&self) -> ProfileOverrides {
        ProfileOverrides {
            gait: self.gait.clone(),
            decide_at: self.decide_at,
            ..ProfileOverrides::default()
        }
    }
}

/// A `--domain-id` in ROS 2's range; out of it, a usage error (exit 2) as for any bad option value.
fn domain_id_arg(text: &str) -> Result<u16, String> {
    text.parse::<u16>()
        .ok()
        .filter(|&id| id <= MAX_DOMAIN_ID)
        .ok_or_else(|| format!("ROS 2 domain ids are 0 to {MAX_DOMAIN_ID}"))
}

pub fn run(args: &Ros2Args, out: &mut dyn Write) -> anyhow::Result<()> {
    // A bad name, QoS, depth or domain id (given, or in ROS_DOMAIN_ID, as clap treats an option's
    // environment variable) is bad usage: exit code 2, as docs/ros2.md says.
    let options = args
        .node_options(|key| std::env::var(key).ok())
        .map_err(|err| UsageError::error("ros2", err))?;
    // The model and the profile before the node joins the graph: a bad one announces nothing.
    let file = args
        .novelty
        .apply(presrs_io::model_file::load_model(&args.model)?);
    presrs::session::check_overrides(&file.model, &args.overrides())
        .map_err(|err| UsageError::error("ros2", err))?;
    let online = file.online.as_ref();
    let profile = resolve_profile(
        args.profile.as_deref(),
        args.calibrate.as_deref(),
        online,
        &args.overrides(),
    )?;
    presrs::session::check_profile(&file.model, &profile)?;
    let signals = StopSignals::register()?;
    let graph = NodeGraph::join(&options)?;
    writeln!(out, "{}", presrs_ros2::joined_event(&graph))?;
    out.flush()?;
    let stop = graph.stop_handle();
    let signal_thread = signals.on_first(move || stop.stop());
    let log = |notice: &_| stderr_line!("presrs ros2: {}", notice_text(notice));
    // What the node finds wrong with its input or the graph (its /diagnostics WARN and ERROR).
    let warn = |text: &str| stderr_line!("presrs ros2: {text}");
    // A closed stdout does not stop the node: its outputs are the topics.
    let mut print = |line: &str| drop(writeln!(out, "{line}").and_then(|()| out.flush()));
    let summary = run_node(graph, &file.model, &profile, &mut print, &log, &warn)?;
    if let Some(signal) = signal_thread.close() {
        stderr_line!("presrs ros2: stopped by {signal}");
    }
    let text = presrs_ros2::summary_text(&summary.input, &summary);
    stderr_line!("presrs ros2: {text}");
    anyhow::ensure!(
        !summary.session.fatal,
        "the input could not go on (see the error event)"
    );
    Ok(())
}
