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

use super::robust::{median, median_and_sigma, quantile};
use crate::error::{CoreError, Result};

/// Residuals further than this many noise sigmas from the baseline are not "unloaded" frames.
const CLIP_SIGMAS: f64 = 4.0;
/// While growing the set of unloaded frames from the low tail, frames up to this many (underestimated)
/// noise sigmas above the median join it.
const GROW_SIGMAS: f64 = 5.0;
/// Below this many frames, the growth of the unloaded set takes its RMS spread into account too (see
/// `estimate_baseline`).
const SMALL_SET_FRAMES: usize = 3 * MIN_START_FRAMES;
/// Sigma clipping normally converges in a handful of rounds; this bounds a (rare) oscillation.
const MAX_CLIP_ROUNDS: usize = 32;
/// Fewest frames the baseline is fitted to: a line through fewer is mostly noise, and a fit that passes
/// exactly through its points reports zero noise.
const MIN_FIT_FRAMES: usize = 5;
/// The clipping starts from at least this many of the lowest frames: the MAD of a handful of tail values
/// can collapse by chance and stall the growth of the unloaded set.
const MIN_START_FRAMES: usize = 10;
/// A block needs this many unloaded frames to get its own baseline correction (else the global one).
const MIN_QUIET_PER_BLOCK: usize = 3;

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

    // Maximal runs of frames above the off level, [start, end).
    let mut runs: Vec<(usize, usize)> = Vec::new();
    let mut open: Option<usize> = None;
    for (frame, &value) in above.iter().enumerate() {
        match (value > off_level, open) {
            (true, None) => open = Some(frame),
            (false, Some(start)) => {
                runs.push((start, frame));
                open = None;
            }
            _ => {}
        }
    }
    if let Some(start) = open {
        runs.push((start, above.len()));
    }

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

/// Per-frame baseline and the baseline noise sigma (see the module docs). `values` must be finite.
fn estimate_baseline(
    values: &[f64],
    window: usize,
    quantile_level: f64,
    off_fraction: f64,
) -> (Vec<f64>, f64) {
    let n = values.len();
    if n == 0 {
        return (Vec::new(), 0.0);
    }
    // Blocks of about `window` frames; at most n blocks since window >= 1, so none is empty.
    let blocks = ((n + window / 2) / window).clamp(1, n);
    let bounds: Vec<(usize, usize)> = (0..blocks)
        .map(|b| (b * n / blocks, (b + 1) * n / blocks))
        .collect();
    let mut scratch = Vec::with_capacity(n);
    let levels: Vec<f64> = bounds
        .iter()
        .map(|&(start, end)| {
            scratch.clear();
            scratch.extend_from_slice(&values[start..end]);
            quantile(&mut scratch, quantile_level)
        })
        .collect();
    let fit = BaselineFit {
        values,
        centres: bounds
            .iter()
            .map(|&(start, end)| (start + end - 1) as f64 / 2.0)
            .collect(),
        coarse: Vec::new(),
        levels,
        bounds,
    };
    let fit = BaselineFit {
        coarse: interpolate(&fit.centres, &fit.levels, n),
        ..fit
    };

    // Sigma clipping from the low tail upwards, refitting the baseline to the unloaded frames each round:
    // the unloaded frames are the cluster at the bottom once the baseline's drift is removed.
    let mut residual: Vec<f64> = values.iter().zip(&fit.coarse).map(|(v, c)| v - c).collect();
    // Start from the lowest `baseline_quantile` of the frames, but from enough of them that a median, a MAD
    // and a line fitted to them mean something (two points fit a line exactly, with zero "noise").
    scratch.clone_from(&residual);
    scratch.sort_unstable_by(f64::total_cmp);
    let start_count = ((quantile_level * n as f64).ceil() as usize).max(MIN_START_FRAMES);
    let start_cut = scratch[start_count.min(n) - 1];
    let mut quiet: Vec<bool> = residual.iter().map(|&r| r <= start_cut).collect();
    // Every block starts with its own lowest frames: under a strong drift the coarse baseline of the
    // last block (its low quantile taken at the block's low end, then extrapolated) lay below all its
    // swings (a walk drifting down 0.49 a frame: 30 counts low at its centre); the block got no frame
    // of the global start set, its level was corrected by the other blocks' median, the growth never
    // reached its swings (they stayed above the limit), and its last stances merged into one.
    if fit.bounds.len() > 1 {
        for &(start, end) in &fit.bounds {
            if (start..end).filter(|&t| quiet[t]).count() >= MIN_QUIET_PER_BLOCK {
                continue;
            }
            let count = ((quantile_level * (end - start) as f64).ceil() as usize)
                .max(MIN_QUIET_PER_BLOCK)
                .min(end - start);
            scratch.clear();
            scratch.extend_from_slice(&residual[start..end]);
            let cut = quantile(
                &mut scratch,
                (count - 1) as f64 / (end - start - 1).max(1) as f64,
            );
            for t in start..end {
                quiet[t] |= residual[t] <= cut;
            }
        }
    }
    // Rounding noise of an exactly linear baseline must not count as structure.
    let floor = 1e-12 * values.iter().fold(0.0, |m: f64, v| m.max(v.abs()));
    let mut baseline = fit.coarse.clone();
    let mut sigma = 0.0;
    let mut lower_bound = 0.0;
    // Two phases. Growing: a low tail's MAD underestimates the noise (the tail is narrower than the
    // cluster), so a symmetric 3-sigma clip can stall at the bottom; instead every frame below
    // median + GROW_SIGMAS x sigma (or below the off level) joins the set (nothing real lies below the
    // baseline), and the set only grows. Refining: one symmetric CLIP_SIGMAS clip around the median, which
    // drops the stance edges the generous growth let in.
    for grow in [true, false] {
        for _ in 0..MAX_CLIP_ROUNDS {
            baseline = fit.refit(&quiet, &mut scratch);
            for ((r, v), b) in residual.iter_mut().zip(values).zip(&baseline) {
                *r = v - b;
            }
            scratch.clear();
            scratch.extend(
                residual
                    .iter()
                    .zip(&quiet)
                    .filter(|&(_, &q)| q)
                    .map(|(r, _)| *r),
            );
            if scratch.is_empty() {
                break;
            }
            let centre;
            (centre, sigma) = median_and_sigma(&mut scratch);
            let next: Vec<bool> = if grow {
                // While growing, the set is the low tail of the unloaded cluster, cut at its top: its MAD
                // underestimates the noise, badly so for the few frames of a short recording (a 53-frame
                // movie grew to 15 of its 42 unloaded frames and stalled with a noise of 2 for a true 9,
                // and noise frames beside the stance then joined it). The tail's lower side is not cut
                // (nothing real lies below the baseline), so its spread below the median bounds the
                // noise from below too.
                // Anything below the off level is unloaded by definition, whatever the noise estimate:
                // this lets the set grow across a drift much larger than the noise.
                let range = residual.iter().fold(0.0, |m: f64, &r| m.max(r - centre));
                // A frame less than twice the off level below the centre is noise, not a glitch, even
                // when the tail's MAD says otherwise: a chance cluster of low frames (9 of the 27
                // unloaded frames of a 50-frame movie within 1.5 of each other, true noise 8) has a
                // tiny MAD, and leaving out the frames below it stalled the growth at the cluster.
                let glitch = (2.0 * CLIP_SIGMAS * sigma).max(2.0 * off_fraction * range);
                // The MAD of a dozen frames is no better than a guess: 8 of the 10 lowest frames of a
                // 46-frame movie (28 unloaded, true noise 8.2) lay within 3 of each other, the set
                // stalled at those 10 with a noise of 1.6, and noise frames beside the stance joined
                // it. A small set's spread is also its RMS distance from its median (which sees the
                // set's frames above the median, not just the middle half), at most three times its
                // MAD: a set that much wider than its MAD mixes two levels (a lead at zero and a
                // preload), and the MAD holds to the larger.
                let set_rms = if quiet.iter().filter(|&&q| q).count() < SMALL_SET_FRAMES {
                    rms_within(&residual, &quiet, centre, glitch).min(3.0 * sigma)
                } else {
                    0.0
                };
                let spread = sigma
                    .max(lower_sigma_within(&residual, &quiet, centre, glitch))
                    .max(set_rms);
                let limit = centre + (GROW_SIGMAS * spread.max(floor)).max(off_fraction * range);
                residual
                    .iter()
                    .zip(&quiet)
                    .map(|(&r, &q)| q || r <= limit)
                    .collect()
            } else {
                lower_bound = lower_sigma(&residual, &quiet, centre, sigma);
                let width = CLIP_SIGMAS * sigma.max(floor);
                residual
                    .iter()
                    .map(|&r| (r - centre).abs() <= width)
                    .collect()
            };
            if next == quiet || !next.contains(&true) {
                break;
            }
            quiet = next;
            if !grow {
                // One refining pass only: iterated clipping of a finite sample shrinks the MAD round after
                // round (each pass trims the tails the previous estimate made look too far).
                baseline = fit.refit(&quiet, &mut scratch);
                scratch.clear();
                scratch.extend(
                    values
                        .iter()
                        .zip(&baseline)
                        .zip(&quiet)
                        .filter(|&(_, &q)| q)
                        .map(|((v, b), _)| v - b),
                );
                if !scratch.is_empty() {
                    sigma = median_and_sigma(&mut scratch).1;
                }
                // The MAD of a few dozen frames varies by a quarter either way, and noise frames beside
                // a stance then join it when it comes out low; the RMS below the centre varies half as
                // much and cannot hold a stance's edge.
                sigma = sigma.max(lower_bound);
                break;
            }
        }
    }
    // The unloaded level is never below the lowest reading: a line fitted to a block can dip under it at
    // the block's end (a sensor that reads 0 in swing got a baseline of -1.8 there, and frames of total
    // load 0 were "1.8 above the baseline").
    let lowest = values.iter().copied().fold(f64::INFINITY, f64::min);
    for level in &mut baseline {
        *level = level.max(lowest);
    }
    (baseline, sigma)
}

/// The noise sigma measured on the frames flagged `quiet` below `centre` only, as the root mean square
/// of their distances below it: loads only add to a frame, so the unloaded frames below the centre are
/// noise alone, neither cut by a clip above nor lifted by a stance's edge. Distances beyond
/// `2 x CLIP_SIGMAS x mad_sigma` (a glitch reading far below zero) are left out; 0 without frames.
fn lower_sigma(residual: &[f64], quiet: &[bool], centre: f64, mad_sigma: f64) -> f64 {
    lower_sigma_within(residual, quiet, centre, 2.0 * CLIP_SIGMAS * mad_sigma)
}

/// [`lower_sigma`] over the distances below `centre` of at most `limit`.
fn lower_sigma_within(residual: &[f64], quiet: &[bool], centre: f64, limit: f64) -> f64 {
    let (sum, count) = residual
        .iter()
        .zip(quiet)
        .filter(|&(&r, &q)| q && r < centre && centre - r <= limit)
        .fold((0.0, 0usize), |(sum, count), (&r, _)| {
            (sum + (centre - r).powi(2), count + 1)
        });
    if count == 0 {
        0.0
    } else {
        (sum / count as f64).sqrt()
    }
}

/// The root mean square distance from `centre` of the frames flagged `quiet`, those more than `limit`
/// below it left out (glitches); 0 without frames.
fn rms_within(residual: &[f64], quiet: &[bool], centre: f64, limit: f64) -> f64 {
    let (sum, count) = residual
        .iter()
        .zip(quiet)
        .filter(|&(&r, &q)| q && centre - r <= limit)
        .fold((0.0, 0usize), |(sum, count), (&r, _)| {
            (sum + (r - centre).powi(2), count + 1)
        });
    if count == 0 {
        0.0
    } else {
        (sum / count as f64).sqrt()
    }
}

/// The pieces of a baseline estimate: blocks, their centres and low-quantile levels, and the coarse
/// baseline interpolated through those levels.
struct BaselineFit<'a> {
    values: &'a [f64],
    bounds: Vec<(usize, usize)>,
    centres: Vec<f64>,
    levels: Vec<f64>,
    coarse: Vec<f64>,
}

impl BaselineFit<'_> {
    /// The baseline through the frames flagged `quiet` (unloaded).
    ///
    /// With several blocks, each block's level is corrected by the median residual of its unloaded frames
    /// and the baseline interpolates between block centres, which follows a drift at the time scale of the
    /// window. A recording of a single block has no second knot to follow a drift with, so there the
    /// baseline is the least-squares line through the unloaded frames (a drift within a short recording
    /// would otherwise tilt the residuals and stall the clipping at one end of the recording).
    fn refit(&self, quiet: &[bool], scratch: &mut Vec<f64>) -> Vec<f64> {
        let n = self.values.len();
        let residual = |frame: usize| self.values[frame] - self.coarse[frame];
        if self.bounds.len() == 1 {
            return line_through(self.values, quiet);
        }
        scratch.clear();
        scratch.extend((0..n).filter(|&t| quiet[t]).map(residual));
        let global = median(scratch);
        let knots: Vec<f64> = self
            .bounds
            .iter()
            .zip(&self.levels)
            .map(|(&(start, end), &level)| {
                scratch.clear();
                scratch.extend((start..end).filter(|&t| quiet[t]).map(residual));
                if scratch.len() >= MIN_QUIET_PER_BLOCK {
                    level + median(scratch)
                } else {
                    level + global
                }
            })
            .collect();
        interpolate(&self.centres, &knots, n)
    }
}

/// The least-squares line through the points `(t, values[t])` with `use_point[t]`, evaluated at every
/// frame; a constant (their mean) unless at least [`MIN_FIT_FRAMES`] points lie in each of the first and
/// last thirds of the recording.
fn line_through(values: &[f64], use_point: &[bool]) -> Vec<f64> {
    let points = || {
        values
            .iter()
            .zip(use_point)
            .enumerate()
            .filter(|&(_, (_, &used))| used)
            .map(|(t, (&v, _))| (t as f64, v))
    };
    let count = points().count() as f64;
    let n = values.len();
    let early = points().filter(|&(t, _)| t < (n / 3) as f64).count();
    let late = points().filter(|&(t, _)| t >= (n - n / 3) as f64).count();
    if early < MIN_FIT_FRAMES || late < MIN_FIT_FRAMES {
        // Too few points, or all at one end: a slope fitted there and extrapolated across the recording is
        // mostly noise. A constant (the mean; 0 without points) until the set has spread.
        let mean = points().map(|(_, v)| v).sum::<f64>() / count.max(1.0);
        return vec![mean; n];
    }
    let mean_t = points().map(|(t, _)| t).sum::<f64>() / count;
    let mean_v = points().map(|(_, v)| v).sum::<f64>() / count;
    let (sxy, sxx) = points().fold((0.0, 0.0), |(sxy, sxx), (t, v)| {
        (
            sxy + (t - mean_t) * (v - mean_v),
            sxx + (t - mean_t) * (t - mean_t),
        )
    });
    let slope = if sxx > 0.0 { sxy / sxx } else { 0.0 };
    (0..values.len())
        .map(|t| mean_v + slope * (t as f64 - mean_t))
        .collect()
}

/// Piecewise-linear curve through `(xs[i], ys[i])` evaluated at 0..n, extrapolated linearly beyond the
/// first/last knots (so that a linear drift is followed to the ends). `xs` strictly increasing.
fn interpolate(xs: &[f64], ys: &[f64], n: usize) -> Vec<f64> {
    match (xs, ys) {
        ([_, _, ..], [_, _, ..]) => {
            let last_segment = xs.len().min(ys.len()) - 2;
            let mut segment = 0;
            (0..n)
                .map(|t| {
                    let t = t as f64;
                    while segment < last_segment && t > xs[segment + 1] {
                        segment += 1;
                    }
                    let (x0, x1, y0, y1) =
                        (xs[segment], xs[segment + 1], ys[segment], ys[segment + 1]);
                    y0 + (y1 - y0) * (t - x0) / (x1 - x0)
                })
                .collect()
        }
        (_, [y, ..]) => vec![*y; n],
        _ => vec![0.0; n],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolation_extrapolates_linearly() {
        let curve = interpolate(&[1.0, 3.0], &[10.0, 20.0], 6);
        assert_eq!(curve, vec![5.0, 10.0, 15.0, 20.0, 25.0, 30.0]);
        assert_eq!(interpolate(&[2.0], &[7.0], 3), vec![7.0; 3]);
    }

    /// A sensor that reads exactly 0 in swing early on and a few counts of noise later: the line fitted to
    /// the unloaded frames slopes up, and below the first frames it would dip under 0, the lowest reading.
    #[test]
    fn the_baseline_never_drops_below_the_lowest_reading() {
        let values: Vec<f64> = (0..256)
            .map(|i| match (i % 16, i) {
                (0..=3, _) => 5000.0,        // stances
                (_, 0..128) => 0.0,          // silent swing
                (k, _) if k % 2 == 0 => 6.0, // noisy swing
                _ => 0.0,
            })
            .collect();
        let (baseline, _) = estimate_baseline(&values, 256, 0.1, 0.01);
        let lowest = baseline.iter().copied().fold(f64::INFINITY, f64::min);
        assert!(lowest >= 0.0, "{lowest}: {baseline:?}");
        assert!(baseline[255] > 0.0, "the rise is still followed");
    }

    #[test]
    fn baseline_of_a_constant_is_the_constant_without_noise() {
        let (baseline, noise) = estimate_baseline(&[5.0; 300], 128, 0.1, 0.01);
        assert!(baseline.iter().all(|&b| (b - 5.0).abs() < 1e-12));
        assert_eq!(noise, 0.0);
    }
}
