//! One viewer's server-sent events: the response body of `GET /events`, and the events' encoding.

use std::convert::Infallible;
use std::future::Future;
use std::pin::Pin;
use std::task::{Context, Poll};
use std::time::Duration;

use hyper::body::{Body, Bytes, Frame};
use serde_json::json;
use tokio::time::{Instant, Sleep};

use super::hub::{Cursor, LatestFrame, LiveHub, Update, ViewerGuard};

/// A comment line this often keeps an idle event stream open and finds viewers that left.
const KEEPALIVE: Duration = Duration::from_secs(2);

/// A future that completes when the server stops.
pub(super) type Stopped = Pin<Box<dyn Future<Output = ()> + Send>>;

/// One viewer's event stream: `hello` first, then at most `max_fps` times a second what is new
/// (`frame`, `loads`, `line` events), until the viewer leaves, is too slow or the server stops.
///
/// An update is taken from the hub only when hyper asks for the next piece of the body, which it does
/// once the previous one is on its way: what came in while a slow viewer was still taking the last one
/// is skipped for it (the latest frame; loads and lines from the bounded histories), not queued.
pub(super) struct EventStream {
    hub: LiveHub,
    /// Counts this viewer in the hub for as long as the stream lives.
    _viewer: ViewerGuard,
    cursor: Cursor,
    hello: Option<Bytes>,
    period: Duration,
    next: Pin<Box<Sleep>>,
    last_write: Instant,
    stopped: Stopped,
}

impl std::fmt::Debug for EventStream {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("EventStream")
            .field("cursor", &self.cursor)
            .field("period", &self.period)
            .finish_non_exhaustive()
    }
}

impl EventStream {
    pub(super) fn new(hub: &LiveHub, max_fps: f64, stopped: Stopped) -> Self {
        let info = hub.info();
        let mut hello = String::new();
        sse_event(
            &mut hello,
            "hello",
            &json!({"source": info.source, "units": info.units, "classes": info.classes, "max_fps": max_fps})
                .to_string(),
        );
        Self {
            hub: hub.clone(),
            _viewer: hub.viewer(),
            cursor: Cursor::default(),
            hello: Some(Bytes::from(hello)),
            period: Duration::from_secs_f64(1.0 / max_fps),
            next: Box::pin(tokio::time::sleep(Duration::ZERO)),
            last_write: Instant::now(),
            stopped,
        }
    }
}

impl Body for EventStream {
    type Data = Bytes;
    type Error = Infallible;

    fn poll_frame(
        self: Pin<&mut Self>,
        cx: &mut Context<'_>,
    ) -> Poll<Option<Result<Frame<Bytes>, Infallible>>> {
        let this = self.get_mut();
        if let Some(hello) = this.hello.take() {
            return Poll::Ready(Some(Ok(Frame::data(hello))));
        }
        loop {
            if this.stopped.as_mut().poll(cx).is_ready() {
                return Poll::Ready(None);
            }
            if this.next.as_mut().poll(cx).is_pending() {
                return Poll::Pending;
            }
            // The next turn one period on, or now for a viewer that fell behind (no catching up).
            let now = Instant::now();
            let next = (this.next.deadline() + this.period).max(now);
            this.next.as_mut().reset(next);
            let mut out = String::new();
            encode_update(&mut out, &this.hub.update(&mut this.cursor));
            if out.is_empty() && now - this.last_write >= KEEPALIVE {
                out.push_str(": keep-alive\n\n");
            }
            if !out.is_empty() {
                this.last_write = now;
                return Poll::Ready(Some(Ok(Frame::data(Bytes::from(out)))));
            }
        }
    }
}

/// Appends one server-sent event: `event: NAME`, the data one `data:` line per line, a blank line.
pub fn sse_event(out: &mut String, name: &str, data: &str) {
    out.push_str("event: ");
    out.push_str(name);
    out.push('\n');
    for line in data.split('\n') {
        out.push_str("data: ");
        out.push_str(line.strip_suffix('\r').unwrap_or(line));
        out.push('\n');
    }
    out.push('\n');
}

/// The events of one update: `frame` (the latest), `loads`, and one `line` per JSON line.
fn encode_update(out: &mut String, update: &Update) {
    if !update.loads.is_empty() {
        let points: Vec<_> = update
            .loads
            .iter()
            .map(|&(session, index, load)| {
                json!([session, index, (load * 1000.0).round() / 1000.0])
            })
            .collect();
        sse_event(out, "loads", &serde_json::Value::Array(points).to_string());
    }
    for line in &update.lines {
        sse_event(out, "line", line);
    }
    if let Some(frame) = &update.frame {
        sse_event(out, "frame", &frame_json(frame).to_string());
    }
}

/// A frame for the page: its values quantized to 0..=254 of the colour scale (255: absent sensel),
/// base64, with the scale's top and the frame's peak in the recording's unit.
pub fn frame_json(frame: &LatestFrame) -> serde_json::Value {
    let top = if frame.scale_max > 0.0 {
        frame.scale_max
    } else {
        1.0
    };
    let mut peak = 0.0f64;
    let bytes: Vec<u8> = frame
        .values
        .iter()
        .enumerate()
        .map(|(i, &v)| {
            if frame.present.get(i) == Some(&false) || !v.is_finite() {
                return 255;
            }
            peak = peak.max(v);
            (v / top * 254.0).round().clamp(0.0, 254.0) as u8
        })
        .collect();
    json!({
        "session": frame.session,
        "index": frame.index,
        "rows": frame.grid.rows,
        "cols": frame.grid.cols,
        "top": top,
        "peak": peak,
        "q": base64(&bytes),
    })
}

/// Standard base64 with padding.
pub fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(char::from(ALPHABET[(n >> (18 - 6 * k)) as usize & 63]));
            } else {
                out.push('=');
            }
        }
    }
    out
}
