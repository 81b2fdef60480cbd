//! The fast MiniRocket transform (the paper's formulation): per dilation, each channel's sum of its
//! nine taps `A = -(x[t - 4d] + ... + x[t + 4d])` is computed once and shared by the 84 kernels; a
//! kernel with `+2` at taps `a, b, c` is then `A + 3 x[t + (a - 4) d] + 3 x[t + (b - 4) d] + 3 x[t +
//! (c - 4) d]` (-1 + 3 = 2), summed over its channels, and each of its biases counts the outputs above
//! it. The sums and the counts are the SIMD kernels of `kernels::rocket`.
//!
//! The sums are those of the definition in another order, so an output can differ from the oracle's
//! in its last bits; a feature changes only if such an output lies within that rounding of a bias.

use std::ops::Range;

use rayon::prelude::*;

use super::kernels::{KERNEL_LENGTH, KERNEL_TAPS};
use super::model::{Combination, RocketModel};
use crate::error::{CoreError, Result, check_len};
use crate::kernels::{count_greater, sum_at_offsets};

/// Convolution outputs are computed and counted in whole multiples of this (the most f64 lanes of a
/// register, AVX-512's 8), so the kernels never fall back to their scalar tails; the outputs past the
/// counted ones are set to -inf, which is above no bias. The rows keep this much slack at their end for
/// the reads of those extra outputs.
const ROUND: usize = 8;

fn rounded(len: usize) -> usize {
    len.div_ceil(ROUND) * ROUND
}

/// The buffers of one transform: the sample padded with zeros (as is and tripled), each channel's
/// nine-tap sums at one dilation, one convolution output and its counts. Made for a model by
/// [`RocketModel::scratch`]; any scratch works with any model (it grows when it must, the only
/// allocation of a transform).
#[derive(Clone, Debug, Default)]
pub struct RocketScratch {
    /// Rows of `width` values: `channels` rows of the series, then `channels` rows of three times it,
    /// each with `pad` zeros before and after; then `channels` rows of `length` tap sums.
    rows: Vec<f64>,
    conv: Vec<f64>,
    offsets: Vec<usize>,
    counts: Vec<u64>,
    channels: usize,
    length: usize,
    pad: usize,
}

impl RocketScratch {
    /// Sizes the buffers for `channels x length` series and dilations up to `max_dilation`.
    fn prepare(
        &mut self,
        channels: usize,
        length: usize,
        max_dilation: usize,
        max_features: usize,
    ) {
        self.channels = channels;
        self.length = length;
        self.pad = (KERNEL_LENGTH / 2) * max_dilation;
        let rows = 2 * channels * self.width() + channels * length + ROUND;
        if self.rows.len() < rows {
            self.rows.resize(rows, 0.0);
        }
        if self.conv.len() < rounded(length) {
            self.conv.resize(rounded(length), 0.0);
        }
        if self.counts.len() < max_features {
            self.counts.resize(max_features, 0);
        }
        let most_offsets = 4 * KERNEL_LENGTH.max(channels);
        if self.offsets.capacity() < most_offsets {
            self.offsets.reserve(most_offsets);
        }
    }

    fn width(&self) -> usize {
        self.length + 2 * self.pad
    }

    /// Start of channel `channel`'s padded series row, of its tripled row and of its tap-sum row.
    fn series_row(&self, channel: usize) -> usize {
        channel * self.width()
    }

    fn tripled_row(&self, channel: usize) -> usize {
        (self.channels + channel) * self.width()
    }

    fn tap_sum_row(&self, channel: usize) -> usize {
        2 * self.channels * self.width() + channel * self.length
    }

    /// Copies one channel's series (`length` values) into its padded rows.
    pub(super) fn load_channel(&mut self, channel: usize, series: &[f64]) {
        let (pad, width) = (self.pad, self.width());
        for (row, factor) in [
            (self.series_row(channel), 1.0),
            (self.tripled_row(channel), 3.0),
        ] {
            let padded = &mut self.rows[row..row + width];
            padded[..pad].fill(0.0);
            padded[pad + series.len()..].fill(0.0);
            for (dst, &value) in padded[pad..pad + series.len()].iter_mut().zip(series) {
                *dst = factor * value;
            }
        }
    }

    /// Channel `channel`'s `-(x[t - 4d] + ... + x[t + 4d])` at dilation `dilation`, for every `t`.
    pub(super) fn load_tap_sums(&mut self, channel: usize, dilation: usize) {
        let first = self.series_row(channel) + self.pad - (KERNEL_LENGTH / 2) * dilation;
        self.offsets.clear();
        self.offsets
            .extend((0..KERNEL_LENGTH).map(|tap| first + tap * dilation));
        let start = self.tap_sum_row(channel);
        let (series, sums) = self.rows.split_at_mut(start);
        let sums = &mut sums[..self.length];
        sum_at_offsets(series, &self.offsets, sums);
        for sum in sums.iter_mut() {
            *sum = -*sum;
        }
    }

    /// The convolution output of `combination` at `outputs`, into `conv[..outputs.len()]`, then -inf
    /// up to a multiple of [`ROUND`] (the tap sums of its dilation must be loaded for its channels).
    pub(super) fn convolve(&mut self, combination: &Combination<'_>, outputs: Range<usize>) {
        let Combination {
            dilation,
            kernel,
            channels,
            ..
        } = *combination;
        let first_tap = self.pad - (KERNEL_LENGTH / 2) * dilation + outputs.start;
        self.offsets.clear();
        for &channel in channels {
            let tripled = self.tripled_row(channel) + first_tap;
            self.offsets.push(self.tap_sum_row(channel) + outputs.start);
            self.offsets.extend(
                KERNEL_TAPS[kernel]
                    .iter()
                    .map(|&tap| tripled + tap * dilation),
            );
        }
        let computed = rounded(outputs.len());
        sum_at_offsets(&self.rows, &self.offsets, &mut self.conv[..computed]);
        self.conv[outputs.len()..computed].fill(f64::NEG_INFINITY);
    }

    /// The last output of [`convolve`](Self::convolve).
    pub(super) fn convolution(&self, len: usize) -> &[f64] {
        &self.conv[..len]
    }
}

impl RocketModel {
    /// A scratch sized for this model, so that [`transform_into`](Self::transform_into) does not
    /// allocate.
    pub fn scratch(&self) -> RocketScratch {
        let mut scratch = RocketScratch::default();
        self.prepare(&mut scratch);
        scratch
    }

    fn prepare(&self, scratch: &mut RocketScratch) {
        let max_dilation = self.dilations.last().copied().unwrap_or(1);
        let max_features = self
            .features_per_dilation
            .iter()
            .copied()
            .max()
            .unwrap_or(0);
        scratch.prepare(self.channels, self.length, max_dilation, max_features);
    }

    /// The features of one sample (`channels x length`, row-major) into `out` (`output_len` long).
    /// Does not allocate with a scratch from [`scratch`](Self::scratch).
    ///
    /// # Errors
    /// If `sample` or `out` has the wrong length, or a value of the sample is not finite (the error
    /// names its channel and position).
    pub fn transform_into(
        &self,
        sample: &[f64],
        out: &mut [f64],
        scratch: &mut RocketScratch,
    ) -> Result<()> {
        check_len("rocket sample", self.sample_len(), sample.len())?;
        check_len("rocket feature buffer", self.output_len(), out.len())?;
        self.for_each_convolution(sample, scratch, |combination, conv, counts| {
            let counted = conv.len();
            let features = combination.features.clone();
            let counts = &mut counts[..features.len()];
            count_greater(conv, &self.biases[features.clone()], counts);
            for (dst, &count) in out[features].iter_mut().zip(counts.iter()) {
                *dst = count as f64 / counted as f64;
            }
        })
    }

    /// Walks every kernel and dilation of the model over `sample` (checked: its length and finite
    /// values), calling `pool` with the combination, its counted convolution outputs (each output of
    /// [`Combination::outputs`], in order) and a buffer of at least as many counts as it has features.
    pub(super) fn for_each_convolution(
        &self,
        sample: &[f64],
        scratch: &mut RocketScratch,
        mut pool: impl FnMut(&Combination<'_>, &[f64], &mut [u64]),
    ) -> Result<()> {
        check_len("rocket sample", self.sample_len(), sample.len())?;
        check_finite(sample, self.channels, self.length, "rocket sample")?;
        self.prepare(scratch);
        for (channel, series) in sample.chunks_exact(self.length).enumerate() {
            scratch.load_channel(channel, series);
        }
        let mut loaded_dilation = None;
        for combination in self.combinations() {
            if loaded_dilation != Some(combination.dilation) {
                for channel in 0..self.channels {
                    scratch.load_tap_sums(channel, combination.dilation);
                }
                loaded_dilation = Some(combination.dilation);
            }
            scratch.convolve(&combination, combination.outputs.clone());
            let counted = combination.outputs.len();
            pool(&combination, &scratch.conv[..counted], &mut scratch.counts);
        }
        Ok(())
    }

    /// The features of many samples (each `channels x length`, one after the other), in parallel
    /// (rayon); row-major, `output_len` per sample. Each row is what
    /// [`transform_into`](Self::transform_into) gives for its sample.
    ///
    /// # Errors
    /// As [`transform_batch_into`](Self::transform_batch_into).
    pub fn transform_batch(&self, samples: &[f64]) -> Result<Vec<f64>> {
        let count = samples.len() / self.sample_len().max(1);
        let mut out = vec![0.0; count * self.output_len()];
        self.transform_batch_into(samples, &mut out)?;
        Ok(out)
    }

    /// [`transform_batch`](Self::transform_batch) into `out` (`output_len` per sample).
    ///
    /// # Errors
    /// If `samples` is not a whole number of samples, `out` has the wrong length, or a value is not
    /// finite (the error names its sample, channel and position).
    pub fn transform_batch_into(&self, samples: &[f64], out: &mut [f64]) -> Result<()> {
        let sample_len = self.sample_len();
        if samples.len() % sample_len != 0 {
            return Err(CoreError::Shape {
                what: "rocket samples",
                expected: format!(
                    "whole samples of {} x {} values",
                    self.channels, self.length
                ),
                got: format!("{} values", samples.len()),
            });
        }
        let count = samples.len() / sample_len;
        check_len("rocket feature rows", count * self.output_len(), out.len())?;
        check_finite(samples, self.channels, self.length, "rocket samples")?;
        samples
            .par_chunks(sample_len)
            .zip(out.par_chunks_mut(self.output_len().max(1)))
            .try_for_each_init(
                || self.scratch(),
                |scratch, (sample, row)| self.transform_into(sample, row, scratch),
            )
    }
}

/// `Ok` when every value of `values` (samples of `channels` rows of `length`) is finite; else an
/// error naming the sample, channel and position of the first that is not.
pub(super) fn check_finite(
    values: &[f64],
    channels: usize,
    length: usize,
    what: &'static str,
) -> Result<()> {
    match values.iter().position(|value| !value.is_finite()) {
        None => Ok(()),
        Some(i) => Err(CoreError::Param {
            name: what,
            reason: format!(
                "{} in sample {}, channel {}, position {} (series of {channels} x {length}); replace \
                 missing values (with zeros, or the last valid value) first",
                values[i],
                i / (channels * length),
                i / length % channels,
                i % length
            ),
        }),
    }
}
