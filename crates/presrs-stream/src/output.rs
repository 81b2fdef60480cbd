//! A bounded queue of output lines, so that a client that does not read cannot grow the server's memory
//! or slow the other clients.

use std::io::{BufWriter, Write};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, SyncSender, TrySendError, sync_channel};
use std::thread::JoinHandle;

use presrs::session::{SessionEvent, SessionObserver};

/// A bounded queue of output lines to a writer thread: `send` never blocks; when the queue is full the
/// line is dropped and counted.
pub struct BoundedOutput {
    sender: Option<SyncSender<String>>,
    dropped: Arc<AtomicU64>,
}

impl BoundedOutput {
    /// Starts the writer thread on `sink` with `capacity` queued lines. Write errors stop the output
    /// (later lines are dropped and counted). Returns the queue and the writer's handle.
    pub fn start<W: Write + Send + 'static>(sink: W, capacity: usize) -> (Self, JoinHandle<()>) {
        let (sender, receiver) = sync_channel::<String>(capacity.max(1));
        let dropped = Arc::new(AtomicU64::new(0));
        let counter = dropped.clone();
        let handle = std::thread::spawn(move || write_lines(sink, receiver, &counter));
        (
            Self {
                sender: Some(sender),
                dropped,
            },
            handle,
        )
    }

    /// Queues a line; false if it was dropped.
    pub fn send(&self, line: String) -> bool {
        let Some(sender) = &self.sender else {
            return false;
        };
        match sender.try_send(line) {
            Ok(()) => true,
            Err(TrySendError::Full(_) | TrySendError::Disconnected(_)) => {
                self.dropped.fetch_add(1, Ordering::Relaxed);
                false
            }
        }
    }

    /// Lines dropped so far (queue full, or output failed).
    pub fn dropped(&self) -> u64 {
        self.dropped.load(Ordering::Relaxed)
    }

    /// Closes the queue; the writer drains it and ends.
    pub fn close(&mut self) {
        self.sender = None;
    }
}

impl std::fmt::Debug for BoundedOutput {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BoundedOutput")
            .field("dropped", &self.dropped())
            .finish()
    }
}

/// A session's events as JSON lines through the queue; an event that did not fit is dropped.
impl SessionObserver for BoundedOutput {
    fn event(&mut self, event: &SessionEvent) -> bool {
        self.send(event.to_line())
    }
}

fn write_lines<W: Write>(sink: W, receiver: Receiver<String>, dropped: &AtomicU64) {
    let mut sink = BufWriter::new(sink);
    let mut failed = false;
    while let Ok(line) = receiver.recv() {
        if failed {
            dropped.fetch_add(1, Ordering::Relaxed);
            continue;
        }
        // Each line goes out at once: a robot waits for its decision.
        let written = writeln!(sink, "{line}").and_then(|()| sink.flush());
        if written.is_err() {
            failed = true;
            dropped.fetch_add(1, Ordering::Relaxed);
        }
    }
    let _ = sink.flush();
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    /// A sink that accepts nothing until released: a client that does not read.
    struct Stalled(std::sync::mpsc::Receiver<()>, Vec<u8>);

    impl Write for Stalled {
        fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
            let _ = self.0.recv();
            self.1.extend_from_slice(buf);
            Ok(buf.len())
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn a_slow_consumer_gets_drops_not_unbounded_memory() {
        let (release, gate) = std::sync::mpsc::channel();
        let (mut output, writer) = BoundedOutput::start(Stalled(gate, Vec::new()), 4);
        let mut accepted = 0;
        for i in 0..1000 {
            if output.send(format!("line {i}")) {
                accepted += 1;
            }
        }
        // At most the queue plus the line being written got through; the rest was dropped at once.
        assert!(accepted <= 6, "{accepted}");
        assert_eq!(output.dropped(), 1000 - accepted);
        drop(release);
        output.close();
        writer.join().unwrap();
    }
}
