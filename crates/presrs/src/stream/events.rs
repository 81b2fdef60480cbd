//! The JSON lines a connection writes (`docs/stream-protocol.md`, "Server -> client").

use presrs_core::online::{DecidedAt, DecisionKind, OnlineEvent, OnlineProfile, Step};
use presrs_core::pipeline::TrainedModel;
use serde_json::{Value, json};

use super::summary::ConnectionSummary;

/// The events of one step of the classifier as JSON values (`docs/stream-protocol.md`: touchdown,
/// classification, error, liftoff), for a face that is not a stream (the Python package).
pub fn event_values(
    step: &Step<'_>,
    model: &TrainedModel,
    profile: &OnlineProfile,
    latency_us: f64,
    timestamp_us: Option<u64>,
) -> Vec<Value> {
    step.events
        .iter()
        .map(|event| match event {
            OnlineEvent::Touchdown(td) => json!({
                "event": "touchdown",
                "stance": td.stance_id,
                "touchdown_frame": td.touchdown_frame,
                "frame": td.frame,
                "partial": td.partial,
            }),
            OnlineEvent::Decision(d) => decision(step, d, model, profile, latency_us, timestamp_us),
            OnlineEvent::Failed(f) => json!({
                "event": "error",
                "message": format!(
                    "stance {}: frame {} could not be classified ({} decision): {}",
                    f.stance_id,
                    f.sample_frame,
                    kind_name(f.kind),
                    step.error(f).map_or_else(|| "unknown error".to_owned(), ToString::to_string)
                ),
                "fatal": false,
                "stance": f.stance_id,
                "frame": f.frame,
            }),
            OnlineEvent::Liftoff(lo) => json!({
                "event": "liftoff",
                "stance": lo.stance_id,
                "touchdown_frame": lo.stance.start,
                "end_frame": lo.stance.end(),
                "len": lo.stance.len,
                "peak_frame": lo.stance.peak_frame,
                "peak_load": lo.stance.peak_load,
                "partial": lo.stance.partial,
                "sampled": lo.sampled,
                "frame": lo.frame,
            }),
        })
        .collect()
}

fn decision(
    step: &Step<'_>,
    d: &presrs_core::online::Decision,
    model: &TrainedModel,
    profile: &OnlineProfile,
    latency_us: f64,
    timestamp_us: Option<u64>,
) -> Value {
    let names = model.class_names();
    let label = names.get(d.class).map_or("?", String::as_str);
    let posteriors: serde_json::Map<String, Value> = names
        .iter()
        .zip(step.posteriors(d))
        .map(|(name, &p)| (name.clone(), json!(p)))
        .collect();
    let mut line = json!({
        "event": "classification",
        "kind": kind_name(d.kind),
        "stance": d.stance_id,
        "label": label,
        "class": d.class,
        "confidence": d.confidence,
        "posteriors": posteriors,
        "sample_frame": d.sample_frame,
        "frame": d.frame,
        "frames_used": d.frames_used,
        "touchdown_frame": d.touchdown_frame,
        "latency_us": (latency_us * 10.0).round() / 10.0,
        "timestamp_us": timestamp_us,
        "gait": profile.gait_table.get(label),
    });
    // A whole stance's decision says what it waited for; a one-frame decision's line is as it was.
    if let Some(how) = d.stance {
        let decided_at = match how.decided_at {
            DecidedAt::Liftoff => "liftoff",
            DecidedAt::Offset(_) => "offset",
            DecidedAt::Length(_) => "length",
        };
        line["decided_at"] = decided_at.into();
        line["decided_at_frame"] = how.waited_for.into();
        line["cut"] = how.cut.into();
    }
    line
}

fn kind_name(kind: DecisionKind) -> &'static str {
    match kind {
        DecisionKind::Single => "single",
        DecisionKind::Fused => "fused",
        DecisionKind::Stance => "stance",
    }
}

/// An `error` event.
pub(super) fn error_event(message: &str, fatal: bool) -> Value {
    json!({"event": "error", "message": message, "fatal": fatal})
}

/// An `error` line.
pub(super) fn error_line(message: &str, fatal: bool) -> String {
    error_event(message, fatal).to_string()
}

/// The `end` event: the connection's counters.
pub(super) fn end_event(summary: &ConnectionSummary) -> Value {
    let s = summary.stats;
    let mut end = json!({
        "event": "end",
        "frames": s.frames,
        "stances": s.stances,
        "decisions": s.decisions,
        "fused_decisions": s.fused_decisions,
        "rejected_frames": summary.rejected_frames,
        "errors": summary.errors,
        "dropped_events": summary.dropped_events,
        "warmup_frames": summary.warmup_frames,
    });
    if let Some(note) = summary.note() {
        end["note"] = note.into();
    }
    end
}
