//! Causal stance detection: one total load at a time, deciding without looking ahead.
//!
//! [`segment`](super::segment()) sees a whole recording; a robot has to decide while its foot is still on
//! the ground. [`CausalSegmenter`] takes one total load at a time and decides without looking ahead,
//! with the offline method's rules (see [`super::offline`]):
//!
//! * **Levels.** The same formulas: `on = max(on_noise x noise, on_fraction x range)`, `off = max(off_noise
//!   x noise, off_fraction x range)`, everything measured above the baseline. Offline, baseline, noise and
//!   load range come from the whole recording; online they come from the past only:
//!   - a [`Calibration`] (baseline, noise, load range) learned from training recordings with the offline
//!     segmentation ([`Calibration::from_segmentations`]), or, without one, from a *warm-up*: the first
//!     [`OnlineParams::warmup_frames`] frames are segmented offline once (no events are emitted for them);
//!   - updated online: **baseline** = median and **noise** = 1.4826 x MAD of the last
//!     `baseline_window_frames` *quiet* frames (frames outside any stance or candidate run, at most the off
//!     level above the baseline), recomputed every `baseline_window_frames / 8` quiet frames once at least
//!     [`MIN_QUIET_FRAMES`] were seen (the calibration is used until then). The median of a window lags a
//!     drift by half a window: the same time scale the offline method follows drift at.
//!   - **load range** = the largest load above the baseline seen so far in the stream, but at least
//!     [`RANGE_PRIOR_FRACTION`] of the calibrated range (offline it is the recording's maximum, which the
//!     running maximum reaches after a few stances; the floor keeps noise before the first stance from
//!     setting the levels of a sensor that reads almost exactly zero in flight). The range belongs to the
//!     stream, not to the training data: a lighter or slower robot has a smaller one.
//! * **Runs, gaps, minimum length.** Exactly the offline rules, decided as soon as they are decidable: a
//!   run of loaded frames (above `off`) is *kept* once it is `min_stance_frames` long or has exceeded
//!   `on` (a short weak run is dropped when it ends); kept runs at most `max_gap_frames` apart form one
//!   stance; a stance is *confirmed* once it is `min_stance_frames` long and has exceeded `on` (it can
//!   only grow after that). Touchdown is reported at confirmation (normally 2 frames after contact),
//!   lift-off at the `max_gap_frames + 1`-th unloaded frame after the last loaded one: a run that starts
//!   after a gap of `max_gap_frames` unloaded frames still joins the stance, so only then can no later
//!   run join it.
//! * **Partial stances.** A stance already under way at the first frame the detector judges (frame 0, or
//!   the end of the warm-up) is partial: reported, never sampled. One still open when the stream ends
//!   ([`CausalSegmenter::finish`]) is partial if it reached the last frame, as offline. A stream that
//!   ends during the warm-up is segmented offline at `finish` and its stances reported then (a
//!   recording that is one contact, loaded whole, gives its one partial stance, as offline).
//! * **One sample per file** ([`BaselineMode::Contact`](super::BaselineMode::Contact)): the stream is one
//!   contact from frame 0 to its end, partial at both ends as offline but sampled: frame `k` is decided
//!   as it arrives, the lift-off comes at `finish`. No warm-up, no fusion.
//! * **The floor mode** ([`BaselineMode::Floor`](super::BaselineMode::Floor), presses or steps on a standing preload): each contact
//!   is measured from the *rest* before it, not from one baseline. At rest the floor is the rest's mean
//!   moved along a slope pooled within the recent rests (a drifting preload is followed; a preload that
//!   steps between rests does not tilt it). A rise of more than the off level above the floor starts a
//!   candidate; it is a contact (touchdown at its first frame) once it is `min_stance_frames` long and
//!   has risen more than the on level above the floor; it was noise if it comes back within the off
//!   level first. A contact ends when the next rest begins: `m = max(max_gap_frames + 1,`
//!   [`MIN_REST_FRAMES`]`)` frames after its peak within the off level of their mean, more than the on
//!   level below the peak (a shorter pause is a dropout inside the contact, as offline); its end is the
//!   first of those flat frames, and the lift-off is reported at the rest's `m`-th frame, i.e.
//!   `max_gap_frames` frames after the end with the defaults (as in the drifting mode), later only if
//!   the rest's first frames were found by looking back. On and off levels use the calibrated noise
//!   and the stream's load range (highest minus lowest total, as offline, at least
//!   [`RANGE_PRIOR_FRACTION`] of the calibrated range). On synthetic preload movies it agrees with the
//!   offline floor segmentation contact by contact (tests `causal_floor`). Limits: a contact that
//!   pauses flat for `m` frames more than the on level below its peak ends there (offline looks at the
//!   whole valley); a stream that starts inside a contact, with a calibration and no warm-up, does not
//!   report that partial contact.
//! * **The automatic choice online** ([`BaselineMode::Auto`](super::BaselineMode::Auto)): the warm-up's offline segmentation
//!   decides. If it chose the floor, the stream is judged in the floor mode; otherwise with the
//!   baseline, as before. With a calibration (no warm-up) the profile's mode is used as it is:
//!   [`OnlineProfile::learn_with`](crate::online::OnlineProfile::learn_with) stores the floor when the
//!   training recordings were segmented from the floor.
//!
//! **The sample frame** is chosen without the future: the `k`-th frame after touchdown
//! ([`OnlineParams::sample_offset`]). The paper samples the mid-stance frame `(len - 1) / 2`, which
//! depends on the lift-off still to come; [`sample_offset_for`] learns `k = (L - 1) / 2` from the
//! training data's median stance length `L`, so that on a typical stance the online sample *is* the
//! paper's (offline) mid-stance frame. If frame `k` is not decidable when it arrives (the stance is not
//! yet confirmed, or frame `k` is a dropout inside the stance) the user (the online classifier) keeps a copy of it and
//! decides as soon as it is; if the stance ends before frame `k`, it is not sampled.
//!

mod detector;
mod events;
mod floor;
mod settings;

pub use detector::{CausalSegmenter, Levels, OpenStance};
pub(crate) use events::MAX_SEG_EVENTS;
pub use events::{Liftoff, SegEvent, SegEvents, Touchdown};
pub use floor::MIN_REST_FRAMES;
pub use settings::{
    AutoWord, Calibration, DecideAt, MAX_FUSION_FRAMES, MAX_OFFSET_FRAMES, MIN_QUIET_FRAMES,
    OnlineParams, PAPER_SAMPLE_OFFSET, RANGE_PRIOR_FRACTION, sample_offset_for,
    typical_stance_frames,
};
