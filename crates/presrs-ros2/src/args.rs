//! The node's options as the `presrs ros2` command line gives them (clap, behind the `cli` feature):
//! the node is a face of presrs, like the Python package, and its arguments live with it.

use std::path::PathBuf;

use presrs::session::ProfileOverrides;
use presrs_io::mcap::FrameType;

use crate::error::Result;
use crate::options::{InputQos, NodeOptions, domain_id, input_type, localhost_only_from_env};

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
    #[arg(long)]
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
    /// Online profile JSON (detector settings, calibration, gait table) [default: the model file's].
    #[arg(long)]
    pub profile: Option<PathBuf>,
    /// Recommended gait per terrain, TERRAIN=GAIT, comma separated (added to the profile's table).
    #[arg(long, value_delimiter = ',', value_name = "TERRAIN=GAIT",
          value_parser = |t: &str| t.split_once('=').map(|(n, v)| (n.trim().to_owned(), v.trim().to_owned())).filter(|(n, v)| !n.is_empty() && !v.is_empty()).ok_or_else(|| format!("expected TERRAIN=GAIT, got {t:?}")))]
    pub gait: Vec<(String, String)>,
    /// A whole-stance model decides K frames after touchdown, on the stance so far [default: at
    /// lift-off], as `presrs stream --decide-at`.
    #[arg(long, value_name = "K")]
    pub decide_at: Option<usize>,
}

impl Ros2Args {
    /// The node's options, the environment read through `var` (`ROS_DOMAIN_ID`, localhost only), and
    /// checked.
    pub fn node_options(&self, var: impl Fn(&str) -> Option<String>) -> Result<NodeOptions> {
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
