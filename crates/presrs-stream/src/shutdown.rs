//! The stop flag a server or a connection is stopped by from another thread: a leaf module, so that the
//! server and the connection (which both take one) do not import each other.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// Stops a [`StreamServer`](super::StreamServer), or a connection on stdin
/// ([`ConnectionOptions::stop`](super::ConnectionOptions)), from another thread.
#[derive(Clone, Debug, Default)]
pub struct ShutdownHandle(Arc<AtomicBool>);

/// Two handles are equal when they stop the same thing.
impl PartialEq for ShutdownHandle {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }
}

impl Eq for ShutdownHandle {}

impl ShutdownHandle {
    /// Asks to stop. A server accepts no more clients, closes the open connections (their connections end
    /// as if the client had hung up, with an `end` line) and
    /// [`StreamServer::serve`](super::StreamServer::serve) returns; a connection takes the end of its input
    /// that follows for a stop.
    pub fn stop(&self) {
        self.0.store(true, Ordering::SeqCst);
    }

    /// Whether [`stop`](Self::stop) was called.
    pub fn is_stopped(&self) -> bool {
        self.0.load(Ordering::SeqCst)
    }
}
