//! [`FeatureConfig`] and [`FeatureExtractor`]: any registered family, or several side by side, behind one
//! type each. A configuration is stored tagged by the family's name (`{"kind": "fft1d", ...its fields}`,
//! a combination as `{"kind": "combined", "parts": [...]}`), as the enums they replace were.
//!
//! Combining is not a family of its own: it holds families, and the registry must not know it (or the
//! registry's file and this one would import each other).

use serde::de::Error as _;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use crate::error::{CoreError, Result};
use crate::features::erased::{ConfigOf, DynConfig, DynExtractor, ExtractorOf};
use crate::features::family::{FeatureFamily, FitImages};
use crate::features::fft1d::Fft1dFamily;
use crate::features::registry::{FeatureKind, families, family_named};
use crate::frame::Grid;

/// The stored name of a combination.
const COMBINED: &str = "combined";

/// A feature family with its parameters, or several side by side. In a combination each part's vector
/// is scaled to unit Euclidean norm before concatenation, so no family dominates the PCA by its units
/// alone.
#[derive(Debug)]
pub struct FeatureConfig(Repr);

#[derive(Debug)]
enum Repr {
    One(Box<dyn DynConfig>),
    Combined(Vec<FeatureConfig>),
}

impl FeatureKind {
    /// The parameters of this preset.
    pub fn default_config(self) -> FeatureConfig {
        FeatureConfig(Repr::One(self.family().preset(self.preset_index())))
    }
}

impl Default for FeatureConfig {
    /// The paper's 1-D |FFT|.
    fn default() -> Self {
        FeatureKind::FFT1D.default_config()
    }
}

impl FeatureConfig {
    /// Family `F` with parameters `config`.
    pub fn of<F: FeatureFamily>(config: F::Config) -> Self {
        Self(Repr::One(Box::new(ConfigOf::<F>(config))))
    }

    /// The default configuration of `kinds` (one family: itself; several: combined).
    pub fn combined(kinds: &[FeatureKind]) -> Self {
        match kinds {
            [one] => one.default_config(),
            _ => Self::of_parts(kinds.iter().map(|kind| kind.default_config()).collect()),
        }
    }

    /// Several configurations side by side.
    pub fn of_parts(parts: Vec<FeatureConfig>) -> Self {
        Self(Repr::Combined(parts))
    }

    /// The parameters, when this is family `F` alone.
    pub fn params<F: FeatureFamily>(&self) -> Option<&F::Config> {
        match &self.0 {
            Repr::One(config) => Some(&config.as_any().downcast_ref::<ConfigOf<F>>()?.0),
            Repr::Combined(_) => None,
        }
    }

    /// The preset this shows as, when one family alone.
    pub fn kind(&self) -> Option<FeatureKind> {
        match &self.0 {
            Repr::One(config) => Some(FeatureKind::from_parts(config.family(), config.preset_of())),
            Repr::Combined(_) => None,
        }
    }

    /// The families side by side, in order: one for a single family.
    pub fn parts(&self) -> Vec<&FeatureConfig> {
        match &self.0 {
            Repr::One(_) => vec![self],
            Repr::Combined(parts) => parts.iter().flat_map(FeatureConfig::parts).collect(),
        }
    }

    /// Whether this is the 1-D |FFT| alone (the paper's family, whatever its length).
    pub fn is_fft1d(&self) -> bool {
        self.params::<Fft1dFamily>().is_some()
    }

    /// Whether any part is costly to compute (scored last by the automatic choice).
    pub fn is_costly(&self) -> bool {
        self.parts()
            .iter()
            .any(|part| part.kind().is_some_and(FeatureKind::costly))
    }

    /// Whether classification computes these features otherwise than training ([`Precision::Fast`]:
    /// the 1-D |FFT| in single precision, alone or as a part).
    pub fn has_fast_path(&self) -> bool {
        match &self.0 {
            Repr::One(config) => config.has_fast_path(),
            Repr::Combined(parts) => parts.iter().any(Self::has_fast_path),
        }
    }

    /// A short name: the preset, or the parts joined with `+`.
    pub fn name(&self) -> String {
        match &self.0 {
            Repr::One(_) => self.kind().map_or("", FeatureKind::as_str).to_owned(),
            Repr::Combined(parts) => parts.iter().map(Self::name).collect::<Vec<_>>().join("+"),
        }
    }

    /// Checks the parameters on their own (the image grid is checked by [`output_len`](Self::output_len)).
    pub fn check(&self) -> Result<()> {
        match &self.0 {
            Repr::One(config) => config.check(),
            Repr::Combined(parts) if parts.is_empty() => Err(CoreError::Param {
                name: "features",
                reason: "a combination needs at least one part".into(),
            }),
            Repr::Combined(parts) => parts.iter().try_for_each(Self::check),
        }
    }

    /// Whether any part learns from the training images ([`FeatureFamily::fit`]).
    pub fn learns(&self) -> bool {
        self.parts().iter().any(|part| match &part.0 {
            Repr::One(config) => config.family().learns(),
            Repr::Combined(_) => false,
        })
    }

    /// Learns what the families need from the training images (see [`FeatureFamily::fit`]); the result
    /// is what the model stores.
    pub fn fit(&self, images: FitImages<'_>) -> Result<Self> {
        Ok(Self(match &self.0 {
            Repr::One(config) => Repr::One(config.fit(images)?),
            Repr::Combined(parts) => Repr::Combined(
                parts
                    .iter()
                    .map(|part| part.fit(images))
                    .collect::<Result<_>>()?,
            ),
        }))
    }

    /// Number of features for images of `grid`, or an error if this configuration cannot take such images.
    pub fn output_len(&self, grid: Grid) -> Result<usize> {
        match &self.0 {
            Repr::One(config) => config.output_len(grid),
            Repr::Combined(parts) => parts.iter().map(|p| p.output_len(grid)).sum(),
        }
    }

    /// The name of each feature for images of `grid`, in order (each family's `feature_names`; the
    /// parts of a combination one after another).
    pub fn feature_names(&self, grid: Grid) -> Result<Vec<String>> {
        let mut names = Vec::new();
        for part in self.parts() {
            if let Repr::One(config) = &part.0 {
                names.extend(config.feature_names(grid)?);
            }
        }
        Ok(names)
    }

    /// The points of the transforms planned for `grid`, summed over the parts (saturating); each
    /// family checks its own against [`MAX_TRANSFORM_LEN`](super::MAX_TRANSFORM_LEN).
    pub fn transform_points(&self, grid: Grid) -> Result<usize> {
        self.parts()
            .iter()
            .try_fold(0usize, |total, part| match &part.0 {
                Repr::One(config) => Ok(total.saturating_add(config.transform_points(grid)?)),
                Repr::Combined(_) => Ok(total),
            })
    }

    /// A reusable extractor for images of `grid`.
    pub fn extractor(&self, grid: Grid) -> Result<FeatureExtractor> {
        match &self.0 {
            Repr::One(config) => Ok(FeatureExtractor(ExtractorRepr::One(
                config.extractor(grid)?,
            ))),
            Repr::Combined(parts) => {
                self.check()?;
                let parts = parts
                    .iter()
                    .map(|p| p.extractor(grid))
                    .collect::<Result<Vec<_>>>()?;
                Ok(FeatureExtractor(ExtractorRepr::Combined(parts)))
            }
        }
    }
}

impl Clone for FeatureConfig {
    fn clone(&self) -> Self {
        Self(match &self.0 {
            Repr::One(config) => Repr::One(config.clone_box()),
            Repr::Combined(parts) => Repr::Combined(parts.clone()),
        })
    }
}

impl PartialEq for FeatureConfig {
    fn eq(&self, other: &Self) -> bool {
        match (&self.0, &other.0) {
            (Repr::One(a), Repr::One(b)) => {
                a.family().name() == b.family().name()
                    && serde_json::to_value(a.fields()).ok()
                        == serde_json::to_value(b.fields()).ok()
            }
            (Repr::Combined(a), Repr::Combined(b)) => a == b,
            _ => false,
        }
    }
}

impl Eq for FeatureConfig {}

/// The stored form of one family: its name under `kind`, then its own fields.
#[derive(Serialize)]
struct Tagged<'a> {
    kind: &'static str,
    #[serde(flatten)]
    fields: &'a dyn erased_serde::Serialize,
}

/// The stored form of a combination.
#[derive(Serialize)]
struct TaggedParts<'a> {
    kind: &'static str,
    parts: &'a [FeatureConfig],
}

impl Serialize for FeatureConfig {
    fn serialize<S: Serializer>(&self, serializer: S) -> std::result::Result<S::Ok, S::Error> {
        match &self.0 {
            Repr::One(config) => Tagged {
                kind: config.family().name(),
                fields: config.fields(),
            }
            .serialize(serializer),
            Repr::Combined(parts) => TaggedParts {
                kind: COMBINED,
                parts,
            }
            .serialize(serializer),
        }
    }
}

/// A combination's stored fields (and nothing else).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PartsFields {
    parts: Vec<FeatureConfig>,
}

impl<'de> Deserialize<'de> for FeatureConfig {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> std::result::Result<Self, D::Error> {
        let mut fields = serde_json::Map::deserialize(deserializer)?;
        let kind = match fields.remove("kind") {
            Some(serde_json::Value::String(name)) => name,
            Some(other) => {
                return Err(D::Error::custom(format!(
                    "`kind` must be a name, got {other}"
                )));
            }
            None => return Err(D::Error::missing_field("kind")),
        };
        let fields = serde_json::Value::Object(fields);
        if kind == COMBINED {
            let parts: PartsFields = serde_json::from_value(fields).map_err(D::Error::custom)?;
            return Ok(Self::of_parts(parts.parts));
        }
        let family = family_named(&kind).ok_or_else(|| {
            let mut known: Vec<&str> = families().iter().map(|f| f.name()).collect();
            known.push(COMBINED);
            D::Error::custom(format!(
                "unknown variant `{kind}`, expected one of {}",
                known.join(", ")
            ))
        })?;
        let config = family.config_from_value(fields).map_err(D::Error::custom)?;
        Ok(Self(Repr::One(config)))
    }
}

/// How features are computed: exactly (training, exported features) or as the classifier's fast path.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Precision {
    Exact,
    Fast,
}

/// A feature extractor bound to one image grid; owns its buffers.
#[derive(Debug)]
pub struct FeatureExtractor(ExtractorRepr);

#[derive(Debug)]
enum ExtractorRepr {
    One(Box<dyn DynExtractor>),
    Combined(Vec<FeatureExtractor>),
}

impl Clone for FeatureExtractor {
    fn clone(&self) -> Self {
        Self(match &self.0 {
            ExtractorRepr::One(extractor) => ExtractorRepr::One(extractor.clone_box()),
            ExtractorRepr::Combined(parts) => ExtractorRepr::Combined(parts.clone()),
        })
    }
}

impl FeatureExtractor {
    /// The extractor, when it is family `F`'s alone.
    pub fn get<F: FeatureFamily>(&self) -> Option<&F::Extractor> {
        match &self.0 {
            ExtractorRepr::One(extractor) => {
                Some(&extractor.as_any().downcast_ref::<ExtractorOf<F>>()?.0)
            }
            ExtractorRepr::Combined(_) => None,
        }
    }

    /// The image grid this extractor takes.
    pub fn grid(&self) -> Grid {
        match &self.0 {
            ExtractorRepr::One(extractor) => extractor.grid(),
            ExtractorRepr::Combined(parts) => parts.first().map_or(Grid::new(0, 0), Self::grid),
        }
    }

    /// Number of features per image.
    pub fn output_len(&self) -> usize {
        match &self.0 {
            ExtractorRepr::One(extractor) => extractor.len(),
            ExtractorRepr::Combined(parts) => parts.iter().map(Self::output_len).sum(),
        }
    }

    /// Writes the features of `image` (row-major, `grid` sized) into `out` (`output_len` long).
    /// Does not allocate.
    pub fn extract_into(&mut self, image: &[f64], out: &mut [f64]) -> Result<()> {
        self.extract_with(image, out, Precision::Exact)
    }

    /// [`extract_into`](Self::extract_into) for classification: each family's fast path (the 1-D |FFT|
    /// in single precision), the others exact. Does not allocate.
    pub fn extract_fast_into(&mut self, image: &[f64], out: &mut [f64]) -> Result<()> {
        self.extract_with(image, out, Precision::Fast)
    }

    /// The fast features of an image that is a window of a larger row-major array, in single precision
    /// (see [`FeatureFamily::extract_fast_window`]); `None` for a combination or a family without it.
    pub fn extract_fast_window(
        &mut self,
        values: &[f64],
        first: usize,
        stride: usize,
    ) -> Option<Result<&[f32]>> {
        match &mut self.0 {
            ExtractorRepr::One(extractor) => extractor.extract_fast_window(values, first, stride),
            ExtractorRepr::Combined(_) => None,
        }
    }

    fn extract_with(&mut self, image: &[f64], out: &mut [f64], precision: Precision) -> Result<()> {
        match &mut self.0 {
            ExtractorRepr::One(extractor) => match precision {
                Precision::Exact => extractor.extract_into(image, out),
                Precision::Fast => extractor.extract_fast_into(image, out),
            },
            ExtractorRepr::Combined(parts) => {
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
