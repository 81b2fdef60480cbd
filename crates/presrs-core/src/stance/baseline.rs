//! The drifting baseline of a recording's total load and the noise about it: step 1 of the offline
//! segmentation (see [`super::offline`]). Blocks of about a window each give a low quantile, interpolated
//! between their centres; the unloaded frames are then found by sigma clipping (grown upwards from the
//! low tail of the recording and of every block, then one symmetric pass), the baseline refitted to them
//! as the set changes.

use super::robust::{median, median_and_sigma, quantile};

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

/// Per-frame baseline and the baseline noise sigma (see the module docs and step 1 of
/// [`super::offline`]). `values` must be finite.
pub(super) fn estimate_baseline(
    values: &[f64],
    window: usize,
    quantile_level: f64,
    off_fraction: f64,
) -> (Vec<f64>, f64) {
    let n = values.len();
    if n == 0 {
        return (Vec::new(), 0.0);
    }
    let mut scratch = Vec::with_capacity(n);
    let fit = BaselineFit::coarse(values, window, quantile_level, &mut scratch);

    // Sigma clipping from the low tail upwards, refitting the baseline to the unloaded frames each round:
    // the unloaded frames are the cluster at the bottom once the baseline's drift is removed.
    let residual: Vec<f64> = values.iter().zip(&fit.coarse).map(|(v, c)| v - c).collect();
    let mut quiet = lowest_frames(&residual, quantile_level, &mut scratch);
    if fit.bounds.len() > 1 {
        add_each_blocks_lowest(
            &mut quiet,
            &residual,
            &fit.bounds,
            quantile_level,
            &mut scratch,
        );
    }
    let mut clip = SigmaClip {
        baseline: fit.coarse.clone(),
        fit,
        residual,
        quiet,
        sigma: 0.0,
        // Rounding noise of an exactly linear baseline must not count as structure.
        floor: 1e-12 * values.iter().fold(0.0, |m: f64, v| m.max(v.abs())),
        scratch,
    };
    // Two phases. Growing: a low tail's MAD underestimates the noise (the tail is narrower than the
    // cluster), so a symmetric 3-sigma clip can stall at the bottom; instead every frame below
    // median + GROW_SIGMAS x sigma (or below the off level) joins the set (nothing real lies below the
    // baseline), and the set only grows. Refining: one symmetric CLIP_SIGMAS clip around the median, which
    // drops the stance edges the generous growth let in.
    clip.grow(off_fraction);
    clip.refine();
    let SigmaClip {
        mut baseline,
        sigma,
        ..
    } = clip;
    // The unloaded level is never below the lowest reading: a line fitted to a block can dip under it at
    // the block's end (a sensor that reads 0 in swing got a baseline of -1.8 there, and frames of total
    // load 0 were "1.8 above the baseline").
    let lowest = values.iter().copied().fold(f64::INFINITY, f64::min);
    for level in &mut baseline {
        *level = level.max(lowest);
    }
    (baseline, sigma)
}

/// The frames the clipping starts from: the lowest `quantile_level` of the `residual`s, but enough of
/// them that a median, a MAD and a line fitted to them mean something (two points fit a line exactly,
/// with zero "noise").
fn lowest_frames(residual: &[f64], quantile_level: f64, scratch: &mut Vec<f64>) -> Vec<bool> {
    let n = residual.len();
    scratch.clear();
    scratch.extend_from_slice(residual);
    scratch.sort_unstable_by(f64::total_cmp);
    let start_count = ((quantile_level * n as f64).ceil() as usize).max(MIN_START_FRAMES);
    let start_cut = scratch[start_count.min(n) - 1];
    residual.iter().map(|&r| r <= start_cut).collect()
}

/// Adds to `quiet` the lowest frames of every block (of `bounds`) that has fewer than
/// [`MIN_QUIET_PER_BLOCK`] of them.
///
/// Every block starts with its own lowest frames: under a strong drift the coarse baseline of the
/// last block (its low quantile taken at the block's low end, then extrapolated) lay below all its
/// swings (a walk drifting down 0.49 a frame: 30 counts low at its centre); the block got no frame
/// of the global start set, its level was corrected by the other blocks' median, the growth never
/// reached its swings (they stayed above the limit), and its last stances merged into one.
fn add_each_blocks_lowest(
    quiet: &mut [bool],
    residual: &[f64],
    bounds: &[(usize, usize)],
    quantile_level: f64,
    scratch: &mut Vec<f64>,
) {
    for &(start, end) in bounds {
        if (start..end).filter(|&t| quiet[t]).count() >= MIN_QUIET_PER_BLOCK {
            continue;
        }
        let count = ((quantile_level * (end - start) as f64).ceil() as usize)
            .max(MIN_QUIET_PER_BLOCK)
            .min(end - start);
        scratch.clear();
        scratch.extend_from_slice(&residual[start..end]);
        let cut = quantile(
            scratch,
            (count - 1) as f64 / (end - start - 1).max(1) as f64,
        );
        for t in start..end {
            quiet[t] |= residual[t] <= cut;
        }
    }
}

/// The state of the sigma clipping of [`estimate_baseline`]: the baseline fitted to the `quiet`
/// (unloaded) frames, the residuals above it, and the noise sigma measured on the quiet ones.
struct SigmaClip<'a> {
    fit: BaselineFit<'a>,
    baseline: Vec<f64>,
    residual: Vec<f64>,
    quiet: Vec<bool>,
    sigma: f64,
    /// The smallest noise counted (rounding noise of an exactly linear baseline is not structure).
    floor: f64,
    scratch: Vec<f64>,
}

impl SigmaClip<'_> {
    /// The growing phase: rounds of [`grown_set`](Self::grown_set) until the set stops changing (or
    /// would be empty), at most [`MAX_CLIP_ROUNDS`].
    fn grow(&mut self, off_fraction: f64) {
        for _ in 0..MAX_CLIP_ROUNDS {
            let Some(centre) = self.refit_and_measure() else {
                break;
            };
            let next = self.grown_set(centre, off_fraction);
            if next == self.quiet || !next.contains(&true) {
                break;
            }
            self.quiet = next;
        }
    }

    /// The refining phase: one symmetric [`CLIP_SIGMAS`] clip around the median, then the baseline
    /// refitted and the noise measured once more. One pass only: iterated clipping of a finite sample
    /// shrinks the MAD round after round (each pass trims the tails the previous estimate made look
    /// too far).
    fn refine(&mut self) {
        let Some(centre) = self.refit_and_measure() else {
            return;
        };
        let lower_bound = lower_sigma(&self.residual, &self.quiet, centre, self.sigma);
        let width = CLIP_SIGMAS * self.sigma.max(self.floor);
        let next: Vec<bool> = self
            .residual
            .iter()
            .map(|&r| (r - centre).abs() <= width)
            .collect();
        if next == self.quiet || !next.contains(&true) {
            return;
        }
        self.quiet = next;
        self.baseline = self.fit.refit(&self.quiet, &mut self.scratch);
        self.scratch.clear();
        self.scratch.extend(
            self.fit
                .values
                .iter()
                .zip(&self.baseline)
                .zip(&self.quiet)
                .filter(|&(_, &q)| q)
                .map(|((v, b), _)| v - b),
        );
        if !self.scratch.is_empty() {
            self.sigma = median_and_sigma(&mut self.scratch).1;
        }
        // The MAD of a few dozen frames varies by a quarter either way, and noise frames beside
        // a stance then join it when it comes out low; the RMS below the centre varies half as
        // much and cannot hold a stance's edge.
        self.sigma = self.sigma.max(lower_bound);
    }

    /// Refits the baseline to the quiet frames, updates the residuals, and measures the median and
    /// noise sigma of the quiet residuals: the median, `None` without quiet frames.
    fn refit_and_measure(&mut self) -> Option<f64> {
        self.baseline = self.fit.refit(&self.quiet, &mut self.scratch);
        for ((r, v), b) in self
            .residual
            .iter_mut()
            .zip(self.fit.values)
            .zip(&self.baseline)
        {
            *r = v - b;
        }
        self.scratch.clear();
        self.scratch.extend(
            self.residual
                .iter()
                .zip(&self.quiet)
                .filter(|&(_, &q)| q)
                .map(|(r, _)| *r),
        );
        if self.scratch.is_empty() {
            return None;
        }
        let centre;
        (centre, self.sigma) = median_and_sigma(&mut self.scratch);
        Some(centre)
    }

    /// The next set while growing: the quiet frames and every frame up to the limit above `centre`.
    fn grown_set(&self, centre: f64, off_fraction: f64) -> Vec<bool> {
        let (residual, quiet, sigma) = (&self.residual, &self.quiet, self.sigma);
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
            rms_within(residual, quiet, centre, glitch).min(3.0 * sigma)
        } else {
            0.0
        };
        let spread = sigma
            .max(lower_sigma_within(residual, quiet, centre, glitch))
            .max(set_rms);
        let limit = centre + (GROW_SIGMAS * spread.max(self.floor)).max(off_fraction * range);
        residual
            .iter()
            .zip(quiet)
            .map(|(&r, &q)| q || r <= limit)
            .collect()
    }
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

impl<'a> BaselineFit<'a> {
    /// The first, coarse fit of `values` (not empty): blocks of about `window` frames, each block's
    /// `quantile_level` quantile as its level at its centre, interpolated between the centres.
    fn coarse(
        values: &'a [f64],
        window: usize,
        quantile_level: f64,
        scratch: &mut Vec<f64>,
    ) -> Self {
        let n = values.len();
        // Blocks of about `window` frames; at most n blocks since window >= 1, so none is empty.
        let blocks = ((n + window / 2) / window).clamp(1, n);
        let bounds: Vec<(usize, usize)> = (0..blocks)
            .map(|b| (b * n / blocks, (b + 1) * n / blocks))
            .collect();
        let levels: Vec<f64> = bounds
            .iter()
            .map(|&(start, end)| {
                scratch.clear();
                scratch.extend_from_slice(&values[start..end]);
                quantile(scratch, quantile_level)
            })
            .collect();
        let centres: Vec<f64> = bounds
            .iter()
            .map(|&(start, end)| (start + end - 1) as f64 / 2.0)
            .collect();
        let coarse = interpolate(&centres, &levels, n);
        Self {
            values,
            bounds,
            centres,
            levels,
            coarse,
        }
    }

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
    fn the_start_set_is_the_low_tail_but_at_least_min_start_frames() {
        let residual: Vec<f64> = (0..100).map(|t| ((t * 61) % 100) as f64).collect();
        let mut scratch = Vec::new();
        // 20 % of 100 frames: the 20 lowest.
        let quiet = lowest_frames(&residual, 0.2, &mut scratch);
        assert_eq!(quiet.iter().filter(|&&q| q).count(), 20);
        assert!(residual.iter().zip(&quiet).all(|(&r, &q)| q == (r < 20.0)));
        // 1 %: still MIN_START_FRAMES of them.
        let quiet = lowest_frames(&residual, 0.01, &mut scratch);
        assert_eq!(quiet.iter().filter(|&&q| q).count(), MIN_START_FRAMES);
        // Fewer frames than that: all of them.
        assert_eq!(
            lowest_frames(&[3.0, 1.0], 0.1, &mut scratch),
            vec![true, true]
        );
    }

    #[test]
    fn a_block_without_enough_quiet_frames_gets_its_own_lowest() {
        // Two blocks of 20: the first has its 5 quiet frames, the second none; it gets its lowest
        // MIN_QUIET_PER_BLOCK (10 % of 20 is 2, fewer).
        let residual: Vec<f64> = (0..40).map(|t| (t * 7 % 20) as f64).collect();
        let mut quiet: Vec<bool> = (0..40).map(|t| t < 5).collect();
        let before = quiet.clone();
        let bounds = [(0, 20), (20, 40)];
        add_each_blocks_lowest(&mut quiet, &residual, &bounds, 0.1, &mut Vec::new());
        assert_eq!(quiet[..20], before[..20], "the first block is left alone");
        let added: Vec<usize> = (20..40).filter(|&t| quiet[t]).collect();
        assert_eq!(added.len(), MIN_QUIET_PER_BLOCK);
        assert!(
            added
                .iter()
                .all(|&t| residual[t] < MIN_QUIET_PER_BLOCK as f64),
            "{added:?}"
        );
    }

    #[test]
    fn baseline_of_a_constant_is_the_constant_without_noise() {
        let (baseline, noise) = estimate_baseline(&[5.0; 300], 128, 0.1, 0.01);
        assert!(baseline.iter().all(|&b| (b - 5.0).abs() < 1e-12));
        assert_eq!(noise, 0.0);
    }
}
