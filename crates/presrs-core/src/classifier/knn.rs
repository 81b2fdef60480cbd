//! k-nearest neighbours (Euclidean, in the PCA space): a simple baseline.
//!
//! `k` is chosen on the validation set among [`KnnConfig::k_grid`] by a model storing the training vectors
//! only (highest accuracy, ties to the larger `k`); the final model stores training + validation vectors.
//! The prediction is the majority of the `k` nearest; a tie in votes goes to the tied class with the
//! nearest member. Posteriors are the smoothed vote fractions `(votes + 1/2) / (k + C/2)`.

use serde::{Deserialize, Serialize};

use super::LabeledVectors;
use super::common::{check_vectors, merged, require_per_class, validation_accuracy};
use crate::error::{CoreError, Result, check_len};

/// Parameters of the k-NN classifier.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KnnConfig {
    /// Candidate neighbour counts (chosen on validation; a single value is used as is).
    #[serde(default = "default_k_grid")]
    pub k_grid: Vec<usize>,
}

fn default_k_grid() -> Vec<usize> {
    vec![1, 3, 5, 7, 9]
}

impl Default for KnnConfig {
    fn default() -> Self {
        Self {
            k_grid: default_k_grid(),
        }
    }
}

impl KnnConfig {
    pub fn check(&self) -> Result<()> {
        if self.k_grid.is_empty() || self.k_grid.contains(&0) {
            return Err(CoreError::Param {
                name: "knn k",
                reason: "at least one neighbour count, each at least 1".into(),
            });
        }
        Ok(())
    }
}

/// A trained k-NN classifier. Deserialising checks that the parts fit together: `dims >= 1`, `vectors`
/// holds `classes.len()` finite rows of `dims`, every class index is below `n_classes` and every class
/// has a stored vector, and `1 <= k <= classes.len()`. A file that breaks one of these is an error naming
/// the field.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "KnnFields", into = "KnnFields")]
pub struct KnnModel {
    dims: usize,
    n_classes: usize,
    k: usize,
    vectors: Vec<f64>,
    classes: Vec<usize>,
    /// Validation accuracy of each candidate `k` (empty when a single `k` was given).
    validation_curve: Vec<(usize, f64)>,
}

/// The serialised form of [`KnnModel`], checked on load (see there).
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct KnnFields {
    dims: usize,
    n_classes: usize,
    k: usize,
    vectors: Vec<f64>,
    classes: Vec<usize>,
    validation_curve: Vec<(usize, f64)>,
}

impl From<KnnModel> for KnnFields {
    fn from(model: KnnModel) -> Self {
        Self {
            dims: model.dims,
            n_classes: model.n_classes,
            k: model.k,
            vectors: model.vectors,
            classes: model.classes,
            validation_curve: model.validation_curve,
        }
    }
}

impl TryFrom<KnnFields> for KnnModel {
    type Error = CoreError;

    fn try_from(fields: KnnFields) -> Result<Self> {
        let bad = |reason: String| {
            Err(CoreError::Param {
                name: "knn model",
                reason,
            })
        };
        let n_stored = fields.classes.len();
        if fields.dims == 0 {
            return bad("`dims` must be at least 1".into());
        }
        if n_stored.checked_mul(fields.dims) != Some(fields.vectors.len()) {
            return bad(format!(
                "`vectors` holds {} values, not {n_stored} `classes` x {} `dims`",
                fields.vectors.len(),
                fields.dims
            ));
        }
        if fields.vectors.iter().any(|v| !v.is_finite()) {
            return bad("`vectors` holds non-finite values".into());
        }
        if let Some(&class) = fields.classes.iter().find(|&&c| c >= fields.n_classes) {
            return bad(format!(
                "`classes` holds class {class} but `n_classes` is {}",
                fields.n_classes
            ));
        }
        // Every class index is below n_classes, so n_classes <= n_stored when no class is empty.
        let mut seen = vec![false; fields.n_classes.min(n_stored)];
        for &class in &fields.classes {
            if let Some(flag) = seen.get_mut(class) {
                *flag = true;
            }
        }
        if let Some(empty) = (0..fields.n_classes).find(|&c| !seen.get(c).copied().unwrap_or(false))
        {
            return bad(format!(
                "class {empty} of `n_classes` {} has no stored vector in `classes`",
                fields.n_classes
            ));
        }
        if fields.k == 0 || fields.k > n_stored {
            return bad(format!(
                "`k` must be in 1 ..= {n_stored} (the stored vectors), got {}",
                fields.k
            ));
        }
        Ok(Self {
            dims: fields.dims,
            n_classes: fields.n_classes,
            k: fields.k,
            vectors: fields.vectors,
            classes: fields.classes,
            validation_curve: fields.validation_curve,
        })
    }
}

impl KnnModel {
    pub fn fit(
        train: LabeledVectors<'_>,
        validation: LabeledVectors<'_>,
        n_classes: usize,
        dims: usize,
        config: &KnnConfig,
    ) -> Result<Self> {
        config.check()?;
        check_vectors(&train, "knn training vectors", dims, n_classes)?;
        check_vectors(&validation, "knn validation vectors", dims, n_classes)?;
        require_per_class(&train, n_classes, 1)?;
        let mut k = config.k_grid[0];
        let mut curve = Vec::new();
        if config.k_grid.len() > 1 && !validation.classes.is_empty() {
            let mut grid = config.k_grid.clone();
            grid.sort_unstable();
            grid.dedup();
            let mut best = f64::NEG_INFINITY;
            for &candidate in &grid {
                let model = Self::store(&train, n_classes, dims, candidate);
                let mut scratch = model.scratch();
                let mut posteriors = vec![0.0; n_classes];
                let accuracy = validation_accuracy(&validation, dims, |x| {
                    model.classify_into(x, &mut scratch, &mut posteriors)
                })?;
                curve.push((candidate, accuracy));
                if accuracy >= best {
                    best = accuracy;
                    k = candidate;
                }
            }
        }
        let (vectors, classes) = merged(&train, &validation);
        let mut model = Self::store(
            &LabeledVectors {
                vectors: &vectors,
                classes: &classes,
            },
            n_classes,
            dims,
            k,
        );
        model.validation_curve = curve;
        Ok(model)
    }

    fn store(data: &LabeledVectors<'_>, n_classes: usize, dims: usize, k: usize) -> Self {
        Self {
            dims,
            n_classes,
            k: k.min(data.classes.len()).max(1),
            vectors: data.vectors.to_vec(),
            classes: data.classes.to_vec(),
            validation_curve: Vec::new(),
        }
    }

    pub fn dims(&self) -> usize {
        self.dims
    }

    pub fn n_classes(&self) -> usize {
        self.n_classes
    }

    pub fn k(&self) -> usize {
        self.k
    }

    pub fn validation_curve(&self) -> &[(usize, f64)] {
        &self.validation_curve
    }

    pub fn scratch(&self) -> KnnScratch {
        KnnScratch {
            nearest: Vec::with_capacity(self.k + 1),
            closest: vec![f64::INFINITY; self.n_classes],
        }
    }

    /// Posteriors into `posteriors`; returns the predicted class. Does not allocate once `scratch` is sized.
    pub fn classify_into(
        &self,
        x: &[f64],
        scratch: &mut KnnScratch,
        posteriors: &mut [f64],
    ) -> Result<usize> {
        check_len("knn input", self.dims, x.len())?;
        check_len("knn posteriors", self.n_classes, posteriors.len())?;
        let nearest = &mut scratch.nearest;
        nearest.clear();
        for (p, &class) in self.vectors.chunks_exact(self.dims).zip(&self.classes) {
            let d2: f64 = p.iter().zip(x).map(|(a, b)| (a - b) * (a - b)).sum();
            if nearest.len() == self.k && d2 >= nearest[self.k - 1].0 {
                continue;
            }
            // insertion into the sorted list of the k nearest (stable: earlier vectors win ties)
            let at = nearest.partition_point(|&(d, _)| d <= d2);
            if nearest.len() == self.k {
                nearest.pop();
            }
            nearest.insert(at, (d2, class));
        }
        posteriors.fill(0.0);
        scratch.closest.resize(self.n_classes, f64::INFINITY);
        scratch.closest.fill(f64::INFINITY);
        for &(d2, class) in nearest.iter() {
            posteriors[class] += 1.0;
            scratch.closest[class] = scratch.closest[class].min(d2);
        }
        let mut best = 0;
        for class in 1..self.n_classes {
            let (v, b) = (posteriors[class], posteriors[best]);
            if v > b || (v == b && scratch.closest[class] < scratch.closest[best]) {
                best = class;
            }
        }
        let denominator = nearest.len() as f64 + 0.5 * self.n_classes as f64;
        for p in posteriors.iter_mut() {
            *p = (*p + 0.5) / denominator;
        }
        Ok(best)
    }
}

/// Reusable buffers of [`KnnModel::classify_into`].
#[derive(Clone, Debug, Default)]
pub struct KnnScratch {
    nearest: Vec<(f64, usize)>,
    closest: Vec<f64>,
}
