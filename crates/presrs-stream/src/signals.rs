//! Stopping cleanly on SIGINT and SIGTERM: the first one calls a stop function (a stream then writes its
//! `end` line, a server closes its connections), a second one gets the default action (the process ends at
//! once). Every face that runs a stream (the CLI's `stream` and `view`, a robot's node) needs the same.

use std::sync::{Arc, Mutex};

use signal_hook::consts::{SIGINT, SIGTERM};
use signal_hook::iterator::Signals;

use presrs::error::{Error, Result};

/// SIGINT and SIGTERM, caught from [`register`](Self::register) on: registered before the work starts, so
/// that a signal during loading is not lost, and handed a stop function once there is something to stop.
#[derive(Debug)]
pub struct StopSignals(Signals);

impl StopSignals {
    /// Catches SIGINT and SIGTERM from now on.
    pub fn register() -> Result<Self> {
        Signals::new([SIGINT, SIGTERM])
            .map(Self)
            .map_err(|err| Error::system("cannot handle SIGINT and SIGTERM", err))
    }

    /// Handles the first signal on a thread of its own: notes it and calls `stop`.
    pub fn on_first(self, stop: impl FnOnce() + Send + 'static) -> SignalWatch {
        let mut signals = self.0;
        let handle = signals.handle();
        let caught = Arc::new(Mutex::new(None));
        let first_caught = caught.clone();
        std::thread::spawn(move || {
            let mut stop = Some(stop);
            for signal in signals.forever() {
                let mut first = first_caught.lock().unwrap_or_else(|p| p.into_inner());
                if first.is_some() {
                    let _ = signal_hook::low_level::emulate_default_handler(signal);
                    continue;
                }
                *first = Some(signal);
                drop(first);
                if let Some(stop) = stop.take() {
                    stop();
                }
            }
        });
        SignalWatch { handle, caught }
    }
}

/// The thread that handles SIGINT and SIGTERM, and the first signal it caught.
#[derive(Debug)]
pub struct SignalWatch {
    handle: signal_hook::iterator::Handle,
    caught: Arc<Mutex<Option<i32>>>,
}

impl SignalWatch {
    /// Stops the thread; the name of the signal it caught, if any.
    pub fn close(self) -> Option<&'static str> {
        self.handle.close();
        let caught = *self.caught.lock().unwrap_or_else(|p| p.into_inner());
        caught.map(signal_name)
    }
}

fn signal_name(signal: i32) -> &'static str {
    match signal {
        SIGINT => "SIGINT",
        SIGTERM => "SIGTERM",
        _ => "a signal",
    }
}
