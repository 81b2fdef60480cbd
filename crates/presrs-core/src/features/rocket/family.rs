//! MiniRocket as a feature family (`--features rocket`). A sample's image is read as a series: its rows
//! are the channels and its columns time (a whole stance's summary, a taxel x time array).
//!
//! Two presets: `rocket` divides each channel by its spread (standard deviation) over the training
//! samples before the convolutions (a channel combination sums channels of different units, a load in
//! the sensor's units and a centre of pressure in fractions of the grid, which would otherwise leave the
//! combination to the channel of largest units); `rocket_unscaled` convolves the channels in their own
//! units, as aeon's MiniRocket does (on `jiku-walk` the scaling cost about 2 points). Which one a data
//! set needs is the automatic choice's to validate. The scales (all 1 unscaled) and the fitted
//! MiniRocket model are learned at training ([`FeatureFamily::fit`]) and stored in the model file with
//! the settings.
//!
//! A series shorter than a kernel (9 values) is padded with zeros after its end to 9, at training and
//! classification alike: a whole stance of a few frames is then that stance followed by no load, as
//! longer stances are padded to the longest. The fitted model's length is 9 and it takes series of 1
//! to 9 values (each padded the same way).

use std::sync::Arc;

use serde::{Deserialize, Serialize};

use crate::error::{CoreError, Result, check_len};
use crate::features::family::{FeatureFamily, FitImages};
use crate::features::rocket::config::{RocketConfig, check_shape};
use crate::features::rocket::kernels::KERNEL_LENGTH;
use crate::features::rocket::model::RocketModel;
use crate::features::rocket::transform::RocketScratch;
use crate::frame::Grid;

/// The rocket family.
#[derive(Debug)]
pub struct RocketFamily;

/// The family's parameters: MiniRocket's settings and, once trained, what was learned.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RocketParams {
    /// Features wanted (rounded down to a multiple of 84: 9,996 for the paper's 10,000).
    #[serde(default = "default_features")]
    pub num_features: usize,
    /// The most dilations per kernel (the paper's 32).
    #[serde(default = "default_dilations")]
    pub max_dilations_per_kernel: usize,
    /// The seed of every random choice.
    #[serde(default)]
    pub seed: u64,
    /// Whether each channel is divided by its spread over the training samples before the
    /// convolutions (model files written before this setting existed scaled: the default).
    #[serde(default = "scaled", skip_serializing_if = "is_scaled")]
    pub channel_scaling: bool,
    /// Learned at training.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fitted: Option<FittedRocket>,
}

fn default_features() -> usize {
    RocketConfig::default().num_features
}

fn default_dilations() -> usize {
    RocketConfig::default().max_dilations_per_kernel
}

pub(super) fn scaled() -> bool {
    true
}

/// (the default is not written, so that a scaled model's file reads as before)
pub(super) fn is_scaled(channel_scaling: &bool) -> bool {
    *channel_scaling
}

impl Default for RocketParams {
    fn default() -> Self {
        let config = RocketConfig::default();
        Self {
            num_features: config.num_features,
            max_dilations_per_kernel: config.max_dilations_per_kernel,
            seed: config.seed,
            channel_scaling: true,
            fitted: None,
        }
    }
}

impl RocketParams {
    /// MiniRocket's settings.
    pub fn config(&self) -> RocketConfig {
        RocketConfig {
            num_features: self.num_features,
            max_dilations_per_kernel: self.max_dilations_per_kernel,
            seed: self.seed,
        }
    }
}

/// What training learned: each channel's scale and the MiniRocket model.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FittedRocket {
    /// Each channel is divided by its scale before the convolutions.
    pub channel_scales: Vec<f64>,
    pub model: RocketModel,
}

/// Rocket features of series of one shape; owns its buffers.
#[derive(Clone, Debug)]
pub struct RocketExtractor {
    grid: Grid,
    fitted: Arc<FittedRocket>,
    scaled: Vec<f64>,
    scratch: RocketScratch,
}

/// The length series of `length` values are transformed at: `length`, or 9 (a kernel's taps) for
/// shorter ones, which are padded with zeros after their end.
pub fn padded_length(length: usize) -> usize {
    length.max(KERNEL_LENGTH)
}

/// `values` (series of `channels x length`, one after the other) each divided by its channel's scale
/// and padded with zeros to `padded` values (at least `length`), into `out` (`channels x padded` per
/// series).
pub(super) fn scale_and_pad(
    values: &[f64],
    length: usize,
    padded: usize,
    scales: &[f64],
    out: &mut [f64],
) {
    let rows = values.chunks_exact(length.max(1));
    for ((row, dst), scale) in rows
        .zip(out.chunks_exact_mut(padded))
        .zip(scales.iter().cycle())
    {
        for (d, v) in dst.iter_mut().zip(row) {
            *d = v / scale;
        }
        dst[length..].fill(0.0);
    }
}

/// `names` (each starting with the family's `name`) starting with `preset` instead.
pub(super) fn with_preset(names: Vec<String>, name: &str, preset: &str) -> Vec<String> {
    if name == preset {
        return names;
    }
    names
        .into_iter()
        .map(|n| format!("{preset}{}", n.strip_prefix(name).unwrap_or(&n)))
        .collect()
}

/// The fitted part, checked against the series' shape `grid` (channels x time).
fn fitted_for(params: &RocketParams, grid: Grid) -> Result<&FittedRocket> {
    let fitted = params.fitted.as_ref().ok_or_else(|| CoreError::Param {
        name: "rocket",
        reason: "the features are not fitted: they are learned from the training samples, so only \
                 a trained model can compute them"
            .into(),
    })?;
    let model = &fitted.model;
    if Grid::new(model.channels(), model.length()) != Grid::new(grid.rows, padded_length(grid.cols))
    {
        let short = if model.length() == KERNEL_LENGTH {
            " (or fewer, padded to it)"
        } else {
            ""
        };
        return Err(CoreError::Shape {
            what: "rocket series",
            expected: format!(
                "{} channels x {} frames{short}",
                model.channels(),
                model.length()
            ),
            got: format!("{} x {}", grid.rows, grid.cols),
        });
    }
    Ok(fitted)
}

impl FeatureFamily for RocketFamily {
    const NAME: &'static str = "rocket";
    const PRESETS: &'static [&'static str] = &["rocket", "rocket_unscaled"];
    const COSTLY: bool = true;
    const LEARNS: bool = true;
    type Config = RocketParams;
    type Extractor = RocketExtractor;

    fn preset(index: usize) -> RocketParams {
        RocketParams {
            channel_scaling: index == 0,
            ..RocketParams::default()
        }
    }

    fn preset_of(params: &RocketParams) -> usize {
        usize::from(!params.channel_scaling)
    }

    fn check(params: &RocketParams) -> Result<()> {
        params.config().check()?;
        if let Some(fitted) = &params.fitted {
            fitted.model.check()?;
            if fitted.model.config() != &params.config() {
                return Err(CoreError::Param {
                    name: "rocket",
                    reason: "the fitted model's settings differ from the family's".into(),
                });
            }
            check_len(
                "rocket channel scales",
                fitted.model.channels(),
                fitted.channel_scales.len(),
            )?;
            if fitted
                .channel_scales
                .iter()
                .any(|s| !(s.is_finite() && *s > 0.0))
            {
                return Err(CoreError::Param {
                    name: "channel_scales",
                    reason: "every channel scale must be positive and finite".into(),
                });
            }
            if !params.channel_scaling && fitted.channel_scales.iter().any(|&s| s != 1.0) {
                return Err(CoreError::Param {
                    name: "channel_scales",
                    reason: "an unscaled rocket model has every channel scale 1".into(),
                });
            }
        }
        Ok(())
    }

    fn fit(params: &RocketParams, images: FitImages<'_>) -> Result<RocketParams> {
        let Grid {
            rows: channels,
            cols: length,
        } = images.grid;
        let padded = padded_length(length);
        check_shape("rocket training series", channels, padded)?;
        if images.is_empty() || length == 0 {
            return Err(CoreError::NotEnoughData(
                "rocket: no training series to fit on".into(),
            ));
        }
        let channel_scales = if params.channel_scaling {
            channel_spreads(images)
        } else {
            vec![1.0; channels]
        };
        let mut scaled = vec![0.0; images.len() * channels * padded];
        scale_and_pad(images.values, length, padded, &channel_scales, &mut scaled);
        let model = RocketModel::fit(&params.config(), &scaled, channels, padded)?;
        Ok(RocketParams {
            fitted: Some(FittedRocket {
                channel_scales,
                model,
            }),
            ..params.clone()
        })
    }

    fn output_len(params: &RocketParams, grid: Grid) -> Result<usize> {
        check_shape("rocket series", grid.rows, padded_length(grid.cols))?;
        match &params.fitted {
            Some(_) => Ok(fitted_for(params, grid)?.model.output_len()),
            None => Ok(params.config().output_len()),
        }
    }

    fn feature_names(params: &RocketParams, grid: Grid) -> Result<Vec<String>> {
        let preset = Self::PRESETS[Self::preset_of(params)];
        match &params.fitted {
            // (`rocket_d1_k0_q0`, or `rocket_unscaled_d1_k0_q0`: each starts with its preset's name)
            Some(_) => Ok(with_preset(
                fitted_for(params, grid)?.model.feature_names(),
                Self::NAME,
                preset,
            )),
            None => {
                let len = Self::output_len(params, grid)?;
                Ok((0..len).map(|i| format!("{preset}_{i}")).collect())
            }
        }
    }

    fn extractor(params: &RocketParams, grid: Grid) -> Result<RocketExtractor> {
        let fitted = fitted_for(params, grid)?;
        Ok(RocketExtractor {
            grid,
            scaled: vec![0.0; fitted.model.sample_len()],
            scratch: fitted.model.scratch(),
            fitted: Arc::new(fitted.clone()),
        })
    }

    fn grid(extractor: &RocketExtractor) -> Grid {
        extractor.grid
    }

    fn len(extractor: &RocketExtractor) -> usize {
        extractor.fitted.model.output_len()
    }

    fn extract_into(extractor: &mut RocketExtractor, image: &[f64], out: &mut [f64]) -> Result<()> {
        check_len("rocket series", extractor.grid.len(), image.len())?;
        let fitted = &extractor.fitted;
        scale_and_pad(
            image,
            extractor.grid.cols,
            padded_length(extractor.grid.cols),
            &fitted.channel_scales,
            &mut extractor.scaled,
        );
        fitted
            .model
            .transform_into(&extractor.scaled, out, &mut extractor.scratch)
    }
}

/// Each channel's standard deviation over every value of every training series (1 for a constant
/// channel, which then stays as it is).
pub(super) fn channel_spreads(images: FitImages<'_>) -> Vec<f64> {
    let Grid {
        rows: channels,
        cols: length,
    } = images.grid;
    (0..channels)
        .map(|channel| {
            let values = (0..images.len())
                .flat_map(|i| &images.image(i)[channel * length..(channel + 1) * length]);
            let (mut count, mut mean, mut m2) = (0.0, 0.0, 0.0);
            for &value in values {
                // Welford's running mean and squared deviations.
                count += 1.0;
                let delta = value - mean;
                mean += delta / count;
                m2 += delta * (value - mean);
            }
            let spread = (m2 / count).sqrt();
            if spread.is_finite() && spread > 0.0 {
                spread
            } else {
                1.0
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;
    use crate::features::FeatureConfig;
    use crate::features::rocket::oracle;

    /// Continuous values (no ties with the biases), channels of very different units.
    fn series(n: usize, channels: usize, length: usize, phase: f64) -> Vec<f64> {
        (0..n * channels * length)
            .map(|i| {
                let unit = if (i / length) % channels == 0 {
                    100.0
                } else {
                    0.01
                };
                unit * ((i as f64 * 0.7 + phase).sin() + 0.3 * (i as f64 * 0.13).cos())
            })
            .collect()
    }

    #[test]
    fn fitted_features_are_the_oracle_s_on_the_scaled_series() {
        let (channels, length) = (3, 20);
        let grid = Grid::new(channels, length);
        let values = series(6, channels, length, 0.0);
        let params = RocketParams {
            num_features: 840,
            ..RocketParams::default()
        };
        let config = FeatureConfig::of::<RocketFamily>(params.clone());
        let images = FitImages {
            grid,
            values: &values,
        };
        let fitted = config.fit(images).unwrap();
        let fitted_params = fitted.params::<RocketFamily>().unwrap();
        let rocket = fitted_params.fitted.as_ref().unwrap();
        assert_eq!(rocket.channel_scales.len(), channels);
        let mut extractor = fitted.extractor(grid).unwrap();
        let fresh = series(1, channels, length, 1.0);
        let sample = &fresh[..];
        let features = extractor.extract(sample).unwrap();
        let scaled: Vec<f64> = sample
            .chunks_exact(length)
            .zip(&rocket.channel_scales)
            .flat_map(|(row, s)| row.iter().map(move |v| v / s))
            .collect();
        assert_eq!(features, oracle::transform(&rocket.model, &scaled));
        assert_eq!(features.len(), 840);
        // Stored and read back whole.
        let json = serde_json::to_string(&fitted).unwrap();
        assert!(json.starts_with(r#"{"kind":"rocket","num_features":840,"#));
        assert_eq!(
            serde_json::from_str::<FeatureConfig>(&json).unwrap(),
            fitted
        );
        // Another shape, or no fit, is a clear error.
        assert!(fitted.extractor(Grid::new(channels, length + 1)).is_err());
        let err = config.extractor(grid).unwrap_err().to_string();
        assert!(err.contains("not fitted"), "{err}");
    }

    /// Series shorter than a kernel are padded with zeros to 9 values, at fit and at extraction: the
    /// features are the oracle's on the scaled series followed by zeros.
    #[test]
    fn short_series_are_padded_to_a_kernel() {
        let (channels, length) = (2, 4);
        let grid = Grid::new(channels, length);
        let values = series(5, channels, length, 0.3);
        let config = FeatureConfig::of::<RocketFamily>(RocketParams {
            num_features: 168,
            ..RocketParams::default()
        });
        let fitted = config
            .fit(FitImages {
                grid,
                values: &values,
            })
            .unwrap();
        let rocket = fitted
            .params::<RocketFamily>()
            .unwrap()
            .fitted
            .clone()
            .unwrap();
        assert_eq!(rocket.model.length(), KERNEL_LENGTH);
        let sample = series(1, channels, length, 2.0);
        let mut padded = vec![0.0; channels * KERNEL_LENGTH];
        for ((dst, row), s) in padded
            .chunks_exact_mut(KERNEL_LENGTH)
            .zip(sample.chunks_exact(length))
            .zip(&rocket.channel_scales)
        {
            for (d, v) in dst.iter_mut().zip(row) {
                *d = v / s;
            }
        }
        let features = fitted.extractor(grid).unwrap().extract(&sample).unwrap();
        assert_eq!(features, oracle::transform(&rocket.model, &padded));
        // Any length up to 9 pads the same way; 10 is another shape, and no channel is an error.
        assert!(fitted.extractor(Grid::new(channels, 9)).is_ok());
        let err = fitted
            .extractor(Grid::new(channels, 10))
            .unwrap_err()
            .to_string();
        assert!(err.contains("or fewer, padded to it"), "{err}");
        assert!(
            FeatureConfig::of::<RocketFamily>(RocketParams::default())
                .fit(FitImages {
                    grid: Grid::new(0, 4),
                    values: &[],
                })
                .is_err()
        );
    }

    /// `rocket_unscaled` convolves the channels as they are: its scales are 1, its features the
    /// oracle's on the raw series (not the scaled preset's), and its name survives the model file.
    #[test]
    fn the_unscaled_preset_convolves_the_raw_channels() {
        let (channels, length) = (3, 20);
        let grid = Grid::new(channels, length);
        let values = series(6, channels, length, 0.0);
        let images = FitImages {
            grid,
            values: &values,
        };
        let kind = crate::features::FeatureKind::parse("rocket_unscaled").unwrap();
        let mut params = kind
            .default_config()
            .params::<RocketFamily>()
            .unwrap()
            .clone();
        assert!(!params.channel_scaling);
        params.num_features = 840;
        let unscaled = FeatureConfig::of::<RocketFamily>(params.clone())
            .fit(images)
            .unwrap();
        let scaled = FeatureConfig::of::<RocketFamily>(RocketParams {
            channel_scaling: true,
            ..params
        })
        .fit(images)
        .unwrap();
        let rocket = unscaled
            .params::<RocketFamily>()
            .unwrap()
            .fitted
            .clone()
            .unwrap();
        assert_eq!(rocket.channel_scales, vec![1.0; channels]);
        let sample = series(1, channels, length, 1.0);
        let features = unscaled.extractor(grid).unwrap().extract(&sample).unwrap();
        assert_eq!(features, oracle::transform(&rocket.model, &sample));
        let other = scaled.extractor(grid).unwrap().extract(&sample).unwrap();
        assert_ne!(features, other, "the channels' units differ by 1e4");
        assert_eq!(unscaled.name(), "rocket_unscaled");
        assert_eq!(scaled.name(), "rocket");
        let json = serde_json::to_string(&unscaled).unwrap();
        assert!(json.contains(r#""channel_scaling":false"#), "{json}");
        assert!(
            !serde_json::to_string(&scaled)
                .unwrap()
                .contains("channel_scaling")
        );
        assert_eq!(
            serde_json::from_str::<FeatureConfig>(&json).unwrap(),
            unscaled
        );
        // An unscaled model with a scale other than 1 is damaged.
        let mut damaged = unscaled.params::<RocketFamily>().unwrap().clone();
        if let Some(fitted) = damaged.fitted.as_mut() {
            fitted.channel_scales[0] = 2.0;
        }
        assert!(RocketFamily::check(&damaged).is_err());
    }

    #[test]
    fn scales_are_the_channel_spreads() {
        let grid = Grid::new(2, 10);
        let mut values = vec![0.0; 2 * 20];
        for (i, v) in values.iter_mut().enumerate() {
            *v = if (i / 10) % 2 == 0 {
                (i % 10) as f64
            } else {
                5.0
            };
        }
        let scales = channel_spreads(FitImages {
            grid,
            values: &values,
        });
        let spread = ((0..10).map(|x| (x as f64 - 4.5).powi(2)).sum::<f64>() / 10.0).sqrt();
        assert!((scales[0] - spread).abs() < 1e-12);
        assert_eq!(scales[1], 1.0, "a constant channel keeps its scale");
    }
}
