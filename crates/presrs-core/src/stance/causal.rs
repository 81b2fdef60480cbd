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
//! * **Not done online:** the floor mode (presses on a preload). The causal detector measures from the
//!   baseline only; a profile with `baseline: floor` calibrates its levels from the floor segmentation
//!   of its warm-up but then judges frames against one baseline.
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
        };
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
                        self.close_group(t, false, &mut events);
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
                self.close_group(t, false, &mut events);
            }
        }

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
        if !loaded && self.run.is_none() && self.group.is_none() {
            self.add_quiet(total);
        }
        Ok(events)
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
