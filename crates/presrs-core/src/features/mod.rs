//! Feature extraction from pressure images (the paper's 1-D |FFT| of eqs. 3-5, and more).
//!
//! A [`FeatureConfig`] names a feature family and its parameters (it is stored in trained models, tagged
//! by `kind` in serde). [`FeatureConfig::extractor`] builds a reusable [`FeatureExtractor`] for one image
//! grid that owns its plans and buffers, so extracting does not allocate.

pub mod fft1d;
pub mod fft2d;
pub mod glcm;
pub mod rocket;

use serde::{Deserialize, Serialize};

use crate::error::{CoreError, Result};
use crate::frame::Grid;

pub use fft1d::{Fft1dConfig, Fft1dExtractor};
pub use fft2d::{Fft2dConfig, Fft2dExtractor, Fft2dForm};
pub use glcm::{GLCM_ATTRIBUTE_NAMES, GlcmConfig, GlcmExtractor};

/// The feature families, by name (as the CLI's `--features` spells them).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FeatureKind {
    /// Magnitude of the 1-D FFT of the row-major image (the paper's eqs. 3-5).
    Fft1d,
    /// The non-redundant half of the 2-D |FFT|.
    Fft2d,
    /// Ring and wedge sums of the 2-D |FFT| (compact, shift- and rotation-robust).
    Fft2dPolar,
    /// Haralick attributes of grey-level co-occurrence matrices.
    Glcm,
    /// Several families side by side (not a name of its own: `fft1d+glcm`).
    Combined,
}

impl FeatureKind {
    /// The single families (what `--features` accepts, alone or joined with `+` or `,`).
    pub const ALL: [Self; 4] = [Self::Fft1d, Self::Fft2d, Self::Fft2dPolar, Self::Glcm];

    pub fn as_str(self) -> &'static str {
        match self {
            Self::Fft1d => "fft1d",
            Self::Fft2d => "fft2d",
            Self::Fft2dPolar => "fft2d_polar",
            Self::Glcm => "glcm",
            Self::Combined => "combined",
        }
    }

    /// Parses a name (case-insensitive).
    pub fn parse(text: &str) -> Result<Self> {
        crate::error::parse_name(text, Self::ALL, Self::as_str, "features", "feature kind")
    }

    /// The default parameters of this family.
    pub fn default_config(self) -> FeatureConfig {
        match self {
            Self::Fft1d => FeatureConfig::Fft1d(Fft1dConfig::PAPER),
            Self::Fft2d => FeatureConfig::Fft2d(Fft2dConfig::HALF),
            Self::Fft2dPolar => FeatureConfig::Fft2d(Fft2dConfig::POLAR),
            Self::Glcm => FeatureConfig::Glcm(GlcmConfig::default()),
            Self::Combined => FeatureConfig::combined(&[Self::Fft1d, Self::Glcm]),
        }
    }

    /// Parses `fft1d`, `glcm`, `fft1d+glcm`, `fft2d_polar,glcm`, ... into the families named.
    pub fn parse_list(text: &str) -> Result<Vec<Self>> {
        let kinds = text
            .split(['+', ','])
            .map(Self::parse)
            .collect::<Result<Vec<_>>>()?;
        Ok(kinds)
    }
}

/// Parameters of several feature families side by side. Each part's vector is scaled to unit Euclidean
/// norm before concatenation, so no family dominates the PCA by its units alone.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CombinedConfig {
    pub parts: Vec<FeatureConfig>,
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
    Fft2d(Fft2dConfig),
    Glcm(GlcmConfig),
    Combined(CombinedConfig),
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
            Self::Fft2d(config) if config.form == Fft2dForm::Polar => FeatureKind::Fft2dPolar,
            Self::Fft2d(_) => FeatureKind::Fft2d,
            Self::Glcm(_) => FeatureKind::Glcm,
            Self::Combined(_) => FeatureKind::Combined,
        }
    }

    /// The default configuration of `kinds` (one family: itself; several: combined).
    pub fn combined(kinds: &[FeatureKind]) -> Self {
        match kinds {
            [one] if *one != FeatureKind::Combined => one.default_config(),
            _ => Self::Combined(CombinedConfig {
                parts: kinds.iter().map(|k| k.default_config()).collect(),
            }),
        }
    }

    /// Whether classification computes these features otherwise than training ([`Precision::Fast`]:
    /// the 1-D |FFT| in single precision, alone or as a part).
    pub fn has_fast_path(&self) -> bool {
        match self {
            Self::Fft1d(_) => true,
            Self::Fft2d(_) | Self::Glcm(_) => false,
            Self::Combined(config) => config.parts.iter().any(Self::has_fast_path),
        }
    }

    /// A short name: the family, or the parts joined with `+`.
    pub fn name(&self) -> String {
        match self {
            Self::Combined(config) => config
                .parts
                .iter()
                .map(Self::name)
                .collect::<Vec<_>>()
                .join("+"),
            other => other.kind().as_str().to_owned(),
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
            Self::Fft2d(config) => config.check(),
            Self::Glcm(config) => config.check(),
            Self::Combined(config) => {
                if config.parts.is_empty() {
                    return Err(CoreError::Param {
                        name: "features",
                        reason: "a combination needs at least one part".into(),
                    });
                }
                config.parts.iter().try_for_each(Self::check)
            }
        }
    }

    /// Number of features for images of `grid`, or an error if this configuration cannot take such images.
    pub fn output_len(&self, grid: Grid) -> Result<usize> {
        match self {
            Self::Fft1d(config) => config.output_len(grid),
            Self::Fft2d(config) => config.output_len(grid),
            Self::Glcm(config) => config.output_len(grid),
            Self::Combined(config) => config.parts.iter().map(|p| p.output_len(grid)).sum(),
        }
    }

    /// The name of each feature for images of `grid`, in order (each family's `feature_names`; the
    /// parts of a combination one after another).
    pub fn feature_names(&self, grid: Grid) -> Result<Vec<String>> {
        match self {
            Self::Fft1d(config) => config.feature_names(grid),
            Self::Fft2d(config) => config.feature_names(grid),
            Self::Glcm(config) => config.feature_names(grid),
            Self::Combined(config) => {
                let mut names = Vec::new();
                for part in &config.parts {
                    names.extend(part.feature_names(grid)?);
                }
                Ok(names)
            }
        }
    }

    /// A reusable extractor for images of `grid`.
    pub fn extractor(&self, grid: Grid) -> Result<FeatureExtractor> {
        match self {
            Self::Fft1d(config) => Fft1dExtractor::new(grid, config).map(FeatureExtractor::Fft1d),
            Self::Fft2d(config) => Fft2dExtractor::new(grid, config).map(FeatureExtractor::Fft2d),
            Self::Glcm(config) => GlcmExtractor::new(grid, config).map(FeatureExtractor::Glcm),
            Self::Combined(config) => {
                self.check()?;
                let parts = config
                    .parts
                    .iter()
                    .map(|p| p.extractor(grid))
                    .collect::<Result<Vec<_>>>()?;
                Ok(FeatureExtractor::Combined(parts))
            }
        }
    }
}

/// How features are computed: exactly (training, exported features) or as the classifier's fast path.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Precision {
    Exact,
    Fast,
}

/// A feature extractor bound to one image grid; owns its buffers.
#[derive(Clone, Debug)]
pub enum FeatureExtractor {
    Fft1d(Fft1dExtractor),
    Fft2d(Fft2dExtractor),
    Glcm(GlcmExtractor),
    Combined(Vec<FeatureExtractor>),
}

impl FeatureExtractor {
    /// The image grid this extractor takes.
    pub fn grid(&self) -> Grid {
        match self {
            Self::Fft1d(extractor) => extractor.grid(),
            Self::Fft2d(extractor) => extractor.grid(),
            Self::Glcm(extractor) => extractor.grid(),
            Self::Combined(parts) => parts.first().map_or(Grid::new(0, 0), Self::grid),
        }
    }

    /// Number of features per image.
    pub fn output_len(&self) -> usize {
        match self {
            Self::Fft1d(extractor) => extractor.output_len(),
            Self::Fft2d(extractor) => extractor.output_len(),
            Self::Glcm(extractor) => extractor.output_len(),
            Self::Combined(parts) => parts.iter().map(Self::output_len).sum(),
        }
    }

    /// Writes the features of `image` (row-major, `grid` sized) into `out` (`output_len` long).
    /// Does not allocate.
    pub fn extract_into(&mut self, image: &[f64], out: &mut [f64]) -> Result<()> {
        self.extract_with(image, out, Precision::Exact)
    }

    /// [`extract_into`](Self::extract_into) for classification: the 1-D |FFT| in single precision
    /// ([`Fft1dExtractor::extract_fast_into`]), every other family exact. Does not allocate.
    pub fn extract_fast_into(&mut self, image: &[f64], out: &mut [f64]) -> Result<()> {
        self.extract_with(image, out, Precision::Fast)
    }

    fn extract_with(&mut self, image: &[f64], out: &mut [f64], precision: Precision) -> Result<()> {
        match self {
            Self::Fft1d(extractor) => match precision {
                Precision::Exact => extractor.extract_into(image, out),
                Precision::Fast => extractor.extract_fast_into(image, out),
            },
            Self::Fft2d(extractor) => extractor.extract_into(image, out),
            Self::Glcm(extractor) => extractor.extract_into(image, out),
            Self::Combined(parts) => {
                let expected: usize = parts.iter().map(Self::output_len).sum();
                crate::error::check_len("feature buffer", expected, out.len())?;
                let mut rest = out;
                for part in parts.iter_mut() {
                    let (head, tail) = rest.split_at_mut(part.output_len());
                    part.extract_with(image, head, precision)?;
                    let norm = head.iter().map(|v| v * v).sum::<f64>().sqrt();
                    if norm > 0.0 {
                        head.iter_mut().for_each(|v| *v /= norm);
                    }
                    rest = tail;
                }
                Ok(())
            }
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

    #[test]
    fn every_family_names_each_of_its_features() {
        let grid = Grid::new(38, 41);
        let mut combined = Vec::new();
        for kind in FeatureKind::ALL {
            let config = kind.default_config();
            let names = config.feature_names(grid).unwrap();
            assert_eq!(names.len(), config.output_len(grid).unwrap(), "{kind}");
            let unique: std::collections::BTreeSet<&String> = names.iter().collect();
            assert_eq!(unique.len(), names.len(), "{kind}: names repeat");
            assert!(names.iter().all(|n| n.starts_with(kind.as_str())), "{kind}");
            combined.extend(names);
        }
        assert_eq!(
            FeatureConfig::combined(&FeatureKind::ALL)
                .feature_names(grid)
                .unwrap(),
            combined
        );
        let fft2d = FeatureKind::Fft2d
            .default_config()
            .feature_names(grid)
            .unwrap();
        assert_eq!(&fft2d[..2], ["fft2d_r0_c0", "fft2d_r0_c1"]);
        let polar = FeatureKind::Fft2dPolar
            .default_config()
            .feature_names(grid)
            .unwrap();
        assert_eq!(
            (polar[0].as_str(), polar[24].as_str()),
            ("fft2d_polar_ring0", "fft2d_polar_wedge0")
        );
        let glcm = FeatureKind::Glcm
            .default_config()
            .feature_names(grid)
            .unwrap();
        assert_eq!(&glcm[..2], ["glcm_contrast_d1", "glcm_dissimilarity_d1"]);
    }

    #[test]
    fn half_spectrum_names_follow_the_extractors_order() {
        // A single frequency (row bin 2, column bin 3) in a 8 x 8 image: its feature is the largest.
        let grid = Grid::new(8, 8);
        let image: Vec<f64> = (0..64)
            .map(|i| {
                let (r, c) = ((i / 8) as f64, (i % 8) as f64);
                (2.0 * std::f64::consts::PI * (2.0 * r + 3.0 * c) / 8.0).cos()
            })
            .collect();
        let config = FeatureKind::Fft2d.default_config();
        let features = config.extractor(grid).unwrap().extract(&image).unwrap();
        let names = config.feature_names(grid).unwrap();
        let top = (0..features.len())
            .max_by(|&a, &b| features[a].total_cmp(&features[b]))
            .unwrap();
        assert_eq!(names[top], "fft2d_r2_c3");
    }
}
