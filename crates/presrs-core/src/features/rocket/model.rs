//! A fitted MiniRocket model: every choice the fit made, as plain serde fields, and the checks that
//! make a crafted model file an error instead of a panic.

use std::ops::Range;

use serde::{Deserialize, Serialize};

use super::config::{RocketConfig, check_shape};
use super::kernels::{KERNEL_COUNT, KERNEL_LENGTH};
use crate::error::{CoreError, Result};

/// A fitted MiniRocket transform (see [the module](super)). Made by [`RocketModel::fit`]; read from a
/// file through serde, which runs [`RocketModel::check`].
///
/// The kernel and dilation pairs ("combinations") are numbered dilation by dilation, the 84 kernels
/// within each: combination `c` has dilation `dilations[c / 84]` and kernel `c % 84`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "RocketModelFields")]
pub struct RocketModel {
    /// The configuration it was fitted with.
    pub(super) config: RocketConfig,
    /// Channels per sample.
    pub(super) channels: usize,
    /// Values per channel (every sample has this length).
    pub(super) length: usize,
    /// The dilations, ascending.
    pub(super) dilations: Vec<usize>,
    /// Biases per kernel at each dilation.
    pub(super) features_per_dilation: Vec<usize>,
    /// Channels summed by each combination.
    pub(super) channels_per_combination: Vec<usize>,
    /// The channels of each combination, one combination after the other.
    pub(super) channel_indices: Vec<usize>,
    /// Whether each combination pads the series with zeros (all `length` outputs) or counts only the
    /// outputs where the kernel lies inside the series.
    pub(super) padded: Vec<bool>,
    /// The training sample whose convolution gave each combination's biases.
    pub(super) examples: Vec<usize>,
    /// One threshold per feature, in feature order.
    pub(super) biases: Vec<f64>,
}

/// The serialised fields of [`RocketModel`], checked before they become one.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RocketModelFields {
    config: RocketConfig,
    channels: usize,
    length: usize,
    dilations: Vec<usize>,
    features_per_dilation: Vec<usize>,
    channels_per_combination: Vec<usize>,
    channel_indices: Vec<usize>,
    padded: Vec<bool>,
    examples: Vec<usize>,
    biases: Vec<f64>,
}

impl TryFrom<RocketModelFields> for RocketModel {
    type Error = CoreError;

    fn try_from(fields: RocketModelFields) -> Result<Self> {
        let model = Self {
            config: fields.config,
            channels: fields.channels,
            length: fields.length,
            dilations: fields.dilations,
            features_per_dilation: fields.features_per_dilation,
            channels_per_combination: fields.channels_per_combination,
            channel_indices: fields.channel_indices,
            padded: fields.padded,
            examples: fields.examples,
            biases: fields.biases,
        };
        model.check()?;
        Ok(model)
    }
}

/// One kernel at one dilation, as the transform walks them.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Combination<'a> {
    /// Its number (dilation index * 84 + kernel).
    pub index: usize,
    /// The dilation.
    pub dilation: usize,
    /// The kernel (an index into [`KERNEL_TAPS`](super::kernels::KERNEL_TAPS)).
    pub kernel: usize,
    /// The channels whose convolutions it sums.
    pub channels: &'a [usize],
    /// Whether it pads (see [`RocketModel`]).
    pub padded: bool,
    /// Its features (and biases), as a range of the feature vector.
    pub features: Range<usize>,
    /// The outputs it counts: `0 .. length` when padded, else `4 * dilation .. length - 4 * dilation`.
    pub outputs: Range<usize>,
}

impl RocketModel {
    /// The configuration it was fitted with.
    pub fn config(&self) -> &RocketConfig {
        &self.config
    }

    /// Channels per sample.
    pub fn channels(&self) -> usize {
        self.channels
    }

    /// Values per channel.
    pub fn length(&self) -> usize {
        self.length
    }

    /// Values per sample: `channels * length`.
    pub fn sample_len(&self) -> usize {
        self.channels * self.length
    }

    /// Features per sample.
    pub fn output_len(&self) -> usize {
        self.biases.len()
    }

    /// The dilations, ascending.
    pub fn dilations(&self) -> &[usize] {
        &self.dilations
    }

    /// Biases per kernel at each dilation.
    pub fn features_per_dilation(&self) -> &[usize] {
        &self.features_per_dilation
    }

    /// One threshold per feature.
    pub fn biases(&self) -> &[f64] {
        &self.biases
    }

    /// The training sample whose convolution gave each combination's biases.
    pub fn examples(&self) -> &[usize] {
        &self.examples
    }

    /// The name of each feature: `rocket_d{dilation}_k{kernel}_q{i}`, the `i`-th bias of kernel
    /// `kernel` at dilation `dilation`.
    pub fn feature_names(&self) -> Vec<String> {
        let mut names = Vec::with_capacity(self.output_len());
        for combination in self.combinations() {
            for i in 0..combination.features.len() {
                names.push(format!(
                    "rocket_d{}_k{}_q{i}",
                    combination.dilation, combination.kernel
                ));
            }
        }
        names
    }

    /// Every kernel at every dilation, in feature order. Assumes a checked model.
    pub fn combinations(&self) -> impl Iterator<Item = Combination<'_>> + '_ {
        let mut channel_start = 0;
        let mut feature_start = 0;
        let length = self.length;
        (0..self.padded.len()).map(move |index| {
            let dilation_index = index / KERNEL_COUNT;
            let dilation = self.dilations[dilation_index];
            let channel_end = channel_start + self.channels_per_combination[index];
            let feature_end = feature_start + self.features_per_dilation[dilation_index];
            let padded = self.padded[index];
            let half_span = (KERNEL_LENGTH / 2) * dilation;
            let combination = Combination {
                index,
                dilation,
                kernel: index % KERNEL_COUNT,
                channels: &self.channel_indices[channel_start..channel_end],
                padded,
                features: feature_start..feature_end,
                outputs: if padded {
                    0..length
                } else {
                    half_span..length - half_span
                },
            };
            channel_start = channel_end;
            feature_start = feature_end;
            combination
        })
    }

    /// `Ok` when every field is consistent with the others, so that transforming cannot panic: the
    /// configuration and shape are valid, the dilations ascend and fit the length, there are 84
    /// combinations per dilation with 1 to `min(channels, 9)` distinct channels each, and one finite
    /// bias per feature. A model file is checked this way when it is read.
    pub fn check(&self) -> Result<()> {
        self.config.check()?;
        check_shape("rocket model series", self.channels, self.length)?;
        self.check_dilations()?;
        let combinations = KERNEL_COUNT * self.dilations.len();
        for (what, len) in [
            (
                "rocket model channels_per_combination",
                self.channels_per_combination.len(),
            ),
            ("rocket model padded", self.padded.len()),
            ("rocket model examples", self.examples.len()),
        ] {
            crate::error::check_len(what, combinations, len)?;
        }
        self.check_channels()?;
        let features = KERNEL_COUNT * self.features_per_dilation.iter().sum::<usize>();
        crate::error::check_len("rocket model biases", features, self.biases.len())?;
        if let Some(i) = self.biases.iter().position(|b| !b.is_finite()) {
            return Err(invalid("biases", format!("bias {i} is {}", self.biases[i])));
        }
        Ok(())
    }

    fn check_dilations(&self) -> Result<()> {
        crate::error::check_len(
            "rocket model features_per_dilation",
            self.dilations.len(),
            self.features_per_dilation.len(),
        )?;
        if self.dilations.is_empty() {
            return Err(invalid("dilations", "no dilation".to_string()));
        }
        if !self.dilations.windows(2).all(|pair| pair[0] < pair[1]) {
            return Err(invalid("dilations", "not strictly ascending".to_string()));
        }
        let largest = super::plan::max_dilation(self.length);
        if let Some(&d) = self.dilations.iter().find(|&&d| d == 0 || d > largest) {
            return Err(invalid(
                "dilations",
                format!(
                    "{d} is not within 1 ..= {largest} for series of {}",
                    self.length
                ),
            ));
        }
        if self
            .features_per_dilation
            .iter()
            .any(|&f| f == 0 || f > super::config::MAX_FEATURES)
        {
            return Err(invalid(
                "features_per_dilation",
                "each must be 1 or more (and not absurdly many)".to_string(),
            ));
        }
        Ok(())
    }

    fn check_channels(&self) -> Result<()> {
        let most = self.channels.min(KERNEL_LENGTH);
        if let Some(c) = self
            .channels_per_combination
            .iter()
            .position(|&n| n == 0 || n > most)
        {
            return Err(invalid(
                "channels_per_combination",
                format!(
                    "combination {c} has {} channels, not 1 ..= {most}",
                    self.channels_per_combination[c]
                ),
            ));
        }
        let total: usize = self.channels_per_combination.iter().sum();
        crate::error::check_len(
            "rocket model channel_indices",
            total,
            self.channel_indices.len(),
        )?;
        let mut start = 0;
        for (c, &n) in self.channels_per_combination.iter().enumerate() {
            let chosen = &self.channel_indices[start..start + n];
            let out_of_range = chosen.iter().any(|&ch| ch >= self.channels);
            let repeated = chosen
                .iter()
                .enumerate()
                .any(|(i, ch)| chosen[..i].contains(ch));
            if out_of_range || repeated {
                return Err(invalid(
                    "channel_indices",
                    format!(
                        "combination {c} has channels {chosen:?}; each must be distinct and below {}",
                        self.channels
                    ),
                ));
            }
            start += n;
        }
        Ok(())
    }
}

fn invalid(field: &'static str, reason: String) -> CoreError {
    CoreError::Param {
        name: field,
        reason: format!(
            "rocket model: {reason}; the model file is damaged or not a rocket model, fit it again"
        ),
    }
}
