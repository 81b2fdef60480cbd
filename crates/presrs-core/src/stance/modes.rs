//! What the stances rise above, and the automatic choice of it ([`segment`]).
//!
//! The drifting baseline ([`super::offline`]) assumes the foot fully unloads between contacts. Two kinds
//! of real recordings break that assumption:
//!
//! - **A standing preload with presses or steps on top** (a foot that never leaves the sensor): the load
//!   between presses stays far above the unloaded level, so every frame after the first contact is
//!   "loaded" and the whole recording is one stance. The [`BaselineMode::Floor`] mode measures each
//!   contact from the *local floor* instead: the load's prominent peaks and valleys are found by
//!   hysteresis (a peak counts once the load has risen by the on level above the valley before it and
//!   fallen by it again), the floor is the valley before a peak on its rising side and the valley after
//!   it on its falling side, and the
//!   contact is the run of frames around the peak above that floor by more than the off level.
//! - **A trial cut to one contact** (loaded from its first frame to its last, no swing in the file):
//!   there is no unloaded frame to measure a baseline on. [`BaselineMode::Contact`] makes the whole
//!   recording one stance, partial at both ends (its touchdown and lift-off are not in the file); the
//!   baseline is 0 (pressure readings are not negative), or the lowest reading if that is negative.
//!
//! [`BaselineMode::Auto`] (the default) decides from the data, in this order:
//! 1. *the floor* when a stance of the drifting baseline holds at least [`PRELOAD_PEAKS`] prominent
//!    peaks whose valleys stay loaded (a foot's contact has at most two, heel and toe), or is longer
//!    than [`SegmentParams::max_stance_frames`](super::SegmentParams::max_stance_frames);
//! 2. *one contact* when the drifting baseline finds no complete stance while the load stays above
//!    [`CONTACT_FRACTION`] of its range on every frame but a few at the ends (at most
//!    [`CONTACT_END_FRACTION`] of the frames at each end, and at least [`MIN_CONTACT_FRAMES`] frames
//!    loaded);
//! 3. the drifting baseline otherwise (the paper's hopper, walking, the simulator: unchanged).

use super::offline::{
    BaselineMode, Segmentation, Stance, ValidSegmentParams, check_finite, segment_drifting,
};
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
/// A stance of the drifting baseline holding this many prominent peaks over loaded valleys is presses
/// on a preload.
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
    if let Some(reason) = preload(total_load, &drifting, params) {
        return Segmentation {
            mode_reason: Some(reason),
            ..segment_floor_from(total_load, &drifting, params)
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

/// Why the drifting segmentation's stances look like presses on a preload, or `None`.
fn preload(
    total_load: &[f64],
    drifting: &Segmentation,
    params: &ValidSegmentParams,
) -> Option<String> {
    let max_len = params.params().max_stance_frames;
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
        let above: Vec<f64> = (stance.start..stance.end())
            .map(|t| total_load[t] - drifting.baseline[t])
            .collect();
        let peaks = zigzag_peaks(&above, drifting.on_level);
        let loaded_valleys = peaks
            .windows(2)
            .filter(|pair| {
                let valley = above[pair[0].peak..pair[1].peak]
                    .iter()
                    .copied()
                    .fold(f64::INFINITY, f64::min);
                valley > drifting.off_level
            })
            .count();
        (loaded_valleys + 1 >= PRELOAD_PEAKS).then(|| {
            format!(
                "the stance at frames {}..{} holds {} presses that never unload (the load between \
                 them stays above the off level): contacts measured from the local floor",
                stance.start,
                stance.end(),
                loaded_valleys + 1
            )
        })
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

/// Contacts as prominent rises above the local floor (see the module docs). The unloaded level, its
/// noise and the load range (hence the on and off levels) are those of the drifting segmentation; the
/// returned baseline is the floor.
fn segment_floor_from(
    total_load: &[f64],
    drifting: &Segmentation,
    params: &ValidSegmentParams,
) -> Segmentation {
    let p = params.params();
    let n = total_load.len();
    let above: Vec<f64> = total_load
        .iter()
        .zip(&drifting.baseline)
        .map(|(load, base)| load - base)
        .collect();
    let (on, off) = (drifting.on_level, drifting.off_level);
    let mut floor = vec![0.0; n];
    let mut stances = Vec::new();
    let peaks = if drifting.load_range > 0.0 {
        zigzag_peaks(&above, on)
    } else {
        Vec::new()
    };
    for (i, peak) in peaks.iter().enumerate() {
        // The floor under this peak: the valley before it on its rising side, the valley after it on its
        // falling side (never below the unloaded level). A step, not a line through the valleys: a first
        // press onto a preload starts from zero and ends on the preload, and a line between the two
        // would leave its tail above the floor until the next press.
        let (a, b) = (peak.valley_before, peak.valley_after);
        let level = |t: usize| {
            if t <= peak.peak {
                above[a].max(0.0)
            } else {
                above[b].max(0.0)
            }
        };
        // Frames between this peak's valleys belong to it; the valley frames themselves are shared.
        let lo = if i == 0 { 0 } else { a };
        let hi = if i + 1 == peaks.len() { n } else { b + 1 };
        for (t, slot) in floor.iter_mut().enumerate().take(hi).skip(lo) {
            *slot = level(t);
        }
        if above[peak.peak] - level(peak.peak) <= on {
            continue;
        }
        let loaded = |t: usize| above[t] - level(t) > off;
        let (mut start, mut end) = (peak.peak, peak.peak + 1);
        // Grow the contact around the peak across dropouts of at most max_gap frames, within its valleys.
        while let Some(next) = (1..=p.max_gap_frames + 1)
            .filter_map(|step| start.checked_sub(step))
            .filter(|&t| t >= lo)
            .find(|&t| loaded(t))
        {
            start = next;
        }
        while let Some(next) = (end..(end + p.max_gap_frames + 1).min(hi)).find(|&t| loaded(t)) {
            end = next + 1;
        }
        let len = end - start;
        if len < p.min_stance_frames {
            continue;
        }
        let peak_frame = (start..end).fold(start, |best, t| {
            if total_load[t] > total_load[best] {
                t
            } else {
                best
            }
        });
        stances.push(Stance {
            start,
            len,
            peak_load: total_load[peak_frame],
            peak_frame,
            partial: start == 0 || end == n,
        });
    }
    Segmentation {
        stances,
        baseline: floor
            .iter()
            .zip(&drifting.baseline)
            .map(|(f, base)| f + base)
            .collect(),
        mode: BaselineMode::Floor,
        mode_reason: None,
        ..drifting.clone()
    }
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
