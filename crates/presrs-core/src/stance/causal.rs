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
//! * **One sample per file** ([`BaselineMode::Contact`]): the stream is one
//!   contact from frame 0 to its end, partial at both ends as offline but sampled: frame `k` is decided
//!   as it arrives, the lift-off comes at `finish`. No warm-up, no fusion.
//! * **The floor mode** ([`BaselineMode::Floor`], presses or steps on a standing preload): each contact
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
//! * **The automatic choice online** ([`BaselineMode::Auto`]): the warm-up's offline segmentation
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

use serde::{Deserialize, Serialize};

use super::modes::{MIN_CONTACT_FRAMES, segment};
use super::offline::{BaselineMode, Segmentation, Stance, ValidSegmentParams};
use super::robust::{MAD_TO_SIGMA, median};
use crate::error::{CoreError, Result};

/// Quiet frames needed before the online baseline/noise estimate replaces the calibration.
pub const MIN_QUIET_FRAMES: usize = 32;
/// The load range is the stream's running maximum above the baseline, but at least this fraction of the
/// calibrated range: before the first stance, noise must not set the levels.
pub const RANGE_PRIOR_FRACTION: f64 = 0.5;
/// Most fusion offsets accepted.
pub const MAX_FUSION_FRAMES: usize = 32;
/// The paper's sample: the 7th frame of a stance (0-based offset 6), the default `k`.
pub const PAPER_SAMPLE_OFFSET: usize = 6;
/// Largest sample or fusion offset accepted, frames (1000 s at 100 Hz; a stance lasts well under a
/// second).
pub const MAX_OFFSET_FRAMES: usize = 100_000;

/// Baseline, noise and load range of the total load, as the offline segmentation measures them.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Calibration {
    /// Unloaded level of the total load.
    pub baseline: f64,
    /// Standard deviation of the unloaded level.
    pub noise: f64,
    /// Largest load above the baseline.
    pub load_range: f64,
}

impl Calibration {
    /// The medians of the per-recording baseline (each recording's median baseline), noise and load
    /// range of offline segmentations, e.g. of the training recordings. `None` without any.
    pub fn from_segmentations<'a>(
        segmentations: impl IntoIterator<Item = &'a Segmentation>,
    ) -> Option<Self> {
        let (mut baselines, mut noises, mut ranges) = (Vec::new(), Vec::new(), Vec::new());
        for seg in segmentations {
            let mut base = seg.baseline.clone();
            if base.is_empty() {
                continue;
            }
            baselines.push(median(&mut base));
            noises.push(seg.noise);
            ranges.push(seg.load_range);
        }
        if baselines.is_empty() {
            return None;
        }
        Some(Self {
            baseline: median(&mut baselines),
            noise: median(&mut noises),
            load_range: median(&mut ranges),
        })
    }

    fn check(&self) -> Result<()> {
        let ok = self.baseline.is_finite()
            && self.noise.is_finite()
            && self.noise >= 0.0
            && self.load_range.is_finite()
            && self.load_range >= 0.0;
        if ok {
            Ok(())
        } else {
            Err(CoreError::Param {
                name: "calibration",
                reason: format!(
                    "baseline must be finite and noise, load range finite and >= 0, got {self:?}"
                ),
            })
        }
    }
}

/// `k = (L - 1) / 2` for the median `L` of `stance_lengths` (frames): the offset after touchdown that is
/// the paper's mid-stance frame on a stance of typical length. [`PAPER_SAMPLE_OFFSET`] without data.
pub fn sample_offset_for(stance_lengths: &[usize]) -> usize {
    typical_stance_frames(stance_lengths)
        .map_or(PAPER_SAMPLE_OFFSET, |len| len.saturating_sub(1) / 2)
}

/// The median stance length (the lower median for an even count), `None` without stances.
pub fn typical_stance_frames(stance_lengths: &[usize]) -> Option<usize> {
    let mut lengths = stance_lengths.to_vec();
    lengths.sort_unstable();
    lengths.get(lengths.len().saturating_sub(1) / 2).copied()
}

/// Settings of the online detector and classifier beyond the offline [`SegmentParams`](super::SegmentParams).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct OnlineParams {
    /// `k`: the frame classified is the `k`-th after touchdown (0 = touchdown), at most
    /// [`MAX_OFFSET_FRAMES`]. Default 6, the paper's 7th frame; learn it with [`sample_offset_for`].
    pub sample_offset: usize,
    /// Offsets after touchdown whose posteriors are averaged into a second, fused decision (empty: none;
    /// at most [`MAX_FUSION_FRAMES`] of them, each at most [`MAX_OFFSET_FRAMES`]).
    pub fusion_offsets: Vec<usize>,
    /// Without a calibration, the first frames are used to calibrate (default 128; at least 8).
    pub warmup_frames: usize,
}

impl Default for OnlineParams {
    fn default() -> Self {
        Self {
            sample_offset: PAPER_SAMPLE_OFFSET,
            fusion_offsets: Vec::new(),
            warmup_frames: 128,
        }
    }
}

impl OnlineParams {
    fn check(&self) -> Result<()> {
        if self.sample_offset > MAX_OFFSET_FRAMES {
            return Err(CoreError::Param {
                name: "sample_offset",
                reason: format!(
                    "must be at most {MAX_OFFSET_FRAMES} frames after touchdown, got {}",
                    self.sample_offset
                ),
            });
        }
        if let Some(&offset) = self
            .fusion_offsets
            .iter()
            .find(|&&offset| offset > MAX_OFFSET_FRAMES)
        {
            return Err(CoreError::Param {
                name: "fusion_offsets",
                reason: format!(
                    "each must be at most {MAX_OFFSET_FRAMES} frames after touchdown, got {offset}"
                ),
            });
        }
        if self.fusion_offsets.len() > MAX_FUSION_FRAMES {
            return Err(CoreError::Param {
                name: "fusion_offsets",
                reason: format!(
                    "at most {MAX_FUSION_FRAMES} offsets, got {}",
                    self.fusion_offsets.len()
                ),
            });
        }
        if self.warmup_frames < 8 {
            return Err(CoreError::Param {
                name: "warmup_frames",
                reason: format!("must be at least 8, got {}", self.warmup_frames),
            });
        }
        Ok(())
    }
}

/// A stance confirmed by the detector (enough frames, on level reached).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Touchdown {
    /// Stance number in this stream, from 0.
    pub stance_id: u64,
    /// First loaded frame.
    pub touchdown_frame: usize,
    /// Frame at which the stance was confirmed.
    pub frame: usize,
    /// The stance was already under way when detection began: it is not sampled.
    pub partial: bool,
}

/// A stance that ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Liftoff {
    pub stance_id: u64,
    /// The stance, as [`segment`] reports it.
    pub stance: Stance,
    /// Frame at which the end was decided (`max_gap_frames + 1` frames after the last loaded frame, or
    /// the last frame of the stream).
    pub frame: usize,
    /// Whether the stance got its (single-frame) decision. From [`CausalSegmenter`], whether it asked
    /// for one; from [`OnlineClassifier`](crate::online::OnlineClassifier), whether a decision was made (false when the sample frame
    /// could not be classified, see [`OnlineEvent::Failed`](crate::online::OnlineEvent::Failed)).
    pub sampled: bool,
}

/// What the segmenter asks its user to do, in order, for one frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SegEvent {
    Touchdown(Touchdown),
    /// Keep a copy of the current frame: it is the sample frame but cannot be decided yet.
    HoldCurrent {
        stance_id: u64,
    },
    /// Classify the sample frame `frame` of the stance: the current frame, or the held copy.
    ClassifySample {
        stance_id: u64,
        touchdown_frame: usize,
        frame: usize,
        held: bool,
    },
    /// Classify the current frame and add its posteriors to the stance's fusion.
    FuseCurrent {
        stance_id: u64,
    },
    /// The fusion of the stance is complete: decide.
    FusionReady {
        stance_id: u64,
        touchdown_frame: usize,
    },
    Liftoff(Liftoff),
}

/// At most this many [`SegEvent`]s come out of one frame.
pub(crate) const MAX_SEG_EVENTS: usize = 8;

/// A fixed-capacity list of the events of one frame (no allocation).
#[derive(Clone, Copy, Debug)]
pub struct SegEvents {
    items: [Option<SegEvent>; MAX_SEG_EVENTS],
    len: usize,
}

impl SegEvents {
    const EMPTY: Self = Self {
        items: [None; MAX_SEG_EVENTS],
        len: 0,
    };

    fn push(&mut self, event: SegEvent) {
        // Capacity: per frame at most liftoff + fusion of a closing stance, then touchdown, hold, sample,
        // fuse and fusion-ready of the current one (7).
        if let Some(slot) = self.items.get_mut(self.len) {
            *slot = Some(event);
            self.len += 1;
        }
    }

    pub fn iter(&self) -> impl Iterator<Item = SegEvent> + '_ {
        self.items[..self.len].iter().flatten().copied()
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    pub fn len(&self) -> usize {
        self.len
    }
}

/// The current maximal run of loaded frames.
#[derive(Clone, Copy, Debug)]
struct Run {
    start: usize,
    reached_on: bool,
    peak_load: f64,
    peak_frame: usize,
}

/// The stance being built (kept runs merged across short gaps).
#[derive(Clone, Copy, Debug)]
struct Group {
    id: u64,
    start: usize,
    /// One past the last loaded frame of its kept runs.
    end: usize,
    reached_on: bool,
    /// Peak over the runs already finished.
    peak_load: f64,
    peak_frame: usize,
    confirmed: bool,
    partial: bool,
    sample_done: bool,
    fused: usize,
    fusion_done: bool,
}

/// Levels the detector currently uses (all above baseline except `baseline`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Levels {
    pub baseline: f64,
    pub noise: f64,
    pub load_range: f64,
    pub on_level: f64,
    pub off_level: f64,
}

/// Fewest frames of a rest in the floor mode online: a rest this long ends a contact (at least
/// `max_gap_frames + 1`: a shorter rest is a dropout inside one contact, as offline).
pub const MIN_REST_FRAMES: usize = 3;
/// Recent totals the floor mode keeps to look back over when a rest is found (the rest's first frames
/// are found from its last ones).
const FLOOR_LOOKBACK: usize = 64;
/// The floor's slope counts as if a level rest of this many frames had been seen.
const SLOPE_PRIOR_FRAMES: f64 = 8.0;
/// Weight the slope evidence of earlier rests keeps each time a new rest starts.
const SLOPE_MEMORY: f64 = 0.75;

/// Least-squares sums of `(t, load)` over frames (times from `origin`, so that they stay small).
#[derive(Clone, Copy, Debug, Default)]
struct LineSums {
    origin: usize,
    n: f64,
    st: f64,
    sx: f64,
    stt: f64,
    stx: f64,
}

impl LineSums {
    fn add(&mut self, t: usize, load: f64) {
        if self.n == 0.0 {
            self.origin = t;
        }
        let dt = t as f64 - self.origin as f64;
        self.n += 1.0;
        self.st += dt;
        self.sx += load;
        self.stt += dt * dt;
        self.stx += dt * load;
    }

    /// Spread of the times about their mean (the slope's denominator).
    fn sxx(&self) -> f64 {
        if self.n == 0.0 {
            0.0
        } else {
            self.stt - self.st * self.st / self.n
        }
    }

    /// Co-spread of times and loads (the slope's numerator).
    fn sxy(&self) -> f64 {
        if self.n == 0.0 {
            0.0
        } else {
            self.stx - self.st * self.sx / self.n
        }
    }
}

/// What the floor mode knows of the local floor (see [`CausalSegmenter::push_floor`]).
#[derive(Clone, Debug)]
struct FloorState {
    /// The current (or last) rest's frames.
    rest: LineSums,
    /// Slope evidence (`sxy`, `sxx`) of the earlier rests, each weighted [`SLOPE_MEMORY`] per rest
    /// since: slopes are pooled *within* rests, so a preload that steps between rests does not tilt them.
    pool_sxy: f64,
    pool_sxx: f64,
    /// The last [`FLOOR_LOOKBACK`] totals, frame `t` at `t % FLOOR_LOOKBACK`.
    recent: Vec<f64>,
    /// Lowest and highest total seen (the load range is their difference, as offline).
    lowest: f64,
    highest: f64,
    /// Frames in a row more than the off level below the floor.
    below: usize,
}

impl FloorState {
    fn new(seen: Option<(f64, f64)>) -> Self {
        let (lowest, highest) = seen.unwrap_or((f64::INFINITY, f64::NEG_INFINITY));
        Self {
            rest: LineSums::default(),
            pool_sxy: 0.0,
            pool_sxx: 0.0,
            recent: vec![0.0; FLOOR_LOOKBACK],
            lowest,
            highest,
            below: 0,
        }
    }

    /// The floor's slope, shrunk towards level by the spread of [`SLOPE_PRIOR_FRAMES`] flat frames (the
    /// two or three frames of a short rest alone would tilt it by their noise).
    fn slope(&self) -> f64 {
        let prior = SLOPE_PRIOR_FRAMES * (SLOPE_PRIOR_FRAMES * SLOPE_PRIOR_FRAMES - 1.0) / 12.0;
        let sxx = self.pool_sxx + self.rest.sxx() + prior;
        if sxx > 0.0 {
            (self.pool_sxy + self.rest.sxy()) / sxx
        } else {
            0.0
        }
    }

    /// The floor at frame `t`: the current rest's mean, moved along the pooled slope; `None` before any
    /// rest.
    fn at(&self, t: usize) -> Option<f64> {
        let rest = &self.rest;
        (rest.n > 0.0).then(|| {
            let centre = rest.origin as f64 + rest.st / rest.n;
            rest.sx / rest.n + self.slope() * (t as f64 - centre)
        })
    }

    /// Ends the current rest (its slope evidence joins the pool) and starts a new one on frames
    /// `first..=last` (all within the lookback).
    fn start_rest(&mut self, first: usize, last: usize) {
        self.close_rest();
        self.below = 0;
        for f in first..=last {
            self.rest.add(f, self.recent[f % FLOOR_LOOKBACK]);
        }
    }

    fn close_rest(&mut self) {
        if self.rest.n >= MIN_REST_FRAMES as f64 {
            self.pool_sxy = SLOPE_MEMORY * self.pool_sxy + self.rest.sxy();
            self.pool_sxx = SLOPE_MEMORY * self.pool_sxx + self.rest.sxx();
        }
        self.rest = LineSums::default();
    }

    /// Whether the `m` frames ending at `t` lie within `off` of their mean, and that mean.
    fn flat(&self, t: usize, m: usize, off: f64) -> Option<f64> {
        if m == 0 || m > FLOOR_LOOKBACK || t + 1 < m {
            return None;
        }
        let window = (t + 1 - m..=t).map(|f| self.recent[f % FLOOR_LOOKBACK]);
        let mean = window.clone().sum::<f64>() / m as f64;
        window
            .clone()
            .all(|v| (v - mean).abs() <= off)
            .then_some(mean)
    }
}

/// The causal stance detector (see the module docs). One [`push`](Self::push) per frame, O(1) amortised,
/// no allocation after construction (the warm-up calibration, if any, allocates once).
#[derive(Clone, Debug)]
pub struct CausalSegmenter {
    params: ValidSegmentParams,
    online: OnlineParams,
    max_fusion_offset: Option<usize>,
    calibration: Option<Calibration>,
    /// Totals of the warm-up frames (capacity `warmup_frames`), while calibrating.
    warmup: Vec<f64>,
    /// First frame judged (0, or the end of the warm-up).
    detect_from: usize,
    /// Frames pushed so far (index of the next frame).
    t: usize,
    levels: Levels,
    /// Ring of the last quiet totals.
    quiet: Vec<f64>,
    quiet_head: usize,
    quiet_seen: usize,
    since_refresh: usize,
    scratch: Vec<f64>,
    max_above: f64,
    run: Option<Run>,
    group: Option<Group>,
    next_id: u64,
    /// [`BaselineMode::Contact`]: the whole stream is one contact (see [`Self::push_contact`]).
    contact: bool,
    /// The floor mode's state: [`BaselineMode::Floor`], or [`BaselineMode::Auto`] once the warm-up chose
    /// the floor (see [`Self::push_floor`]).
    floor: Option<Box<FloorState>>,
}

impl CausalSegmenter {
    /// A detector with the offline `params`; `calibration` from training data, or `None` to calibrate on
    /// the first `online.warmup_frames` frames.
    pub fn new(
        params: &ValidSegmentParams,
        online: &OnlineParams,
        calibration: Option<Calibration>,
    ) -> Result<Self> {
        online.check()?;
        if let Some(cal) = &calibration {
            cal.check()?;
        }
        let window = params.params().baseline_window_frames;
        let mut segmenter = Self {
            params: params.clone(),
            online: online.clone(),
            max_fusion_offset: online.fusion_offsets.iter().copied().max(),
            calibration,
            warmup: Vec::new(),
            detect_from: 0,
            t: 0,
            levels: Levels {
                baseline: 0.0,
                noise: 0.0,
                load_range: 0.0,
                on_level: 0.0,
                off_level: 0.0,
            },
            quiet: vec![0.0; window],
            quiet_head: 0,
            quiet_seen: 0,
            since_refresh: 0,
            scratch: Vec::with_capacity(window),
            max_above: 0.0,
            run: None,
            group: None,
            next_id: 0,
            contact: params.params().baseline == BaselineMode::Contact,
            floor: None,
        };
        if params.params().baseline == BaselineMode::Floor && calibration.is_some() {
            segmenter.floor = Some(Box::new(FloorState::new(None)));
        }
        match calibration {
            Some(cal) => segmenter.apply_calibration(cal),
            None => segmenter.warmup = Vec::with_capacity(online.warmup_frames),
        }
        Ok(segmenter)
    }

    /// The levels in use now.
    pub fn levels(&self) -> Levels {
        self.levels
    }

    /// The calibration in use (`None` while warming up).
    pub fn calibration(&self) -> Option<Calibration> {
        self.calibration
    }

    /// Frames pushed so far.
    pub fn frames_seen(&self) -> usize {
        self.t
    }

    /// Whether the detector is still calibrating on its warm-up frames.
    pub fn warming_up(&self) -> bool {
        self.calibration.is_none()
    }

    /// The online parameters.
    pub fn online_params(&self) -> &OnlineParams {
        &self.online
    }

    fn apply_calibration(&mut self, cal: Calibration) {
        self.calibration = Some(cal);
        self.levels.baseline = cal.baseline;
        self.levels.noise = cal.noise;
        self.max_above = 0.0;
        self.update_levels();
    }

    fn update_levels(&mut self) {
        let p = self.params.params();
        let prior = self.calibration.map_or(0.0, |c| c.load_range) * RANGE_PRIOR_FRACTION;
        let range = prior.max(self.max_above);
        self.levels.load_range = range;
        self.levels.on_level = (p.on_noise * self.levels.noise).max(p.on_fraction * range);
        self.levels.off_level = (p.off_noise * self.levels.noise).max(p.off_fraction * range);
    }

    fn add_quiet(&mut self, total: f64) {
        let window = self.quiet.len();
        if window == 0 {
            return;
        }
        self.quiet[self.quiet_head] = total;
        self.quiet_head = (self.quiet_head + 1) % window;
        self.quiet_seen += 1;
        self.since_refresh += 1;
        let filled = self.quiet_seen.min(window);
        if filled >= MIN_QUIET_FRAMES.min(window) && self.since_refresh >= (window / 8).max(1) {
            self.since_refresh = 0;
            self.scratch.clear();
            self.scratch.extend_from_slice(&self.quiet[..filled]);
            let centre = median(&mut self.scratch);
            for value in &mut self.scratch {
                *value = (*value - centre).abs();
            }
            let sigma = MAD_TO_SIGMA * median(&mut self.scratch);
            self.levels.baseline = centre;
            self.levels.noise = sigma;
            self.update_levels();
        }
    }

    /// Judges the next frame from its total load. A non-finite total is an error and the frame is not
    /// counted (the state is unchanged).
    pub fn push(&mut self, total: f64) -> Result<SegEvents> {
        if !total.is_finite() {
            return Err(CoreError::Param {
                name: "total load",
                reason: format!(
                    "frame {} has load {total}; total loads must be finite",
                    self.t
                ),
            });
        }
        if self.contact {
            return Ok(self.push_contact(total));
        }
        let mut events = SegEvents::EMPTY;
        let t = self.t;
        self.t += 1;
        if self.calibration.is_none() {
            self.warmup.push(total);
            if self.warmup.len() >= self.online.warmup_frames {
                self.finish_warmup()?;
            }
            return Ok(events);
        }

        let loaded = if self.floor.is_some() {
            self.push_floor(total, t, &mut events)
        } else {
            self.push_drifting(total, t, &mut events)
        };

        let min_len = self.params.params().min_stance_frames;
        let k = self.online.sample_offset;
        // A copy of the sample frame is kept in case it cannot be decided now (stance not yet confirmed,
        // or a dropout frame); the candidate stance may still be a run that is not yet kept.
        let hold_for = match (&self.group, &self.run) {
            (Some(g), _) => {
                (!g.partial && !g.sample_done && g.start.checked_add(k) == Some(t)).then_some(g.id)
            }
            (None, Some(r)) => (r.start != self.detect_from && r.start.checked_add(k) == Some(t))
                .then_some(self.next_id),
            (None, None) => None,
        };
        if let Some(stance_id) = hold_for {
            events.push(SegEvent::HoldCurrent { stance_id });
        }
        if let Some(group) = &mut self.group {
            if !group.confirmed && group.end - group.start >= min_len && group.reached_on {
                group.confirmed = true;
                events.push(SegEvent::Touchdown(Touchdown {
                    stance_id: group.id,
                    touchdown_frame: group.start,
                    frame: t,
                    partial: group.partial,
                }));
            }
            if !group.partial {
                if let Some(sample) = group.start.checked_add(k)
                    && !group.sample_done
                    && group.confirmed
                    && sample < group.end
                {
                    group.sample_done = true;
                    events.push(SegEvent::ClassifySample {
                        stance_id: group.id,
                        touchdown_frame: group.start,
                        frame: sample,
                        held: t != sample,
                    });
                }
                if let Some(max_offset) = self.max_fusion_offset
                    && !group.fusion_done
                {
                    let offset = t - group.start;
                    if group.confirmed && loaded && self.online.fusion_offsets.contains(&offset) {
                        group.fused += 1;
                        events.push(SegEvent::FuseCurrent {
                            stance_id: group.id,
                        });
                    }
                    if offset >= max_offset {
                        group.fusion_done = true;
                        if group.fused > 0 {
                            events.push(SegEvent::FusionReady {
                                stance_id: group.id,
                                touchdown_frame: group.start,
                            });
                        }
                    }
                }
            }
        }

        // Quiet frames feed the baseline and noise estimate.
        if self.floor.is_none() && !loaded && self.run.is_none() && self.group.is_none() {
            self.add_quiet(total);
        }
        Ok(events)
    }

    /// The floor mode for frame `t` (see the module docs); whether the frame is in a contact.
    ///
    /// * **At rest** the floor is the current rest's mean moved along the slope pooled within the recent
    ///   rests. A frame more than `off` above it starts a candidate contact; `m` flat frames in a row
    ///   more than `off` below it start a new (lower) rest; otherwise it joins the rest.
    /// * **A candidate** becomes a contact (touchdown at its first frame) once it is
    ///   `min_stance_frames` long and has risen more than `on` above the floor. One that comes back
    ///   within `off` first was noise (the rest goes on, as offline); one that settles flat without
    ///   reaching `on` is a new rest.
    /// * **A contact** ends when a rest begins after its peak: the last `m = max(max_gap_frames + 1,`
    ///   [`MIN_REST_FRAMES`]`)` frames within `off` of their mean, which is more than `on` below the
    ///   peak. The rest (and the stance's end) starts at the first of the frames after the peak that
    ///   stay within `off` of that mean; the lift-off is reported at its `m`-th frame normally.
    fn push_floor(&mut self, total: f64, t: usize, events: &mut SegEvents) -> bool {
        let p = self.params.params();
        let (min_len, max_gap) = (p.min_stance_frames, p.max_gap_frames);
        let m = (max_gap + 1).max(MIN_REST_FRAMES);
        let prior = self.calibration.map_or(0.0, |c| c.load_range) * RANGE_PRIOR_FRACTION;
        let Some(floor) = self.floor.as_deref_mut() else {
            return false;
        };
        floor.recent[t % FLOOR_LOOKBACK] = total;
        floor.lowest = floor.lowest.min(total);
        floor.highest = floor.highest.max(total);
        let range = prior.max(floor.highest - floor.lowest);
        let noise = self.levels.noise;
        let on = (p.on_noise * noise).max(p.on_fraction * range);
        let off = (p.off_noise * noise).max(p.off_fraction * range);
        self.levels.load_range = range;
        self.levels.on_level = on;
        self.levels.off_level = off;

        if let Some(group) = &mut self.group {
            group.end = t + 1;
            if total > group.peak_load {
                group.peak_load = total;
                group.peak_frame = t;
            }
            let after_peak = t + 1 >= m && t + 1 - m > group.peak_frame;
            let rest = floor
                .flat(t, m, off)
                .filter(|&mean| group.peak_load - mean > on);
            if let (true, Some(mean)) = (after_peak, rest) {
                let mut first = t + 1 - m;
                while first > group.peak_frame + 1
                    && t + 1 - first < FLOOR_LOOKBACK
                    && (floor.recent[(first - 1) % FLOOR_LOOKBACK] - mean).abs() <= off
                {
                    first -= 1;
                }
                group.end = first;
                floor.start_rest(first, t);
                self.levels.baseline = floor.at(t).unwrap_or(mean);
                self.close_group(t, false, events);
                return false;
            }
            return true;
        }

        let Some(level) = floor.at(t) else {
            floor.start_rest(t, t);
            self.levels.baseline = total;
            return false;
        };
        self.levels.baseline = level;
        let rise = total - level;
        if let Some(run) = &mut self.run {
            if rise > off {
                run.reached_on |= rise > on;
                if total > run.peak_load {
                    run.peak_load = total;
                    run.peak_frame = t;
                }
                let run = *run;
                if t + 1 - run.start >= min_len && run.reached_on {
                    self.run = None;
                    self.open_group(run, t);
                    if let Some(group) = &mut self.group {
                        group.peak_load = run.peak_load;
                        group.peak_frame = run.peak_frame;
                    }
                    return true;
                }
                // A new level, flat, that never rose to `on`: the floor moved.
                if !run.reached_on
                    && t + 1 - run.start >= min_len + m
                    && floor.flat(t, m, off).is_some()
                {
                    self.run = None;
                    floor.start_rest(t + 1 - m, t);
                    return false;
                }
                return true;
            }
            // Back within `off` before it became a contact: noise, the rest goes on.
            self.run = None;
        }
        if rise < -off {
            // The floor fell (a lighter preload, or the end of a slow unloading) once `m` frames in a
            // row are below it and flat; one low frame is noise.
            floor.below += 1;
            if floor.below >= m && floor.flat(t, m, off).is_some() {
                floor.below = 0;
                floor.start_rest(t + 1 - m, t);
            }
            return false;
        }
        floor.below = 0;
        if rise > off {
            let run = Run {
                start: t,
                reached_on: rise > on,
                peak_load: total,
                peak_frame: t,
            };
            if min_len <= 1 && run.reached_on {
                self.open_group(run, t);
                if let Some(group) = &mut self.group {
                    group.peak_load = total;
                }
                return true;
            }
            self.run = Some(run);
            return true;
        } else {
            floor.rest.add(t, total);
        }
        false
    }

    /// The drifting (and fixed) baseline's runs, gaps and closing for frame `t`; whether it is loaded.
    fn push_drifting(&mut self, total: f64, t: usize, events: &mut SegEvents) -> bool {
        let above = total - self.levels.baseline;
        if above > self.max_above {
            self.max_above = above;
            self.update_levels();
        }
        let (off, on) = (self.levels.off_level, self.levels.on_level);
        let p = self.params.params();
        let (min_len, max_gap) = (p.min_stance_frames, p.max_gap_frames);
        let loaded = above > off && self.levels.load_range > 0.0;

        if loaded {
            let run = self.run.get_or_insert(Run {
                start: t,
                reached_on: false,
                peak_load: total,
                peak_frame: t,
            });
            run.reached_on |= above > on;
            if total > run.peak_load {
                run.peak_load = total;
                run.peak_frame = t;
            }
            let run = *run;
            if t + 1 - run.start >= min_len || run.reached_on {
                // The run is kept: it joins the open stance or starts one.
                match &mut self.group {
                    Some(group) if run.start <= group.end + max_gap => {
                        group.end = t + 1;
                        group.reached_on |= run.reached_on;
                    }
                    Some(_) => {
                        self.close_group(t, false, events);
                        self.open_group(run, t);
                    }
                    None => self.open_group(run, t),
                }
            }
        } else if let Some(run) = self.run.take() {
            // The run ended at t; fold its peak into its stance if it was kept.
            if let Some(group) = &mut self.group
                && group.end == t
                && run.start >= group.start
                && run.peak_load > group.peak_load
            {
                group.peak_load = run.peak_load;
                group.peak_frame = run.peak_frame;
            }
        }

        // Close the stance once no later run can join it.
        if let Some(group) = self.group {
            let pending = self
                .run
                .is_some_and(|run| run.start <= group.end + max_gap && run.start >= group.end);
            if t + 1 > group.end + max_gap && !pending {
                self.close_group(t, false, events);
            }
        }

        loaded
    }

    fn open_group(&mut self, run: Run, t: usize) {
        let id = self.next_id;
        self.next_id += 1;
        self.group = Some(Group {
            id,
            start: run.start,
            end: t + 1,
            reached_on: run.reached_on,
            peak_load: f64::NEG_INFINITY,
            peak_frame: run.start,
            confirmed: false,
            partial: run.start == self.detect_from,
            sample_done: false,
            fused: 0,
            fusion_done: false,
        });
    }

    /// Ends the open stance (if any): its fusion decision if due, then its lift-off if it was confirmed.
    fn close_group(&mut self, t: usize, at_end: bool, events: &mut SegEvents) {
        let Some(mut group) = self.group.take() else {
            return;
        };
        // The current run's peak counts if the run belongs to the stance (it ends at group.end).
        if let Some(run) = self.run
            && run.start >= group.start
            && run.start < group.end
            && run.peak_load > group.peak_load
        {
            group.peak_load = run.peak_load;
            group.peak_frame = run.peak_frame;
        }
        if at_end && group.end == self.t {
            group.partial = true;
        }
        if !group.confirmed {
            return;
        }
        if !group.fusion_done && group.fused > 0 && !group.partial {
            events.push(SegEvent::FusionReady {
                stance_id: group.id,
                touchdown_frame: group.start,
            });
        }
        events.push(SegEvent::Liftoff(Liftoff {
            stance_id: group.id,
            stance: Stance {
                start: group.start,
                len: group.end - group.start,
                peak_load: group.peak_load,
                peak_frame: group.peak_frame,
                partial: group.partial,
            },
            frame: t,
            sampled: group.sample_done,
        }));
    }

    /// [`BaselineMode::Contact`] (one sample per file): the stream is one contact from its first frame,
    /// as offline, partial at both ends but sampled all the same (that is what the mode is for). It is
    /// confirmed once it is `min_stance_frames` (and [`MIN_CONTACT_FRAMES`]) long with some load; its
    /// sample is frame `k` (held until the confirmation if it comes first); it ends with the stream
    /// ([`Self::finish`]). No fusion, no warm-up: there is no baseline to learn.
    fn push_contact(&mut self, total: f64) -> SegEvents {
        let mut events = SegEvents::EMPTY;
        let t = self.t;
        self.t += 1;
        let min_len = self
            .params
            .params()
            .min_stance_frames
            .max(MIN_CONTACT_FRAMES);
        let k = self.online.sample_offset;
        let group = self.group.get_or_insert(Group {
            id: 0,
            start: 0,
            end: 0,
            reached_on: false,
            peak_load: total,
            peak_frame: 0,
            confirmed: false,
            partial: true,
            sample_done: false,
            fused: 0,
            fusion_done: true,
        });
        self.next_id = 1;
        group.end = t + 1;
        if total > group.peak_load {
            group.peak_load = total;
            group.peak_frame = t;
        }
        // Some load: a reading above zero, as offline.
        group.reached_on = group.peak_load > 0.0;
        if t == k && !group.confirmed {
            events.push(SegEvent::HoldCurrent { stance_id: 0 });
        }
        if !group.confirmed && group.end >= min_len && group.reached_on {
            group.confirmed = true;
            events.push(SegEvent::Touchdown(Touchdown {
                stance_id: 0,
                touchdown_frame: 0,
                frame: t,
                partial: true,
            }));
        }
        if group.confirmed && !group.sample_done && k < group.end {
            group.sample_done = true;
            events.push(SegEvent::ClassifySample {
                stance_id: 0,
                touchdown_frame: 0,
                frame: k,
                held: t != k,
            });
        }
        events
    }

    /// The stream ended: closes the open stance (partial if it reached the last frame). While still
    /// warming up, calibrates on what was seen and judges it, offline, and reports its stances (so a
    /// short stream is not lost: a one-contact recording gives its one partial stance); they are not
    /// sampled (their frames have passed). At most `MAX_SEG_EVENTS / 2` of them are reported.
    pub fn finish(&mut self) -> Result<SegEvents> {
        let mut events = SegEvents::EMPTY;
        if self.calibration.is_none() && !self.contact {
            if self.warmup.is_empty() {
                return Ok(events);
            }
            let seen = self.warmup.len();
            let seg = self.finish_warmup()?;
            let last = seen.saturating_sub(1);
            for stance in seg.stances.iter().take(MAX_SEG_EVENTS / 2) {
                let stance_id = self.next_id;
                self.next_id += 1;
                events.push(SegEvent::Touchdown(Touchdown {
                    stance_id,
                    touchdown_frame: stance.start,
                    frame: last,
                    partial: stance.partial,
                }));
                events.push(SegEvent::Liftoff(Liftoff {
                    stance_id,
                    stance: *stance,
                    frame: last,
                    sampled: false,
                }));
            }
            self.run = None;
            return Ok(events);
        }
        let last = self.t.saturating_sub(1);
        self.close_group(last, true, &mut events);
        self.run = None;
        Ok(events)
    }

    /// The floor mode's state after a warm-up segmented (offline) with `seg`: the recent totals, the
    /// lowest and highest, the slope of each rest (the frames outside stances within the off level of
    /// the floor), the last rest as the current one, or the contact under way at its end as a partial
    /// stance.
    fn seed_floor(&mut self, warmup: &[f64], seg: &Segmentation) {
        let lowest = warmup.iter().copied().fold(f64::INFINITY, f64::min);
        let highest = warmup.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let mut floor = FloorState::new(Some((lowest, highest)));
        for (frame, &value) in warmup.iter().enumerate() {
            floor.recent[frame % FLOOR_LOOKBACK] = value;
        }
        let off = seg.off_level;
        let mut rest = LineSums::default();
        for (frame, &value) in warmup.iter().enumerate() {
            if seg.stances.iter().any(|s| s.contains(frame)) {
                if rest.n > 0.0 {
                    floor.rest = rest;
                    floor.close_rest();
                    rest = LineSums::default();
                }
                continue;
            }
            let base = seg.baseline.get(frame).copied().unwrap_or(value);
            if (value - base).abs() <= off {
                rest.add(frame, value);
            }
        }
        floor.rest = rest;
        let n = warmup.len();
        match seg.stances.last() {
            Some(last) if last.end() == n => {
                let (peak_load, peak_frame) = (last.peak_load, self.t);
                self.group = Some(Group {
                    id: self.next_id,
                    start: self.t,
                    end: self.t,
                    reached_on: true,
                    peak_load,
                    peak_frame,
                    confirmed: false,
                    partial: true,
                    sample_done: false,
                    fused: 0,
                    fusion_done: false,
                });
                self.next_id += 1;
            }
            _ if floor.rest.n == 0.0 && n > 0 => floor.start_rest(n - 1, n - 1),
            _ => {}
        }
        self.levels.baseline = floor
            .at(n.saturating_sub(1))
            .unwrap_or(self.levels.baseline);
        self.floor = Some(Box::new(floor));
    }

    /// Calibrates on the warm-up totals with the offline segmentation; detection starts at the next frame.
    fn finish_warmup(&mut self) -> Result<Segmentation> {
        let seg = segment(&self.warmup, &self.params)?;
        let mut base = seg.baseline.clone();
        let baseline = median(&mut base);
        let cal = Calibration {
            baseline,
            noise: seg.noise,
            load_range: seg.load_range,
        };
        // Seed the quiet ring with the warm-up frames outside stances.
        let warmup = std::mem::take(&mut self.warmup);
        self.apply_calibration(cal);
        // The warm-up is this stream's own past: its largest load is the running maximum so far.
        self.max_above = seg.load_range;
        self.update_levels();
        self.detect_from = self.t;
        let mode = self.params.params().baseline;
        if mode == BaselineMode::Floor
            || mode == BaselineMode::Auto && seg.mode == BaselineMode::Floor
        {
            self.seed_floor(&warmup, &seg);
            return Ok(seg);
        }
        for (frame, &value) in warmup.iter().enumerate() {
            let in_stance = seg.stances.iter().any(|s| s.contains(frame));
            if !in_stance && value - self.levels.baseline <= self.levels.off_level {
                self.add_quiet(value);
            }
        }
        // A stance still under way at the end of the warm-up continues as a partial one.
        if let Some(last) = seg.stances.last()
            && last.end() == warmup.len()
        {
            self.run = Some(Run {
                start: self.t,
                reached_on: true,
                peak_load: f64::NEG_INFINITY,
                peak_frame: self.t,
            });
        }
        Ok(seg)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offset_from_typical_length() {
        assert_eq!(sample_offset_for(&[14, 14, 13, 15, 14]), 6);
        assert_eq!(sample_offset_for(&[17, 16, 16]), 7);
        assert_eq!(sample_offset_for(&[]), PAPER_SAMPLE_OFFSET);
    }
}
