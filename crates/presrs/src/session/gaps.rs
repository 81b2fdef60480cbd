//! Frames missing from the input, seen in the frames' own times: a step between two accepted frames
//! well above the frame period (a publisher restarted during a step, a burst lost on the way). The
//! decisions and lift-offs of stances with such a gap say how many frames are missing
//! (`gap_frames`), so that no face takes a stance with a hole for a whole one.

use std::collections::VecDeque;

use super::events::SessionEvent;

/// Steps between frames kept for the frame period (their median).
const PERIOD_WINDOW: usize = 15;
/// Steps needed before the period is trusted.
const MIN_STEPS: usize = 3;
/// A step this many frame periods long or more is a gap (a single missing frame makes a step of 2
/// periods; jitter of up to 3/4 of a period is not one).
const GAP_RATIO: f64 = 1.75;
/// Gaps remembered for the stances still open (each a stance's worth is far fewer).
const GAPS_KEPT: usize = 1024;

/// The gaps in one session's accepted frames, from their times.
#[derive(Debug, Default)]
pub struct FrameGaps {
    /// The last accepted frame's time.
    last_us: Option<u64>,
    /// Recent steps that were not gaps, µs.
    steps: VecDeque<u64>,
    /// (accepted frame index, frames missing just before it).
    gaps: VecDeque<(u64, u64)>,
}

impl FrameGaps {
    /// Accepted frame `index` came at `timestamp_us` (`None`: the input gives no times, so nothing
    /// is known across it). Returns the frames missing just before it.
    pub fn frame(&mut self, index: u64, timestamp_us: Option<u64>) -> u64 {
        let previous = std::mem::replace(&mut self.last_us, timestamp_us);
        let (Some(previous), Some(now)) = (previous, timestamp_us) else {
            return 0;
        };
        // Times that go back (a publisher restarted with its own clock) say nothing about a gap.
        let Some(step) = now.checked_sub(previous) else {
            return 0;
        };
        let missing = self
            .period_us()
            .map_or(0, |period| missing_frames(step, period));
        if missing > 0 {
            if self.gaps.len() == GAPS_KEPT {
                self.gaps.pop_front();
            }
            self.gaps.push_back((index, missing));
        } else {
            if self.steps.len() == PERIOD_WINDOW {
                self.steps.pop_front();
            }
            self.steps.push_back(step);
        }
        missing
    }

    /// The frame period: the median of the recent steps, once there are enough.
    fn period_us(&self) -> Option<u64> {
        if self.steps.len() < MIN_STEPS {
            return None;
        }
        let mut sorted: Vec<u64> = self.steps.iter().copied().collect();
        sorted.sort_unstable();
        Some(sorted[sorted.len() / 2]).filter(|&period| period > 0)
    }

    /// Frames missing between accepted frame `first` and accepted frame `last` (both included in the
    /// span: gaps just before frames `first + 1 ..= last`).
    pub fn missing_within(&self, first: u64, last: u64) -> u64 {
        self.gaps
            .iter()
            .filter(|&&(index, _)| index > first && index <= last)
            .map(|&(_, missing)| missing)
            .sum()
    }

    /// Puts the frames missing inside its stance on a decision (up to its sample frame) or a lift-off
    /// (up to the stance's last frame); other events are left as they are.
    pub fn mark(&self, event: &mut SessionEvent) {
        match event {
            SessionEvent::Classification(decision) => {
                decision.gap_frames =
                    self.missing_within(decision.touchdown_frame, decision.sample_frame);
            }
            SessionEvent::Liftoff(liftoff) => {
                let last = liftoff.end_frame.saturating_sub(1);
                liftoff.gap_frames = self.missing_within(liftoff.touchdown_frame, last);
            }
            _ => {}
        }
    }
}

/// The frames missing in a step of `step` µs at `period` µs a frame (0 when it is not a gap).
fn missing_frames(step: u64, period: u64) -> u64 {
    let periods = step as f64 / period as f64;
    if periods < GAP_RATIO {
        return 0;
    }
    (periods.round() as u64).saturating_sub(1).max(1)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fed(times_ms: &[u64]) -> (FrameGaps, Vec<u64>) {
        let mut gaps = FrameGaps::default();
        let missing = times_ms
            .iter()
            .enumerate()
            .map(|(i, &t)| gaps.frame(i as u64, Some(t * 1000)))
            .collect();
        (gaps, missing)
    }

    #[test]
    fn a_step_of_several_periods_is_that_many_frames_missing() {
        // 10 ms a frame; frame 5 comes 21 periods after frame 4: 20 frames missing before it.
        let (gaps, missing) = fed(&[0, 10, 20, 30, 40, 250, 260, 270]);
        assert_eq!(missing, [0, 0, 0, 0, 0, 20, 0, 0]);
        assert_eq!(gaps.missing_within(0, 7), 20);
        assert_eq!(gaps.missing_within(5, 7), 0, "the gap is before frame 5");
        assert_eq!(gaps.missing_within(4, 5), 20);
        assert_eq!(gaps.missing_within(0, 4), 0);
    }

    #[test]
    fn jitter_is_not_a_gap_and_one_missing_frame_is() {
        let (_, missing) = fed(&[0, 10, 20, 30, 46, 50, 60, 80, 90]);
        assert_eq!(missing, [0, 0, 0, 0, 0, 0, 0, 1, 0]);
    }

    #[test]
    fn no_times_or_times_going_back_say_nothing() {
        let mut gaps = FrameGaps::default();
        for (i, t) in [Some(0), Some(10), Some(20), Some(30), None, Some(500)]
            .into_iter()
            .enumerate()
        {
            assert_eq!(gaps.frame(i as u64, t.map(|ms| ms * 1000)), 0);
        }
        let (_, missing) = fed(&[100, 110, 120, 130, 5, 15]);
        assert_eq!(missing, [0; 6]);
    }
}
