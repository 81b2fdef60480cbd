//! `presrs ros2`: the ROS 2 node ([`presrs_ros2`], whose options `Ros2Args` are): the call, and what
//! goes to stdout (the `joined` line, the JSON events) and stderr (notices, the summary).

use std::io::Write;

use presrs::session::resolve_profile;
use presrs::stream::StopSignals;
pub use presrs_ros2::Ros2Args;
use presrs_ros2::{NodeGraph, run_node};

use crate::printer::stream_log::notice_text;

pub fn run(args: &Ros2Args, out: &mut dyn Write) -> anyhow::Result<()> {
    let options = args.node_options(|key| std::env::var(key).ok())?;
    // The model and the profile before the node joins the graph: a bad one announces nothing.
    let file = presrs_io::model_file::load_model(&args.model)?;
    let online = file.online.as_ref();
    let profile = resolve_profile(args.profile.as_deref(), None, online, &args.overrides())?;
    presrs::session::check_profile(&file.model, &profile)?;
    let signals = StopSignals::register()?;
    let graph = NodeGraph::join(&options)?;
    writeln!(out, "{}", presrs_ros2::joined_event(&graph))?;
    out.flush()?;
    let stop = graph.stop_handle();
    let signal_thread = signals.on_first(move || stop.stop());
    let log = |notice: &_| stderr_line!("presrs ros2: {}", notice_text(notice));
    // A closed stdout does not stop the node: its outputs are the topics.
    let mut print = |line: &str| drop(writeln!(out, "{line}").and_then(|()| out.flush()));
    let summary = run_node(graph, &file.model, &profile, &mut print, &log)?;
    if let Some(signal) = signal_thread.close() {
        stderr_line!("presrs ros2: stopped by {signal}");
    }
    let text = presrs_ros2::summary_text(&options.input, &summary);
    stderr_line!("presrs ros2: {text}");
    anyhow::ensure!(
        !summary.session.fatal,
        "the input could not go on (see the error event)"
    );
    Ok(())
}
