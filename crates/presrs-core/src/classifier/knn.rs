//! k-nearest neighbours (Euclidean, in the PCA space): a simple baseline.
//!
//! `k` is chosen on the validation set among [`KnnConfig::k_grid`] by a model storing the training vectors
//! only (highest accuracy, ties to the larger `k`); the final model stores training + validation vectors.
//! The prediction is the majority of the `k` nearest; a tie in votes goes to the tied class with the
//! nearest member.
//!
//! Posteriors are the smoothed vote counts at a temperature: `softmax(ln(votes + 1/2) / T)`, that is
//! `(votes_c + 1/2)^(1/T)` normalised over the classes. At `T = 1` they are the smoothed vote fractions
//! `(votes + 1/2) / (k + C/2)`, which are far from calibrated: with `k = 9` of four classes a unanimous
//! vote gives 0.86 and `k = 1` gives 0.5, whatever the data. `T` is fitted to the leave-one-out votes of
//! the stored vectors (each scored by the `k` nearest of the others) by
//! [`fit_temperature`], as the Parzen window's is; it never changes a
//! label (the vote counts keep their order; tied counts stay tied and go to the nearest member).

use serde::{Deserialize, Serialize};

use super::calibration::{fit_temperature, is_usable_temperature, unit_temperature};
use super::common::LabeledVectors;
use super::common::{
    check_vectors, merged, require_per_class, softmax_in_place, validation_accuracy,
};
use super::family::{ClassifierFamily, FitData};
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
    /// The posteriors' temperature, fitted on the leave-one-out votes of the stored vectors.
    temperature: f64,
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
    /// Absent from model files written before calibration: their posteriors were the plain smoothed
    /// vote fractions (1).
    #[serde(default = "unit_temperature")]
    temperature: f64,
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
            temperature: model.temperature,
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
        if !is_usable_temperature(fields.temperature) {
            return bad(format!(
                "`temperature` must be finite and positive, got {}",
                fields.temperature
            ));
        }
        Ok(Self {
            dims: fields.dims,
            n_classes: fields.n_classes,
            k: fields.k,
            vectors: fields.vectors,
            classes: fields.classes,
            validation_curve: fields.validation_curve,
            temperature: fields.temperature,
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
        if !validation.classes.is_empty() {
            model.temperature = model.leave_one_out_temperature()?;
        }
        Ok(model)
    }

    /// The temperature fitted to the leave-one-out vote scores `ln(votes + 1/2)` of the stored vectors
    /// (at most [`MAX_CALIBRATION_QUERIES`] of them, evenly spaced): each is scored by the `k` nearest of
    /// the others (all of them when fewer remain), so the fit sees the model `classify` will use, less
    /// one vector, on every image it has. 1 when a single vector is stored.
    fn leave_one_out_temperature(&self) -> Result<f64> {
        let n = self.classes.len();
        if n < 2 {
            return Ok(1.0);
        }
        let k = self.k.min(n - 1);
        let mut scratch = self.scratch();
        let mut scores = Vec::new();
        let mut truths = Vec::new();
        let stride = n.div_ceil(MAX_CALIBRATION_QUERIES).max(1);
        let rows = self.vectors.chunks_exact(self.dims).zip(&self.classes);
        for (i, (x, &truth)) in rows.enumerate().step_by(stride) {
            self.find_nearest(x, k, Some(i), &mut scratch.nearest);
            let start = scores.len();
            scores.resize(start + self.n_classes, 0.5);
            for &(_, class) in &scratch.nearest {
                scores[start + class] += 1.0;
            }
            for score in &mut scores[start..] {
                *score = f64::ln(*score);
            }
            truths.push(truth);
        }
        fit_temperature(&scores, &truths, self.n_classes)
    }

    /// The `k` stored vectors nearest to `x` (leaving out the one at index `skip`) into `nearest`, as
    /// (squared distance, class), nearest first; equal distances keep the stored order.
    fn find_nearest(
        &self,
        x: &[f64],
        k: usize,
        skip: Option<usize>,
        nearest: &mut Vec<(f64, usize)>,
    ) {
        nearest.clear();
        let rows = self.vectors.chunks_exact(self.dims).zip(&self.classes);
        for (i, (p, &class)) in rows.enumerate() {
            if Some(i) == skip {
                continue;
            }
            let d2: f64 = p.iter().zip(x).map(|(a, b)| (a - b) * (a - b)).sum();
            if nearest.len() == k && d2 >= nearest[k - 1].0 {
                continue;
            }
            // insertion into the sorted list of the k nearest (stable: earlier vectors win ties)
            let at = nearest.partition_point(|&(d, _)| d <= d2);
            if nearest.len() == k {
                nearest.pop();
            }
            nearest.insert(at, (d2, class));
        }
    }

    fn store(data: &LabeledVectors<'_>, n_classes: usize, dims: usize, k: usize) -> Self {
        Self {
            dims,
            n_classes,
            k: k.min(data.classes.len()).max(1),
            vectors: data.vectors.to_vec(),
            classes: data.classes.to_vec(),
            validation_curve: Vec::new(),
            temperature: 1.0,
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

    /// The posteriors' temperature: [`classify_into`](Self::classify_into)'s posteriors are
    /// `softmax(ln(votes + 1/2) / T)` (see the module documentation).
    pub fn temperature(&self) -> f64 {
        self.temperature
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
        self.find_nearest(x, self.k, None, &mut scratch.nearest);
        let nearest = &scratch.nearest;
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
        if self.temperature == 1.0 {
            // The smoothed vote fractions, exactly as before calibration.
            let denominator = nearest.len() as f64 + 0.5 * self.n_classes as f64;
            for p in posteriors.iter_mut() {
                *p = (*p + 0.5) / denominator;
            }
        } else {
            for p in posteriors.iter_mut() {
                *p = (*p + 0.5).ln();
            }
            // Ranks the scores as the vote counts do: `best` (with its tie-break) keeps the top posterior.
            softmax_in_place(posteriors, self.temperature);
        }
        Ok(best)
    }
}

/// Most stored vectors the temperature is fitted on (evenly spaced through the stored order when there
/// are more): leave-one-out costs `queries x stored x dims`.
const MAX_CALIBRATION_QUERIES: usize = 1000;

/// Reusable buffers of [`KnnModel::classify_into`].
#[derive(Clone, Debug, Default)]
pub struct KnnScratch {
    nearest: Vec<(f64, usize)>,
    closest: Vec<f64>,
}

/// k-nearest neighbours as a registered family (`knn`).
#[derive(Debug)]
pub struct KnnFamily;

impl ClassifierFamily for KnnFamily {
    const NAME: &'static str = "knn";
    type Config = KnnConfig;
    type Model = KnnModel;
    type Scratch = KnnScratch;

    fn check(config: &KnnConfig) -> Result<()> {
        config.check()
    }

    fn fit(config: &KnnConfig, data: FitData<'_>) -> Result<KnnModel> {
        KnnModel::fit(
            data.train,
            data.validation,
            data.n_classes,
            data.dims,
            config,
        )
    }

    fn dims(model: &KnnModel) -> usize {
        model.dims()
    }

    fn n_classes(model: &KnnModel) -> usize {
        model.n_classes()
    }

    fn describe(model: &KnnModel) -> String {
        format!("k {}, temperature {:.3e}", model.k(), model.temperature())
    }

    fn scratch(model: &KnnModel) -> KnnScratch {
        model.scratch()
    }

    fn classify_into(
        model: &KnnModel,
        x: &[f64],
        scratch: &mut KnnScratch,
        posteriors: &mut [f64],
    ) -> Result<usize> {
        model.classify_into(x, scratch, posteriors)
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use crate::classifier::calibration::fit_temperature;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    const DIMS: usize = 2;
    const CLASSES: usize = 3;

    /// `per_class` draws of each of three overlapping classes: uniform squares of side 2 whose centres
    /// are 1.2 apart, so that about a fifth of the draws lie nearer another class.
    fn draw(per_class: usize, seed: u64) -> (Vec<f64>, Vec<usize>) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let centres = [[0.0, 0.0], [1.2, 0.0], [0.6, 1.0]];
        let (mut x, mut y) = (Vec::new(), Vec::new());
        for i in 0..per_class * CLASSES {
            let class = i % CLASSES;
            for centre in centres[class] {
                x.push(centre + rng.random_range(-1.0..1.0));
            }
            y.push(class);
        }
        (x, y)
    }

    fn fit(k_grid: Vec<usize>, seed: u64) -> KnnModel {
        let (train_x, train_y) = draw(40, seed);
        let (val_x, val_y) = draw(15, seed + 100);
        KnnModel::fit(
            LabeledVectors {
                vectors: &train_x,
                classes: &train_y,
            },
            LabeledVectors {
                vectors: &val_x,
                classes: &val_y,
            },
            CLASSES,
            DIMS,
            &KnnConfig { k_grid },
        )
        .unwrap()
    }

    /// The vote counts of the `k` nearest stored vectors to `x`, leaving out index `skip`, by sorting
    /// every distance (stable, so equal distances keep the stored order).
    fn naive_votes(model: &KnnModel, x: &[f64], k: usize, skip: Option<usize>) -> Vec<f64> {
        let mut all: Vec<(f64, usize)> = model
            .vectors
            .chunks_exact(model.dims)
            .zip(&model.classes)
            .enumerate()
            .filter(|(i, _)| Some(*i) != skip)
            .map(|(_, (p, &c))| (p.iter().zip(x).map(|(a, b)| (a - b).powi(2)).sum(), c))
            .collect();
        all.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut votes = vec![0.0; model.n_classes];
        for &(_, class) in &all[..k] {
            votes[class] += 1.0;
        }
        votes
    }

    #[test]
    fn the_temperature_is_the_fit_on_naive_leave_one_out_votes() {
        let model = fit(vec![5], 1);
        let mut scores = Vec::new();
        for (i, x) in model.vectors.chunks_exact(DIMS).enumerate() {
            let votes = naive_votes(&model, x, 5, Some(i));
            scores.extend(votes.iter().map(|v| (v + 0.5).ln()));
        }
        let expected = fit_temperature(&scores, &model.classes, CLASSES).unwrap();
        assert!(
            (model.temperature() - expected).abs() <= 1e-12 * expected,
            "{} vs {expected}",
            model.temperature()
        );
        assert!(model.temperature() != 1.0);
    }

    #[test]
    fn posteriors_are_the_tempered_softmax_of_the_smoothed_votes() {
        let mut model = fit(vec![7], 2);
        let (test_x, _) = draw(30, 3);
        let mut scratch = model.scratch();
        let mut posteriors = vec![0.0; CLASSES];
        let mut plain = vec![0.0; CLASSES];
        let temperature = model.temperature();
        for x in test_x.chunks_exact(DIMS) {
            let votes = naive_votes(&model, x, 7, None);
            model.temperature = 1.0;
            let plain_class = model.classify_into(x, &mut scratch, &mut plain).unwrap();
            model.temperature = temperature;
            let class = model
                .classify_into(x, &mut scratch, &mut posteriors)
                .unwrap();
            assert_eq!(class, plain_class, "the temperature changed a label");
            let powers: Vec<f64> = votes
                .iter()
                .map(|v| (v + 0.5).powf(1.0 / temperature))
                .collect();
            let total: f64 = powers.iter().sum();
            for ((p, power), (q, v)) in posteriors.iter().zip(&powers).zip(plain.iter().zip(&votes))
            {
                assert!(
                    (p - power / total).abs() < 1e-12,
                    "{p} vs {}",
                    power / total
                );
                // T = 1: the smoothed vote fractions
                assert!((q - (v + 0.5) / (7.0 + 0.5 * CLASSES as f64)).abs() < 1e-15);
            }
            assert!(posteriors[class] >= posteriors.iter().copied().fold(0.0, f64::max));
        }
    }

    #[test]
    fn calibrated_confidences_match_the_accuracy() {
        let (test_x, test_y) = draw(400, 7);
        let mut gaps = Vec::new();
        for k in [1, 5, 9] {
            let mut model = fit(vec![k], 5);
            let mut scratch = model.scratch();
            let mut posteriors = vec![0.0; CLASSES];
            let mut gap = |model: &KnnModel| {
                let (mut confidence, mut correct) = (0.0, 0.0);
                for (x, &truth) in test_x.chunks_exact(DIMS).zip(&test_y) {
                    let class = model
                        .classify_into(x, &mut scratch, &mut posteriors)
                        .unwrap();
                    confidence += posteriors[class];
                    correct += f64::from(u8::from(class == truth));
                }
                (confidence - correct) / test_y.len() as f64
            };
            let calibrated = gap(&model);
            model.temperature = 1.0;
            gaps.push((k, calibrated, gap(&model)));
        }
        // Calibrated, the mean confidence is within 0.03 of the accuracy for every k; the plain vote
        // fractions are that close only where k happens to suit the number of classes.
        assert!(
            gaps.iter()
                .all(|&(_, calibrated, _)| calibrated.abs() < 0.03)
                && gaps.iter().any(|&(_, _, plain)| plain.abs() > 0.06),
            "(k, mean confidence less accuracy calibrated, plain): {gaps:?}"
        );
    }

    #[test]
    fn models_without_a_temperature_load_with_one_and_bad_ones_are_refused() {
        let model = fit(vec![3], 4);
        let mut value = serde_json::to_value(&model).unwrap();
        value.as_object_mut().unwrap().remove("temperature");
        let old: KnnModel = serde_json::from_value(value.clone()).unwrap();
        assert_eq!(old.temperature(), 1.0);
        for bad in [0.0, -1.0] {
            value["temperature"] = serde_json::json!(bad);
            let err = serde_json::from_value::<KnnModel>(value.clone()).unwrap_err();
            assert!(err.to_string().contains("`temperature`"), "{err}");
        }
    }
}
