//! MultiRocket (Tan, Dempster, Bergmeir & Webb, "MultiRocket: multiple pooling operators and
//! transformations for fast and effective time series classification", Data Mining and Knowledge
//! Discovery, 2022): MiniRocket's kernels on two representations of a series, the series as it is and
//! its first differences (`x[t + 1] - x[t]`, one value shorter), each with its own dilations, channel
//! combinations and biases (two [`RocketModel`]s), and four pooling operators of each convolution
//! against each bias instead of MiniRocket's one:
//!
//! - **PPV**, the proportion of positive values: the share of counted outputs above the bias
//!   (MiniRocket's feature);
//! - **LSPV**, the longest stretch of positive values, as aeon computes it: the largest gap between
//!   consecutive outputs *below* the bias, the first output and the last standing as bounds (an
//!   output equal to the bias breaks nothing), in outputs, not normalised;
//! - **MPV**, the mean of positive values: the mean of `C[t] + bias` over the outputs above the bias,
//!   0 when there are none (aeon's and the reference code's formula, `+ bias`; the paper writes the
//!   mean of `C[t] - bias`, which differs by `2 bias` wherever an output is above it);
//! - **MIPV**, the mean of indices of positive values: the mean position (among the counted outputs)
//!   of those above the bias, -1 when there are none.
//!
//! Features, in aeon's order: the series' PPV of every bias (in MiniRocket's order), then its LSPV,
//! MPV and MIPV of every bias, then the same four blocks of the differences. The default, 10,000
//! features asked, gives 9,408 (14 biases per kernel and representation: aeon's `MultiRocket` with
//! `n_kernels = 1250`), as many as MiniRocket's 9,996, so that both cost the same memory per sample;
//! aeon's default (`n_kernels = 6250`, 49,728 features) is `num_features = 50_000`
//! ([`MultiRocketConfig`]). On `jiku-walk` aeon's 49,728 scored below its 9,408 (issue #44's notes).
//!
//! The convolutions are MiniRocket's fast path (`transform.rs`: shared tap sums, SIMD sums); the
//! pooling is one pass over each convolution per bias. Both are checked against the definition
//! (`oracle::multi_transform`), and the series' features against aeon's output given aeon's fitted
//! parameters (`tests/fixtures/multirocket/`; aeon 1.6 aligns the differences' left taps one value off
//! the definition, so their features differ from presrs's there).

use serde::{Deserialize, Serialize};

use super::config::{MAX_FEATURES, RocketConfig};
use super::kernels::KERNEL_LENGTH;
use super::model::RocketModel;
use super::transform::RocketScratch;
use crate::error::{CoreError, Result, check_len};

/// Pooling operators per bias: PPV, LSPV, MPV, MIPV.
pub const POOLS: usize = 4;

/// Representations of a series: as it is, and its first differences.
pub const REPRESENTATIONS: usize = 2;

/// The shortest series MultiRocket takes: its differences must span a kernel (9 values).
pub const MIN_LENGTH: usize = KERNEL_LENGTH + 1;

/// Parameters of the MultiRocket features.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MultiRocketConfig {
    /// Features wanted in all: each representation gets `num_features / 8` biases (rounded down to a
    /// multiple of the 84 kernels, at least 84), each pooled four ways. The default 10,000 gives 9,408;
    /// 50,000 gives aeon's default 49,728.
    pub num_features: usize,
    /// The most dilations per kernel (the paper's 32).
    pub max_dilations_per_kernel: usize,
    /// The seed of every random choice (the differences draw with `seed + 1`, so that their channel
    /// combinations and examples are not the series').
    pub seed: u64,
}

impl Default for MultiRocketConfig {
    /// 9,408 features (aeon's `n_kernels = 1250`), at most 32 dilations per kernel, seed 0.
    fn default() -> Self {
        Self {
            num_features: 10_000,
            max_dilations_per_kernel: 32,
            seed: 0,
        }
    }
}

impl MultiRocketConfig {
    /// `Ok` when the parameters can make a model; else an error naming the field.
    pub fn check(&self) -> Result<()> {
        if self.num_features == 0 || self.num_features > MAX_FEATURES {
            return Err(CoreError::Param {
                name: "num_features",
                reason: format!(
                    "{} features; ask for 1 to {MAX_FEATURES} (the default is 10000)",
                    self.num_features
                ),
            });
        }
        self.representation(0).check()
    }

    /// The MiniRocket settings of representation `index` (0: the series, 1: its differences).
    pub fn representation(&self, index: u64) -> RocketConfig {
        RocketConfig {
            num_features: (self.num_features / (POOLS * REPRESENTATIONS)).max(1),
            max_dilations_per_kernel: self.max_dilations_per_kernel,
            seed: self.seed.wrapping_add(index),
        }
    }

    /// Features a model of this configuration gives.
    pub fn output_len(&self) -> usize {
        POOLS * REPRESENTATIONS * self.representation(0).output_len()
    }
}

/// A fitted MultiRocket transform (see [the module](self)): a MiniRocket model of the series and one
/// of its first differences. Read from a file through serde, which checks both and that they fit
/// together.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "MultiRocketFields")]
pub struct MultiRocketModel {
    config: MultiRocketConfig,
    /// The kernels on the series (`channels x length`).
    series: RocketModel,
    /// The kernels on its first differences (`channels x (length - 1)`).
    differences: RocketModel,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MultiRocketFields {
    config: MultiRocketConfig,
    series: RocketModel,
    differences: RocketModel,
}

impl TryFrom<MultiRocketFields> for MultiRocketModel {
    type Error = CoreError;

    fn try_from(fields: MultiRocketFields) -> Result<Self> {
        let model = Self {
            config: fields.config,
            series: fields.series,
            differences: fields.differences,
        };
        model.check()?;
        Ok(model)
    }
}

/// The buffers of one transform: MiniRocket's, and the sample's differences.
#[derive(Clone, Debug, Default)]
pub struct MultiRocketScratch {
    rocket: RocketScratch,
    differences: Vec<f64>,
}

impl MultiRocketModel {
    /// Fits both representations to `samples` (whole samples of `channels x length` values, row-major,
    /// one after the other; `length >= 10`).
    ///
    /// # Errors
    /// As [`RocketModel::fit`], or if the series are shorter than 10 values.
    pub fn fit(
        config: &MultiRocketConfig,
        samples: &[f64],
        channels: usize,
        length: usize,
    ) -> Result<Self> {
        config.check()?;
        check_length(length)?;
        let series = RocketModel::fit(&config.representation(0), samples, channels, length)?;
        let mut differences = vec![0.0; samples.len() / length * (length - 1)];
        first_differences(samples, length, &mut differences);
        let differences = RocketModel::fit(
            &config.representation(1),
            &differences,
            channels,
            length - 1,
        )?;
        Ok(Self {
            config: *config,
            series,
            differences,
        })
    }

    /// A model of two fitted MiniRocket models (aeon's parameters, in a test), checked.
    ///
    /// # Errors
    /// If they do not fit together (see [`check`](Self::check)).
    pub fn from_parts(
        config: MultiRocketConfig,
        series: RocketModel,
        differences: RocketModel,
    ) -> Result<Self> {
        let model = Self {
            config,
            series,
            differences,
        };
        model.check()?;
        Ok(model)
    }

    /// `Ok` when both models are valid and fit together: the same channels, the differences one value
    /// shorter, the series at least 10 values.
    pub fn check(&self) -> Result<()> {
        self.config.check()?;
        self.series.check()?;
        self.differences.check()?;
        check_length(self.series.length())?;
        let expected = (self.series.channels(), self.series.length() - 1);
        let got = (self.differences.channels(), self.differences.length());
        if expected != got {
            return Err(CoreError::Param {
                name: "multirocket model",
                reason: format!(
                    "the differences' model takes {} x {} series, expected {} x {}; the model file \
                     is damaged, fit it again",
                    got.0, got.1, expected.0, expected.1
                ),
            });
        }
        Ok(())
    }

    pub fn config(&self) -> &MultiRocketConfig {
        &self.config
    }

    /// The MiniRocket model of the series.
    pub fn series(&self) -> &RocketModel {
        &self.series
    }

    /// The MiniRocket model of the first differences.
    pub fn differences(&self) -> &RocketModel {
        &self.differences
    }

    pub fn channels(&self) -> usize {
        self.series.channels()
    }

    pub fn length(&self) -> usize {
        self.series.length()
    }

    pub fn sample_len(&self) -> usize {
        self.series.sample_len()
    }

    /// Features per sample: four per bias of each representation.
    pub fn output_len(&self) -> usize {
        POOLS * (self.series.output_len() + self.differences.output_len())
    }

    /// `multirocket_{series|diff}_{ppv|lspv|mpv|mipv}_d{dilation}_k{kernel}_q{i}`, in feature order.
    pub fn feature_names(&self) -> Vec<String> {
        let mut names = Vec::with_capacity(self.output_len());
        for (representation, model) in [("series", &self.series), ("diff", &self.differences)] {
            let base = model.feature_names();
            for pool in ["ppv", "lspv", "mpv", "mipv"] {
                names.extend(base.iter().map(|name| {
                    let rest = name.trim_start_matches("rocket_");
                    format!("multirocket_{representation}_{pool}_{rest}")
                }));
            }
        }
        names
    }

    /// A scratch sized for this model, so that [`transform_into`](Self::transform_into) does not
    /// allocate.
    pub fn scratch(&self) -> MultiRocketScratch {
        MultiRocketScratch {
            rocket: self.series.scratch(),
            differences: vec![0.0; self.differences.sample_len()],
        }
    }

    /// The features of one sample (`channels x length`, row-major) into `out`
    /// ([`output_len`](Self::output_len) long). Does not allocate with a scratch from
    /// [`scratch`](Self::scratch).
    ///
    /// # Errors
    /// If `sample` or `out` has the wrong length, or a value is not finite.
    pub fn transform_into(
        &self,
        sample: &[f64],
        out: &mut [f64],
        scratch: &mut MultiRocketScratch,
    ) -> Result<()> {
        check_len("multirocket sample", self.sample_len(), sample.len())?;
        check_len("multirocket feature buffer", self.output_len(), out.len())?;
        let (series_out, differences_out) = out.split_at_mut(POOLS * self.series.output_len());
        pool_into(&self.series, sample, series_out, &mut scratch.rocket)?;
        scratch
            .differences
            .resize(self.differences.sample_len(), 0.0);
        first_differences(sample, self.length(), &mut scratch.differences);
        pool_into(
            &self.differences,
            &scratch.differences,
            differences_out,
            &mut scratch.rocket,
        )
    }
}

/// `Ok` when series of `length` values have differences long enough for a kernel.
fn check_length(length: usize) -> Result<()> {
    if length < MIN_LENGTH {
        return Err(CoreError::Shape {
            what: "multirocket series",
            expected: format!(
                "series of at least {MIN_LENGTH} values (their differences span a kernel); pad \
                 shorter ones with zeros"
            ),
            got: format!("{length} values"),
        });
    }
    Ok(())
}

/// Each row of `length` values of `series` as its `length - 1` first differences, into `out`.
pub(super) fn first_differences(series: &[f64], length: usize, out: &mut [f64]) {
    for (row, dst) in series
        .chunks_exact(length)
        .zip(out.chunks_exact_mut(length - 1))
    {
        for (d, pair) in dst.iter_mut().zip(row.windows(2)) {
            *d = pair[1] - pair[0];
        }
    }
}

/// The four pooled features of every bias of `model` over `sample`, into `out`'s four blocks (PPV,
/// LSPV, MPV, MIPV, each `model.output_len()` long).
fn pool_into(
    model: &RocketModel,
    sample: &[f64],
    out: &mut [f64],
    scratch: &mut RocketScratch,
) -> Result<()> {
    let features = model.output_len();
    let biases = model.biases();
    model.for_each_convolution(sample, scratch, |combination, conv, _| {
        for feature in combination.features.clone() {
            let pooled = pool(conv, biases[feature]);
            for (block, value) in pooled.into_iter().enumerate() {
                out[block * features + feature] = value;
            }
        }
    })
}

/// PPV, LSPV, MPV and MIPV of one convolution's counted outputs (at least one) against `bias`, in one
/// pass, as aeon's `_transform` computes them (see the module documentation).
pub(super) fn pool(conv: &[f64], bias: f64) -> [f64; POOLS] {
    let (mut positive, mut index_sum, mut value_sum) = (0usize, 0usize, 0.0);
    let (mut last_below, mut longest) = (0usize, 0usize);
    for (j, &value) in conv.iter().enumerate() {
        if value > bias {
            positive += 1;
            index_sum += j;
            value_sum += value + bias;
        } else if value < bias {
            longest = longest.max(j - last_below);
            last_below = j;
        }
    }
    longest = longest.max(conv.len().saturating_sub(1) - last_below);
    let (mean, mean_index) = if positive > 0 {
        (
            value_sum / positive as f64,
            index_sum as f64 / positive as f64,
        )
    } else {
        (0.0, -1.0)
    };
    [
        positive as f64 / conv.len().max(1) as f64,
        longest as f64,
        mean,
        mean_index,
    ]
}
