//! The live view: a page in the browser that shows a stream as it is classified — the latest pressure
//! image with its colour scale in the recording's unit, the total-load trace with the stances shaded,
//! the current terrain, its confidence and the recommended gait, and the decision log.
//!
//! - [`LiveHub`] holds what the viewers are shown; its [`LiveTap`] (a
//!   [`SessionObserver`](presrs::session::SessionObserver)) feeds it from a connection and never waits for a viewer:
//!   the latest frame goes to one slot, the total loads and the
//!   JSON lines to bounded histories.
//! - [`LiveServer`] serves it over HTTP/1.1 (hyper, on a tokio runtime of its own thread): `GET /` the
//!   page (HTML, JavaScript and CSS built into the binary, no CDN), `GET /events` server-sent events
//!   (`hello`, then `frame`, `loads` and `line` events at most [`LiveOptions::max_fps`] times a second,
//!   skipping the frames a slow viewer could not take), `GET /state` a JSON snapshot. Several viewers
//!   at once; a viewer that takes nothing for [`LiveOptions::write_timeout`] is dropped.
//! - [`replay_recording`] replays a file into a hub at its frame rate (`presrs view FILE`).
//!
//! The load trace is indexed by input frame (every frame read), the stances by the classifier's frame
//! numbers (the accepted frames): the two agree unless frames were rejected.

mod events;
mod hub;
mod server;
mod view;
mod write_timeout;

pub use events::{base64, frame_json, sse_event};
pub use hub::{
    Cursor, LINE_HISTORY, LOAD_HISTORY, LatestFrame, LiveHub, LiveInfo, LiveTap, Update,
};
pub use server::{LiveOptions, LiveServer, state_json};
pub use view::{ReplayOptions, replay_period_s, replay_recording};
