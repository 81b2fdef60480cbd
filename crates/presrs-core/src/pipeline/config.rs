//! The training configuration: what training needs besides the data, checked once into a valid type.

use serde::{Deserialize, Serialize};

use crate::classifier::ClassifierConfig;
use crate::crop::Crop;
use crate::error::{CoreError, Result};
use crate::features::FeatureConfig;
use crate::preprocess::Preprocess;

/// Everything training needs besides the data. `Default` is the paper's setting.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrainConfig {
    /// The region of each image that is used (applied before the features).
    pub crop: Crop,
    pub features: FeatureConfig,
    /// Number of principal components kept (capped at `n_train - 1` and at the feature count); unused
    /// when the classifier takes every feature ([`TrainConfig::pca_dims`]).
    pub dims: usize,
    pub classifier: ClassifierConfig,
    /// Steps after the crop (fill absent sensels, normalise the load); none by default (the paper).
    #[serde(default, skip_serializing_if = "Preprocess::is_none")]
    pub preprocess: Preprocess,
}

impl Default for TrainConfig {
    /// The paper: 38 x 41 foot region of the 44 x 44 array, 1-D |FFT| with N = 2048, 51 components,
    /// Parzen window with σ chosen on the validation set.
    fn default() -> Self {
        Self {
            crop: Crop::PAPER,
            features: FeatureConfig::default(),
            dims: 51,
            classifier: ClassifierConfig::default(),
            preprocess: Preprocess::NONE,
        }
    }
}

impl TrainConfig {
    /// The principal components the PCA step keeps at most, or `None` when the classifier takes every
    /// feature and there is no PCA step (ridge:
    /// [`ClassifierKind::takes_all_features`](crate::classifier::ClassifierKind::takes_all_features)).
    pub fn pca_dims(&self) -> Option<usize> {
        (!self.classifier.kind().takes_all_features()).then_some(self.dims)
    }

    /// Checks the parameters once; the result is what [`train`](crate::pipeline::train) takes.
    pub fn check(self) -> Result<CheckedTrainConfig> {
        if self.dims == 0 {
            return Err(CoreError::Param {
                name: "dims",
                reason: "at least one principal component must be kept".into(),
            });
        }
        self.features.check()?;
        self.classifier.check()?;
        Ok(CheckedTrainConfig(self))
    }
}

/// A [`TrainConfig`] whose parameters have been checked ([`TrainConfig::check`]).
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(transparent)]
pub struct CheckedTrainConfig(TrainConfig);

impl CheckedTrainConfig {
    pub fn config(&self) -> &TrainConfig {
        &self.0
    }

    pub fn into_inner(self) -> TrainConfig {
        self.0
    }
}

impl TryFrom<TrainConfig> for CheckedTrainConfig {
    type Error = CoreError;

    fn try_from(config: TrainConfig) -> Result<Self> {
        config.check()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::features::Fft1dConfig;

    #[test]
    fn the_paper_setting_passes_the_check() {
        let checked = TrainConfig::default().check().unwrap();
        assert_eq!(checked.config(), &TrainConfig::default());
        assert_eq!(checked.into_inner(), TrainConfig::default());
    }

    #[test]
    fn the_check_refuses_no_components_and_a_bad_family() {
        let no_dims = TrainConfig {
            dims: 0,
            ..TrainConfig::default()
        };
        let err = no_dims.check().unwrap_err();
        assert!(
            matches!(err, CoreError::Param { name: "dims", .. }),
            "{err}"
        );
        let empty_transform = TrainConfig {
            features: FeatureConfig::of::<crate::features::Fft1dFamily>(Fft1dConfig {
                fft_len: Some(0),
            }),
            ..TrainConfig::default()
        };
        let err = CheckedTrainConfig::try_from(empty_transform).unwrap_err();
        assert!(
            matches!(
                err,
                CoreError::Param {
                    name: "fft_len",
                    ..
                }
            ),
            "{err}"
        );
    }

    #[test]
    fn unknown_fields_are_refused() {
        let mut value = serde_json::to_value(TrainConfig::default()).unwrap();
        value["dimz"] = serde_json::json!(3);
        assert!(serde_json::from_value::<TrainConfig>(value).is_err());
    }
}
