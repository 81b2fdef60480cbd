//! Feature extraction from pressure images (the paper's 1-D |FFT| of eqs. 3-5, and more).
//!
//! A [`FeatureConfig`] names a feature family and its parameters (it is stored in trained models, tagged
//! by `kind` in serde). [`FeatureConfig::extractor`] builds a reusable [`FeatureExtractor`] for one image
//! grid that owns its plans and buffers, so extracting does not allocate.

pub mod fft1d;

use serde::{Deserialize, Serialize};

use crate::error::{CoreError, Result};
use crate::frame::Grid;

pub use fft1d::{Fft1dConfig, Fft1dExtractor};

/// The feature families, by name (as the CLI's `--features` spells them).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FeatureKind {
    /// Magnitude of the 1-D FFT of the row-major image (the paper's eqs. 3-5).
    Fft1d,
}

impl FeatureKind {
    pub const ALL: [Self; 1] = [Self::Fft1d];

    pub fn as_str(self) -> &'static str {
        match self {
            Self::Fft1d => "fft1d",
        }
    }

    /// Parses a name (case-insensitive).
    pub fn parse(text: &str) -> Result<Self> {
        let wanted = text.trim().to_ascii_lowercase();
        Self::ALL
            .into_iter()
            .find(|kind| kind.as_str() == wanted)
            .ok_or_else(|| CoreError::Param {
                name: "features",
                reason: format!(
                    "unknown feature kind {text:?}; known: {}",
                    Self::ALL.map(Self::as_str).join(", ")
                ),
            })
    }

    /// The default parameters of this family.
    pub fn default_config(self) -> FeatureConfig {
        match self {
            Self::Fft1d => FeatureConfig::Fft1d(Fft1dConfig::PAPER),
        }
    }
}

impl std::fmt::Display for FeatureKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// A feature family with its parameters.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum FeatureConfig {
    Fft1d(Fft1dConfig),
}

impl Default for FeatureConfig {
    fn default() -> Self {
        Self::Fft1d(Fft1dConfig::PAPER)
    }
}

impl FeatureConfig {
    pub fn kind(&self) -> FeatureKind {
        match self {
            Self::Fft1d(_) => FeatureKind::Fft1d,
        }
    }

    /// Checks the parameters on their own (the image grid is checked by [`output_len`](Self::output_len)).
    pub fn check(&self) -> Result<()> {
        match self {
            Self::Fft1d(Fft1dConfig { fft_len: Some(0) }) => Err(CoreError::Param {
                name: "fft_len",
                reason: "the transform length must be positive".into(),
            }),
            Self::Fft1d(_) => Ok(()),
        }
    }

    /// Number of features for images of `grid`, or an error if this configuration cannot take such images.
    pub fn output_len(&self, grid: Grid) -> Result<usize> {
        match self {
            Self::Fft1d(config) => config.output_len(grid),
        }
    }

    /// A reusable extractor for images of `grid`.
    pub fn extractor(&self, grid: Grid) -> Result<FeatureExtractor> {
        match self {
            Self::Fft1d(config) => Fft1dExtractor::new(grid, config).map(FeatureExtractor::Fft1d),
        }
    }
}

/// A feature extractor bound to one image grid; owns its buffers.
#[derive(Clone, Debug)]
pub enum FeatureExtractor {
    Fft1d(Fft1dExtractor),
}

impl FeatureExtractor {
    /// The image grid this extractor takes.
    pub fn grid(&self) -> Grid {
        match self {
            Self::Fft1d(extractor) => extractor.grid(),
        }
    }

    /// Number of features per image.
    pub fn output_len(&self) -> usize {
        match self {
            Self::Fft1d(extractor) => extractor.output_len(),
        }
    }

    /// Writes the features of `image` (row-major, `grid` sized) into `out` (`output_len` long).
    /// Does not allocate.
    pub fn extract_into(&mut self, image: &[f64], out: &mut [f64]) -> Result<()> {
        match self {
            Self::Fft1d(extractor) => extractor.extract_into(image, out),
        }
    }

    /// The features of `image` in a new vector.
    pub fn extract(&mut self, image: &[f64]) -> Result<Vec<f64>> {
        let mut out = vec![0.0; self.output_len()];
        self.extract_into(image, &mut out)?;
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kind_names_round_trip() {
        for kind in FeatureKind::ALL {
            assert_eq!(FeatureKind::parse(kind.as_str()).unwrap(), kind);
            assert_eq!(kind.default_config().kind(), kind);
        }
        assert_eq!(FeatureKind::parse(" FFT1D ").unwrap(), FeatureKind::Fft1d);
        assert!(FeatureKind::parse("wavelet").is_err());
    }

    #[test]
    fn config_serde_is_tagged() {
        let config = FeatureConfig::Fft1d(Fft1dConfig {
            fft_len: Some(4096),
        });
        let json = serde_json::to_string(&config).unwrap();
        assert_eq!(json, r#"{"kind":"fft1d","fft_len":4096}"#);
        assert_eq!(
            serde_json::from_str::<FeatureConfig>(&json).unwrap(),
            config
        );
        let default: FeatureConfig = serde_json::from_str(r#"{"kind":"fft1d"}"#).unwrap();
        assert_eq!(default, FeatureConfig::default());
    }
}
