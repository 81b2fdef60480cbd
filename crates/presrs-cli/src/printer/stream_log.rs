//! What the log of `presrs stream` and `presrs view` says (stderr lines, and the server's `stopped`
//! event): a connection's notices, a connection's summary, the server's notices, an error with its causes
//! in one line.

use presrs::session::{ConnectionNotice, ConnectionSummary};
use presrs_stream::{ServeSummary, ServerNotice};
use serde_json::json;

/// A connection's notice as the log says it.
pub fn notice_text(notice: &ConnectionNotice) -> String {
    match notice {
        ConnectionNotice::Error(message) => message.clone(),
        ConnectionNotice::ErrorsMuted => "further errors are counted, not logged".to_owned(),
        ConnectionNotice::WarmupDone { frames } => format!(
            "warm-up calibration done on the first {frames} frames: stances before frame {frames} were \
             not classified (give --calibrate MANIFEST or --profile, or a model with an online profile, to \
             classify from the first frame)"
        ),
        ConnectionNotice::WarmupUnfinished { frames } => format!(
            "the stream ended during the warm-up calibration ({frames} frames): no stance was classified \
             (give --calibrate MANIFEST or --profile, or a model with an online profile, to classify from \
             the first frame)"
        ),
        // A notice newer than this log (the enum is non-exhaustive): said as it is rather than lost.
    }
}

/// A connection's (or stdin's) summary, named `name`.
pub fn summary_text(name: &str, s: &ConnectionSummary) -> String {
    format!(
        "{name}: {} frames, {} stances, {} decisions ({} fused), {} rejected frames, {} errors, {} dropped events",
        s.stats.frames,
        s.stats.stances,
        s.stats.decisions,
        s.stats.fused_decisions,
        s.rejected_frames,
        s.errors,
        s.dropped_events
    )
}

/// What the server saw, as the log says it (each about a client named by its address).
pub fn server_notice_text(notice: &ServerNotice<'_>) -> String {
    match notice {
        ServerNotice::AcceptFailed(err) => format!("accept failed: {err}"),
        ServerNotice::Refused { peer, max_clients } => {
            format!("{peer}: refused, {max_clients} clients already connected")
        }
        ServerNotice::Connected { peer } => format!("{peer}: connected"),
        ServerNotice::Connection { peer, notice } => format!("{peer}: {}", notice_text(notice)),
        ServerNotice::Ended { peer, summary } => summary_text(peer, summary),
        ServerNotice::Failed { peer, error } => format!("{peer}: {}", chain_text(*error)),
        // A notice newer than this log (the enum is non-exhaustive): said as it is rather than lost.
    }
}

/// The first line of a server: where it listens (port 0 asked for any).
pub fn listening_event(addr: std::net::SocketAddr) -> serde_json::Value {
    json!({"event": "listening", "addr": addr.to_string()})
}

/// Why a finite input (stdin) counts as failed, once read to its end: an error that ended it, or any
/// rejected frame or error event; `None` when it went through clean.
pub fn input_failure(name: &str, summary: &ConnectionSummary) -> Option<String> {
    if summary.fatal {
        return Some("the input stream ended with an error (see above)".to_owned());
    }
    summary.had_errors().then(|| {
        format!(
            "{name}: {} rejected frame(s), {} error(s) in the input (see the error events)",
            summary.rejected_frames, summary.errors
        )
    })
}

/// The `stopped` event of a server stopped by `signal` (its name), with what it served.
pub fn stopped_event(signal: &str, served: &ServeSummary) -> serde_json::Value {
    json!({
        "event": "stopped",
        "signal": signal,
        "connections": served.connections,
        "with_errors": served.with_errors,
        "failed": served.failed,
        "refused": served.refused,
    })
}

/// An error and its causes in one line, skipping causes whose text is already there.
pub fn chain_text(error: &(dyn std::error::Error + 'static)) -> String {
    let mut text = String::new();
    let mut cause = Some(error);
    while let Some(err) = cause {
        let part = err.to_string();
        if !text.contains(&part) {
            if !text.is_empty() {
                text.push_str(": ");
            }
            text.push_str(&part);
        }
        cause = err.source();
    }
    text
}
