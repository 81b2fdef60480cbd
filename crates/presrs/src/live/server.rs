//! The viewers' HTTP server: a small HTTP/1.1 server on `std::net` (GET only, one request per
//! connection) that serves the page and a server-sent-events stream per viewer.

use std::io::{Read, Write};
use std::net::{Shutdown, SocketAddr, TcpListener, TcpStream};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use serde_json::json;

use super::hub::{Cursor, LatestFrame, LiveHub, Update};
use crate::error::{Error, Result};
use crate::stream::ShutdownHandle;

const PAGE: &str = include_str!("page/index.html");
const SCRIPT: &str = include_str!("page/app.js");
const STYLE: &str = include_str!("page/style.css");

/// The server's limits.
#[derive(Clone, Debug, PartialEq)]
pub struct LiveOptions {
    /// Most frames a second sent to each viewer (the frames in between are skipped for it).
    pub max_fps: f64,
    /// Most viewers at once; further ones get `503`.
    pub max_viewers: usize,
    /// A viewer that takes nothing for this long is dropped (a write waits at most this long).
    pub write_timeout: Duration,
}

impl Default for LiveOptions {
    fn default() -> Self {
        Self {
            max_fps: 30.0,
            max_viewers: 16,
            write_timeout: Duration::from_secs(5),
        }
    }
}

/// The live view's HTTP server, serving on its own threads until [`stop`](Self::stop) (or drop):
/// `GET /` the page, `GET /events` the server-sent events, `GET /state` a JSON snapshot.
#[derive(Debug)]
pub struct LiveServer {
    local: SocketAddr,
    stop: ShutdownHandle,
    accept: Option<JoinHandle<()>>,
    viewers: Arc<Mutex<Vec<JoinHandle<()>>>>,
}

/// How often the accept loop looks at the stop flag.
const POLL: Duration = Duration::from_millis(10);
/// A comment line this often keeps an idle event stream open and finds viewers that left.
const KEEPALIVE: Duration = Duration::from_secs(2);
/// The largest request head read.
const MAX_REQUEST: usize = 8 * 1024;

impl LiveServer {
    /// Serves `hub` on `addr`, a loopback address unless the caller decided otherwise (port 0 picks
    /// one: see [`local_addr`](Self::local_addr)).
    pub fn start(addr: SocketAddr, hub: LiveHub, options: LiveOptions) -> Result<Self> {
        let cannot = |err| Error::system(format!("cannot serve the live view on {addr}"), err);
        let listener = TcpListener::bind(addr).map_err(cannot)?;
        let local = listener.local_addr().map_err(cannot)?;
        listener.set_nonblocking(true).map_err(cannot)?;
        if !(options.max_fps.is_finite() && options.max_fps > 0.0) {
            return Err(Error::invalid(format!(
                "the live view's frame rate must be above 0, got {}",
                options.max_fps
            )));
        }
        let stop = ShutdownHandle::default();
        let viewers = Arc::new(Mutex::new(Vec::new()));
        let accept = {
            let (stop, viewers) = (stop.clone(), viewers.clone());
            std::thread::spawn(move || accept_loop(&listener, &hub, &options, &stop, &viewers))
        };
        Ok(Self {
            local,
            stop,
            accept: Some(accept),
            viewers,
        })
    }

    pub fn local_addr(&self) -> SocketAddr {
        self.local
    }

    /// `http://ADDR/`.
    pub fn url(&self) -> String {
        format!("http://{}/", self.local)
    }

    /// Stops serving: no new viewers, and every viewer's stream ends within a frame period (or the
    /// write timeout of a viewer that takes nothing); returns when all have.
    pub fn stop(mut self) {
        self.shutdown();
    }

    fn shutdown(&mut self) {
        self.stop.stop();
        if let Some(accept) = self.accept.take() {
            let _ = accept.join();
        }
        let viewers = std::mem::take(&mut *lock(&self.viewers));
        for viewer in viewers {
            let _ = viewer.join();
        }
    }
}

impl Drop for LiveServer {
    fn drop(&mut self) {
        self.shutdown();
    }
}

fn lock<T>(mutex: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    mutex
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

fn accept_loop(
    listener: &TcpListener,
    hub: &LiveHub,
    options: &LiveOptions,
    stop: &ShutdownHandle,
    viewers: &Mutex<Vec<JoinHandle<()>>>,
) {
    while !stop.is_stopped() {
        match listener.accept() {
            Ok((stream, _)) => {
                let (hub, options, stop) = (hub.clone(), options.clone(), stop.clone());
                let handle = std::thread::spawn(move || {
                    let _ = handle_connection(stream, &hub, &options, &stop);
                });
                let mut viewers = lock(viewers);
                viewers.retain(|h| !h.is_finished());
                viewers.push(handle);
            }
            Err(err) if err.kind() == std::io::ErrorKind::WouldBlock => std::thread::sleep(POLL),
            Err(_) => std::thread::sleep(10 * POLL),
        }
    }
}

/// Reads the request head (up to [`MAX_REQUEST`] bytes): the method and the path without its query.
fn read_request(stream: &mut TcpStream) -> std::io::Result<Option<(String, String)>> {
    let mut head = Vec::new();
    let mut buf = [0u8; 1024];
    while !head.windows(4).any(|w| w == b"\r\n\r\n") {
        let n = stream.read(&mut buf)?;
        if n == 0 || head.len() + n > MAX_REQUEST {
            return Ok(None);
        }
        head.extend_from_slice(&buf[..n]);
    }
    let text = String::from_utf8_lossy(&head);
    let mut parts = text.lines().next().unwrap_or("").split_whitespace();
    let (Some(method), Some(target)) = (parts.next(), parts.next()) else {
        return Ok(None);
    };
    let path = target.split('?').next().unwrap_or("/");
    Ok(Some((method.to_owned(), path.to_owned())))
}

fn respond(stream: &mut TcpStream, status: &str, kind: &str, body: &str) -> std::io::Result<()> {
    write!(
        stream,
        "HTTP/1.1 {status}\r\nContent-Type: {kind}\r\nContent-Length: {}\r\nCache-Control: no-store\r\n\
         Connection: close\r\n\r\n{body}",
        body.len()
    )?;
    stream.flush()
}

fn handle_connection(
    mut stream: TcpStream,
    hub: &LiveHub,
    options: &LiveOptions,
    stop: &ShutdownHandle,
) -> std::io::Result<()> {
    stream.set_nonblocking(false)?;
    stream.set_read_timeout(Some(options.write_timeout))?;
    stream.set_write_timeout(Some(options.write_timeout))?;
    let _ = stream.set_nodelay(true);
    let Some((method, path)) = read_request(&mut stream)? else {
        return respond(
            &mut stream,
            "400 Bad Request",
            "text/plain",
            "bad request\n",
        );
    };
    if method != "GET" {
        return respond(
            &mut stream,
            "405 Method Not Allowed",
            "text/plain",
            "GET only\n",
        );
    }
    let result = match path.as_str() {
        "/" | "/index.html" => respond(&mut stream, "200 OK", "text/html; charset=utf-8", PAGE),
        "/app.js" => respond(
            &mut stream,
            "200 OK",
            "text/javascript; charset=utf-8",
            SCRIPT,
        ),
        "/style.css" => respond(&mut stream, "200 OK", "text/css; charset=utf-8", STYLE),
        "/state" => {
            let body = state_json(hub).to_string();
            respond(&mut stream, "200 OK", "application/json", &body)
        }
        "/events" if hub.viewers() >= options.max_viewers => respond(
            &mut stream,
            "503 Service Unavailable",
            "text/plain",
            "too many viewers\n",
        ),
        "/events" => serve_events(&mut stream, hub, options, stop),
        _ => respond(&mut stream, "404 Not Found", "text/plain", "not found\n"),
    };
    let _ = stream.shutdown(Shutdown::Both);
    result
}

/// A snapshot: the source, units, classes, frames seen, viewers, and the latest classification.
pub fn state_json(hub: &LiveHub) -> serde_json::Value {
    let info = hub.info();
    let last = hub
        .recent_lines()
        .iter()
        .rev()
        .filter_map(|line| serde_json::from_str::<serde_json::Value>(line).ok())
        .find(|value| value["event"] == "classification");
    json!({
        "source": info.source,
        "units": info.units,
        "classes": info.classes,
        "frames": hub.frames_seen(),
        "viewers": hub.viewers(),
        "classification": last,
    })
}

/// One viewer's event stream: `hello` first, then at most `max_fps` times a second what is new
/// (`frame`, `loads`, `line` events), until the viewer leaves, is too slow or the server stops.
fn serve_events(
    stream: &mut TcpStream,
    hub: &LiveHub,
    options: &LiveOptions,
    stop: &ShutdownHandle,
) -> std::io::Result<()> {
    let _viewer = hub.viewer();
    stream.write_all(
        b"HTTP/1.1 200 OK\r\nContent-Type: text/event-stream\r\nCache-Control: no-store\r\n\
          Connection: close\r\nX-Accel-Buffering: no\r\n\r\n",
    )?;
    let info = hub.info();
    let mut out = String::new();
    sse_event(
        &mut out,
        "hello",
        &json!({"source": info.source, "units": info.units, "classes": info.classes, "max_fps": options.max_fps})
            .to_string(),
    );
    stream.write_all(out.as_bytes())?;
    let period = Duration::from_secs_f64(1.0 / options.max_fps);
    let mut cursor = Cursor::default();
    let mut next = Instant::now();
    let mut last_write = Instant::now();
    while !stop.is_stopped() {
        let update = hub.update(&mut cursor);
        out.clear();
        encode_update(&mut out, &update);
        if out.is_empty() && last_write.elapsed() >= KEEPALIVE {
            out.push_str(": keep-alive\n\n");
        }
        if !out.is_empty() {
            // A slow viewer blocks here (its own thread only) until the write timeout; what came in
            // the meantime is skipped for it, not queued.
            stream.write_all(out.as_bytes())?;
            stream.flush()?;
            last_write = Instant::now();
        }
        next += period;
        let now = Instant::now();
        if next > now {
            std::thread::sleep(next - now);
        } else {
            next = now;
        }
    }
    Ok(())
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
pub(super) fn encode_update(out: &mut String, update: &Update) {
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
