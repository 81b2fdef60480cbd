//! MiniRocket (Dempster, Schmidt & Webb, KDD 2021): random-convolution features of multivariate series.
//!
//! A sample is a series of `channels x length` values, row-major (channel after channel). Every sample
//! a model fits on or transforms has the model's length: the caller pads (zeros at the end keep the
//! duration as information; nothing here resamples).
//!
//! - [`kernels`]: the 84 fixed kernels of length 9, weight -1 everywhere but +2 at three taps;
//! - [`plan`]: what follows from the length and the configuration alone: the dilations (exponentially
//!   spaced from 1 up to `(length - 1) / 8`, so that a dilated kernel spans the series), the features
//!   per dilation and the quantile levels of the biases;
//! - [`config`]: [`RocketConfig`] (features wanted, dilations per kernel at most, seed), checked once;
//! - [`model`]: [`RocketModel`], every fitted choice as plain serde fields, checked on loading;
//! - [`fit`]: the random choices (channels per kernel and dilation, training example per bias) from the
//!   seed, and the biases from quantiles of the chosen examples' convolutions (in parallel);
//! - [`transform`]: the fast transform of one sample into the proportions of positive values (PPV),
//!   without allocating ([`RocketScratch`]), and of many samples in parallel;
//! - [`draws`]: several independent draws (seeds) side by side, the family's `draws` setting;
//! - [`family`]: MiniRocket as the feature family `rocket` (an image read as channels x time, its
//!   channels scaled by their spread in the training samples, or in their own units, or their signed
//!   logs), and [`duration`] the whole stance's duration as one more feature;
//! - [`multi`]: MultiRocket (Tan et al. 2022), the kernels on the series and on its first
//!   differences, each convolution pooled four ways (PPV, LSPV, MPV, MIPV);
//!   [`multi_family`] the feature family `multirocket`;
//! - [`oracle`]: the same features by the definition, slowly (each output a dilated convolution summed
//!   tap by tap), which the fast paths are tested against.
//!
//! Features, in order: for each dilation, for each of the 84 kernels, `features_per_dilation[j]`
//! thresholds (the biases) of that kernel's convolution output. There are `84 * (num_features / 84)` of
//! them (9,996 for the default 10,000). Each kernel and dilation sums its convolution over a random
//! combination of 1 to `min(channels, 9)` channels (the same weights on each); with one channel every
//! combination is that channel, which is univariate MiniRocket. Padding alternates: a kernel and
//! dilation with even `dilation_index + kernel_index` pads the series with zeros and counts over all
//! `length` outputs; an odd one counts only where the kernel lies inside the series
//! (`length - 8 * dilation` outputs).

pub mod config;
pub mod draws;
pub mod duration;
pub mod family;
pub mod fit;
pub mod kernels;
pub mod model;
pub mod multi;
pub mod multi_family;
pub mod oracle;
pub mod plan;
pub mod transform;

pub use config::RocketConfig;
pub use model::RocketModel;
pub use multi::{MultiRocketConfig, MultiRocketModel, MultiRocketScratch};
pub use transform::RocketScratch;
