//! The viewers' HTTP server: hyper's HTTP/1.1 (GET only, one request per connection) on a tokio
//! runtime of one thread, the server's own, serving the page, a JSON snapshot and a server-sent-events
//! stream per viewer ([`EventStream`](super::events)).
//!
//! Why hyper: parsing requests is where hand-written servers break (split heads, odd targets, header
//! limits, clients that never finish a request), and hyper is the most used and most maintained HTTP
//! implementation in Rust (the base of axum, reqwest and tonic), with a timeout for slow request heads.
//! tiny_http, the synchronous candidate that fits a thread per viewer, has had no release since 2022 and
//! gives no access to the socket, so a viewer that reads nothing could not be dropped after a write
//! timeout; axum would add a router and tower on top of hyper for three routes. The runtime is
//! tokio's current-thread one with only `rt`, `net`, `time` and `sync`, so that the live view costs the
//! build little. The session's thread never waits for it: it only fills the [`LiveHub`].

use std::convert::Infallible;
use std::future::{Future, poll_fn};
use std::net::{SocketAddr, TcpListener as StdListener};
use std::pin::pin;
use std::task::Poll;
use std::thread::JoinHandle;
use std::time::Duration;

use http_body_util::{Either, Full};
use hyper::body::{Bytes, Incoming};
use hyper::header::{CACHE_CONTROL, CONNECTION, CONTENT_TYPE, HeaderValue};
use hyper::server::conn::http1;
use hyper::service::service_fn;
use hyper::{Method, Request, Response, StatusCode};
use hyper_util::rt::{TokioIo, TokioTimer};
use serde_json::json;
use tokio::net::{TcpListener, TcpStream};
use tokio::sync::watch;
use tokio::task::JoinSet;

use super::events::{EventStream, Stopped};
use super::hub::LiveHub;
use super::write_timeout::WriteTimeout;
use presrs::error::{Error, Result};
use presrs::session::SessionEvent;

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
    /// A viewer that takes nothing for this long is dropped (a write waits at most this long); so is
    /// a client whose request head has not come in within it.
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

/// The live view's HTTP server, serving on its own thread until [`stop`](Self::stop) (or drop):
/// `GET /` the page, `GET /events` the server-sent events, `GET /state` a JSON snapshot.
#[derive(Debug)]
pub struct LiveServer {
    local: SocketAddr,
    stop: watch::Sender<bool>,
    thread: Option<JoinHandle<()>>,
}

/// A response body: a page or snapshot whole, or a viewer's event stream.
type LiveBody = Either<Full<Bytes>, EventStream>;

impl LiveServer {
    /// Serves `hub` on `addr`, a loopback address unless the caller decided otherwise (port 0 picks
    /// one: see [`local_addr`](Self::local_addr)).
    pub fn start(addr: SocketAddr, hub: LiveHub, options: LiveOptions) -> Result<Self> {
        if !(options.max_fps.is_finite() && options.max_fps > 0.0) {
            return Err(Error::invalid(format!(
                "the live view's frame rate must be above 0, got {}",
                options.max_fps
            )));
        }
        let cannot = |err| Error::system(format!("cannot serve the live view on {addr}"), err);
        let listener = StdListener::bind(addr).map_err(cannot)?;
        let local = listener.local_addr().map_err(cannot)?;
        listener.set_nonblocking(true).map_err(cannot)?;
        let runtime = tokio::runtime::Builder::new_current_thread()
            .enable_io()
            .enable_time()
            .build()
            .map_err(cannot)?;
        let listener = {
            let _entered = runtime.enter();
            TcpListener::from_std(listener).map_err(cannot)?
        };
        let (stop, stopped) = watch::channel(false);
        let thread = std::thread::Builder::new()
            .name("presrs-live".into())
            .spawn(move || runtime.block_on(serve(listener, hub, options, stopped)))
            .map_err(cannot)?;
        Ok(Self {
            local,
            stop,
            thread: Some(thread),
        })
    }

    pub fn local_addr(&self) -> SocketAddr {
        self.local
    }

    /// `http://ADDR/`.
    pub fn url(&self) -> String {
        format!("http://{}/", self.local)
    }

    /// Stops serving: no new viewers, every viewer's stream ends at once (or after the write timeout
    /// of a viewer that takes nothing); returns when all have.
    pub fn stop(mut self) {
        self.shutdown();
    }

    fn shutdown(&mut self) {
        self.stop.send_replace(true);
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

impl Drop for LiveServer {
    fn drop(&mut self) {
        self.shutdown();
    }
}

/// A future that completes once `stop` says so (or its sender is gone).
fn stopped(mut stop: watch::Receiver<bool>) -> Stopped {
    Box::pin(async move {
        let _ = stop.wait_for(|stopped| *stopped).await;
    })
}

/// Accepts connections until stopped (the listener closes then), then waits for them all to end.
async fn serve(
    listener: TcpListener,
    hub: LiveHub,
    options: LiveOptions,
    stop: watch::Receiver<bool>,
) {
    let mut connections = JoinSet::new();
    let mut until_stopped = stopped(stop.clone());
    loop {
        let accepted = poll_fn(|cx| {
            if until_stopped.as_mut().poll(cx).is_ready() {
                return Poll::Ready(None);
            }
            listener.poll_accept(cx).map(Some)
        })
        .await;
        match accepted {
            None => break,
            Some(Ok((stream, _))) => {
                let (hub, options, stop) = (hub.clone(), options.clone(), stop.clone());
                connections.spawn(serve_connection(stream, hub, options, stop));
            }
            // Out of descriptors, say: the listener stays; try again a little later.
            Some(Err(_)) => tokio::time::sleep(Duration::from_millis(100)).await,
        }
        while connections.try_join_next().is_some() {}
    }
    drop(listener);
    while connections.join_next().await.is_some() {}
}

/// One connection, one request. On stop, a connection still waiting for its request is closed and
/// one responding finishes (an event stream ends by itself).
async fn serve_connection(
    stream: TcpStream,
    hub: LiveHub,
    options: LiveOptions,
    stop: watch::Receiver<bool>,
) {
    let _ = stream.set_nodelay(true);
    let timeout = options.write_timeout;
    let io = TokioIo::new(WriteTimeout::new(stream, timeout));
    let service = {
        let stop = stop.clone();
        service_fn(move |request| {
            let response = respond(&request, &hub, &options, &stop);
            async move { Ok::<_, Infallible>(response) }
        })
    };
    let mut connection = pin!(
        http1::Builder::new()
            .keep_alive(false)
            .timer(TokioTimer::new())
            .header_read_timeout(timeout)
            .serve_connection(io, service)
    );
    let mut until_stopped = Some(stopped(stop));
    // Errors (a viewer gone, a write timed out, a malformed request already answered with 400) end
    // only this connection.
    let _ = poll_fn(|cx| {
        if let Some(stop) = until_stopped.as_mut()
            && stop.as_mut().poll(cx).is_ready()
        {
            until_stopped = None;
            connection.as_mut().graceful_shutdown();
        }
        connection.as_mut().poll(cx)
    })
    .await;
}

/// The response to one request: the routes.
fn respond(
    request: &Request<Incoming>,
    hub: &LiveHub,
    options: &LiveOptions,
    stop: &watch::Receiver<bool>,
) -> Response<LiveBody> {
    if request.method() != Method::GET {
        return whole(StatusCode::METHOD_NOT_ALLOWED, "text/plain", "GET only\n");
    }
    match request.uri().path() {
        "/" | "/index.html" => whole(StatusCode::OK, "text/html; charset=utf-8", PAGE),
        "/app.js" => whole(StatusCode::OK, "text/javascript; charset=utf-8", SCRIPT),
        "/style.css" => whole(StatusCode::OK, "text/css; charset=utf-8", STYLE),
        "/state" => whole(
            StatusCode::OK,
            "application/json",
            state_json(hub).to_string(),
        ),
        "/events" if hub.viewers() >= options.max_viewers => whole(
            StatusCode::SERVICE_UNAVAILABLE,
            "text/plain",
            "too many viewers\n",
        ),
        "/events" => {
            let events = EventStream::new(hub, options.max_fps, stopped(stop.clone()));
            let mut response = with_headers(Either::Right(events), "text/event-stream");
            let headers = response.headers_mut();
            headers.insert("x-accel-buffering", HeaderValue::from_static("no"));
            response
        }
        _ => whole(StatusCode::NOT_FOUND, "text/plain", "not found\n"),
    }
}

/// A response with a body known whole (hyper adds its `Content-Length`).
fn whole(status: StatusCode, kind: &'static str, body: impl Into<Bytes>) -> Response<LiveBody> {
    let mut response = with_headers(Either::Left(Full::new(body.into())), kind);
    *response.status_mut() = status;
    response
}

/// `200 OK`, `Content-Type: kind`, never cached, the connection closed after it.
fn with_headers(body: LiveBody, kind: &'static str) -> Response<LiveBody> {
    let mut response = Response::new(body);
    let headers = response.headers_mut();
    headers.insert(CONTENT_TYPE, HeaderValue::from_static(kind));
    headers.insert(CACHE_CONTROL, HeaderValue::from_static("no-store"));
    headers.insert(CONNECTION, HeaderValue::from_static("close"));
    response
}

/// A snapshot: the source, units, classes, frames seen, viewers, and the latest classification.
pub fn state_json(hub: &LiveHub) -> serde_json::Value {
    let info = hub.info();
    let last = hub.last_decision().map(SessionEvent::Classification);
    json!({
        "source": info.source,
        "units": info.units,
        "classes": info.classes,
        "frames": hub.frames_seen(),
        "viewers": hub.viewers(),
        "classification": last,
    })
}
