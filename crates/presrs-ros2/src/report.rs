//! What the node says about itself to a person or a script: the `joined` line and the final summary.

use serde_json::{Value, json};

use crate::graph::NodeGraph;
use crate::node::NodeSummary;

/// The first JSON line of `presrs ros2`: the node is in the graph (a script may publish from now on).
pub fn joined_event(graph: &NodeGraph) -> Value {
    let options = &graph.options;
    json!({
        "event": "joined",
        "node": graph.fully_qualified_name(),
        "domain_id": options.domain_id,
        "input": graph.input_topic(),
        "localhost_only": options.localhost_only,
    })
}

/// The final summary line: the session's counts (as `presrs stream` gives them) and the node's own.
/// Frames processed (every frame the stance detector took) and decisions made are counted apart: a
/// stance is decided once, on one frame or a few.
pub fn summary_text(input: &str, summary: &NodeSummary) -> String {
    let (s, c) = (&summary.session, &summary.counters);
    format!(
        "{input}: {} messages received, {} frames processed, {} stances, {} decisions made ({} \
         fused), {} rejected frames, {} errors, {} frames dropped before the node took them, {} \
         publish failures, {} frames sent before the first one taken from their publisher (before \
         it matched the node, before the node had discovered it, or lost before the first one \
         taken)",
        c.received,
        s.stats.frames,
        s.stats.stances,
        s.stats.decisions,
        s.stats.fused_decisions,
        s.rejected_frames,
        s.errors,
        c.dropped,
        c.publish_failures,
        c.before_first,
    )
}
