//! Fitting MiniRocket: the random choices from the seed, then the biases from quantiles of training
//! convolutions (in parallel over the kernel and dilation pairs; the result does not depend on the
//! number of threads).

use rand::seq::index::sample as choose_indices;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use super::config::{RocketConfig, check_shape};
use super::kernels::{KERNEL_COUNT, KERNEL_LENGTH};
use super::model::RocketModel;
use super::plan::{dilations, quantile_level, quantile_of_sorted};
use super::transform::check_finite;
use crate::error::{CoreError, Result};

/// The random stream of the channel combinations, and that of the examples (one seed, two streams, so
/// that each choice is independent of how many of the other were drawn).
const CHANNEL_STREAM: u64 = 0;
const EXAMPLE_STREAM: u64 = 1;

impl RocketModel {
    /// Fits MiniRocket to `samples`: whole samples of `channels x length` values each, row-major, one
    /// after the other (at least one sample).
    ///
    /// Every kernel at every dilation draws, from the seed, 1 to `min(channels, 9)` distinct channels
    /// (exponentially distributed counts, as the reference: `floor(2^u)`, `u` uniform in `[0,
    /// log2(min(channels, 9) + 1))`) and one training sample; its biases are quantiles of that
    /// sample's convolution (zero-padded, all `length` outputs) at the levels of
    /// [`quantile_level`]. One channel is univariate MiniRocket (every combination is that channel).
    ///
    /// # Errors
    /// If the configuration is invalid, there are no channels, the series are shorter than 9 values,
    /// `samples` is empty or not whole samples, or a value is not finite.
    pub fn fit(
        config: &RocketConfig,
        samples: &[f64],
        channels: usize,
        length: usize,
    ) -> Result<Self> {
        config.check()?;
        check_shape("rocket training series", channels, length)?;
        let sample_len = channels * length;
        if samples.is_empty() || samples.len() % sample_len != 0 {
            return Err(CoreError::NotEnoughData(format!(
                "rocket fit: {} values are not one or more whole samples of {channels} x {length}",
                samples.len()
            )));
        }
        check_finite(samples, channels, length, "rocket training samples")?;
        let mut model = Self::draw(config, channels, length, samples.len() / sample_len);
        model.biases = model.fit_biases(samples);
        model.check()?;
        Ok(model)
    }

    /// The dilations and every random choice; the biases are left at zero.
    fn draw(config: &RocketConfig, channels: usize, length: usize, count: usize) -> Self {
        let (dilations, features_per_dilation) = dilations(
            length,
            config.features_per_kernel(),
            config.max_dilations_per_kernel,
        );
        let combinations = KERNEL_COUNT * dilations.len();
        let mut rng = ChaCha8Rng::seed_from_u64(config.seed);
        rng.set_stream(CHANNEL_STREAM);
        let most = channels.min(KERNEL_LENGTH);
        let max_exponent = ((most + 1) as f64).log2();
        let mut channels_per_combination = Vec::with_capacity(combinations);
        let mut channel_indices = Vec::new();
        for _ in 0..combinations {
            let drawn = 2f64.powf(rng.random_range(0.0..max_exponent)) as usize;
            let chosen = drawn.clamp(1, most);
            channels_per_combination.push(chosen);
            channel_indices.extend(choose_indices(&mut rng, channels, chosen));
        }
        rng.set_stream(EXAMPLE_STREAM);
        let examples = (0..combinations)
            .map(|_| rng.random_range(0..count))
            .collect();
        let padded = (0..combinations)
            .map(|c| (c / KERNEL_COUNT + c % KERNEL_COUNT) % 2 == 0)
            .collect();
        let features = KERNEL_COUNT * features_per_dilation.iter().sum::<usize>();
        Self {
            config: *config,
            channels,
            length,
            dilations,
            features_per_dilation,
            channels_per_combination,
            channel_indices,
            padded,
            examples,
            biases: vec![0.0; features],
        }
    }

    /// Each combination's biases: quantiles of its convolution of its example, in parallel.
    fn fit_biases(&self, samples: &[f64]) -> Vec<f64> {
        let sample_len = self.sample_len();
        let combinations: Vec<_> = self.combinations().collect();
        let per_combination: Vec<Vec<f64>> = combinations
            .par_iter()
            .map_init(
                || (self.scratch(), Vec::with_capacity(self.length)),
                |(scratch, sorted), combination| {
                    let example = self.examples[combination.index];
                    let sample = &samples[example * sample_len..(example + 1) * sample_len];
                    for &channel in combination.channels {
                        let series = &sample[channel * self.length..(channel + 1) * self.length];
                        scratch.load_channel(channel, series);
                        scratch.load_tap_sums(channel, combination.dilation);
                    }
                    scratch.convolve(combination, 0..self.length);
                    sorted.clear();
                    sorted.extend_from_slice(scratch.convolution(self.length));
                    sorted.sort_unstable_by(f64::total_cmp);
                    combination
                        .features
                        .clone()
                        .map(|feature| quantile_of_sorted(sorted, quantile_level(feature)))
                        .collect()
                },
            )
            .collect();
        per_combination.concat()
    }
}
