//! MiniRocket as a feature family (`--features rocket`). A sample's image is read as a series: its rows
//! are the channels and its columns time (a whole stance's summary, a taxel x time array).
//!
//! Five presets: `rocket` divides each channel by its spread (standard deviation) over the training
//! samples before the convolutions (a channel combination sums channels of different units, a load in
//! the sensor's units and a centre of pressure in fractions of the grid, which would otherwise leave the
//! combination to the channel of largest units); `rocket_unscaled` convolves the channels in their own
//! units, as aeon's MiniRocket does (on `jiku-walk` the scaling cost about 2 points). Which one a data
//! set needs is the automatic choice's to validate. Fixed choices only (issue #44: none helped on every
//! shared set): `rocket_log` convolves every value's `sign(x) ln(1 + |x|)`, `rocket_duration` adds the
//! stance's duration after the features ([`super::duration`]), `rocket_log_duration` both (other
//! combinations of the settings, in a model file only, are named `rocket`). The scales (all 1
//! unscaled), the fitted MiniRocket model and the duration's scale are learned at training
//! ([`FeatureFamily::fit`]) and stored in the model file with the settings.
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
use crate::features::rocket::draws;
use crate::features::rocket::duration::{DurationScale, frames_before_padding};
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
    /// Whether every value is replaced by `sign(x) ln(1 + |x|)` (after the channel scaling) before
    /// the convolutions: a compression of the channels' units, which a channel combination sums.
    #[serde(default, skip_serializing_if = "is_false")]
    pub log_values: bool,
    /// Whether the sample's duration (its frames before the zero padding) follows MiniRocket's
    /// features as one more ([`super::duration`]); for whole stances, whose lengths vary.
    #[serde(default, skip_serializing_if = "is_false")]
    pub duration: bool,
    /// Independent MiniRocket draws whose features stand side by side ([`super::draws`]); 1, the
    /// paper's single model, unless set (and then not written, so that such files read as before).
    #[serde(default = "one_draw", skip_serializing_if = "is_one_draw")]
    pub draws: usize,
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

fn is_false(flag: &bool) -> bool {
    !*flag
}

fn one_draw() -> usize {
    1
}

fn is_one_draw(draws: &usize) -> bool {
    *draws == 1
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
            log_values: false,
            duration: false,
            draws: 1,
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

/// What training learned: each channel's scale and the MiniRocket model (its first draw, and the
/// others when there are several).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FittedRocket {
    /// Each channel is divided by its scale before the convolutions.
    pub channel_scales: Vec<f64>,
    pub model: RocketModel,
    /// The draws after the first (seeds `seed + 1, ...`), their features after the first's.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub more_draws: Vec<RocketModel>,
    /// The duration feature's scale, when the family adds it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub duration: Option<DurationScale>,
}

impl FittedRocket {
    /// Features: MiniRocket's of every draw, and the duration when there is one.
    pub fn output_len(&self) -> usize {
        self.minirocket_len() + usize::from(self.duration.is_some())
    }

    /// MiniRocket's features of every draw.
    pub fn minirocket_len(&self) -> usize {
        self.draws().map(RocketModel::output_len).sum()
    }

    /// The draws, the first one first.
    pub fn draws(&self) -> impl Iterator<Item = &RocketModel> {
        std::iter::once(&self.model).chain(&self.more_draws)
    }
}

/// Rocket features of series of one shape; owns its buffers.
#[derive(Clone, Debug)]
pub struct RocketExtractor {
    grid: Grid,
    fitted: Arc<FittedRocket>,
    scaled: Vec<f64>,
    scratch: RocketScratch,
    log_values: bool,
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

/// Every value replaced by `sign(x) ln(1 + |x|)` (numpy's `sign(x) * log1p(abs(x))`).
pub(super) fn signed_log(values: &mut [f64]) {
    for value in values {
        *value = value.signum() * value.abs().ln_1p();
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
    const PRESETS: &'static [&'static str] = &[
        "rocket",
        "rocket_unscaled",
        "rocket_log",
        "rocket_duration",
        "rocket_log_duration",
    ];
    const COSTLY: bool = true;
    const LEARNS: bool = true;
    type Config = RocketParams;
    type Extractor = RocketExtractor;

    /// `rocket` scales the channels; the others convolve them in their own units, `rocket_log` and
    /// `rocket_log_duration` their signed logs, and the `_duration` ones add the duration feature.
    fn preset(index: usize) -> RocketParams {
        RocketParams {
            channel_scaling: index == 0,
            log_values: index == 2 || index == 4,
            duration: index == 3 || index == 4,
            ..RocketParams::default()
        }
    }

    fn preset_of(params: &RocketParams) -> usize {
        match (params.channel_scaling, params.log_values, params.duration) {
            (true, ..) => 0,
            (false, false, false) => 1,
            (false, true, false) => 2,
            (false, false, true) => 3,
            (false, true, true) => 4,
        }
    }

    fn check(params: &RocketParams) -> Result<()> {
        params.config().check()?;
        draws::check_count(params.draws)?;
        if let Some(fitted) = &params.fitted {
            fitted.model.check()?;
            if fitted.model.config() != &params.config() {
                return Err(CoreError::Param {
                    name: "rocket",
                    reason: "the fitted model's settings differ from the family's".into(),
                });
            }
            draws::check_more(
                &params.config(),
                params.draws,
                &fitted.model,
                &fitted.more_draws,
            )?;
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
            match &fitted.duration {
                Some(scale) if params.duration => scale.check()?,
                None if !params.duration => {}
                _ => {
                    return Err(CoreError::Param {
                        name: "duration",
                        reason: "a rocket model has a fitted duration scale exactly when it adds \
                                 the duration feature"
                            .into(),
                    });
                }
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
        if params.log_values {
            signed_log(&mut scaled);
        }
        let model = RocketModel::fit(&params.config(), &scaled, channels, padded)?;
        let more_draws =
            draws::fit_more(&params.config(), params.draws, &scaled, channels, padded)?;
        let minirocket_len = model.output_len() * params.draws;
        let duration = params
            .duration
            .then(|| DurationScale::fit(images, minirocket_len));
        Ok(RocketParams {
            fitted: Some(FittedRocket {
                channel_scales,
                model,
                more_draws,
                duration,
            }),
            ..params.clone()
        })
    }

    fn output_len(params: &RocketParams, grid: Grid) -> Result<usize> {
        check_shape("rocket series", grid.rows, padded_length(grid.cols))?;
        match &params.fitted {
            Some(_) => Ok(fitted_for(params, grid)?.output_len()),
            None => Ok(params.config().output_len() * params.draws + usize::from(params.duration)),
        }
    }

    fn feature_names(params: &RocketParams, grid: Grid) -> Result<Vec<String>> {
        let preset = Self::PRESETS[Self::preset_of(params)];
        match &params.fitted {
            // (`rocket_d1_k0_q0`, or `rocket_unscaled_d1_k0_q0`: each starts with its preset's name)
            Some(_) => {
                let fitted = fitted_for(params, grid)?;
                let mut names: Vec<String> = fitted
                    .draws()
                    .enumerate()
                    .flat_map(|(index, model)| draws::names_of_draw(model, Self::NAME, index))
                    .collect();
                if fitted.duration.is_some() {
                    names.push(format!("{}_frames", Self::NAME));
                }
                Ok(with_preset(names, Self::NAME, preset))
            }
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
            log_values: params.log_values,
            fitted: Arc::new(fitted.clone()),
        })
    }

    fn grid(extractor: &RocketExtractor) -> Grid {
        extractor.grid
    }

    fn len(extractor: &RocketExtractor) -> usize {
        extractor.fitted.output_len()
    }

    fn extract_into(extractor: &mut RocketExtractor, image: &[f64], out: &mut [f64]) -> Result<()> {
        check_len("rocket series", extractor.grid.len(), image.len())?;
        let fitted = &extractor.fitted;
        check_len("rocket feature buffer", fitted.output_len(), out.len())?;
        scale_and_pad(
            image,
            extractor.grid.cols,
            padded_length(extractor.grid.cols),
            &fitted.channel_scales,
            &mut extractor.scaled,
        );
        if extractor.log_values {
            signed_log(&mut extractor.scaled);
        }
        let (mut rocket, duration) = out.split_at_mut(fitted.minirocket_len());
        for model in fitted.draws() {
            let (draw, rest) = rocket.split_at_mut(model.output_len());
            model.transform_into(&extractor.scaled, draw, &mut extractor.scratch)?;
            rocket = rest;
        }
        if let (Some(scale), [slot]) = (&fitted.duration, duration) {
            *slot = scale.feature(frames_before_padding(image, extractor.grid.cols));
        }
        Ok(())
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
    use crate::features::rocket::RocketConfig;
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

    /// The signed log is numpy's `np.sign(x) * np.log1p(np.abs(x))` (values printed by numpy 2.3).
    #[test]
    fn the_signed_log_is_numpy_s() {
        let mut values = [-2.5, -3.0, 0.0, 0.5, 100.0, -1e-9];
        signed_log(&mut values);
        let numpy = [
            -1.252762968495368,
            -1.3862943611198906,
            0.0,
            0.4054651081081644,
            4.61512051684126,
            -9.999999995e-10,
        ];
        for (got, want) in values.iter().zip(numpy) {
            assert!(
                (got - want).abs() <= 1e-15 * want.abs().max(1.0),
                "{got} {want}"
            );
        }
    }

    /// Fits `preset` (with 840 features) on six series of 3 channels x 20 values.
    fn fitted_preset(preset: &str, values: &[f64]) -> FeatureConfig {
        let kind = crate::features::FeatureKind::parse(preset).unwrap();
        let mut params = kind
            .default_config()
            .params::<RocketFamily>()
            .unwrap()
            .clone();
        params.num_features = 840;
        FeatureConfig::of::<RocketFamily>(params)
            .fit(FitImages {
                grid: Grid::new(3, 20),
                values,
            })
            .unwrap()
    }

    /// `rocket_log` is the oracle's MiniRocket on every value's signed log (the channels unscaled),
    /// fitted on the logs too; `rocket_log_duration` adds the duration after the same features.
    #[test]
    fn the_log_preset_convolves_the_signed_logs() {
        let values = series(6, 3, 20, 0.0);
        let fitted = fitted_preset("rocket_log", &values);
        assert_eq!(fitted.name(), "rocket_log");
        let params = fitted.params::<RocketFamily>().unwrap();
        assert!(params.log_values && !params.channel_scaling && !params.duration);
        let rocket = params.fitted.as_ref().unwrap();
        // The biases come from the logs: the same fit as MiniRocket's on the logged series.
        let logged: Vec<f64> = values
            .iter()
            .map(|&v| v.signum() * v.abs().ln_1p())
            .collect();
        let direct = RocketModel::fit(&params.config(), &logged, 3, 20).unwrap();
        assert_eq!(rocket.model, direct);
        let sample = series(1, 3, 20, 1.0);
        let sample_log: Vec<f64> = sample
            .iter()
            .map(|&v| v.signum() * v.abs().ln_1p())
            .collect();
        let features = fitted
            .extractor(Grid::new(3, 20))
            .unwrap()
            .extract(&sample)
            .unwrap();
        assert_eq!(features, oracle::transform(&rocket.model, &sample_log));
        let json = serde_json::to_string(&fitted).unwrap();
        assert!(json.contains(r#""log_values":true"#), "{json}");
        assert_eq!(
            serde_json::from_str::<FeatureConfig>(&json).unwrap(),
            fitted
        );
        let both = fitted_preset("rocket_log_duration", &values);
        let with_duration = both
            .extractor(Grid::new(3, 20))
            .unwrap()
            .extract(&sample)
            .unwrap();
        assert_eq!(with_duration[..features.len()], features[..]);
        assert_eq!(with_duration.len(), features.len() + 1);
    }

    /// `rocket_duration`: MiniRocket's features on the raw channels, then the sample's frames before
    /// its zero padding, standardised over the training samples and weighted; named, stored, checked.
    #[test]
    fn the_duration_preset_adds_the_frames_before_the_padding() {
        let (channels, length) = (3, 20);
        let grid = Grid::new(channels, length);
        let mut values = series(6, channels, length, 0.0);
        // Training durations 20, 17, 14, 11, 8, 5 frames: zeros after them.
        for (i, sample) in values.chunks_exact_mut(channels * length).enumerate() {
            for row in sample.chunks_exact_mut(length) {
                row[length - 3 * i..].fill(0.0);
            }
        }
        let fitted = fitted_preset("rocket_duration", &values);
        assert_eq!(fitted.name(), "rocket_duration");
        let params = fitted.params::<RocketFamily>().unwrap();
        let rocket = params.fitted.as_ref().unwrap();
        let scale = rocket.duration.clone().unwrap();
        let durations = [20.0, 17.0, 14.0, 11.0, 8.0, 5.0];
        let mean = durations.iter().sum::<f64>() / 6.0;
        let spread = (durations.iter().map(|d| (d - mean).powi(2)).sum::<f64>() / 6.0).sqrt();
        assert_eq!(scale.mean, mean);
        assert!((scale.spread - spread).abs() < 1e-12);
        let mut sample = series(1, channels, length, 1.0);
        for row in sample.chunks_exact_mut(length) {
            row[12..].fill(0.0);
        }
        let features = fitted.extractor(grid).unwrap().extract(&sample).unwrap();
        let minirocket = oracle::transform(&rocket.model, &sample);
        assert_eq!(features.len(), minirocket.len() + 1);
        assert_eq!(features[..minirocket.len()], minirocket[..]);
        let expected = (12.0 - mean) / spread * scale.weight;
        assert!((features[minirocket.len()] - expected).abs() < 1e-12);
        assert_eq!(
            scale.weight,
            crate::features::rocket::duration::DURATION_WEIGHT * (minirocket.len() as f64).sqrt()
        );
        let names = RocketFamily::feature_names(params, grid).unwrap();
        assert_eq!(names.len(), features.len());
        assert_eq!(
            names.last().map(String::as_str),
            Some("rocket_duration_frames")
        );
        assert_eq!(
            RocketFamily::output_len(params, grid).unwrap(),
            features.len()
        );
        let json = serde_json::to_string(&fitted).unwrap();
        assert_eq!(
            serde_json::from_str::<FeatureConfig>(&json).unwrap(),
            fitted
        );
        // A duration scale without the setting (or the setting without one) is damaged.
        let mut damaged = params.clone();
        damaged.duration = false;
        assert!(RocketFamily::check(&damaged).is_err_and(|e| e.to_string().contains("duration")));
        // Model files written before these settings read as before (no duration, no logs).
        let plain = fitted_preset("rocket_unscaled", &values);
        let plain_json = serde_json::to_string(&plain).unwrap();
        assert!(!plain_json.contains("duration") && !plain_json.contains("log_values"));
    }

    /// `draws: 3` is three MiniRocket models fitted with the seeds 0, 1, 2 on the same series, their
    /// features (the oracle's) side by side and named apart; stored, read back and checked.
    #[test]
    fn several_draws_stand_side_by_side() {
        let (channels, length) = (3, 20);
        let grid = Grid::new(channels, length);
        let values = series(6, channels, length, 0.0);
        let params = RocketParams {
            num_features: 168,
            channel_scaling: false,
            draws: 3,
            ..RocketParams::default()
        };
        let fitted = FeatureConfig::of::<RocketFamily>(params.clone())
            .fit(FitImages {
                grid,
                values: &values,
            })
            .unwrap();
        let fitted_params = fitted.params::<RocketFamily>().unwrap();
        let rocket = fitted_params.fitted.as_ref().unwrap();
        let sample = series(1, channels, length, 1.0);
        let features = fitted.extractor(grid).unwrap().extract(&sample).unwrap();
        let mut expected = Vec::new();
        for seed in 0..3 {
            let config = RocketConfig {
                seed,
                ..params.config()
            };
            let model = RocketModel::fit(&config, &values, channels, length).unwrap();
            expected.extend(oracle::transform(&model, &sample));
        }
        assert_eq!(features, expected);
        assert_eq!(features.len(), 3 * 168);
        assert_ne!(features[..168], features[168..336], "the draws differ");
        assert_eq!(
            RocketFamily::output_len(fitted_params, grid).unwrap(),
            features.len()
        );
        assert_eq!(
            RocketFamily::output_len(&params, grid).unwrap(),
            features.len()
        );
        let names = RocketFamily::feature_names(fitted_params, grid).unwrap();
        let distinct: std::collections::HashSet<_> = names.iter().collect();
        assert_eq!(
            (names.len(), distinct.len()),
            (features.len(), features.len())
        );
        assert!(
            names[168].starts_with("rocket_unscaled_r1_d"),
            "{}",
            names[168]
        );
        let json = serde_json::to_string(&fitted).unwrap();
        assert!(json.contains(r#""draws":3"#), "{json}");
        assert_eq!(
            serde_json::from_str::<FeatureConfig>(&json).unwrap(),
            fitted
        );
        // One draw is not written (older files read as before); a draw missing or of another seed,
        // or no draw at all, is an error naming the setting.
        assert!(
            !serde_json::to_string(&RocketParams::default())
                .unwrap()
                .contains("draws")
        );
        let mut missing = fitted_params.clone();
        if let Some(rocket) = missing.fitted.as_mut() {
            rocket.more_draws.pop();
        }
        assert!(RocketFamily::check(&missing).is_err_and(|e| e.to_string().contains("draws")));
        let mut reseeded = fitted_params.clone();
        if let Some(rocket) = reseeded.fitted.as_mut() {
            rocket.more_draws.swap(0, 1);
        }
        assert!(RocketFamily::check(&reseeded).is_err_and(|e| e.to_string().contains("draw 1")));
        let none = RocketParams {
            draws: 0,
            ..RocketParams::default()
        };
        assert!(RocketFamily::check(&none).is_err_and(|e| e.to_string().contains("draws")));
        assert_eq!(rocket.draws().count(), 3);
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
