//! Online (causal) stance detection and classification of a live frame stream.
//!
//! [`crate::stance::segment`] sees a whole recording; a robot has to decide while its foot is still on
//! the ground. [`CausalSegmenter`] takes one total load at a time and decides without looking ahead,
//! with the offline method's rules (see [`crate::stance`]):
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
//!   ([`CausalSegmenter::finish`]) is partial if it reached the last frame, as offline.
//!
//! **The sample frame** is chosen without the future: the `k`-th frame after touchdown
//! ([`OnlineParams::sample_offset`]). The paper samples the mid-stance frame `(len - 1) / 2`, which
//! depends on the lift-off still to come; [`sample_offset_for`] learns `k = (L - 1) / 2` from the
//! training data's median stance length `L`, so that on a typical stance the online sample *is* the
//! paper's (offline) mid-stance frame. If frame `k` is not decidable when it arrives (the stance is not
//! yet confirmed, or frame `k` is a dropout inside the stance) the classifier keeps a copy of it and
//! decides as soon as it is; if the stance ends before frame `k`, it is not sampled.
//!
//! **Fusion** ([`OnlineParams::fusion_offsets`], optional): the loaded frames at these offsets after
//! touchdown are classified as they arrive and their posteriors averaged; the fused decision is a
//! separate event, emitted once the last offset has passed (or at lift-off, over the frames seen).
//!
//! [`OnlineClassifier`] puts the segmenter and a [`Session`] together: one frame in, zero or more
//! [`OnlineEvent`]s out, with all buffers allocated up front (no allocation per frame in steady state).

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::error::{CoreError, Result};
use crate::frame::{FrameView, Grid};
use crate::pipeline::{Session, TrainedModel};
use crate::stance::{Segmentation, Stance, ValidSegmentParams, segment};

/// Scale factor turning a median absolute deviation into a standard deviation for Gaussian noise.
const MAD_TO_SIGMA: f64 = 1.482_602_218_505_602;
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

/// Settings of the online detector and classifier beyond the offline [`crate::stance::SegmentParams`].
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

/// What a model needs to run online: the detector settings, its calibration and the terrain-to-gait
/// table. Stored next to a model (in the model file or a JSON file of its own).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct OnlineProfile {
    pub params: OnlineParams,
    /// Median stance length of the data `params.sample_offset` was learned from, frames.
    pub typical_stance_frames: Option<usize>,
    pub calibration: Option<Calibration>,
    /// Terrain label -> recommended gait name.
    pub gait_table: BTreeMap<String, String>,
}

impl OnlineProfile {
    /// A profile learned from offline segmentations of training recordings: calibration (medians) and `k`
    /// from the median length of their complete stances.
    pub fn learn(segmentations: &[Segmentation]) -> Self {
        let lengths: Vec<usize> = segmentations
            .iter()
            .flat_map(|seg| seg.complete().map(|stance| stance.len))
            .collect();
        Self {
            params: OnlineParams {
                sample_offset: sample_offset_for(&lengths),
                ..OnlineParams::default()
            },
            typical_stance_frames: typical_stance_frames(&lengths),
            calibration: Calibration::from_segmentations(segmentations),
            gait_table: BTreeMap::new(),
        }
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
    /// The stance, as [`crate::stance::segment`] reports it.
    pub stance: Stance,
    /// Frame at which the end was decided (`max_gap_frames + 1` frames after the last loaded frame, or
    /// the last frame of the stream).
    pub frame: usize,
    /// Whether the stance got its (single-frame) decision. From [`CausalSegmenter`], whether it asked
    /// for one; from [`OnlineClassifier`], whether a decision was made (false when the sample frame
    /// could not be classified, see [`OnlineEvent::Failed`]).
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
const MAX_SEG_EVENTS: usize = 8;

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

    /// The stream ended: closes the open stance (partial if it reached the last frame). While still
    /// warming up, calibrates on what was seen and judges it (so a short stream is not lost).
    pub fn finish(&mut self) -> Result<SegEvents> {
        let mut events = SegEvents::EMPTY;
        if self.calibration.is_none() {
            if self.warmup.is_empty() {
                return Ok(events);
            }
            self.finish_warmup()?;
        }
        let last = self.t.saturating_sub(1);
        self.close_group(last, true, &mut events);
        self.run = None;
        Ok(events)
    }

    /// Calibrates on the warm-up totals with the offline segmentation; detection starts at the next frame.
    fn finish_warmup(&mut self) -> Result<()> {
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
        Ok(())
    }
}

/// Median of `values` (reordered); 0 for none.
fn median(values: &mut [f64]) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    let mid = values.len() / 2;
    let (_, upper, _) = values.select_nth_unstable_by(mid, f64::total_cmp);
    let upper = *upper;
    if values.len() % 2 == 1 {
        upper
    } else {
        let lower = values[..mid]
            .iter()
            .copied()
            .fold(f64::NEG_INFINITY, f64::max);
        0.5 * (lower + upper)
    }
}

/// Whether a decision is the single sample frame or the fusion of several.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DecisionKind {
    Single,
    Fused,
}

/// A classification of a stance. The posteriors are in [`Step::posteriors`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Decision {
    pub stance_id: u64,
    pub kind: DecisionKind,
    pub touchdown_frame: usize,
    /// The frame classified (single), or the last frame fused.
    pub sample_frame: usize,
    /// Frame whose arrival triggered the decision.
    pub frame: usize,
    /// Frames whose posteriors were averaged (1 for single).
    pub frames_used: usize,
    pub class: usize,
    pub confidence: f64,
    /// Index of this decision's posteriors in the step's posterior buffer.
    slot: usize,
}

/// A frame the classifier was asked for but could not classify (e.g. its values are so large that its
/// features overflow). The reason is in [`Step::error`]; the stance goes on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Failure {
    pub stance_id: u64,
    /// The decision the frame was for: the single sample (which the stance then does not get), or one
    /// frame of the fusion (which goes on without it).
    pub kind: DecisionKind,
    /// The frame that could not be classified.
    pub sample_frame: usize,
    /// Frame whose arrival triggered the attempt.
    pub frame: usize,
    /// Index of the error in the step's error buffer.
    slot: usize,
}

/// One output of [`OnlineClassifier::push`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum OnlineEvent {
    Touchdown(Touchdown),
    Decision(Decision),
    /// A frame to classify could not be: no decision from it (see [`Failure`]).
    Failed(Failure),
    Liftoff(Liftoff),
}

/// The events of one frame, borrowing the classifier's buffers.
#[derive(Clone, Copy, Debug)]
pub struct Step<'a> {
    pub events: &'a [OnlineEvent],
    posteriors: &'a [f64],
    errors: &'a [CoreError],
    n_classes: usize,
}

impl<'a> Step<'a> {
    /// The posteriors of `decision` (one per class, class-index order).
    pub fn posteriors(&self, decision: &Decision) -> &'a [f64] {
        let start = decision.slot * self.n_classes;
        self.posteriors
            .get(start..start + self.n_classes)
            .unwrap_or(&[])
    }

    /// Why the frame of `failure` could not be classified.
    pub fn error(&self, failure: &Failure) -> Option<&'a CoreError> {
        self.errors.get(failure.slot)
    }
}

/// Counters of an [`OnlineClassifier`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct OnlineStats {
    pub frames: u64,
    pub stances: u64,
    pub decisions: u64,
    pub fused_decisions: u64,
    /// Frames refused (wrong grid, non-finite values).
    pub rejected_frames: u64,
}

/// Causal segmentation + classification of a frame stream with one model (see the module docs).
#[derive(Debug)]
pub struct OnlineClassifier<'m> {
    session: Session<'m>,
    segmenter: CausalSegmenter,
    grid: Option<Grid>,
    held: Vec<f64>,
    held_present: Vec<bool>,
    held_has_mask: bool,
    held_valid: bool,
    fusion_sum: Vec<f64>,
    fusion_frames: usize,
    fusion_last: usize,
    /// The current frame's classification, once made in this push (the sample frame is usually also a
    /// fusion frame: it is classified once, not twice); `Err` holds the index of its error in `errors`.
    current: Option<std::result::Result<(usize, f64), usize>>,
    current_posteriors: Vec<f64>,
    /// The last stance that got its single decision (for [`Liftoff::sampled`]).
    decided_stance: Option<u64>,
    n_classes: usize,
    events: Vec<OnlineEvent>,
    posteriors: Vec<f64>,
    /// Why the frames of this step's [`Failure`]s could not be classified (empty unless one failed).
    errors: Vec<CoreError>,
    stats: OnlineStats,
}

impl<'m> OnlineClassifier<'m> {
    pub fn new(
        model: &'m TrainedModel,
        params: &ValidSegmentParams,
        online: &OnlineParams,
        calibration: Option<Calibration>,
    ) -> Result<Self> {
        let n_classes = model.class_names().len();
        Ok(Self {
            session: model.session(),
            segmenter: CausalSegmenter::new(params, online, calibration)?,
            grid: None,
            held: Vec::new(),
            held_present: Vec::new(),
            held_has_mask: false,
            held_valid: false,
            fusion_sum: vec![0.0; n_classes],
            fusion_frames: 0,
            fusion_last: 0,
            current: None,
            current_posteriors: vec![0.0; n_classes],
            decided_stance: None,
            n_classes,
            events: Vec::with_capacity(MAX_SEG_EVENTS),
            posteriors: Vec::with_capacity(MAX_SEG_EVENTS * n_classes),
            errors: Vec::new(),
            stats: OnlineStats::default(),
        })
    }

    pub fn segmenter(&self) -> &CausalSegmenter {
        &self.segmenter
    }

    pub fn model(&self) -> &'m TrainedModel {
        self.session.model()
    }

    pub fn stats(&self) -> OnlineStats {
        self.stats
    }

    /// The grid every frame must have (set by the first frame).
    pub fn grid(&self) -> Option<Grid> {
        self.grid
    }

    /// Judges the next frame. A frame of another grid than the first one, a first frame whose grid the
    /// model cannot classify (its crop does not give the model's image), or a frame with a non-finite
    /// total load is an error and is not counted; the stream can go on. A counted frame whose
    /// classification fails (its values overflow the features) still gives its touchdown and lift-off
    /// events, with an [`OnlineEvent::Failed`] in place of the decision.
    pub fn push(&mut self, frame: &FrameView<'_>) -> Result<Step<'_>> {
        self.events.clear();
        self.posteriors.clear();
        self.errors.clear();
        let grid = frame.grid();
        match self.grid {
            None => {
                let model = self.session.model();
                if model.crop().output_grid(grid).ok() != Some(model.image_grid()) {
                    self.stats.rejected_frames += 1;
                    return Err(CoreError::Shape {
                        what: "stream frame",
                        expected: format!(
                            "a grid that the model's crop {} turns into its {} image",
                            model.crop(),
                            model.image_grid()
                        ),
                        got: grid.to_string(),
                    });
                }
                self.grid = Some(grid);
                self.held = vec![0.0; grid.len()];
                self.held_present = vec![true; grid.len()];
            }
            Some(expected) if expected != grid => {
                self.stats.rejected_frames += 1;
                return Err(CoreError::Shape {
                    what: "stream frame",
                    expected: format!("a {expected} frame (the stream's first frame)"),
                    got: grid.to_string(),
                });
            }
            Some(_) => {}
        }
        let total = frame.total();
        let seg_events = match self.segmenter.push(total) {
            Ok(events) => events,
            Err(err) => {
                self.stats.rejected_frames += 1;
                return Err(err);
            }
        };
        self.stats.frames += 1;
        let t = self.segmenter.frames_seen() - 1;
        self.handle(seg_events, Some(frame), t);
        Ok(self.step())
    }

    /// The stream ended: closes the open stance.
    pub fn finish(&mut self) -> Result<Step<'_>> {
        self.events.clear();
        self.posteriors.clear();
        self.errors.clear();
        let seg_events = self.segmenter.finish()?;
        let t = self.segmenter.frames_seen().saturating_sub(1);
        self.handle(seg_events, None, t);
        Ok(self.step())
    }

    fn step(&self) -> Step<'_> {
        Step {
            events: &self.events,
            posteriors: &self.posteriors,
            errors: &self.errors,
            n_classes: self.n_classes,
        }
    }

    /// Keeps `err` for this step; its index in the error buffer.
    fn keep_error(&mut self, err: CoreError) -> usize {
        self.errors.push(err);
        self.errors.len() - 1
    }

    /// Classifies the current frame once per push; later requests reuse the result (or the failure:
    /// the index of its error).
    fn classify_current(
        &mut self,
        frame: &FrameView<'_>,
    ) -> std::result::Result<(usize, f64), usize> {
        if let Some(result) = self.current {
            return result;
        }
        let result = match self.session.classify(frame) {
            Ok(prediction) => {
                self.current_posteriors
                    .copy_from_slice(prediction.posteriors);
                Ok((prediction.class, prediction.confidence))
            }
            Err(err) => Err(self.keep_error(err)),
        };
        self.current = Some(result);
        result
    }

    /// Classifies the held copy of the sample frame (once: the copy is then released).
    fn classify_held(
        &mut self,
        stance_id: u64,
        sample_frame: usize,
    ) -> std::result::Result<(usize, f64), usize> {
        if !self.held_valid {
            return Err(self.keep_error(CoreError::NotEnoughData(format!(
                "stance {stance_id}: no copy of its sample frame {sample_frame} was kept"
            ))));
        }
        self.held_valid = false;
        let mask = self.held_has_mask.then_some(self.held_present.as_slice());
        let grid = self.grid.unwrap_or(Grid::new(0, 0));
        let outcome = FrameView::new(grid, &self.held, mask).and_then(|view| {
            self.session.classify(&view).map(|prediction| {
                self.posteriors.extend_from_slice(prediction.posteriors);
                (prediction.class, prediction.confidence)
            })
        });
        outcome.map_err(|err| self.keep_error(err))
    }

    /// Turns the segmenter's requests for one frame into events. Never fails: a frame that cannot be
    /// classified gives an [`OnlineEvent::Failed`], and the other events of the frame are kept.
    fn handle(&mut self, events: SegEvents, frame: Option<&FrameView<'_>>, t: usize) {
        self.current = None;
        for event in events.iter() {
            match event {
                SegEvent::Touchdown(touchdown) => {
                    self.stats.stances += 1;
                    self.fusion_sum.fill(0.0);
                    self.fusion_frames = 0;
                    self.events.push(OnlineEvent::Touchdown(touchdown));
                }
                SegEvent::HoldCurrent { .. } => {
                    if let Some(frame) = frame {
                        self.held.copy_from_slice(frame.values());
                        self.held_has_mask = frame.present().is_some();
                        if let Some(mask) = frame.present() {
                            self.held_present.copy_from_slice(mask);
                        }
                        self.held_valid = true;
                    }
                }
                SegEvent::ClassifySample {
                    stance_id,
                    touchdown_frame,
                    frame: sample_frame,
                    held,
                } => {
                    let outcome = if held {
                        self.classify_held(stance_id, sample_frame)
                    } else {
                        let Some(frame) = frame else {
                            continue;
                        };
                        let outcome = self.classify_current(frame);
                        if outcome.is_ok() {
                            self.posteriors.extend_from_slice(&self.current_posteriors);
                        }
                        outcome
                    };
                    let (class, confidence) = match outcome {
                        Ok(result) => result,
                        Err(slot) => {
                            self.events.push(OnlineEvent::Failed(Failure {
                                stance_id,
                                kind: DecisionKind::Single,
                                sample_frame,
                                frame: t,
                                slot,
                            }));
                            continue;
                        }
                    };
                    let slot = (self.posteriors.len() / self.n_classes.max(1)).saturating_sub(1);
                    let decision = Decision {
                        stance_id,
                        kind: DecisionKind::Single,
                        touchdown_frame,
                        sample_frame,
                        frame: t,
                        frames_used: 1,
                        class,
                        confidence,
                        slot,
                    };
                    self.stats.decisions += 1;
                    self.decided_stance = Some(stance_id);
                    self.events.push(OnlineEvent::Decision(decision));
                }
                SegEvent::FuseCurrent { stance_id } => {
                    if let Some(frame) = frame {
                        match self.classify_current(frame) {
                            Ok(_) => {
                                for (sum, p) in
                                    self.fusion_sum.iter_mut().zip(&self.current_posteriors)
                                {
                                    *sum += p;
                                }
                                self.fusion_frames += 1;
                                self.fusion_last = t;
                            }
                            Err(slot) => self.events.push(OnlineEvent::Failed(Failure {
                                stance_id,
                                kind: DecisionKind::Fused,
                                sample_frame: t,
                                frame: t,
                                slot,
                            })),
                        }
                    }
                }
                SegEvent::FusionReady {
                    stance_id,
                    touchdown_frame,
                } => {
                    if self.fusion_frames == 0 {
                        continue;
                    }
                    let slot = self.posteriors.len() / self.n_classes.max(1);
                    let count = self.fusion_frames as f64;
                    let start = self.posteriors.len();
                    self.posteriors
                        .extend(self.fusion_sum.iter().map(|sum| sum / count));
                    let fused = &self.posteriors[start..];
                    let (class, confidence) = fused.iter().copied().enumerate().fold(
                        (0, f64::NEG_INFINITY),
                        |best, (class, p)| {
                            if p > best.1 { (class, p) } else { best }
                        },
                    );
                    self.events.push(OnlineEvent::Decision(Decision {
                        stance_id,
                        kind: DecisionKind::Fused,
                        touchdown_frame,
                        sample_frame: self.fusion_last,
                        frame: t,
                        frames_used: self.fusion_frames,
                        class,
                        confidence,
                        slot,
                    }));
                    self.stats.fused_decisions += 1;
                    self.fusion_sum.fill(0.0);
                    self.fusion_frames = 0;
                }
                SegEvent::Liftoff(mut liftoff) => {
                    self.held_valid = false;
                    liftoff.sampled &= self.decided_stance == Some(liftoff.stance_id);
                    self.events.push(OnlineEvent::Liftoff(liftoff));
                }
            }
        }
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

    #[test]
    fn median_of_even_and_odd() {
        assert_eq!(median(&mut [3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&mut [4.0, 1.0, 3.0, 2.0]), 2.5);
        assert_eq!(median(&mut []), 0.0);
    }
}
