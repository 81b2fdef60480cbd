//! MultiRocket as a feature family (`--features multirocket`, [`super::multi`]): a sample's rows are
//! channels over time, as for `rocket`. Two presets, as `rocket`'s: `multirocket` divides each channel
//! by its spread over the training samples before the convolutions, `multirocket_unscaled` convolves
//! the channels in their own units (aeon's input).
//!
//! A series shorter than 10 values (its differences must span a kernel) is padded with zeros after its
//! end to 10, at training and classification alike; the fitted model then takes series of 1 to 10
//! values.

use std::sync::Arc;

use serde::{Deserialize, Serialize};

use crate::error::{CoreError, Result, check_len};
use crate::features::family::{FeatureFamily, FitImages};
use crate::features::rocket::config::check_shape;
use crate::features::rocket::family::{
    channel_spreads, is_scaled, scale_and_pad, scaled, with_preset,
};
use crate::features::rocket::multi::{
    MIN_LENGTH, MultiRocketConfig, MultiRocketModel, MultiRocketScratch,
};
use crate::frame::Grid;

/// The multirocket family.
#[derive(Debug)]
pub struct MultiRocketFamily;

/// The family's parameters: MultiRocket's settings, the channel scaling and, once trained, what was
/// learned.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MultiRocketParams {
    /// Features wanted in all (10,000: 9,408; 50,000: aeon's default 49,728).
    #[serde(default = "default_features")]
    pub num_features: usize,
    /// The most dilations per kernel (the paper's 32).
    #[serde(default = "default_dilations")]
    pub max_dilations_per_kernel: usize,
    /// The seed of every random choice.
    #[serde(default)]
    pub seed: u64,
    /// Whether each channel is divided by its spread over the training samples first.
    #[serde(default = "scaled", skip_serializing_if = "is_scaled")]
    pub channel_scaling: bool,
    /// Learned at training.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fitted: Option<FittedMultiRocket>,
}

fn default_features() -> usize {
    MultiRocketConfig::default().num_features
}

fn default_dilations() -> usize {
    MultiRocketConfig::default().max_dilations_per_kernel
}

impl Default for MultiRocketParams {
    fn default() -> Self {
        let config = MultiRocketConfig::default();
        Self {
            num_features: config.num_features,
            max_dilations_per_kernel: config.max_dilations_per_kernel,
            seed: config.seed,
            channel_scaling: true,
            fitted: None,
        }
    }
}

impl MultiRocketParams {
    /// MultiRocket's settings.
    pub fn config(&self) -> MultiRocketConfig {
        MultiRocketConfig {
            num_features: self.num_features,
            max_dilations_per_kernel: self.max_dilations_per_kernel,
            seed: self.seed,
        }
    }
}

/// What training learned: each channel's scale (all 1 unscaled) and the MultiRocket model.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FittedMultiRocket {
    pub channel_scales: Vec<f64>,
    pub model: MultiRocketModel,
}

/// MultiRocket features of series of one shape; owns its buffers.
#[derive(Clone, Debug)]
pub struct MultiRocketExtractor {
    grid: Grid,
    fitted: Arc<FittedMultiRocket>,
    scaled: Vec<f64>,
    scratch: MultiRocketScratch,
}

/// The length series of `length` values are transformed at: `length`, or 10 for shorter ones.
pub fn padded_length(length: usize) -> usize {
    length.max(MIN_LENGTH)
}

/// The fitted part, checked against the series' shape `grid` (channels x time).
fn fitted_for(params: &MultiRocketParams, grid: Grid) -> Result<&FittedMultiRocket> {
    let fitted = params.fitted.as_ref().ok_or_else(|| CoreError::Param {
        name: "multirocket",
        reason: "the features are not fitted: they are learned from the training samples, so only \
                 a trained model can compute them"
            .into(),
    })?;
    let model = &fitted.model;
    if Grid::new(model.channels(), model.length()) != Grid::new(grid.rows, padded_length(grid.cols))
    {
        let short = if model.length() == MIN_LENGTH {
            " (or fewer, padded to it)"
        } else {
            ""
        };
        return Err(CoreError::Shape {
            what: "multirocket series",
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

/// `Ok` when a fitted part agrees with the settings and its scales are usable.
fn check_fitted(params: &MultiRocketParams, fitted: &FittedMultiRocket) -> Result<()> {
    fitted.model.check()?;
    if fitted.model.config() != &params.config() {
        return Err(CoreError::Param {
            name: "multirocket",
            reason: "the fitted model's settings differ from the family's".into(),
        });
    }
    check_len(
        "multirocket channel scales",
        fitted.model.channels(),
        fitted.channel_scales.len(),
    )?;
    let usable = |s: &f64| s.is_finite() && *s > 0.0 && (params.channel_scaling || *s == 1.0);
    if !fitted.channel_scales.iter().all(usable) {
        return Err(CoreError::Param {
            name: "channel_scales",
            reason: "every channel scale must be positive and finite (and 1 unscaled)".into(),
        });
    }
    Ok(())
}

impl FeatureFamily for MultiRocketFamily {
    const NAME: &'static str = "multirocket";
    const PRESETS: &'static [&'static str] = &["multirocket", "multirocket_unscaled"];
    const COSTLY: bool = true;
    const LEARNS: bool = true;
    type Config = MultiRocketParams;
    type Extractor = MultiRocketExtractor;

    fn preset(index: usize) -> MultiRocketParams {
        MultiRocketParams {
            channel_scaling: index == 0,
            ..MultiRocketParams::default()
        }
    }

    fn preset_of(params: &MultiRocketParams) -> usize {
        usize::from(!params.channel_scaling)
    }

    fn check(params: &MultiRocketParams) -> Result<()> {
        params.config().check()?;
        match &params.fitted {
            Some(fitted) => check_fitted(params, fitted),
            None => Ok(()),
        }
    }

    fn fit(params: &MultiRocketParams, images: FitImages<'_>) -> Result<MultiRocketParams> {
        let Grid {
            rows: channels,
            cols: length,
        } = images.grid;
        let padded = padded_length(length);
        check_shape("multirocket training series", channels, padded)?;
        if images.is_empty() || length == 0 {
            return Err(CoreError::NotEnoughData(
                "multirocket: no training series to fit on".into(),
            ));
        }
        let channel_scales = if params.channel_scaling {
            channel_spreads(images)
        } else {
            vec![1.0; channels]
        };
        let mut scaled = vec![0.0; images.len() * channels * padded];
        scale_and_pad(images.values, length, padded, &channel_scales, &mut scaled);
        let model = MultiRocketModel::fit(&params.config(), &scaled, channels, padded)?;
        Ok(MultiRocketParams {
            fitted: Some(FittedMultiRocket {
                channel_scales,
                model,
            }),
            ..params.clone()
        })
    }

    fn output_len(params: &MultiRocketParams, grid: Grid) -> Result<usize> {
        check_shape("multirocket series", grid.rows, padded_length(grid.cols))?;
        match &params.fitted {
            Some(_) => Ok(fitted_for(params, grid)?.model.output_len()),
            None => Ok(params.config().output_len()),
        }
    }

    fn feature_names(params: &MultiRocketParams, grid: Grid) -> Result<Vec<String>> {
        let preset = Self::PRESETS[Self::preset_of(params)];
        match &params.fitted {
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

    fn extractor(params: &MultiRocketParams, grid: Grid) -> Result<MultiRocketExtractor> {
        let fitted = fitted_for(params, grid)?;
        Ok(MultiRocketExtractor {
            grid,
            scaled: vec![0.0; fitted.model.sample_len()],
            scratch: fitted.model.scratch(),
            fitted: Arc::new(fitted.clone()),
        })
    }

    fn grid(extractor: &MultiRocketExtractor) -> Grid {
        extractor.grid
    }

    fn len(extractor: &MultiRocketExtractor) -> usize {
        extractor.fitted.model.output_len()
    }

    fn extract_into(
        extractor: &mut MultiRocketExtractor,
        image: &[f64],
        out: &mut [f64],
    ) -> Result<()> {
        check_len("multirocket series", extractor.grid.len(), image.len())?;
        let fitted = &extractor.fitted;
        scale_and_pad(
            image,
            extractor.grid.cols,
            fitted.model.length(),
            &fitted.channel_scales,
            &mut extractor.scaled,
        );
        fitted
            .model
            .transform_into(&extractor.scaled, out, &mut extractor.scratch)
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;
    use crate::features::rocket::oracle;
    use crate::features::{FeatureConfig, FeatureKind};

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

    /// Both presets: fitted features are the oracle's on the (scaled or raw) series, the names and
    /// the model file round trip.
    #[test]
    fn fitted_features_are_the_oracle_s() {
        let (channels, length) = (3, 24);
        let grid = Grid::new(channels, length);
        let values = series(6, channels, length, 0.0);
        let images = FitImages {
            grid,
            values: &values,
        };
        for name in ["multirocket", "multirocket_unscaled"] {
            let kind = FeatureKind::parse(name).unwrap();
            let mut params = kind
                .default_config()
                .params::<MultiRocketFamily>()
                .unwrap()
                .clone();
            params.num_features = 8 * 84 * 3;
            let fitted = FeatureConfig::of::<MultiRocketFamily>(params)
                .fit(images)
                .unwrap();
            assert_eq!(fitted.name(), name);
            let learned = fitted
                .params::<MultiRocketFamily>()
                .unwrap()
                .fitted
                .clone()
                .unwrap();
            let sample = series(1, channels, length, 1.0);
            let input: Vec<f64> = sample
                .chunks_exact(length)
                .zip(&learned.channel_scales)
                .flat_map(|(row, s)| row.iter().map(move |v| v / s))
                .collect();
            let features = fitted.extractor(grid).unwrap().extract(&sample).unwrap();
            assert_eq!(features.len(), 8 * 84 * 3);
            let slow = oracle::multi_transform(&learned.model, &input);
            for (i, (f, s)) in features.iter().zip(&slow).enumerate() {
                assert!(
                    (f - s).abs() <= 1e-9 * (1.0 + s.abs()),
                    "{name} {i}: {f} {s}"
                );
            }
            let json = serde_json::to_string(&fitted).unwrap();
            assert_eq!(
                serde_json::from_str::<FeatureConfig>(&json).unwrap(),
                fitted
            );
            assert!(fitted.extractor(Grid::new(channels, length + 1)).is_err());
        }
    }

    /// Series shorter than 10 values are padded with zeros to 10.
    #[test]
    fn short_series_are_padded_to_ten() {
        let (channels, length) = (2, 6);
        let grid = Grid::new(channels, length);
        let values = series(4, channels, length, 0.2);
        let fitted = FeatureConfig::of::<MultiRocketFamily>(MultiRocketParams {
            num_features: 8 * 84,
            channel_scaling: false,
            ..MultiRocketParams::default()
        })
        .fit(FitImages {
            grid,
            values: &values,
        })
        .unwrap();
        let learned = fitted
            .params::<MultiRocketFamily>()
            .unwrap()
            .fitted
            .clone()
            .unwrap();
        assert_eq!(learned.model.length(), MIN_LENGTH);
        let sample = series(1, channels, length, 3.0);
        let mut padded = vec![0.0; channels * MIN_LENGTH];
        for (dst, row) in padded
            .chunks_exact_mut(MIN_LENGTH)
            .zip(sample.chunks_exact(length))
        {
            dst[..length].copy_from_slice(row);
        }
        let features = fitted.extractor(grid).unwrap().extract(&sample).unwrap();
        let slow = oracle::multi_transform(&learned.model, &padded);
        for (f, s) in features.iter().zip(&slow) {
            assert!((f - s).abs() <= 1e-9 * (1.0 + s.abs()));
        }
        assert!(fitted.extractor(Grid::new(channels, 10)).is_ok());
        assert!(fitted.extractor(Grid::new(channels, 11)).is_err());
    }
}
