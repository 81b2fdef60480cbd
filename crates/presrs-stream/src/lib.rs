//! presrs's transports: the online stream (stdin, TCP), the live view (HTTP), replay, the bags
//! `--record` writes, signals and stoppable input. A face of the library like the Python package and
//! the ROS 2 node; the library itself (`presrs`) links no server, no HTTP and no signal handling.
//!
//! The online stream: pressure frames in as they come, terrain decisions out as JSON lines.
//!
//! Input is TekScan ASCII text or the binary frame protocol of `docs/stream-protocol.md`
//! ([`presrs_io::frame_protocol`]); output is one JSON object per line (`touchdown`, `classification`,
//! `liftoff`, `error`, `end`). Two ways to run it:
//! - [`run_connection`]: one connection over any reader and writer (stdin and stdout, a pipe, a file);
//! - [`StreamServer`]: binary-protocol clients over TCP on a loopback address, several at once, until
//!   [`ShutdownHandle::stop`] (or a given number of connections).
//!
//! Each connection is one session of [`presrs::session`] (the classifier, its error policy and its
//! typed events); here are the transports around it: the readers of each input format, the JSON-lines
//! output, the TCP server, and the bags `--record` writes.
//!
//! Each connection has its own causal detector and classifier (`presrs_core::online`); the model is shared
//! read-only. Faults never panic and never grow memory without bound: frame sizes are capped before
//! reading, output to a client goes through a [`BoundedOutput`] (overflow is dropped and counted), the
//! number of clients is capped, idle connections are closed. Nothing here prints: what a person should
//! see comes back through the notice callbacks and the summaries ([`ConnectionSummary`](presrs::session::ConnectionSummary)).

mod bag;
mod connection;
pub mod live;
mod output;
pub mod replay;
mod server;
mod shutdown;
mod signals;
pub mod stoppable_input;

pub use bag::{
    BagRecorder, BagReport, ConnectionBags, FRAME_TIMES_KEY, FrameTimes, RECORDING_METADATA,
    RecordedBag,
};
pub use connection::{ConnectionOptions, InputFormat, run_connection, run_connection_observed};
pub use output::BoundedOutput;
pub use presrs_io::mcap::{DECISIONS_SCHEMA, DECISIONS_SCHEMA_NAME, DECISIONS_TOPIC, FRAMES_TOPIC};
pub use server::{ObserverFactory, ServeSummary, ServerNotice, ServerOptions, StreamServer};
pub use shutdown::ShutdownHandle;
pub use signals::{SignalWatch, StopSignals};
