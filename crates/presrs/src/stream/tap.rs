//! A tap on a connection: what else sees its frames and its decisions besides the output (a bag being
//! recorded, a live viewer in a browser).

use presrs_core::Grid;

/// Sees every frame a connection reads and every JSON line it emits, in order, as they happen.
///
/// Frames come as they were read (before the model's crop), rejected ones included, so a recording of
/// the connection holds what the sensor sent; lines are exactly those written to the connection's output
/// (`touchdown`, `classification`, `liftoff`, `error`, `end`). A tap must not block for long: the
/// connection waits for it.
pub trait ConnectionTap {
    /// Input frame `index` (counting every frame read), row-major `values`, `present` false where a
    /// sensel is absent (`None`: all present), the sender's timestamp when it gave one.
    fn frame(
        &mut self,
        index: u64,
        grid: Grid,
        values: &[f64],
        present: Option<&[bool]>,
        timestamp_us: Option<u64>,
    );

    /// One JSON line the connection emitted.
    fn line(&mut self, line: &str);

    /// The connection ended (after its `end` line): a tap that owns a file closes it.
    fn end(&mut self) {}
}

/// The tap that sees nothing.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoTap;

impl ConnectionTap for NoTap {
    fn frame(&mut self, _: u64, _: Grid, _: &[f64], _: Option<&[bool]>, _: Option<u64>) {}
    fn line(&mut self, _: &str) {}
}

/// Several taps, each seeing everything in turn: borrowed (`Taps<&mut dyn ConnectionTap>`: a bag being
/// recorded and a live viewer) or owned ([`OwnedTaps`]: what a server's
/// [`TapFactory`](super::TapFactory) makes for each client).
pub struct Taps<P>(pub Vec<P>);

/// The taps a connection owns.
pub type OwnedTaps = Taps<Box<dyn ConnectionTap + Send>>;

impl<P> std::fmt::Debug for Taps<P> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Taps({})", self.0.len())
    }
}

impl<P: ConnectionTap> ConnectionTap for Taps<P> {
    fn frame(
        &mut self,
        index: u64,
        grid: Grid,
        values: &[f64],
        present: Option<&[bool]>,
        timestamp_us: Option<u64>,
    ) {
        for tap in &mut self.0 {
            tap.frame(index, grid, values, present, timestamp_us);
        }
    }

    fn line(&mut self, line: &str) {
        for tap in &mut self.0 {
            tap.line(line);
        }
    }

    fn end(&mut self) {
        for tap in &mut self.0 {
            tap.end();
        }
    }
}

/// A borrowed tap is a tap.
impl<T: ConnectionTap + ?Sized> ConnectionTap for &mut T {
    fn frame(
        &mut self,
        index: u64,
        grid: Grid,
        values: &[f64],
        present: Option<&[bool]>,
        timestamp_us: Option<u64>,
    ) {
        (**self).frame(index, grid, values, present, timestamp_us);
    }

    fn line(&mut self, line: &str) {
        (**self).line(line);
    }

    fn end(&mut self) {
        (**self).end();
    }
}

/// A boxed tap is a tap.
impl<T: ConnectionTap + ?Sized> ConnectionTap for Box<T> {
    fn frame(
        &mut self,
        index: u64,
        grid: Grid,
        values: &[f64],
        present: Option<&[bool]>,
        timestamp_us: Option<u64>,
    ) {
        (**self).frame(index, grid, values, present, timestamp_us);
    }

    fn line(&mut self, line: &str) {
        (**self).line(line);
    }

    fn end(&mut self) {
        (**self).end();
    }
}
