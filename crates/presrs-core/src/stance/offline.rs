//! Stance segmentation: finding the stance phases of a recording from its total load per frame.
//!
//! The paper classifies one pressure image per stance: the 7th of the ~14 frames a hopper stance lasts at
//! 100 Hz, i.e. the mid-stance frame `(len - 1) / 2` frames after touchdown. To pick that frame from a movie
//! we need touchdown and lift-off, which we read off the total load per frame:
//!
//! 1. **Baseline and noise.** Real sensors do not read zero in flight/swing, and their zero drifts over a
//!    long recording (temperature, creep). The recording is cut into blocks of about
//!    [`SegmentParams::baseline_window_frames`] frames; a low quantile of each block is a first baseline
//!    (robust as long as every block has a few unloaded frames, which holds when the window spans a few
//!    strides), interpolated linearly between block centres so that a linear drift is followed exactly. The
//!    unloaded frames are then found by sigma clipping the residuals (grown upwards from the low tail of
//!    the recording and of every block, then one pass of median +- 4 x 1.4826 x MAD), refitting the
//!    baseline to them as the set changes: their median corrects each block's level (a recording shorter
//!    than ~1.5 windows gets a least-squares line instead) and their MAD is the noise. Drift is followed at the time scale of the window: within one
//!    window it should stay small against the off level. Cost: O(n) per clipping round.
//! 2. **Hysteresis.** A frame is *loaded* when its load above the baseline exceeds the *off* level and a
//!    stance must reach the higher *on* level somewhere. Each level is the larger of a multiple of the
//!    baseline noise (so that noise does not make stances) and a fraction of the recording's load range
//!    above the baseline (so that a noiseless sensor, which reads exactly zero in swing, still needs real
//!    load). Stance boundaries therefore come from the low level (touchdown is the first frame with real
//!    load, not the first *heavily* loaded one) while detection is decided by the high one.
//! 3. **Clean-up.** Runs that are both shorter than the minimum stance and never reach the on level are
//!    noise and dropped. The remaining loaded runs separated by at most [`SegmentParams::max_gap_frames`]
//!    unloaded frames are merged (a sensor dropout of a frame or two inside a stance), then runs shorter than
//!    [`SegmentParams::min_stance_frames`] are dropped (a knock or spike is not a stance).
//! 4. **Partial stances.** A stance that starts at the first frame or ends at the last one was cut by the
//!    recording; its touchdown (and therefore its mid-stance frame) is unknown. It is reported with
//!    `partial: true` and skipped by [`Segmentation::samples`] unless asked for.
//!
//! Non-finite loads (NaN, infinity) are rejected with an error rather than guessed at: a NaN total means
//! a broken frame upstream, and silently treating it as "no load" could split a stance.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use super::baseline::estimate_baseline;
use crate::error::{CoreError, Result};

/// Settings of [`segment`](super::segment()), as written by a user (unchecked). Turn them into [`ValidSegmentParams`] with
/// [`SegmentParams::check`] once; the segmentation functions only accept the checked type.
///
/// The defaults work for both the paper's hopper (100 Hz, ~14-frame stances, ~20-frame flights) and
/// overground walking sampled at ~31 Hz (~23-frame stances, ~12-frame swings).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SegmentParams {
    /// A stance must somewhere exceed this fraction of the load range above baseline (default 0.10).
    pub on_fraction: f64,
    /// A frame belongs to a stance while its load exceeds this fraction of the load range above baseline
    /// (default 0.01). Low, so that touchdown is the first frame with real load: on a real walking file
    /// 1% puts the boundaries on the first/last non-zero frames of each stance.
    pub off_fraction: f64,
    /// A stance must somewhere exceed this many baseline noise sigmas (default 8: pure noise never does).
    pub on_noise: f64,
    /// A frame belongs to a stance while its load exceeds this many baseline noise sigmas (default 4: a
    /// swing frame does so with probability ~3e-5, so noise rarely lengthens a stance).
    pub off_noise: f64,
    /// Shortest stance kept, in frames (default 3). In frames rather than seconds because the frame period
    /// is not always known; 3 rejects one- and two-frame spikes while keeping the stances of any gait we
    /// know of (14 frames for the hopper at 100 Hz, ~23 for walking at 31 Hz, and still ~4 for a hopper
    /// sampled as slowly as 30 Hz). Applies to partial stances too (a 2-frame tail is not worth reporting).
    pub min_stance_frames: usize,
    /// Loaded runs separated by at most this many unloaded frames are one stance (default 2; 0 disables).
    /// Flights and swings last far longer than two frames at any rate we use.
    pub max_gap_frames: usize,
    /// Length of the blocks the baseline is estimated on, in frames (default 128, at least 4). It must span
    /// a few strides so that every block holds unloaded frames (128 frames is ~4 hopper strides at 100 Hz,
    /// ~3.5 walking strides at 31 Hz), and be short against the time scale of the baseline's drift.
    /// A stance longer than about `(1 - baseline_quantile)` of a window (standing still) is taken for
    /// baseline.
    pub baseline_window_frames: usize,
    /// The quantile of a block's loads used as its first baseline guess (default 0.10, in (0, 0.5]).
    /// Tolerates stance duty factors up to ~85%.
    pub baseline_quantile: f64,
    /// What the stances rise above (default [`BaselineMode::Auto`]: chosen from the data, see
    /// [`segment`](super::segment())).
    pub baseline: BaselineMode,
    /// Longest stance, in frames (default none). A longer one is dropped in the drifting mode, and with
    /// [`BaselineMode::Auto`] is taken as a sign of a standing preload (the floor mode is tried).
    pub max_stance_frames: Option<usize>,
}

/// What a stance's load is measured from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BaselineMode {
    /// Chosen from the data: one contact if the recording never unloads, the floor if a contact holds
    /// several presses over a standing preload, the drifting baseline otherwise.
    #[default]
    Auto,
    /// The unloaded level between stances, a baseline that may be non-zero and drift slowly (the
    /// method of the module docs; right when the foot fully unloads between contacts).
    Drifting,
    /// The local floor: contacts are rises above the lowest load around them (prominence, then
    /// hysteresis relative to that floor), for presses or steps on a standing preload.
    Floor,
    /// The whole recording is one contact, loaded from its first frame to its last (a trial cut to one
    /// foot contact): one stance, partial at both ends.
    Contact,
}

impl FromStr for BaselineMode {
    type Err = CoreError;

    fn from_str(text: &str) -> Result<Self> {
        match text.trim().to_ascii_lowercase().as_str() {
            "auto" => Ok(Self::Auto),
            "drifting" => Ok(Self::Drifting),
            "floor" => Ok(Self::Floor),
            "contact" | "one-contact" => Ok(Self::Contact),
            _ => Err(CoreError::Param {
                name: "baseline mode",
                reason: format!("expected auto, drifting, floor or contact, got {text:?}"),
            }),
        }
    }
}

impl fmt::Display for BaselineMode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Auto => "auto",
            Self::Drifting => "drifting",
            Self::Floor => "floor",
            Self::Contact => "contact",
        })
    }
}

impl Default for SegmentParams {
    fn default() -> Self {
        Self {
            on_fraction: 0.10,
            off_fraction: 0.01,
            on_noise: 8.0,
            off_noise: 4.0,
            min_stance_frames: 3,
            max_gap_frames: 2,
            baseline_window_frames: 128,
            baseline_quantile: 0.10,
            baseline: BaselineMode::Auto,
            max_stance_frames: None,
        }
    }
}

impl SegmentParams {
    /// Checks every setting once, so that the algorithm never meets a nonsensical one.
    pub fn check(&self) -> Result<ValidSegmentParams> {
        let bad = |name: &'static str, reason: String| Err(CoreError::Param { name, reason });
        if !(self.on_fraction > 0.0 && self.on_fraction <= 1.0) {
            return bad(
                "on_fraction",
                format!(
                    "must be in (0, 1] (a stance needs some real load), got {}",
                    self.on_fraction
                ),
            );
        }
        if !(self.off_fraction >= 0.0 && self.off_fraction <= self.on_fraction) {
            return bad(
                "off_fraction",
                format!(
                    "must be in [0, on_fraction = {}] (hysteresis), got {}",
                    self.on_fraction, self.off_fraction
                ),
            );
        }
        if !(self.on_noise.is_finite() && self.on_noise >= 0.0) {
            return bad(
                "on_noise",
                format!("must be a finite number >= 0, got {}", self.on_noise),
            );
        }
        if !(self.off_noise >= 0.0 && self.off_noise <= self.on_noise) {
            return bad(
                "off_noise",
                format!(
                    "must be in [0, on_noise = {}] (hysteresis), got {}",
                    self.on_noise, self.off_noise
                ),
            );
        }
        if self.min_stance_frames == 0 {
            return bad("min_stance_frames", "must be at least 1".to_owned());
        }
        if self.baseline_window_frames < 4 {
            return bad(
                "baseline_window_frames",
                format!(
                    "must be at least 4 frames, got {}",
                    self.baseline_window_frames
                ),
            );
        }
        if !(self.baseline_quantile > 0.0 && self.baseline_quantile <= 0.5) {
            return bad(
                "baseline_quantile",
                format!("must be in (0, 0.5], got {}", self.baseline_quantile),
            );
        }
        if let Some(max) = self.max_stance_frames
            && max < self.min_stance_frames
        {
            return bad(
                "max_stance_frames",
                format!(
                    "must be at least min_stance_frames = {}, got {max}",
                    self.min_stance_frames
                ),
            );
        }
        Ok(ValidSegmentParams(self.clone()))
    }
}

/// [`SegmentParams`] that passed [`SegmentParams::check`]. Deserializing checks too.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "SegmentParams", into = "SegmentParams")]
pub struct ValidSegmentParams(SegmentParams);

impl ValidSegmentParams {
    pub fn params(&self) -> &SegmentParams {
        &self.0
    }
}

impl Default for ValidSegmentParams {
    /// The defaults of [`SegmentParams`], which are valid.
    fn default() -> Self {
        Self(SegmentParams::default())
    }
}

impl TryFrom<SegmentParams> for ValidSegmentParams {
    type Error = CoreError;

    fn try_from(params: SegmentParams) -> Result<Self> {
        params.check()
    }
}

impl From<ValidSegmentParams> for SegmentParams {
    fn from(valid: ValidSegmentParams) -> Self {
        valid.0
    }
}

/// One stance phase. Frames are 0-based indices into the recording.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Stance {
    /// First loaded frame (touchdown, unless `partial`).
    pub start: usize,
    /// Number of frames, touchdown to lift-off inclusive.
    pub len: usize,
    /// Largest total load in the stance, as recorded (the baseline is not subtracted).
    pub peak_load: f64,
    /// Frame of `peak_load` (the first one on ties).
    pub peak_frame: usize,
    /// The stance touches the first or last frame of the recording, so it may have been cut.
    pub partial: bool,
}

impl Stance {
    /// One past the last frame.
    pub fn end(&self) -> usize {
        self.start + self.len
    }

    /// The paper's mid-stance frame: `(len - 1) / 2` frames after touchdown (the 7th of 14).
    pub fn mid_frame(&self) -> usize {
        self.start + self.len.saturating_sub(1) / 2
    }

    pub fn contains(&self, frame: usize) -> bool {
        (self.start..self.end()).contains(&frame)
    }
}

/// Which frame(s) of a stance to use as samples. Parsed from `mid`, `peak`, `all`, or a 0-based frame
/// offset `K` after touchdown (the paper uses a fixed stance time: `6` is its 7th frame).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(try_from = "String", into = "String")]
pub enum SampleFrame {
    /// [`Stance::mid_frame`].
    #[default]
    Mid,
    /// [`Stance::peak_frame`].
    Peak,
    /// The K-th frame after touchdown (0 = touchdown).
    Offset(usize),
    /// Every frame of the stance.
    All,
}

impl FromStr for SampleFrame {
    type Err = CoreError;

    fn from_str(text: &str) -> Result<Self> {
        let text = text.trim();
        match text.to_ascii_lowercase().as_str() {
            "mid" => Ok(Self::Mid),
            "peak" => Ok(Self::Peak),
            "all" => Ok(Self::All),
            _ => text.parse().map(Self::Offset).map_err(|_| CoreError::Param {
                name: "sample frame",
                reason: format!(
                    "expected mid, peak, all or a frame offset K >= 0 after touchdown, got {text:?}"
                ),
            }),
        }
    }
}

impl fmt::Display for SampleFrame {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Mid => f.write_str("mid"),
            Self::Peak => f.write_str("peak"),
            Self::All => f.write_str("all"),
            Self::Offset(k) => write!(f, "{k}"),
        }
    }
}

impl TryFrom<String> for SampleFrame {
    type Error = CoreError;

    fn try_from(text: String) -> Result<Self> {
        text.parse()
    }
}

impl From<SampleFrame> for String {
    fn from(sample: SampleFrame) -> Self {
        sample.to_string()
    }
}

/// The frames of `stance` selected by `sample`, in increasing order.
///
/// An offset at or past the end of the stance is an error, not clamped: clamping would silently sample a
/// different phase of the stance (lift-off instead of, say, frame 20), which is exactly what a fixed
/// stance time is meant to avoid. The caller decides whether to skip such a stance or stop.
pub fn sample_frames(stance: &Stance, sample: SampleFrame) -> Result<Vec<usize>> {
    match sample {
        SampleFrame::Mid => Ok(vec![stance.mid_frame()]),
        SampleFrame::Peak => Ok(vec![stance.peak_frame]),
        SampleFrame::All => Ok((stance.start..stance.end()).collect()),
        SampleFrame::Offset(k) if k < stance.len => Ok(vec![stance.start + k]),
        SampleFrame::Offset(k) => Err(CoreError::Param {
            name: "sample frame",
            reason: format!(
                "frame offset {k} is past the stance at frames {}..{} ({} frames long)",
                stance.start,
                stance.end(),
                stance.len
            ),
        }),
    }
}

/// The result of [`segment`](super::segment()).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Segmentation {
    /// Every stance found, in time order, partial ones included (flagged).
    pub stances: Vec<Stance>,
    /// Estimated unloaded level of every frame (same length as the input).
    pub baseline: Vec<f64>,
    /// Estimated standard deviation of the unloaded level (0 for a sensor that reads exactly zero).
    pub noise: f64,
    /// Largest load above the baseline in the recording (0 when nothing rises above it).
    pub load_range: f64,
    /// Load above baseline a stance had to exceed somewhere.
    pub on_level: f64,
    /// Load above baseline that a frame had to exceed to be part of a stance.
    pub off_level: f64,
    /// What the stances were measured from (never [`BaselineMode::Auto`]: the mode chosen). With
    /// [`BaselineMode::Floor`], `baseline` is the local floor.
    #[serde(default = "drifting")]
    pub mode: BaselineMode,
    /// Why the mode was chosen, when it was chosen automatically and is not the drifting baseline.
    #[serde(default)]
    pub mode_reason: Option<String>,
}

fn drifting() -> BaselineMode {
    BaselineMode::Drifting
}

impl Segmentation {
    /// The stances not cut by the start or end of the recording: the ones to sample by default.
    pub fn complete(&self) -> impl Iterator<Item = &Stance> + '_ {
        self.stances.iter().filter(|stance| !stance.partial)
    }

    /// The sample frames of every complete stance (and of partial ones with `include_partial`), in order.
    /// Fails like [`sample_frames`] when an offset is past the end of a stance.
    pub fn samples(&self, sample: SampleFrame, include_partial: bool) -> Result<Vec<usize>> {
        let mut frames = Vec::new();
        for stance in self
            .stances
            .iter()
            .filter(|stance| include_partial || !stance.partial)
        {
            frames.extend(sample_frames(stance, sample)?);
        }
        Ok(frames)
    }
}

/// An error naming the first non-finite load, if any.
pub(crate) fn check_finite(total_load: &[f64]) -> Result<()> {
    match total_load
        .iter()
        .enumerate()
        .find(|(_, value)| !value.is_finite())
    {
        Some((frame, value)) => Err(CoreError::Param {
            name: "total load",
            reason: format!("frame {frame} has load {value}; total loads must be finite"),
        }),
        None => Ok(()),
    }
}

/// The stance phases measured from a drifting baseline (the method of the module docs), whatever
/// `params.baseline` says. Loads must be finite ([`check_finite`]).
pub(crate) fn segment_drifting(total_load: &[f64], params: &ValidSegmentParams) -> Segmentation {
    let p = params.params();
    let (baseline, noise) = estimate_baseline(
        total_load,
        p.baseline_window_frames,
        p.baseline_quantile,
        p.off_fraction,
    );
    let above: Vec<f64> = total_load
        .iter()
        .zip(&baseline)
        .map(|(load, base)| load - base)
        .collect();
    let load_range = above.iter().copied().fold(0.0, f64::max);
    let on_level = (p.on_noise * noise).max(p.on_fraction * load_range);
    let off_level = (p.off_noise * noise).max(p.off_fraction * load_range);
    let mut segmentation = Segmentation {
        stances: Vec::new(),
        baseline,
        noise,
        load_range,
        on_level,
        off_level,
        mode: BaselineMode::Drifting,
        mode_reason: None,
    };
    if load_range <= 0.0 {
        return segmentation;
    }

    let mut runs = runs_above(&above, off_level);

    // Bridge short dropouts. A run that is both short and weak (never above the on level) is dropped
    // first rather than bridged: it is far more likely a noise excursion just beside a stance, which
    // would otherwise lengthen the stance by the gap, than the tail of a stance after a dropout.
    let reaches_on =
        |&(start, end): &(usize, usize)| above[start..end].iter().any(|&v| v > on_level);
    runs.retain(|run| run.1 - run.0 >= p.min_stance_frames || reaches_on(run));
    let mut merged: Vec<(usize, usize)> = Vec::with_capacity(runs.len());
    for run in runs {
        match merged.last_mut() {
            Some(last) if run.0 - last.1 <= p.max_gap_frames => last.1 = run.1,
            _ => merged.push(run),
        }
    }

    let n = total_load.len();
    for (start, end) in merged {
        let len = end - start;
        if len < p.min_stance_frames || !reaches_on(&(start, end)) {
            continue;
        }
        let mut peak_frame = start;
        for frame in start..end {
            if total_load[frame] > total_load[peak_frame] {
                peak_frame = frame;
            }
        }
        segmentation.stances.push(Stance {
            start,
            len,
            peak_load: total_load[peak_frame],
            peak_frame,
            partial: start == 0 || end == n,
        });
    }
    segmentation
}

/// The maximal runs of frames whose value is above `level`, as `[start, end)`.
fn runs_above(values: &[f64], level: f64) -> Vec<(usize, usize)> {
    let mut runs: Vec<(usize, usize)> = Vec::new();
    let mut open: Option<usize> = None;
    for (frame, &value) in values.iter().enumerate() {
        match (value > level, open) {
            (true, None) => open = Some(frame),
            (false, Some(start)) => {
                runs.push((start, frame));
                open = None;
            }
            _ => {}
        }
    }
    if let Some(start) = open {
        runs.push((start, values.len()));
    }
    runs
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn runs_above_are_the_maximal_runs_over_the_level() {
        let values = [5.0, 0.0, 2.0, 3.0, 1.0, 1.0, 4.0];
        assert_eq!(runs_above(&values, 1.0), vec![(0, 1), (2, 4), (6, 7)]);
        assert_eq!(runs_above(&values, 5.0), Vec::<(usize, usize)>::new());
        assert_eq!(runs_above(&[], 0.0), Vec::<(usize, usize)>::new());
        // Against the obvious oracle: frame t is in a run exactly when values[t] > level.
        let wavy: Vec<f64> = (0..200).map(|t| ((t * 37 % 23) as f64).sin()).collect();
        let runs = runs_above(&wavy, 0.2);
        let mut covered = vec![false; wavy.len()];
        for &(start, end) in &runs {
            assert!(start < end);
            covered[start..end].iter_mut().for_each(|c| *c = true);
        }
        for (t, &v) in wavy.iter().enumerate() {
            assert_eq!(covered[t], v > 0.2, "frame {t}");
        }
        assert!(
            runs.windows(2).all(|pair| pair[0].1 < pair[1].0),
            "maximal: {runs:?}"
        );
    }
}
