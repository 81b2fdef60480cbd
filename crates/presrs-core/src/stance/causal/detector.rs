//! The causal stance detector itself ([`CausalSegmenter`]): its state and one step per frame, in each
//! mode (drifting baseline, floor, one contact), the warm-up included.

use super::events::{Liftoff, MAX_SEG_EVENTS, SegEvent, SegEvents, Touchdown};
use super::floor::{FLOOR_LOOKBACK, FloorState, LineSums, MIN_REST_FRAMES};
use super::settings::{Calibration, MIN_QUIET_FRAMES, OnlineParams, RANGE_PRIOR_FRACTION};
use crate::error::{CoreError, Result};
use crate::stance::modes::{MIN_CONTACT_FRAMES, segment};
use crate::stance::offline::{BaselineMode, Segmentation, Stance, ValidSegmentParams};
use crate::stance::robust::{MAD_TO_SIGMA, median};

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

/// A confirmed stance still under way ([`CausalSegmenter::open_stance`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct OpenStance {
    pub stance_id: u64,
    /// First loaded frame (its touchdown).
    pub start: usize,
    /// Frames from `start` certain to be in the stance, whatever the frames still to come: its length
    /// at lift-off is at least this.
    pub known_len: usize,
    pub partial: bool,
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

/// The causal stance detector (see the [`causal`](crate::stance::causal) module docs). One [`push`](Self::push) per frame, O(1) amortised,
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

    /// The confirmed stance under way (between its touchdown and its lift-off events), if any.
    pub fn open_stance(&self) -> Option<OpenStance> {
        let group = self.group.filter(|group| group.confirmed)?;
        // The frames certain to be in the stance whatever comes next: in the floor mode the end is
        // found by looking back from the rest after the peak (at most FLOOR_LOOKBACK frames), so
        // only the frames up to the peak, and those further back than that, are certain.
        let known_end = if self.floor.is_some() {
            (group.peak_frame + 1)
                .max(self.t.saturating_sub(FLOOR_LOOKBACK))
                .min(group.end)
        } else {
            group.end
        };
        Some(OpenStance {
            stance_id: group.id,
            start: group.start,
            known_len: known_end.saturating_sub(group.start),
            partial: group.partial,
        })
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
        if let Some(stance_id) = self.stance_to_hold_for(t) {
            events.push(SegEvent::HoldCurrent { stance_id });
        }
        self.stance_requests(t, loaded, &mut events);

        // Quiet frames feed the baseline and noise estimate.
        if self.floor.is_none() && !loaded && self.run.is_none() && self.group.is_none() {
            self.add_quiet(total);
        }
        Ok(events)
    }

    /// The stance whose sample frame is frame `t`, if any: a copy of it is kept in case it cannot be
    /// decided now (stance not yet confirmed, or a dropout frame); the candidate stance may still be a
    /// run that is not yet kept.
    fn stance_to_hold_for(&self, t: usize) -> Option<u64> {
        let k = self.online.sample_offset;
        match (&self.group, &self.run) {
            (Some(g), _) => {
                (!g.partial && !g.sample_done && g.start.checked_add(k) == Some(t)).then_some(g.id)
            }
            (None, Some(r)) => (r.start != self.detect_from && r.start.checked_add(k) == Some(t))
                .then_some(self.next_id),
            (None, None) => None,
        }
    }

    /// The open stance's requests at frame `t` (`loaded`: the frame is in it): its touchdown once it is
    /// confirmed, then, unless it is partial, its sample once decidable, its fusion frames, and its fusion
    /// decision after the last fusion offset.
    fn stance_requests(&mut self, t: usize, loaded: bool, events: &mut SegEvents) {
        let min_len = self.params.params().min_stance_frames;
        let k = self.online.sample_offset;
        let Some(group) = &mut self.group else {
            return;
        };
        if !group.confirmed && group.end - group.start >= min_len && group.reached_on {
            group.confirmed = true;
            events.push(SegEvent::Touchdown(Touchdown {
                stance_id: group.id,
                touchdown_frame: group.start,
                frame: t,
                partial: group.partial,
            }));
        }
        if group.partial {
            return;
        }
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
        let m = (p.max_gap_frames + 1).max(MIN_REST_FRAMES);
        let Some(levels) = self.floor_levels(total, t) else {
            return false;
        };
        if self.group.is_some() {
            return self.floor_contact(total, t, levels, m, events);
        }
        let Some(floor) = self.floor.as_deref_mut() else {
            return false;
        };
        let Some(level) = floor.at(t) else {
            floor.start_rest(t, t);
            self.levels.baseline = total;
            return false;
        };
        self.levels.baseline = level;
        let rise = total - level;
        if let Some(in_candidate) = self.floor_candidate(total, t, rise, levels, m) {
            return in_candidate;
        }
        self.floor_rest(total, t, rise, levels, m)
    }

    /// Keeps frame `t`'s `total` in the floor state and sets the levels from the stream's load range
    /// (highest minus lowest total, at least the calibrated prior); `(on, off)`, `None` outside the
    /// floor mode.
    fn floor_levels(&mut self, total: f64, t: usize) -> Option<(f64, f64)> {
        let p = self.params.params();
        let prior = self.calibration.map_or(0.0, |c| c.load_range) * RANGE_PRIOR_FRACTION;
        let floor = self.floor.as_deref_mut()?;
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
        Some((on, off))
    }

    /// Frame `t` of the open contact in the floor mode: the contact ends (and a rest starts) once the
    /// last `m` frames, after its peak, lie within `off` of their mean, more than `on` below the peak;
    /// whether the frame is still in the contact.
    fn floor_contact(
        &mut self,
        total: f64,
        t: usize,
        (on, off): (f64, f64),
        m: usize,
        events: &mut SegEvents,
    ) -> bool {
        let (Some(floor), Some(group)) = (self.floor.as_deref_mut(), &mut self.group) else {
            return false;
        };
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
        true
    }

    /// The candidate contact (a run above the floor) at frame `t`, `rise` above the floor: it becomes a
    /// contact once `min_stance_frames` long and above `on`, or a new rest once it settles flat without
    /// reaching `on`. `Some(whether the frame is in a contact or candidate)`; `None` without a
    /// candidate, or when it came back within `off` (noise: the rest goes on).
    fn floor_candidate(
        &mut self,
        total: f64,
        t: usize,
        rise: f64,
        (on, off): (f64, f64),
        m: usize,
    ) -> Option<bool> {
        let min_len = self.params.params().min_stance_frames;
        let run = self.run.as_mut()?;
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
                return Some(true);
            }
            // A new level, flat, that never rose to `on`: the floor moved.
            if !run.reached_on
                && t + 1 - run.start >= min_len + m
                && let Some(floor) = self.floor.as_deref_mut()
                && floor.flat(t, m, off).is_some()
            {
                self.run = None;
                floor.start_rest(t + 1 - m, t);
                return Some(false);
            }
            return Some(true);
        }
        // Back within `off` before it became a contact: noise, the rest goes on.
        self.run = None;
        None
    }

    /// Frame `t` at rest in the floor mode, `rise` above the floor: it starts a candidate (or, for
    /// one-frame stances, a contact) if more than `off` above the floor, a new, lower rest once `m`
    /// frames in a row lie flat more than `off` below it, and joins the rest otherwise; whether it
    /// starts a candidate.
    fn floor_rest(
        &mut self,
        total: f64,
        t: usize,
        rise: f64,
        (on, off): (f64, f64),
        m: usize,
    ) -> bool {
        let min_len = self.params.params().min_stance_frames;
        let Some(floor) = self.floor.as_deref_mut() else {
            return false;
        };
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
        }
        floor.rest.add(t, total);
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
