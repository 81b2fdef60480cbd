//! What the stances rise above, and the automatic choice of it ([`segment`]).
//!
//! The drifting baseline ([`super::offline`]) assumes the foot fully unloads between contacts. Two kinds
//! of real recordings break that assumption:
//!
//! - **A standing preload with presses or steps on top** (a foot that never leaves the sensor): the load
//!   between presses stays far above the unloaded level, so every frame after the first contact is
//!   "loaded" and the whole recording is one stance. The [`BaselineMode::Floor`] mode measures each
//!   contact from the *local floor* instead:
//!   1. the load's prominent peaks are found by hysteresis (a peak counts once the load has risen by
//!      the on fraction of its range above the valley before it and fallen by it again);
//!   2. in each valley (before the first peak, between two, after the last) the *rest* is the flat
//!      stretch at its bottom: a line is fitted to the valley's frames within the off level of it,
//!      refitted until the set is stable (so a preload that drifts is followed), and the rest is the
//!      run of frames around the lowest one within the off level of that line (excursions shorter
//!      than a stance that stay below the on level are noise, as in the drifting mode);
//!   3. the noise is measured on the rests (their residuals to their lines), which sets the on and off
//!      levels as in the drifting mode; a peak that does not rise the on level above the rests on both
//!      sides is dropped, and the rests are found again;
//!   4. a contact runs from the frame after the rest before its peak to the frame before the rest after
//!      it; two contacts separated by a rest of at most `max_gap_frames` frames are one (a dropout). A
//!      recording that starts or ends inside a contact (its first or last "rest" higher than the next
//!      by the on level) gives a partial contact.
//!
//!   The floor (the segmentation's `baseline`) is each rest's line on its frames, and under a contact
//!   the level of the rest before it on its rising side and of the rest after it on its falling side
//!   (a first press onto a preload starts from zero and ends on the preload).
//! - **A trial cut to one contact** (loaded from its first frame to its last, no swing in the file):
//!   there is no unloaded frame to measure a baseline on. [`BaselineMode::Contact`] makes the whole
//!   recording one stance, partial at both ends (its touchdown and lift-off are not in the file); the
//!   baseline is 0 (pressure readings are not negative), or the lowest reading if that is negative.
//!
//! [`BaselineMode::Auto`] (the default) decides from the data, in this order:
//! 1. *the floor* when the floor's contacts show presses on a preload (see `preload`): a stance of the
//!    drifting baseline holds at least [`PRELOAD_PEAKS`] of them (a foot's contact splits into at
//!    most two, heel and toe) or is longer than
//!    [`SegmentParams::max_stance_frames`](super::SegmentParams::max_stance_frames); or the floor finds
//!    at least [`PRELOAD_PEAKS`] complete contacts and the drifting baseline none; or the drifting
//!    baseline found a rest between two contacts (or after the last) loaded (one of its frames, but
//!    its first two and last two, in one of its stances: each segmentation's edge may be a frame off,
//!    and a walking swing may lose a frame to the stance on each side) and the next rest, at the same level within the on level, unloaded (it took a preload
//!    for unloaded in some windows: a walking foot's heel-toe valley is far above the swing beside it);
//!    or [`PRELOAD_PEAKS`] contacts in a row never unload between them (each rest above the drifting
//!    baseline by the off level, or in one of its stances) and the drifting baseline misses one of them
//!    by more than a frame, or lies above a rest of the floor (its median load, over at least a
//!    stance's frames, below the drifting baseline by more than the floor's off level: nothing real
//!    lies below the unloaded level, so the drifting baseline took a preload for its baseline, e.g.
//!    an unloaded lead before the first press for glitches, and its levels and edges are biased). A
//!    rest above the recording's lowest load alone is not loaded (a swing level that drifts is), unless
//!    the drifting baseline mixed two levels (its off level more than twice the floor's, or it lies
//!    above a rest);
//! 2. *one contact* when the drifting baseline finds no complete stance while the load stays above
//!    [`CONTACT_FRACTION`] of its range on every frame but a few at the ends (at most
//!    [`CONTACT_END_FRACTION`] of the frames at each end, and at least [`MIN_CONTACT_FRAMES`] frames
//!    loaded);
//! 3. the drifting baseline otherwise (the paper's hopper, walking, the simulator: unchanged).

use super::offline::{
    BaselineMode, SegmentParams, Segmentation, Stance, ValidSegmentParams, check_finite,
    segment_drifting,
};
use super::robust::median;
use crate::error::Result;
use crate::recording::Recording;

/// A recording is one contact when, but for its ends, its load stays above this fraction of its range
/// above its lowest reading: halfway (on a log scale, roughly) between the default off (1%) and on
/// (10%) fractions. Between two real contacts the load falls to the off level.
pub const CONTACT_FRACTION: f64 = 0.05;
/// At most this fraction of the frames at each end may be below [`CONTACT_FRACTION`] in a one-contact
/// recording (the foot arriving and leaving).
pub const CONTACT_END_FRACTION: f64 = 0.1;
/// Fewest loaded frames of a one-contact recording.
pub const MIN_CONTACT_FRAMES: usize = 3;
/// This many contacts of the floor without an unloaded frame between them are presses on a preload (a
/// walking foot's contact has at most two peaks, heel and toe).
pub const PRELOAD_PEAKS: usize = 3;

/// Finds the stance phases in a series of total loads (one value per frame), measured from what
/// `params.baseline` says (see the module docs; [`BaselineMode::Auto`] chooses). Empty input, or a
/// recording without contact, gives no stances; a non-finite load is an error.
pub fn segment(total_load: &[f64], params: &ValidSegmentParams) -> Result<Segmentation> {
    check_finite(total_load)?;
    let p = params.params();
    let segmentation = match p.baseline {
        BaselineMode::Drifting => segment_drifting(total_load, params),
        BaselineMode::Floor => segment_floor(total_load, params),
        BaselineMode::Contact => segment_contact(total_load),
        BaselineMode::Auto => segment_auto(total_load, params),
    };
    Ok(drop_too_long(segmentation, p.max_stance_frames))
}

/// [`segment`] on a recording's total load per frame.
pub fn segment_recording(
    recording: &Recording,
    params: &ValidSegmentParams,
) -> Result<Segmentation> {
    segment(&recording.total_per_frame(), params)
}

fn segment_auto(total_load: &[f64], params: &ValidSegmentParams) -> Segmentation {
    let drifting = segment_drifting(total_load, params);
    // Presses on a preload first: such a recording is loaded throughout too, but holds many contacts.
    let floor = segment_floor_from(total_load, &drifting, params);
    if let Some(reason) = preload(total_load, &drifting, &floor, params) {
        return Segmentation {
            mode_reason: Some(reason),
            ..floor
        };
    }
    if drifting.complete().next().is_none()
        && let Some(reason) = one_contact(total_load)
    {
        return Segmentation {
            mode_reason: Some(reason),
            ..segment_contact(total_load)
        };
    }
    drifting
}

/// Why `total_load` is one contact, or `None` if it is not (see the module docs).
fn one_contact(total_load: &[f64]) -> Option<String> {
    let n = total_load.len();
    let lowest = total_load.iter().copied().fold(f64::INFINITY, f64::min);
    let highest = total_load.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let range = highest - lowest;
    if n < MIN_CONTACT_FRAMES || range <= 0.0 {
        return None;
    }
    let level = lowest + CONTACT_FRACTION * range;
    let first = total_load.iter().position(|&v| v > level)?;
    let last = total_load.iter().rposition(|&v| v > level)?;
    // At least one frame at each end: the foot arriving and leaving.
    let ends = ((CONTACT_END_FRACTION * n as f64).floor() as usize).max(1);
    let unbroken = total_load[first..=last].iter().all(|&v| v > level);
    let loaded = last + 1 - first;
    (unbroken && first <= ends && n - 1 - last <= ends && loaded >= MIN_CONTACT_FRAMES).then(|| {
        format!(
            "the load stays above {:.0}% of its range from frame {first} to frame {last} of {n}: \
             one contact, no unloaded frame between contacts",
            CONTACT_FRACTION * 100.0
        )
    })
}

/// Why the recording looks like presses on a preload, or `None`: a stance of the drifting baseline is
/// longer than the longest allowed, or holds at least [`PRELOAD_PEAKS`] of the floor's contacts (a
/// foot's contact splits into at most two, heel and toe), or the floor finds at least
/// [`PRELOAD_PEAKS`] complete contacts and the drifting baseline finds none, or the rests between them
/// stay loaded [`PRELOAD_PEAKS`] contacts in a row and the drifting baseline misses one of them by more
/// than a frame.
fn preload(
    total_load: &[f64],
    drifting: &Segmentation,
    floor: &Segmentation,
    params: &ValidSegmentParams,
) -> Option<String> {
    let merged = merged_presses(drifting, floor, params.params().max_stance_frames);
    let complete = floor.complete().count();
    if merged.is_some() || complete < PRELOAD_PEAKS {
        return merged;
    }
    if drifting.complete().next().is_none() {
        return Some(format!(
            "no complete stance above the drifting baseline, but {complete} presses rise above a \
             floor that never unloads: contacts measured from the local floor"
        ));
    }
    // The load rests on a preload between the floor's contacts (above the lowest rest by more than the
    // off level), and the drifting baseline puts a contact's edges elsewhere: it has taken the preload
    // for its baseline in some windows, and a noise mixed from the unloaded and preloaded frames.
    let lowest = floor.baseline.iter().copied().fold(f64::INFINITY, f64::min);
    // A rest is loaded when it is above the drifting baseline by the floor's off level, or lies in a
    // stance of the drifting baseline (which found it loaded), or, when the drifting baseline mixed two
    // levels (its off level more than twice the floor's), above the lowest rest. Not above the lowest
    // rest alone: a swing level that drifts is above it too.
    let mut mixed = drifting.off_level > 2.0 * floor.off_level;
    // The drifting baseline above a rest of the floor (the median load of a rest at least a stance
    // long below it by more than the floor's off level): nothing real lies below the unloaded level,
    // so it took a preload for its baseline there and the unloaded frames (a lead before the first
    // press) for glitches, and its levels and edges are biased. Its levels mixed two floors too.
    let sunk = sunk_rest(
        total_load,
        drifting,
        floor,
        params.params().min_stance_frames,
    );
    mixed |= sunk.is_some();
    let contradiction = rests_loaded_at_one_level(drifting, floor, lowest);
    if contradiction.is_some() {
        return contradiction;
    }
    let loaded_rests = longest_loaded_chain(drifting, floor, lowest, mixed);
    if loaded_rests + 1 < PRELOAD_PEAKS {
        return None;
    }
    if let Some((first, last)) = sunk {
        return Some(format!(
            "{} presses in a row never unload between them, and the drifting baseline lies above \
             the rest at frames {first}..{last} (it took the preload for its baseline): contacts \
             measured from the local floor",
            loaded_rests + 1
        ));
    }
    floor.complete().find_map(|press| {
        let matched = drifting.stances.iter().any(|stance| {
            stance.start.abs_diff(press.start) <= 1 && stance.end().abs_diff(press.end()) <= 1
        });
        (!matched).then(|| {
            format!(
                "{} presses in a row never unload between them, and the drifting \
                 baseline does not find the press at frames {}..{}: contacts measured from the \
                 local floor",
                loaded_rests + 1,
                press.start,
                press.end()
            )
        })
    })
}

/// Why the drifting baseline merged presses, or `None`: its first stance longer than `max_len`, or
/// holding at least [`PRELOAD_PEAKS`] of the floor's contacts.
fn merged_presses(
    drifting: &Segmentation,
    floor: &Segmentation,
    max_len: Option<usize>,
) -> Option<String> {
    drifting.stances.iter().find_map(|stance| {
        if let Some(max) = max_len
            && stance.len > max
        {
            return Some(format!(
                "a stance of {} frames from frame {} is longer than the longest allowed ({max}): \
                 contacts measured from the local floor",
                stance.len, stance.start
            ));
        }
        let inside = floor
            .stances
            .iter()
            .filter(|press| press.start + 1 >= stance.start && press.end() <= stance.end() + 1)
            .count();
        (inside >= PRELOAD_PEAKS).then(|| {
            format!(
                "the stance at frames {}..{} holds {inside} presses that never unload (the load \
                 between them stays above the off level): contacts measured from the local floor",
                stance.start,
                stance.end(),
            )
        })
    })
}

/// The middle frame of the rest between two of the floor's contacts.
fn rest_frame(pair: &[Stance]) -> usize {
    (pair[0].end() + pair[1].start) / 2
}

/// Why the drifting baseline took a preload for unloaded, or `None`: a rest of the floor it found
/// loaded (in one of its stances) next to one it found unloaded at the same level (within the on
/// level), both above the `lowest` rest by the off level. It took the preload for unloaded there, not
/// here; a walking foot's heel-toe valley is far above the swing level beside it.
fn rests_loaded_at_one_level(
    drifting: &Segmentation,
    floor: &Segmentation,
    lowest: f64,
) -> Option<String> {
    let in_stance = |t: usize| drifting.stances.iter().any(|stance| stance.contains(t));
    // A rest counts as loaded for the drifting baseline when one of its frames but the first two and
    // the last two lies in one of its stances: each segmentation's boundary may be a frame off, so the
    // two may differ by two (a walking swing often loses a frame to the stance on each side; a floor
    // contact that ended a frame early and a drifting stance that ended a frame late made a swing
    // "loaded" on its second frame and walking a preload).
    let mut rests: Vec<(usize, bool)> = floor
        .stances
        .windows(2)
        .map(|pair| {
            let loaded = (pair[0].end() + 2..pair[1].start.saturating_sub(2)).any(in_stance);
            (rest_frame(pair), loaded)
        })
        .collect();
    // The rest after the last contact too: a drifting stance that runs on into it has stretched the
    // last press over a preload it took for loaded.
    let n = floor.baseline.len();
    if let Some(last) = floor.stances.last()
        && !last.partial
        && last.end() + 2 < n
    {
        let loaded = (last.end() + 2..n - 1).any(in_stance);
        rests.push(((last.end() + n) / 2, loaded));
    }
    rests.windows(2).find_map(|pair| {
        let ((a, a_loaded), (b, b_loaded)) = (pair[0], pair[1]);
        let (inside, outside) = match (a_loaded, b_loaded) {
            (true, false) => (a, b),
            (false, true) => (b, a),
            _ => return None,
        };
        let (level, beside) = (floor.baseline[inside], floor.baseline[outside]);
        (level - lowest > floor.off_level && (level - beside).abs() < floor.on_level).then(|| {
            format!(
                "the load between presses rests at the same level at frames {inside} and \
                 {outside}, loaded for the drifting baseline at one and unloaded at the other (a \
                 preload): contacts measured from the local floor"
            )
        })
    })
}

/// The longest chain of the floor's contacts with loaded rests between them, as its number of rests
/// (see [`preload`]; `mixed`: the drifting baseline mixed two levels, and a rest above the `lowest`
/// one by the off level counts): a walking foot's heel and toe make two, with an unloaded swing
/// before the next pair.
fn longest_loaded_chain(
    drifting: &Segmentation,
    floor: &Segmentation,
    lowest: f64,
    mixed: bool,
) -> usize {
    let in_stance = |t: usize| drifting.stances.iter().any(|stance| stance.contains(t));
    let (mut loaded_rests, mut chain) = (0, 0);
    for pair in floor.stances.windows(2) {
        let t = rest_frame(pair);
        let above = |level: f64| floor.baseline[t] - level > floor.off_level;
        chain = if above(drifting.baseline[t]) || in_stance(t) || mixed && above(lowest) {
            chain + 1
        } else {
            0
        };
        loaded_rests = loaded_rests.max(chain);
    }
    loaded_rests
}

/// The first rest of the floor (the frames before its first contact, between two, or after its last;
/// at least `min_len` of them) whose median load lies below the drifting baseline by more than the
/// floor's off level, as `(first, last)` frames (exclusive end), or `None`.
fn sunk_rest(
    total_load: &[f64],
    drifting: &Segmentation,
    floor: &Segmentation,
    min_len: usize,
) -> Option<(usize, usize)> {
    let n = total_load.len();
    let mut edges = vec![0];
    for stance in &floor.stances {
        edges.push(stance.start);
        edges.push(stance.end());
    }
    edges.push(n);
    edges.chunks_exact(2).find_map(|gap| {
        let (first, last) = (gap[0], gap[1]);
        if last < first + min_len.max(1) {
            return None;
        }
        let mut below: Vec<f64> = (first..last)
            .map(|t| total_load[t] - drifting.baseline[t])
            .collect();
        (median(&mut below) < -floor.off_level).then_some((first, last))
    })
}

/// A prominent peak and the valleys before and after it (frame indices into the series).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Peak {
    pub valley_before: usize,
    pub peak: usize,
    pub valley_after: usize,
}

/// The peaks of `values` that rise at least `prominence` above the valley before them and fall at least
/// `prominence` below them again (or reach the end of the series), by hysteresis: a peak is confirmed once
/// the values have fallen `prominence` below it, a valley once they have risen `prominence` above it.
pub(crate) fn zigzag_peaks(values: &[f64], prominence: f64) -> Vec<Peak> {
    let mut peaks = Vec::new();
    let Some(&first) = values.first() else {
        return peaks;
    };
    let prominence = prominence.max(f64::MIN_POSITIVE);
    // The lowest frame since the last peak, and the highest since that valley was passed.
    let (mut valley, mut valley_value) = (0, first);
    let mut candidate: Option<(usize, f64)> = None;
    for (t, &v) in values.iter().enumerate() {
        match candidate {
            None => {
                if v < valley_value {
                    (valley, valley_value) = (t, v);
                } else if v - valley_value >= prominence {
                    candidate = Some((t, v));
                }
            }
            Some((peak, peak_value)) => {
                if v > peak_value {
                    candidate = Some((t, v));
                } else if peak_value - v >= prominence {
                    peaks.push(Peak {
                        valley_before: valley,
                        peak,
                        valley_after: t,
                    });
                    (valley, valley_value) = (t, v);
                    candidate = None;
                }
            }
        }
        // After a confirmation the valley keeps sinking until the next rise.
        if candidate.is_none()
            && let Some(last) = peaks.last_mut()
            && last.valley_after < t
            && v < values[last.valley_after]
        {
            last.valley_after = t;
        }
    }
    if let Some((peak, _)) = candidate {
        peaks.push(Peak {
            valley_before: valley,
            peak,
            valley_after: values.len() - 1,
        });
    }
    peaks
}

fn segment_floor(total_load: &[f64], params: &ValidSegmentParams) -> Segmentation {
    let drifting = segment_drifting(total_load, params);
    segment_floor_from(total_load, &drifting, params)
}

/// The flat stretch of load at the bottom of one valley between prominent peaks (or before the first
/// peak, or after the last): frames `first..=last`, whose load stays within the off level of the line
/// `level + slope x (t - centre)` fitted to them.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Rest {
    first: usize,
    last: usize,
    level: f64,
    slope: f64,
    centre: f64,
}

impl Rest {
    fn at(&self, t: usize) -> f64 {
        self.level + self.slope * (t as f64 - self.centre)
    }

    fn len(&self) -> usize {
        self.last + 1 - self.first
    }
}

/// Fewest frames a rest's floor is fitted as a line through (a constant, their median, for fewer). The line
/// is only ever read within one frame of the frames it was fitted to.
const MIN_LINE_FRAMES: usize = 3;
/// Fewest rest frames the noise is measured on (else the drifting segmentation's is kept).
const MIN_NOISE_FRAMES: usize = 12;

/// The least-squares line through `(t, values[t])` for `t` in `frames` as `(level, slope, centre)`; a
/// constant (the median) for fewer than [`MIN_LINE_FRAMES`] frames.
fn fit_floor(values: &[f64], frames: &[usize]) -> (f64, f64, f64) {
    if frames.len() < MIN_LINE_FRAMES {
        let mut loads: Vec<f64> = frames.iter().map(|&t| values[t]).collect();
        let centre = frames.iter().sum::<usize>() as f64 / frames.len().max(1) as f64;
        return (median(&mut loads), 0.0, centre);
    }
    let count = frames.len() as f64;
    let centre = frames.iter().map(|&t| t as f64).sum::<f64>() / count;
    let mean = frames.iter().map(|&t| values[t]).sum::<f64>() / count;
    let (sxy, sxx) = frames.iter().fold((0.0, 0.0), |(sxy, sxx), &t| {
        let dt = t as f64 - centre;
        (sxy + dt * (values[t] - mean), sxx + dt * dt)
    });
    (mean, if sxx > 0.0 { sxy / sxx } else { 0.0 }, centre)
}

/// The rest in `values[region]` (a non-empty range of frames between peaks): a line (or constant) is
/// fitted to the frames within `2 off` of the lowest one (a drifting rest spans more than `off`), then, until the set stops changing, to the frames
/// of the valley within `off` of that line (a set, not a run: a line fitted to the low frames of a
/// drifting rest is tilted, and a run cut where it leaves the off level would keep the tilt); the rest is
/// the run of frames around the lowest one within `off` of the last line, across excursions of fewer
/// than `bridge` frames that stay below `on`.
fn find_rest(
    values: &[f64],
    region: std::ops::Range<usize>,
    (on, off): (f64, f64),
    bridge: usize,
) -> Rest {
    let lowest = region.clone().fold(region.start, |best, t| {
        if values[t] < values[best] { t } else { best }
    });
    let mut frames: Vec<usize> = region
        .clone()
        .filter(|&t| values[t] <= values[lowest] + 2.0 * off)
        .collect();
    let mut rest = Rest {
        first: lowest,
        last: lowest,
        level: values[lowest],
        slope: 0.0,
        centre: lowest as f64,
    };
    for _ in 0..MAX_REST_ROUNDS {
        let (level, slope, centre) = fit_floor(values, &frames);
        rest = Rest {
            level,
            slope,
            centre,
            ..rest
        };
        let next: Vec<usize> = region
            .clone()
            .filter(|&t| (values[t] - rest.at(t)).abs() <= off || t == lowest)
            .collect();
        if next == frames {
            break;
        }
        frames = next;
    }
    let line = rest;
    let near = |t: usize| values[t] - line.at(t) <= off;
    // An excursion above the off level of fewer than `bridge` frames that stays below the on level and
    // comes back is noise, as in the drifting mode (it would be too short to be a stance).
    let noise_only = |frames: &mut dyn Iterator<Item = usize>| {
        let mut excursion = 0;
        for t in frames {
            if near(t) {
                return Some(t);
            }
            excursion += 1;
            if excursion >= bridge || values[t] - line.at(t) > on {
                return None;
            }
        }
        None
    };
    while rest.first > region.start
        && let Some(t) = noise_only(&mut (region.start..rest.first).rev())
    {
        rest.first = t;
    }
    while rest.last + 1 < region.end
        && let Some(t) = noise_only(&mut (rest.last + 1..region.end))
    {
        rest.last = t;
    }
    rest
}

/// Rounds of [`find_rest`]'s fit (it converges in a few).
const MAX_REST_ROUNDS: usize = 8;

/// The noise of the load on the rests: the larger of 1.4826 x the MAD of the residuals to their floor
/// lines and the RMS of the residuals below their median (a rest is cut above, at the off level, never
/// below, so its lower side is the whole noise); `None` for fewer than [`MIN_NOISE_FRAMES`] frames.
fn rest_noise(values: &[f64], rests: &[Option<Rest>]) -> Option<f64> {
    // Each residual scaled up for the degrees of freedom its rest's fit took (a line through 3 frames
    // leaves a third of their spread).
    let residuals: Vec<f64> = rests
        .iter()
        .flatten()
        .flat_map(|rest| {
            let fitted = if rest.len() >= MIN_LINE_FRAMES { 2 } else { 1 };
            let scale =
                (rest.len() as f64 / (rest.len().saturating_sub(fitted)).max(1) as f64).sqrt();
            (rest.first..=rest.last)
                .filter(move |_| rest.len() > fitted)
                .map(move |t| scale * (values[t] - rest.at(t)))
        })
        .collect();
    if residuals.len() < MIN_NOISE_FRAMES {
        return None;
    }
    let (centre, sigma) = super::robust::median_and_sigma(&mut residuals.clone());
    let (sum, count) = residuals
        .iter()
        .filter(|&&r| r < centre)
        .fold((0.0, 0usize), |(sum, count), &r| {
            (sum + (centre - r).powi(2), count + 1)
        });
    let lower = if count == 0 {
        0.0
    } else {
        (sum / count as f64).sqrt()
    };
    Some(sigma.max(lower))
}

/// The valleys around `peaks` (before the first, between each two, after the last; each possibly
/// empty) and the rest in each non-empty one ([`find_rest`]).
#[allow(clippy::type_complexity)]
fn rests_between(
    values: &[f64],
    peaks: &[usize],
    levels: (f64, f64),
    bridge: usize,
) -> (Vec<std::ops::Range<usize>>, Vec<Option<Rest>>) {
    let regions: Vec<std::ops::Range<usize>> = (0..=peaks.len())
        .map(|k| {
            let start = if k == 0 { 0 } else { peaks[k - 1] + 1 };
            let end = peaks.get(k).copied().unwrap_or(values.len());
            start..end
        })
        .collect();
    let rests = regions
        .iter()
        .map(|region| {
            (!region.is_empty()).then(|| find_rest(values, region.clone(), levels, bridge))
        })
        .collect();
    (regions, rests)
}

/// Contacts as prominent rises above the local floor (see the module docs). The noise starts from the
/// drifting segmentation's and is then measured on the rests; the returned baseline is the floor.
fn segment_floor_from(
    total_load: &[f64],
    drifting: &Segmentation,
    params: &ValidSegmentParams,
) -> Segmentation {
    let p = params.params();
    let n = total_load.len();
    let lowest = total_load.iter().copied().fold(f64::INFINITY, f64::min);
    let range = total_load.iter().copied().fold(lowest, f64::max) - lowest;
    let empty = Segmentation {
        stances: Vec::new(),
        mode: BaselineMode::Floor,
        mode_reason: None,
        ..drifting.clone()
    };
    if n == 0 || range <= 0.0 {
        return empty;
    }
    let (peaks, rests, noise) = prominent_peaks(total_load, p, range, drifting.noise);
    let (on, off) = floor_levels(p, noise, range);
    let peaks = peaks_above_their_rests(total_load, &peaks, &rests, on);
    if peaks.is_empty() {
        return empty;
    }
    let (regions, mut rests) = rests_between(total_load, &peaks, (on, off), p.min_stance_frames);
    drop_edge_rests_of_contacts(&mut rests, on);
    let (floor, spans) = floor_and_spans(total_load, &peaks, &regions, &rests, on, lowest, p);
    Segmentation {
        stances: stances_of_spans(total_load, spans, p.min_stance_frames),
        baseline: floor,
        noise,
        load_range: range,
        on_level: on,
        off_level: off,
        mode: BaselineMode::Floor,
        mode_reason: None,
    }
}

/// The on and off levels of the floor mode for `noise` and the load `range`.
fn floor_levels(p: &SegmentParams, noise: f64, range: f64) -> (f64, f64) {
    (
        (p.on_noise * noise).max(p.on_fraction * range),
        (p.off_noise * noise).max(p.off_fraction * range),
    )
}

/// The prominent peaks, the rests between them and the noise measured on those rests (`noise` if
/// they are too short to measure it on).
///
/// The peaks come from the load range alone (the drifting segmentation's noise may be inflated by a
/// preload it took for its baseline); the rests are found twice, since the first are cut at an off
/// level from the range alone, which may be below the noise.
fn prominent_peaks(
    total_load: &[f64],
    p: &SegmentParams,
    range: f64,
    mut noise: f64,
) -> (Vec<usize>, Vec<Option<Rest>>, f64) {
    let peaks: Vec<usize> = zigzag_peaks(total_load, p.on_fraction * range)
        .iter()
        .map(|peak| peak.peak)
        .collect();
    let (_, mut rests) = rests_between(
        total_load,
        &peaks,
        (p.on_fraction * range, p.off_fraction * range),
        p.min_stance_frames,
    );
    for _ in 0..2 {
        if let Some(sigma) = rest_noise(total_load, &rests) {
            noise = sigma;
        }
        rests = rests_between(
            total_load,
            &peaks,
            floor_levels(p, noise, range),
            p.min_stance_frames,
        )
        .1;
    }
    (peaks, rests, noise)
}

/// The `peaks` that rise more than `on` above the rests on both sides of them (`rests[k]` before peak
/// `k`, `rests[k + 1]` after it; a side without a rest does not count).
fn peaks_above_their_rests(
    total_load: &[f64],
    peaks: &[usize],
    rests: &[Option<Rest>],
    on: f64,
) -> Vec<usize> {
    peaks
        .iter()
        .enumerate()
        .filter(|&(k, &peak)| {
            let floors = [
                rests[k].map(|r| r.at(r.last)),
                rests[k + 1].map(|r| r.at(r.first)),
            ];
            floors
                .iter()
                .flatten()
                .all(|&floor| total_load[peak] - floor > on)
        })
        .map(|(_, &peak)| peak)
        .collect()
}

/// A recording that starts (ends) rising into (falling from) a contact has no rest before (after) it:
/// its first (last) "rest" is then higher than the next (previous) one by more than the `on` level,
/// and is dropped so that that one's floor is used instead.
fn drop_edge_rests_of_contacts(rests: &mut [Option<Rest>], on: f64) {
    let last = rests.len() - 1;
    if rests.len() >= 3 {
        for (edge, inner, at_edge) in [(0, 1, true), (last, last - 1, false)] {
            if let (Some(e), Some(i)) = (rests[edge], rests[inner]) {
                let (edge_level, inner_level) = if at_edge {
                    (e.at(e.last), i.at(i.first))
                } else {
                    (e.at(e.first), i.at(i.last))
                };
                if edge_level > inner_level + on {
                    rests[edge] = None;
                }
            }
        }
    }
}

/// The floor under every frame and the presses as spans of frames `(start, end)`: each press from
/// the frame after the rest before it to the frame before the rest after it, presses split by a rest
/// of at most `max_gap_frames` merged. Under a press the floor is the rest before it up to its peak
/// and the rest after it from there (either one where the other is missing, `lowest` without both).
fn floor_and_spans(
    total_load: &[f64],
    peaks: &[usize],
    regions: &[std::ops::Range<usize>],
    rests: &[Option<Rest>],
    on: f64,
    lowest: f64,
    p: &SegmentParams,
) -> (Vec<f64>, Vec<(usize, usize)>) {
    let mut floor = vec![0.0; total_load.len()];
    let mut spans: Vec<(usize, usize)> = Vec::new();
    // A recording that starts falling from a contact: no peak of its own, the frames before the first
    // rest rise above it by the on level.
    if let Some(rest) = rests[0]
        && rest.first > 0
        && (0..rest.first).any(|t| total_load[t] - rest.at(rest.first) > on)
    {
        spans.push((0, rest.first));
        for slot in floor.iter_mut().take(rest.first) {
            *slot = rest.at(rest.first);
        }
    }
    for (k, &peak) in peaks.iter().enumerate() {
        let before = rests[k];
        let after = rests[k + 1];
        let start = before.map_or(regions[k].start, |r| r.last + 1);
        let end = after.map_or(regions[k + 1].end, |r| r.first);
        let rising = before
            .map(|r| r.at(r.last))
            .or(after.map(|r| r.at(r.first)))
            .unwrap_or(lowest);
        let falling = after
            .map(|r| r.at(r.first))
            .or(before.map(|r| r.at(r.last)))
            .unwrap_or(lowest);
        for (t, slot) in floor.iter_mut().enumerate().take(end).skip(start) {
            *slot = if t <= peak { rising } else { falling };
        }
        // A rest no longer than max_gap_frames is a dropout inside one contact.
        match (spans.last_mut(), before) {
            (Some(span), Some(rest)) if rest.len() <= p.max_gap_frames && span.1 == rest.first => {
                span.1 = end;
            }
            _ => spans.push((start, end)),
        }
    }
    for rest in rests.iter().flatten() {
        for (t, slot) in floor
            .iter_mut()
            .enumerate()
            .take(rest.last + 1)
            .skip(rest.first)
        {
            *slot = rest.at(t);
        }
    }
    (floor, spans)
}

/// The stances of the `spans` at least `min_stance_frames` long, each with its peak (the first
/// highest frame), partial if it touches either end of the recording.
fn stances_of_spans(
    total_load: &[f64],
    spans: Vec<(usize, usize)>,
    min_stance_frames: usize,
) -> Vec<Stance> {
    let n = total_load.len();
    spans
        .into_iter()
        .filter(|&(start, end)| end - start >= min_stance_frames)
        .map(|(start, end)| {
            let peak_frame = (start..end).fold(start, |best, t| {
                if total_load[t] > total_load[best] {
                    t
                } else {
                    best
                }
            });
            Stance {
                start,
                len: end - start,
                peak_load: total_load[peak_frame],
                peak_frame,
                partial: start == 0 || end == n,
            }
        })
        .collect()
}

/// The whole recording as one stance, partial at both ends (see the module docs). No stance for fewer
/// than [`MIN_CONTACT_FRAMES`] frames or a recording that carries no load.
fn segment_contact(total_load: &[f64]) -> Segmentation {
    let n = total_load.len();
    let lowest = total_load.iter().copied().fold(f64::INFINITY, f64::min);
    let base = if n == 0 { 0.0 } else { lowest.min(0.0) };
    let peak_frame = (0..n).fold(0, |best, t| {
        if total_load[t] > total_load[best] {
            t
        } else {
            best
        }
    });
    let load_range = total_load.get(peak_frame).map_or(0.0, |&peak| peak - base);
    let stances = if n >= MIN_CONTACT_FRAMES && load_range > 0.0 {
        vec![Stance {
            start: 0,
            len: n,
            peak_load: total_load[peak_frame],
            peak_frame,
            partial: true,
        }]
    } else {
        Vec::new()
    };
    Segmentation {
        stances,
        baseline: vec![base; n],
        noise: 0.0,
        load_range,
        on_level: 0.0,
        off_level: 0.0,
        mode: BaselineMode::Contact,
        mode_reason: None,
    }
}

/// Drops the stances longer than `max` frames (the limit of
/// [`SegmentParams::max_stance_frames`](super::SegmentParams::max_stance_frames)); a one-contact
/// recording's stance is the recording and is kept.
fn drop_too_long(mut segmentation: Segmentation, max: Option<usize>) -> Segmentation {
    if let Some(max) = max
        && segmentation.mode != BaselineMode::Contact
    {
        segmentation.stances.retain(|stance| stance.len <= max);
    }
    segmentation
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stances_of_spans_keep_long_spans_with_their_first_peak() {
        let load = [0.0, 3.0, 5.0, 5.0, 1.0, 0.0, 2.0, 0.0, 4.0, 6.0];
        let stances = stances_of_spans(&load, vec![(0, 4), (5, 7), (7, 10)], 3);
        // (5, 7) is too short; the first span touches the start, the last the end.
        let summary: Vec<_> = stances
            .iter()
            .map(|s| (s.start, s.len, s.peak_frame, s.peak_load, s.partial))
            .collect();
        assert_eq!(summary, vec![(0, 4, 2, 5.0, true), (7, 3, 9, 6.0, true)]);
        let inside = stances_of_spans(&load, vec![(1, 4)], 3);
        assert!(!inside[0].partial);
    }

    #[test]
    fn an_edge_rest_above_its_neighbour_by_the_on_level_is_dropped() {
        let rest = |first: usize, level| {
            Some(Rest {
                first,
                last: first + 2,
                level,
                slope: 0.0,
                centre: first as f64,
            })
        };
        let mut rests = vec![rest(0, 50.0), rest(10, 0.0), rest(20, 5.0)];
        drop_edge_rests_of_contacts(&mut rests, 10.0);
        assert_eq!(rests[0], None, "rising into a contact at the start");
        assert!(
            rests[1].is_some() && rests[2].is_some(),
            "within the on level"
        );
        // Two rests (one contact): nothing to compare an edge with.
        let mut two = vec![rest(0, 50.0), rest(10, 0.0)];
        drop_edge_rests_of_contacts(&mut two, 10.0);
        assert!(two[0].is_some());
    }

    #[test]
    fn zigzag_finds_prominent_peaks_only() {
        let values = [0.0, 5.0, 10.0, 4.0, 6.0, 3.0, 12.0, 11.0, 2.0, 2.5, 9.0];
        let peaks = zigzag_peaks(&values, 5.0);
        let at: Vec<usize> = peaks.iter().map(|p| p.peak).collect();
        // 6 at frame 4 rises only 2 above the valley at 3: not a peak; the last rise reaches the end.
        assert_eq!(at, vec![2, 6, 10]);
        assert_eq!(peaks[0].valley_before, 0);
        assert_eq!(peaks[0].valley_after, 5);
        assert_eq!(peaks[1].valley_after, 8);
        assert!(zigzag_peaks(&[], 1.0).is_empty());
        assert!(zigzag_peaks(&[3.0; 5], 1.0).is_empty());
    }
}
