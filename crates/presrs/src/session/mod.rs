//! The online session every face runs (`presrs stream`, the live view's replay, the ROS 2 node,
//! Python's `OnlineClassifier`): frames in one at a time through the causal classifier, typed events
//! out ([`SessionEvent`], whose JSON is `docs/stream-protocol.md`'s lines) to a [`SessionObserver`].
//!
//! A bad frame (unreadable, non-finite, or of a size the model cannot use) is rejected with an `error`
//! event and the session goes on; the `end` event and the [`ConnectionSummary`] count it among
//! `rejected_frames` and `errors`. But when the first frame already has a size the model cannot use,
//! the frames come from another sensor: one fatal `error` ends the session instead of one error per
//! frame.
//!
//! Without a calibration (in the [`OnlineProfile`](presrs_core::online::OnlineProfile)) the detector
//! calibrates on the first frames (the warm-up); stances in them are not classified, and a
//! [`ConnectionNotice`] says so when the warm-up ends. Frames missing from the input (a step in the
//! frames' times well above the frame period, [`FrameGaps`]) are stated on the decisions and lift-offs
//! of their stances (`gap_frames`). Nothing here reads files or sockets, or prints.

mod events;
mod gaps;
mod observer;
mod profile;
mod run;
mod summary;

pub use events::{
    Classification, DecisionPoint, EarlyDecisionEvent, EarlyRule, End, ErrorEvent, EventTiming,
    Liftoff, NoveltyVerdict, Posteriors, SessionEvent, Touchdown, WholeStance, step_events,
};
pub use gaps::FrameGaps;
pub use observer::{JsonLines, NoObserver, Observers, OwnedObservers, SessionObserver};
pub use profile::{
    ProfileOverrides, check_overrides, check_profile, parse_profile, read_profile, resolve_profile,
};
pub use run::{ConnectionNotice, Input, MAX_ERROR_NOTICES, run_frames};
pub use summary::ConnectionSummary;
