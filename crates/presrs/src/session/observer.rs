//! What sees a session: one trait through which every face takes its frames and typed events, and the
//! JSON-lines writer, its implementation for a stream's output.

use std::io::Write;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use presrs_core::Grid;

use super::events::SessionEvent;

/// Sees every frame a session reads and every event it makes, in order, as they happen. Faces
/// implement it: the JSON-lines writer, a bag being recorded, the live view, the ROS 2 node. It must
/// not block for long: the session waits for it.
pub trait SessionObserver {
    /// Input frame `index` (counting every frame read, rejected ones included), row-major `values`,
    /// `present` false where a sensel is absent (`None`: all present), the sender's timestamp when it
    /// gave one. Frames come before the model's crop, as the sensor sent them.
    fn frame(
        &mut self,
        index: u64,
        grid: Grid,
        values: &[f64],
        present: Option<&[bool]>,
        timestamp_us: Option<u64>,
    ) {
        let _ = (index, grid, values, present, timestamp_us);
    }

    /// One event; false when it could not be delivered (the session counts it as dropped).
    fn event(&mut self, event: &SessionEvent) -> bool;

    /// The session ended (after its `end` event): an observer that owns a file closes it.
    fn end(&mut self) {}
}

/// The observer that sees nothing.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoObserver;

impl SessionObserver for NoObserver {
    fn event(&mut self, _: &SessionEvent) -> bool {
        true
    }
}

/// Several observers, each seeing everything in turn: borrowed (`Observers<&mut dyn SessionObserver>`:
/// a bag being recorded and a live viewer) or owned ([`OwnedObservers`]).
pub struct Observers<P>(pub Vec<P>);

/// Observers a session owns (what a server makes for each client).
pub type OwnedObservers = Observers<Box<dyn SessionObserver + Send>>;

impl<P> std::fmt::Debug for Observers<P> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Observers({})", self.0.len())
    }
}

impl<P: std::ops::DerefMut<Target = O>, O: SessionObserver + ?Sized> SessionObserver
    for Observers<P>
{
    fn frame(
        &mut self,
        index: u64,
        grid: Grid,
        values: &[f64],
        present: Option<&[bool]>,
        timestamp_us: Option<u64>,
    ) {
        for observer in &mut self.0 {
            observer.frame(index, grid, values, present, timestamp_us);
        }
    }

    /// Every observer sees the event; false when any could not take it.
    fn event(&mut self, event: &SessionEvent) -> bool {
        self.0.iter_mut().fold(true, |delivered, observer| {
            observer.event(event) & delivered
        })
    }

    fn end(&mut self) {
        for observer in &mut self.0 {
            observer.end();
        }
    }
}

/// The protocol's JSON lines to a writer, each flushed at once (a robot waits for its decision). A
/// closed output (a broken pipe: `presrs stream | head`) is remembered, so that the session can end as
/// it would at the end of its input.
#[derive(Debug)]
pub struct JsonLines<W: Write> {
    output: W,
    closed: Arc<AtomicBool>,
}

impl<W: Write> JsonLines<W> {
    pub fn new(output: W) -> Self {
        Self {
            output,
            closed: Arc::default(),
        }
    }

    /// Set when the output was closed by its reader; shared, so that the session's input can look at it
    /// while the writer is the session's.
    pub fn closed_flag(&self) -> Arc<AtomicBool> {
        self.closed.clone()
    }
}

impl<W: Write> SessionObserver for JsonLines<W> {
    fn event(&mut self, event: &SessionEvent) -> bool {
        let written =
            writeln!(self.output, "{}", event.to_line()).and_then(|()| self.output.flush());
        if let Err(err) = &written
            && err.kind() == std::io::ErrorKind::BrokenPipe
        {
            self.closed.store(true, Ordering::Relaxed);
        }
        written.is_ok()
    }
}
