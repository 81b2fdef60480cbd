//! The TCP server: binary-protocol clients on a loopback address, one connection each, several at once.

use std::collections::HashMap;
use std::io::{BufReader, Write};
use std::net::{Shutdown, SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use presrs_core::online::OnlineProfile;
use presrs_core::pipeline::TrainedModel;
use presrs_io::frame_protocol::DEFAULT_MAX_PAYLOAD_BYTES;

use super::connection::binary_source;
use super::output::BoundedOutput;
use super::shutdown::ShutdownHandle;
use presrs::error::{Error, Result};
use presrs::session::{
    ConnectionNotice, ConnectionSummary, NoObserver, Observers, SessionEvent, SessionObserver,
    run_frames,
};

/// The server's limits.
#[derive(Clone, Debug, PartialEq)]
pub struct ServerOptions {
    /// Most simultaneous clients; further ones get a fatal `error` line and are closed.
    pub max_clients: usize,
    /// Largest frame payload accepted, bytes (checked before it is read).
    pub max_frame_bytes: usize,
    /// Output lines queued per client before further ones are dropped (and counted).
    pub queue: usize,
    /// A connection idle this long is closed.
    pub idle_timeout: Duration,
    /// Return after this many connections have ended, refused ones included (demos and tests);
    /// `None`: serve until stopped.
    pub exit_after: Option<usize>,
}

impl Default for ServerOptions {
    fn default() -> Self {
        Self {
            max_clients: 16,
            max_frame_bytes: DEFAULT_MAX_PAYLOAD_BYTES,
            queue: 256,
            idle_timeout: Duration::from_secs(30),
            exit_after: None,
        }
    }
}

/// What the server tells the person watching it, as it happens. `peer` names the client (its address).
#[derive(Debug)]
pub enum ServerNotice<'a> {
    /// Accepting a connection failed (the server goes on).
    AcceptFailed(&'a std::io::Error),
    /// A client was turned away: `max_clients` were already connected.
    Refused {
        peer: SocketAddr,
        max_clients: usize,
    },
    Connected {
        peer: &'a str,
    },
    /// Something a client's connection noticed.
    Connection {
        peer: &'a str,
        notice: &'a ConnectionNotice,
    },
    /// A client's connection ended.
    Ended {
        peer: &'a str,
        summary: &'a ConnectionSummary,
    },
    /// A client's connection could not run (its socket could not be set up, the profile was refused).
    Failed {
        peer: &'a str,
        error: &'a Error,
    },
}

/// What a [`StreamServer::serve`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ServeSummary {
    /// Connections that ended with a summary.
    pub connections: usize,
    /// Of those, connections with a rejected frame or an error.
    pub with_errors: usize,
    /// Connections that could not run.
    pub failed: usize,
    /// Clients turned away (too many at once).
    pub refused: usize,
}

/// Makes the [`SessionObserver`] of each client's connection, given the client's name (its address): what
/// else sees the connections of a server (a live view).
pub type ObserverFactory = Arc<dyn Fn(&str) -> Box<dyn SessionObserver + Send> + Send + Sync>;

/// The stream server, bound and ready to [`serve`](Self::serve). The model is shared read-only by the
/// connections; each has its own detector and classifier.
pub struct StreamServer {
    listener: TcpListener,
    local: SocketAddr,
    model: TrainedModel,
    profile: OnlineProfile,
    options: ServerOptions,
    stop: ShutdownHandle,
    observers: Option<ObserverFactory>,
}

impl std::fmt::Debug for StreamServer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("StreamServer")
            .field("local", &self.local)
            .field("options", &self.options)
            .field("observers", &self.observers.is_some())
            .finish_non_exhaustive()
    }
}

/// How often the accept loop looks at the stop flag and the connection count.
const POLL: Duration = Duration::from_millis(5);

impl StreamServer {
    /// Listens on `addr`, a loopback address (port 0 picks one: see [`local_addr`](Self::local_addr)).
    pub fn bind(
        addr: SocketAddr,
        model: TrainedModel,
        profile: OnlineProfile,
        options: ServerOptions,
    ) -> Result<Self> {
        // The protocol has no authentication: only this machine may send frames.
        if !addr.ip().is_loopback() {
            return Err(Error::invalid(format!(
                "{addr}: only loopback addresses are served (127.0.0.1 or [::1])"
            )));
        }
        let cannot = |err| Error::system(format!("cannot listen on {addr}"), err);
        let listener = TcpListener::bind(addr).map_err(cannot)?;
        let local = listener.local_addr().map_err(cannot)?;
        // Non-blocking accept: the loop must notice a stop request without a client arriving.
        listener.set_nonblocking(true).map_err(cannot)?;
        Ok(Self {
            listener,
            local,
            model,
            profile,
            options,
            stop: ShutdownHandle::default(),
            observers: None,
        })
    }

    /// Gives each client's connection the observer `observers` makes for it.
    #[must_use]
    pub fn with_observers(mut self, observers: ObserverFactory) -> Self {
        self.observers = Some(observers);
        self
    }

    /// The address clients connect to.
    pub fn local_addr(&self) -> SocketAddr {
        self.local
    }

    /// A handle that stops [`serve`](Self::serve) from another thread.
    pub fn shutdown_handle(&self) -> ShutdownHandle {
        self.stop.clone()
    }

    /// Serves clients until stopped (or `exit_after` connections have ended), each on its own thread;
    /// `notify` hears what happens (from those threads too). A client's faults end at most its own
    /// connection.
    pub fn serve(&self, notify: &(dyn Fn(&ServerNotice<'_>) + Sync)) -> Result<ServeSummary> {
        let state = ServeState::default();
        std::thread::scope(|scope| {
            loop {
                if self.stop.is_stopped() {
                    state.close_all();
                    break;
                }
                let ended = state.ended.load(Ordering::SeqCst);
                if self.options.exit_after.is_some_and(|n| ended >= n) {
                    break;
                }
                let (stream, peer) = match self.listener.accept() {
                    Ok(conn) => conn,
                    Err(err) if err.kind() == std::io::ErrorKind::WouldBlock => {
                        std::thread::sleep(POLL);
                        continue;
                    }
                    Err(err) => {
                        notify(&ServerNotice::AcceptFailed(&err));
                        std::thread::sleep(10 * POLL);
                        continue;
                    }
                };
                if state.active.load(Ordering::SeqCst) >= self.options.max_clients {
                    self.refuse(stream, peer, notify);
                    state.record(|s| s.refused += 1);
                    continue;
                }
                state.active.fetch_add(1, Ordering::SeqCst);
                // Registered here, not in the client's thread: a stop that comes next must find it.
                let id = state.register(&stream);
                let state = &state;
                scope.spawn(move || self.run_client(stream, peer, (state, id), notify));
            }
        });
        Ok(state.into_summary())
    }

    /// Turns a client away with a fatal `error` line.
    fn refuse(
        &self,
        mut stream: TcpStream,
        peer: SocketAddr,
        notify: &(dyn Fn(&ServerNotice<'_>) + Sync),
    ) {
        let max_clients = self.options.max_clients;
        notify(&ServerNotice::Refused { peer, max_clients });
        let line =
            SessionEvent::error(format!("server full ({max_clients} clients)"), true).to_line();
        let _ = stream.set_nonblocking(false);
        let _ = writeln!(stream, "{line}");
    }

    /// One client's thread: its connection, then the notice of how it ended.
    fn run_client(
        &self,
        stream: TcpStream,
        peer: SocketAddr,
        (state, id): (&ServeState, u64),
        notify: &(dyn Fn(&ServerNotice<'_>) + Sync),
    ) {
        let name = peer.to_string();
        let outcome = self.handle_client(stream, &name, notify);
        match &outcome {
            Ok(summary) => notify(&ServerNotice::Ended {
                peer: &name,
                summary,
            }),
            Err(error) => notify(&ServerNotice::Failed { peer: &name, error }),
        }
        state.unregister(id);
        state.active.fetch_sub(1, Ordering::SeqCst);
        state.record(|s| match &outcome {
            Ok(summary) => {
                s.connections += 1;
                s.with_errors += usize::from(summary.had_errors());
            }
            Err(_) => s.failed += 1,
        });
    }

    fn handle_client(
        &self,
        stream: TcpStream,
        name: &str,
        notify: &(dyn Fn(&ServerNotice<'_>) + Sync),
    ) -> Result<ConnectionSummary> {
        let setup = |err| Error::system("cannot set up the connection", err);
        let idle = self.options.idle_timeout.max(Duration::from_millis(1));
        stream.set_nonblocking(false).map_err(setup)?;
        stream.set_read_timeout(Some(idle)).map_err(setup)?;
        stream.set_write_timeout(Some(idle)).map_err(setup)?;
        let _ = stream.set_nodelay(true);
        notify(&ServerNotice::Connected { peer: name });
        let (mut output, writer) =
            BoundedOutput::start(stream.try_clone().map_err(setup)?, self.options.queue);
        let reader = BufReader::with_capacity(64 * 1024, stream.try_clone().map_err(setup)?);
        let connection_notice = |notice: &ConnectionNotice| {
            notify(&ServerNotice::Connection { peer: name, notice });
        };
        let mut observer: Box<dyn SessionObserver + Send> = match &self.observers {
            Some(observers) => observers(name),
            None => Box::new(NoObserver),
        };
        let result = run_frames(
            &self.model,
            &self.profile,
            binary_source(reader, name, self.options.max_frame_bytes),
            &mut Observers::<&mut dyn SessionObserver>(vec![observer.as_mut(), &mut output]),
            &connection_notice,
        );
        observer.end();
        let dropped_in_writer = output.dropped();
        output.close();
        let _ = writer.join();
        let _ = stream.shutdown(Shutdown::Both);
        let mut summary = result?;
        summary.dropped_events = summary.dropped_events.max(dropped_in_writer);
        Ok(summary)
    }
}

/// What the accept loop and the client threads share.
#[derive(Default)]
struct ServeState {
    active: AtomicUsize,
    /// Connections ended, refused ones included (for `exit_after`).
    ended: AtomicUsize,
    summary: Mutex<ServeSummary>,
    /// The open connections, to close them on stop.
    open: Mutex<(u64, HashMap<u64, TcpStream>)>,
}

impl ServeState {
    fn record(&self, update: impl FnOnce(&mut ServeSummary)) {
        update(&mut lock(&self.summary));
        self.ended.fetch_add(1, Ordering::SeqCst);
    }

    /// Keeps a handle on `stream` to close it on stop; without one the connection is closed only by
    /// its client or the idle timeout.
    fn register(&self, stream: &TcpStream) -> u64 {
        let mut open = lock(&self.open);
        open.0 += 1;
        let id = open.0;
        if let Ok(handle) = stream.try_clone() {
            open.1.insert(id, handle);
        }
        id
    }

    fn unregister(&self, id: u64) {
        lock(&self.open).1.remove(&id);
    }

    /// Ends the input of every open connection: each connection ends as if its client had hung up, and
    /// still sends its last lines.
    fn close_all(&self) {
        for stream in lock(&self.open).1.values() {
            let _ = stream.shutdown(Shutdown::Read);
        }
    }

    fn into_summary(self) -> ServeSummary {
        self.summary
            .into_inner()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }
}

/// A panicking client thread leaves the counters as they were; they are still worth reading.
fn lock<T>(mutex: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    mutex
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}
