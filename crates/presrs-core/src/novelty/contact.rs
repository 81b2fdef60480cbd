//! The contact's geometry as a part of a frame model's novelty score, and the check inside the
//! training data that decides whether a model takes it.
//!
//! A new object that lands among the known ones in the classifier's space (tais22's cylinders of other
//! diameters) often differs in the size and shape of its contact, which a spectrum or a texture holds
//! only implicitly. The part appends the 20 measures of [`crate::features::contact`] (standardised over
//! the training images, then weighted so that a measure varies as much as a classifier value does on
//! average) to the classifier's vector before the discriminant space; the classifier is untouched.
//!
//! Those measures also vary between recordings of one terrain (the simulator's grass: twice the new
//! trials called `unknown` with them), so a model takes the part only when leaving its own classes out,
//! inside its training data, shows that the part separates them better (`pipeline::contact_check`): the
//! AUROC of the score with and without the part, a class at a time against the known samples of
//! held-out groups, and the part only when its gain exceeds one standard error of the per-class gains
//! (bench/real/RESULTS.md, "The contact part decided by leaving classes out inside the training
//! data").

use serde::{Deserialize, Serialize};

use crate::error::{CoreError, Result, check_len};
use crate::features::contact::{ContactConfig, ContactScale};
use crate::linalg::column_standardisation;

/// The contact part of a novelty score: each raw measure's training mean and spread, and the weight
/// of the standardised measures beside the classifier's values.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NoveltyContact {
    /// The measures (their levels and radii) and their standardisation.
    pub(crate) config: ContactConfig,
    /// The standardised measures' weight: the square root of the classifier values' mean variance.
    pub(crate) weight: f64,
}

impl NoveltyContact {
    /// Fits the part on `raw` (`n x measures` raw measures of `config`, row-major) beside `vectors`
    /// (`n x dims`, the classifier's).
    pub fn fit(config: &ContactConfig, raw: &[f64], vectors: &[f64], dims: usize) -> Result<Self> {
        let measures = config.measures();
        let n = vectors.len() / dims.max(1);
        check_len("contact measures", n * measures, raw.len())?;
        check_len("novelty vectors", n * dims, vectors.len())?;
        if n < 2 || dims == 0 {
            return Err(CoreError::NotEnoughData(
                "the contact part needs two vectors or more".into(),
            ));
        }
        let (mean, spread) = column_standardisation(|| raw.chunks_exact(measures), measures);
        let (_, scales) = column_standardisation(|| vectors.chunks_exact(dims), dims);
        let weight = (scales.iter().map(|s| s * s).sum::<f64>() / dims as f64).sqrt();
        let config = ContactConfig {
            fitted: Some(ContactScale { mean, spread }),
            ..config.clone()
        };
        let part = Self { config, weight };
        part.check()?;
        Ok(part)
    }

    /// Number of measures appended.
    pub fn measures(&self) -> usize {
        self.config.measures()
    }

    /// The measures' configuration, to compute the raw measures of an image with
    /// ([`crate::features::contact::raw_measures_into`]).
    pub fn config(&self) -> &ContactConfig {
        &self.config
    }

    /// Writes `vector` followed by the weighted standardised `raw` measures into `out`.
    pub fn join_into(&self, vector: &[f64], raw: &[f64], out: &mut [f64]) -> Result<()> {
        check_len("contact measures", self.measures(), raw.len())?;
        check_len("novelty vector", vector.len() + raw.len(), out.len())?;
        let scale = self.scale()?;
        let (head, tail) = out.split_at_mut(vector.len());
        head.copy_from_slice(vector);
        for (((dst, &v), m), s) in tail.iter_mut().zip(raw).zip(&scale.mean).zip(&scale.spread) {
            *dst = self.weight * (v - m) / s;
        }
        Ok(())
    }

    /// Every row of `vectors` (`n x dims`) joined with its row of `raw`.
    pub fn joined(&self, vectors: &[f64], dims: usize, raw: &[f64]) -> Result<Vec<f64>> {
        let measures = self.measures();
        let n = vectors.len() / dims.max(1);
        check_len("contact measures", n * measures, raw.len())?;
        let mut out = vec![0.0; n * (dims + measures)];
        for ((row, raw), dst) in vectors
            .chunks_exact(dims)
            .zip(raw.chunks_exact(measures))
            .zip(out.chunks_exact_mut(dims + measures))
        {
            self.join_into(row, raw, dst)?;
        }
        Ok(out)
    }

    fn scale(&self) -> Result<&ContactScale> {
        self.config.fitted.as_ref().ok_or_else(|| CoreError::Param {
            name: "novelty contact",
            reason: "the contact part holds no fitted scale".into(),
        })
    }

    /// The parts fit together (a model file's part is checked on load).
    pub(crate) fn check(&self) -> Result<()> {
        self.config.check()?;
        let measures = self.config.measures();
        let fits = self.config.fitted.as_ref().is_some_and(|scale| {
            scale.mean.len() == measures
                && scale.spread.len() == measures
                && scale.mean.iter().all(|v| v.is_finite())
                && scale.spread.iter().all(|v| v.is_finite() && *v > 0.0)
        });
        if !(fits && self.weight.is_finite() && self.weight > 0.0) {
            return Err(CoreError::Param {
                name: "novelty contact",
                reason: format!(
                    "the contact part needs a finite positive weight and a mean and positive spread for \
                     each of its {measures} measures"
                ),
            });
        }
        Ok(())
    }
}

/// What the check of the contact part (`pipeline::contact_check`) measured: the mean inner AUROC without and with the part, the standard error
/// of the per-class gains, and whether the part is taken.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactCheck {
    pub without: f64,
    pub with: f64,
    pub standard_error: f64,
    /// Classes left out (each with both scores).
    pub classes: usize,
    pub taken: bool,
}
