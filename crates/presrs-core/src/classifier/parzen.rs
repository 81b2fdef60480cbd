//! The Parzen-window estimator (PWE) of the paper: a Gaussian kernel density per class.
//!
//! The density of class `c` at `x` is the mean over that class's stored vectors `p` of
//! `exp(-|x - p|² / (2 σ²))` (the normalisation `(2πσ²)^(-h/2)` is common to all classes and left out of
//! scores). Scores are kept as logarithms and summed with log-sum-exp, so far-away samples do not underflow
//! to 0/0. The prediction is the class with the largest density; the posteriors assume **equal class
//! priors** (the paper trains on the same number of images per terrain, and equal priors keep the
//! confidence independent of how many images each class happened to get).
//!
//! # Choosing σ
//! `σ = factor · scale`, where `scale` is the median, over the training vectors, of the Euclidean distance
//! to their nearest other training vector (robust to outliers and to the units of the features), and
//! `factor` runs over a log-spaced grid ([`SigmaSearch`]). A model fitted on the training vectors alone
//! classifies the validation vectors for each σ; the σ with the highest validation accuracy wins, ties going
//! to the lowest validation log-loss (the highest mean log posterior of the true class), then to the
//! larger σ. The final model stores training and validation vectors, like
//! the paper's `P` with `p + q` columns. Every grid point is recorded in [`ParzenModel::validation_curve`].
//!
//! # Calibrated posteriors
//! The posteriors are `softmax(scores / T)` with a temperature `T` fitted on the leave-one-out scores of
//! the stored vectors ([`super::calibration`]; `T = 1` without a validation set). `T` never changes the
//! label; it makes the confidence mean what it says.

use serde::{Deserialize, Serialize};

use super::calibration::{fit_temperature, is_usable_temperature, log_sum_exp, unit_temperature};
use super::common::{argmax, check_vectors, require_per_class};
// Defined with the other shared helpers (calibration needs it too); kept nameable from here.
pub use super::common::LabeledVectors;
use super::family::{ClassifierFamily, FitData};
use crate::error::{CoreError, Result, check_len};
use crate::kernels::{Aligned, columns_times_vector, exp_neg_in_place, ln_in_place};

/// How σ is chosen.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "mode", rename_all = "snake_case", deny_unknown_fields)]
pub enum SigmaChoice {
    /// Grid search on the validation set (the default).
    Search(SigmaSearch),
    /// A fixed kernel width in the units of the reduced feature vectors; no validation set needed.
    Fixed { sigma: f64 },
}

impl Default for SigmaChoice {
    fn default() -> Self {
        Self::Search(SigmaSearch::default())
    }
}

/// Whether `sigma` is a usable kernel width: positive, and its square neither underflows to 0 nor
/// overflows, so that the kernel's `1 / (2σ²)` and the density's normalisation `2πσ²` are finite and
/// positive (about `1e-154 < σ < 1e153`). Outside that range the scores would be infinite or NaN.
pub fn is_usable_sigma(sigma: f64) -> bool {
    let variance = sigma * sigma;
    let inv_two_var = 0.5 / variance;
    let two_pi_var = 2.0 * std::f64::consts::PI * variance;
    sigma > 0.0
        && inv_two_var.is_finite()
        && inv_two_var > 0.0
        && two_pi_var.is_finite()
        && two_pi_var > 0.0
}

/// A log-spaced grid of `steps` factors from `min_factor` to `max_factor` (both included), multiplied by
/// the median nearest-neighbour distance of the training vectors.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SigmaSearch {
    pub min_factor: f64,
    pub max_factor: f64,
    pub steps: usize,
}

impl Default for SigmaSearch {
    /// 1/32 to 32 times the nearest-neighbour scale, 41 points (about six per factor of two).
    fn default() -> Self {
        Self {
            min_factor: 1.0 / 32.0,
            max_factor: 32.0,
            steps: 41,
        }
    }
}

impl SigmaSearch {
    /// The grid factors, ascending.
    pub fn factors(&self) -> Vec<f64> {
        if self.steps == 1 {
            return vec![self.min_factor];
        }
        let (lo, hi) = (self.min_factor.ln(), self.max_factor.ln());
        (0..self.steps)
            .map(|i| (lo + (hi - lo) * i as f64 / (self.steps - 1) as f64).exp())
            .collect()
    }
}

/// Parameters of the Parzen-window classifier.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParzenConfig {
    #[serde(default)]
    pub sigma: SigmaChoice,
}

impl ParzenConfig {
    /// Checks the parameters on their own (no data needed).
    pub fn check(&self) -> Result<()> {
        let bad = |reason: String| {
            Err(CoreError::Param {
                name: "pwe sigma",
                reason,
            })
        };
        match &self.sigma {
            SigmaChoice::Fixed { sigma } if !is_usable_sigma(*sigma) => bad(format!(
                "a fixed sigma must be positive, with 1/(2 sigma²) and 2 pi sigma² finite \
                 (about 1e-154 < sigma < 1e153), got {sigma}"
            )),
            SigmaChoice::Search(search) => {
                let SigmaSearch {
                    min_factor,
                    max_factor,
                    steps,
                } = *search;
                if steps == 0 {
                    bad("the sigma grid needs at least one step".into())
                } else if !(min_factor.is_finite()
                    && max_factor.is_finite()
                    && min_factor > 0.0
                    && max_factor >= min_factor)
                {
                    bad(format!(
                        "the sigma grid needs 0 < min_factor <= max_factor, got {min_factor} and {max_factor}"
                    ))
                } else {
                    Ok(())
                }
            }
            SigmaChoice::Fixed { .. } => Ok(()),
        }
    }
}

/// One point of the validation curve.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SigmaPoint {
    pub factor: f64,
    pub sigma: f64,
    /// Fraction of validation vectors classified correctly by the training-only model.
    pub accuracy: f64,
    /// Mean over validation vectors of the log density (normalised Gaussian kernel) of their true class.
    pub mean_log_likelihood: f64,
    /// Mean over validation vectors of the log posterior (equal priors) of their true class: minus the
    /// log-loss, 0 when every validation vector gets its own class with confidence 1. `None` in model
    /// files written before it was recorded.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mean_log_posterior: Option<f64>,
}

/// A trained Parzen-window classifier. Deserialising checks that the parts fit together: `dims >= 1`, a
/// [usable](is_usable_sigma) `sigma`, `class_starts` splitting the finite stored `vectors` into non-empty
/// classes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "ParzenFields", into = "ParzenFields")]
pub struct ParzenModel {
    dims: usize,
    sigma: f64,
    /// Stored vectors grouped by class: class `c` owns rows `class_starts[c]..class_starts[c + 1]`.
    vectors: Vec<f64>,
    class_starts: Vec<usize>,
    /// The median nearest-neighbour distance the σ grid was scaled by (`None` for a fixed σ).
    scale: Option<f64>,
    validation_curve: Vec<SigmaPoint>,
    /// The posteriors' temperature ([`super::calibration`]), fitted on the leave-one-out scores of the
    /// stored vectors when training had a validation set; 1 without one.
    temperature: f64,
    /// `|p|²` of each stored vector, derived (not serialised): `|x - p|² = |x|² + |p|² - 2 p·x` turns the
    /// distances into one SIMD matrix-vector product.
    sq_norms: Aligned<f64>,
    /// The stored vectors by dimension (`dims x n_stored`, derived, not serialised): the product `P · x`
    /// on short rows runs faster column by column (`kernels::columns_times_vector`).
    vectors_by_dim: Aligned<f64>,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct ParzenFields {
    dims: usize,
    sigma: f64,
    vectors: Vec<f64>,
    class_starts: Vec<usize>,
    scale: Option<f64>,
    validation_curve: Vec<SigmaPoint>,
    /// Absent from model files written before calibration: those posteriors were uncalibrated (1).
    #[serde(default = "unit_temperature")]
    temperature: f64,
}

impl From<ParzenModel> for ParzenFields {
    fn from(model: ParzenModel) -> Self {
        Self {
            dims: model.dims,
            sigma: model.sigma,
            vectors: model.vectors,
            class_starts: model.class_starts,
            scale: model.scale,
            validation_curve: model.validation_curve,
            temperature: model.temperature,
        }
    }
}

impl TryFrom<ParzenFields> for ParzenModel {
    type Error = CoreError;

    fn try_from(fields: ParzenFields) -> Result<Self> {
        let bad = |reason: String| CoreError::Param {
            name: "pwe model",
            reason,
        };
        if fields.dims == 0 {
            return Err(bad("`dims` must be at least 1, got 0".into()));
        }
        if !is_usable_sigma(fields.sigma) {
            return Err(bad(format!(
                "`sigma` must be positive, with 1/(2 sigma²) and 2 pi sigma² finite (about 1e-154 < \
                 sigma < 1e153), got {}",
                fields.sigma
            )));
        }
        let starts = &fields.class_starts;
        let rows = fields.vectors.len() / fields.dims;
        let consistent = fields.vectors.len() % fields.dims == 0
            && starts.len() >= 2
            && starts.first() == Some(&0)
            && starts.last() == Some(&rows)
            && starts.windows(2).all(|pair| pair[0] < pair[1]);
        if !consistent {
            return Err(bad(
                "class_starts must split the stored vectors into non-empty classes".into(),
            ));
        }
        if !is_usable_temperature(fields.temperature) {
            return Err(bad(format!(
                "`temperature` must be finite and positive, got {}",
                fields.temperature
            )));
        }
        if fields.vectors.iter().any(|value| !value.is_finite()) {
            return Err(bad("non-finite stored vectors".into()));
        }
        if fields.vectors.chunks_exact(fields.dims).any(too_long) {
            return Err(bad(format!("a stored vector {TOO_LONG}")));
        }
        Ok(Self::assemble(
            fields.dims,
            fields.sigma,
            (fields.vectors, fields.class_starts),
            fields.scale,
            fields.validation_curve,
            fields.temperature,
        ))
    }
}

impl ParzenModel {
    /// Trains on `train`, choosing σ with `validation` as described in the module documentation; the
    /// returned model stores both sets. Every class in `0..n_classes` needs a training vector.
    pub fn fit(
        train: LabeledVectors<'_>,
        validation: LabeledVectors<'_>,
        n_classes: usize,
        dims: usize,
        config: &ParzenConfig,
    ) -> Result<Self> {
        config.check()?;
        check_vectors(&train, "pwe training vectors", dims, n_classes)?;
        check_vectors(&validation, "pwe validation vectors", dims, n_classes)?;
        for (what, data) in [
            ("pwe training vectors", &train),
            ("pwe validation vectors", &validation),
        ] {
            if data.vectors.chunks_exact(dims).any(too_long) {
                return Err(CoreError::Param {
                    name: what,
                    reason: format!("a vector {TOO_LONG}"),
                });
            }
        }
        require_per_class(&train, n_classes, 1)?;

        let (sigma, scale, validation_curve) = match &config.sigma {
            SigmaChoice::Fixed { sigma } => (*sigma, None, Vec::new()),
            SigmaChoice::Search(search) => {
                if validation.classes.is_empty() {
                    return Err(CoreError::NotEnoughData(
                        "choosing the Parzen sigma needs a validation set (or give a fixed sigma)"
                            .into(),
                    ));
                }
                let scale = median_nearest_neighbour_distance(train.vectors, dims);
                if scale.is_nan() || scale <= 0.0 {
                    return Err(CoreError::NotEnoughData(
                        "the training vectors are all identical to a neighbour; sigma cannot be scaled".into(),
                    ));
                }
                let curve = validation_curve(train, validation, n_classes, dims, scale, search)?;
                let best = best_point(&curve).ok_or_else(|| CoreError::Param {
                    name: "pwe sigma",
                    reason: "empty sigma grid".into(),
                })?;
                (best.sigma, Some(scale), curve)
            }
        };

        let all = LabeledVectors {
            vectors: &[train.vectors, validation.vectors].concat(),
            classes: &[train.classes, validation.classes].concat(),
        };
        let temperature = if validation.classes.is_empty() {
            1.0
        } else {
            calibrate(&all, n_classes, dims, sigma)?
        };
        Ok(Self::assemble(
            dims,
            sigma,
            group_by_class(all, n_classes, dims),
            scale,
            validation_curve,
            temperature,
        ))
    }

    /// A model from already grouped data with a given σ (used for the validation search).
    fn from_parts(train: LabeledVectors<'_>, n_classes: usize, dims: usize, sigma: f64) -> Self {
        Self::assemble(
            dims,
            sigma,
            group_by_class(train, n_classes, dims),
            None,
            Vec::new(),
            1.0,
        )
    }

    /// Builds a model from checked parts and derives the stored vectors' squared norms and by-dimension copy.
    fn assemble(
        dims: usize,
        sigma: f64,
        (vectors, class_starts): (Vec<f64>, Vec<usize>),
        scale: Option<f64>,
        validation_curve: Vec<SigmaPoint>,
        temperature: f64,
    ) -> Self {
        let sq_norms: Vec<f64> = vectors
            .chunks_exact(dims)
            .map(|p| p.iter().map(|v| v * v).sum())
            .collect();
        let n_stored = vectors.len() / dims;
        let vectors_by_dim: Vec<f64> = (0..dims)
            .flat_map(|j| (0..n_stored).map(move |k| k * dims + j))
            .map(|index| vectors[index])
            .collect();
        // Aligned: the distance kernel loads them a register at a time, every query.
        let (sq_norms, vectors_by_dim) = (
            Aligned::from_slice(&sq_norms),
            Aligned::from_slice(&vectors_by_dim),
        );
        Self {
            dims,
            sigma,
            vectors,
            class_starts,
            scale,
            validation_curve,
            temperature,
            sq_norms,
            vectors_by_dim,
        }
    }

    /// Length of the vectors this model classifies.
    pub fn dims(&self) -> usize {
        self.dims
    }

    pub fn n_classes(&self) -> usize {
        self.class_starts.len() - 1
    }

    /// Number of stored vectors (training + validation).
    pub fn n_stored(&self) -> usize {
        self.vectors.len() / self.dims
    }

    /// The chosen kernel width.
    pub fn sigma(&self) -> f64 {
        self.sigma
    }

    /// The posteriors' temperature: [`classify_into`](Self::classify_into)'s posteriors are the softmax of
    /// [`log_scores_into`](Self::log_scores_into)'s scores divided by it (1: uncalibrated).
    pub fn temperature(&self) -> f64 {
        self.temperature
    }

    /// The data scale the σ grid was multiplied by (`None` when σ was fixed).
    pub fn scale(&self) -> Option<f64> {
        self.scale
    }

    /// Validation accuracy for each σ of the grid, ascending σ (empty when σ was fixed).
    pub fn validation_curve(&self) -> &[SigmaPoint] {
        &self.validation_curve
    }

    /// The stored vectors of class `class`, `n x dims` row-major.
    pub fn class_vectors(&self, class: usize) -> &[f64] {
        &self.vectors
            [self.class_starts[class] * self.dims..self.class_starts[class + 1] * self.dims]
    }

    /// A scratch buffer sized for [`classify_into`](Self::classify_into).
    pub fn scratch(&self) -> ParzenScratch {
        ParzenScratch {
            sq_distances: vec![0.0; self.n_stored()],
            log_means: vec![0.0; self.n_classes()],
        }
    }

    /// Classifies `x`: writes the class posteriors (equal priors, calibrated by the model's
    /// [`temperature`](Self::temperature)) into `posteriors` (`n_classes` long) and returns the most
    /// likely class (the first on ties). Does not allocate.
    ///
    /// The posteriors are the softmax of [`log_scores_into`](Self::log_scores_into)'s scores, formed
    /// without logarithms: with `n_c` the nearest squared distance of class `c`, `m_c` its mean kernel
    /// value relative to that nearest member (at least `1 / count`) and `a = 1 / (2σ²)`, the score is
    /// `-a n_c + ln m_c`, so `exp(score_c - score_b) = exp(-a (n_c - n_b)) · m_c / m_b`: one vectorised
    /// `exp` over every stored vector and one over the classes, where libm's `exp` and `ln` per class cost
    /// as much as the kernel terms of all 80 vectors.
    pub fn classify_into(
        &self,
        x: &[f64],
        scratch: &mut ParzenScratch,
        posteriors: &mut [f64],
    ) -> Result<usize> {
        check_len("pwe input", self.dims, x.len())?;
        check_len("pwe class scores", self.n_classes(), posteriors.len())?;
        let inv_two_var = self.relative_kernels(x, scratch, posteriors)?;
        // `posteriors` holds each class's nearest squared distance.
        let nearest = posteriors.iter().copied().fold(f64::INFINITY, f64::min);
        if self.temperature != 1.0 {
            return Ok(self.tempered_posteriors(nearest, inv_two_var, scratch, posteriors));
        }
        for value in posteriors.iter_mut() {
            *value = (*value - nearest) * inv_two_var;
        }
        exp_neg_in_place(posteriors);
        let mut total = 0.0;
        for (class, value) in posteriors.iter_mut().enumerate() {
            let members =
                &scratch.sq_distances[self.class_starts[class]..self.class_starts[class + 1]];
            *value *= members.iter().sum::<f64>() / members.len() as f64;
            total += *value;
        }
        let mut best = 0;
        for (class, &value) in posteriors.iter().enumerate() {
            if value > posteriors[best] {
                best = class;
            }
        }
        for value in posteriors.iter_mut() {
            *value /= total;
        }
        Ok(best)
    }

    /// The posteriors `softmax(scores / T)` from each class's nearest squared distance (in `posteriors`)
    /// and its relative kernel terms (in `scratch`), in the log domain: the scores of other classes are
    /// often hundreds below the best one, where `exp(score)` underflows (or is floored at `exp(-700)`)
    /// but `exp(score / T)` with a large `T` is a confidence that counts. Returns the best class (the
    /// first on ties). One vectorised `ln` over the classes.
    fn tempered_posteriors(
        &self,
        nearest: f64,
        inv_two_var: f64,
        scratch: &mut ParzenScratch,
        posteriors: &mut [f64],
    ) -> usize {
        // value_c = -score_c + a constant: a (n_c - nearest) - ln(mean relative kernel), the mean being at
        // least 1 / count (the class's nearest member contributes exp(0)).
        scratch.log_means.resize(posteriors.len(), 0.0);
        for (class, mean) in scratch.log_means.iter_mut().enumerate() {
            let members =
                &scratch.sq_distances[self.class_starts[class]..self.class_starts[class + 1]];
            *mean = members.iter().sum::<f64>() / members.len() as f64;
        }
        ln_in_place(&mut scratch.log_means);
        for (value, log_mean) in posteriors.iter_mut().zip(&scratch.log_means) {
            *value = (*value - nearest) * inv_two_var - log_mean;
        }
        let mut best = 0;
        for (class, &value) in posteriors.iter().enumerate() {
            if value < posteriors[best] {
                best = class;
            }
        }
        let (lowest, inverse_temperature) = (posteriors[best], 1.0 / self.temperature);
        for value in posteriors.iter_mut() {
            *value = (*value - lowest) * inverse_temperature;
        }
        exp_neg_in_place(posteriors);
        let total: f64 = posteriors.iter().sum();
        for value in posteriors.iter_mut() {
            *value /= total;
        }
        best
    }

    /// Writes `log(mean_p exp(-|x - p|² / (2σ²)))` for each class into `out`. Does not allocate.
    pub fn log_scores_into(
        &self,
        x: &[f64],
        scratch: &mut ParzenScratch,
        out: &mut [f64],
    ) -> Result<()> {
        check_len("pwe input", self.dims, x.len())?;
        check_len("pwe class scores", self.n_classes(), out.len())?;
        let inv_two_var = self.relative_kernels(x, scratch, out)?;
        for (class, score) in out.iter_mut().enumerate() {
            let members =
                &scratch.sq_distances[self.class_starts[class]..self.class_starts[class + 1]];
            let sum: f64 = members.iter().sum();
            *score = -*score * inv_two_var + (sum / members.len() as f64).ln();
        }
        Ok(())
    }

    /// The kernel terms of every stored vector relative to its class's nearest one,
    /// `exp(-(|x - p|² - n_c) / (2σ²))`, into `scratch.sq_distances`, and each class's nearest squared
    /// distance `n_c` into `nearest` (log-sum-exp around the nearest member: the largest term is
    /// exp(0) = 1, no underflow). Returns `1 / (2σ²)`, or an error when `x`'s squared length overflows.
    /// Lengths are the caller's to check.
    fn relative_kernels(
        &self,
        x: &[f64],
        scratch: &mut ParzenScratch,
        nearest: &mut [f64],
    ) -> Result<f64> {
        let x_sq_norm = sum_of_squares(x);
        if !x_sq_norm.is_finite() {
            return Err(CoreError::Param {
                name: "pwe input",
                reason: format!("the vector {TOO_LONG}"),
            });
        }
        scratch.sq_distances.resize(self.n_stored(), 0.0);
        // sq_distances <- p·x, then |x|² + |p|² - 2 p·x (clamped: rounding can make it slightly negative)
        columns_times_vector(&self.vectors_by_dim, x, &mut scratch.sq_distances);
        for (dist, p_sq_norm) in scratch.sq_distances.iter_mut().zip(self.sq_norms.iter()) {
            *dist = (x_sq_norm + p_sq_norm - 2.0 * *dist).max(0.0);
        }
        let inv_two_var = 0.5 / (self.sigma * self.sigma);
        for (class, nearest) in nearest.iter_mut().enumerate() {
            let members =
                &mut scratch.sq_distances[self.class_starts[class]..self.class_starts[class + 1]];
            *nearest = members.iter().copied().fold(f64::INFINITY, f64::min);
            for d in members.iter_mut() {
                *d = (*d - *nearest) * inv_two_var;
            }
        }
        // One call over every stored vector: whole registers across class boundaries.
        exp_neg_in_place(&mut scratch.sq_distances);
        Ok(inv_two_var)
    }
}

/// Why a vector is refused when its squared length is not finite: the distances are formed as
/// `|x|² + |p|² - 2 p·x`, and an infinite square makes them NaN (the posteriors with them).
const TOO_LONG: &str = "is too long for the Parzen window: its squared length overflows f64 (a component beyond about 1e153)";

/// Whether `v`'s squared length overflows (or `v` holds a non-finite value).
fn too_long(v: &[f64]) -> bool {
    !sum_of_squares(v).is_finite()
}

/// `Σ v²` in four running sums: one sum would wait for each addition before the next (51 in a row for the
/// paper's vectors, the latency and not the arithmetic being the cost).
fn sum_of_squares(values: &[f64]) -> f64 {
    let mut sums = [0.0; 4];
    let groups = values.chunks_exact(4);
    let tail: f64 = groups.remainder().iter().map(|v| v * v).sum();
    for group in groups {
        for (sum, v) in sums.iter_mut().zip(group) {
            *sum += v * v;
        }
    }
    (sums[0] + sums[1]) + (sums[2] + sums[3]) + tail
}

/// Reusable buffers of [`ParzenModel::classify_into`].
#[derive(Clone, Debug, Default)]
pub struct ParzenScratch {
    sq_distances: Vec<f64>,
    /// Per class, the log of the mean relative kernel term (calibrated posteriors only).
    log_means: Vec<f64>,
}

fn validation_curve(
    train: LabeledVectors<'_>,
    validation: LabeledVectors<'_>,
    n_classes: usize,
    dims: usize,
    scale: f64,
    search: &SigmaSearch,
) -> Result<Vec<SigmaPoint>> {
    let n_validation = validation.classes.len();
    let mut model = ParzenModel::from_parts(train, n_classes, dims, scale);
    let mut scratch = model.scratch();
    let mut scores = vec![0.0; n_classes];
    let mut curve = Vec::with_capacity(search.steps);
    for factor in search.factors() {
        model.sigma = factor * scale;
        if !is_usable_sigma(model.sigma) {
            return Err(CoreError::Param {
                name: "pwe sigma",
                reason: format!(
                    "the sigma grid reaches {:e} ({factor} x the nearest-neighbour distance {scale:e}), \
                     where 1/(2 sigma²) or 2 pi sigma² is not finite; narrow the grid or rescale the \
                     features",
                    model.sigma
                ),
            });
        }
        let log_norm =
            -0.5 * dims as f64 * (2.0 * std::f64::consts::PI * model.sigma * model.sigma).ln();
        let mut correct = 0usize;
        let mut log_likelihood = 0.0;
        let mut log_posterior = 0.0;
        for (x, &class) in validation
            .vectors
            .chunks_exact(dims)
            .zip(validation.classes)
        {
            model.log_scores_into(x, &mut scratch, &mut scores)?;
            log_likelihood += scores[class] + log_norm;
            log_posterior += scores[class] - log_sum_exp(&scores);
            if argmax(&scores) == class {
                correct += 1;
            }
        }
        let mean_log_likelihood = log_likelihood / n_validation as f64;
        let mean_log_posterior = log_posterior / n_validation as f64;
        // A non-finite value would be saved as JSON `null` and the model could not be read back.
        if !(mean_log_likelihood.is_finite() && mean_log_posterior.is_finite()) {
            return Err(CoreError::NotEnoughData(format!(
                "the validation log-likelihood at sigma {:e} is not finite (the vectors are too far \
                 apart for f64 at this width)",
                model.sigma
            )));
        }
        curve.push(SigmaPoint {
            factor,
            sigma: model.sigma,
            accuracy: correct as f64 / n_validation as f64,
            mean_log_likelihood,
            mean_log_posterior: Some(mean_log_posterior),
        });
    }
    Ok(curve)
}

/// Most stored vectors the temperature is fitted on (evenly spaced through the stored order when there
/// are more): leave-one-out costs `queries x stored x dims`.
const MAX_CALIBRATION_QUERIES: usize = 1000;

/// The temperature of the posteriors ([`super::calibration`]), fitted to the leave-one-out scores of the
/// final model's stored vectors (training and validation) at the chosen `sigma`: each vector is scored by
/// the model of all the others, so the fit sees the model `classify` will use, less one vector, on every
/// image it has. Returns 1 when there is nothing to fit (no validation set, so no chosen σ; or a single
/// class). Vectors that are the only one of their class are skipped (left out, their class has no
/// density).
fn calibrate(all: &LabeledVectors<'_>, n_classes: usize, dims: usize, sigma: f64) -> Result<f64> {
    let n = all.classes.len();
    let mut counts = vec![0usize; n_classes];
    for &class in all.classes {
        counts[class] += 1;
    }
    let inv_two_var = 0.5 / (sigma * sigma);
    let stride = n.div_ceil(MAX_CALIBRATION_QUERIES).max(1);
    let mut scores = Vec::new();
    let mut truths = Vec::new();
    let mut exponents: Vec<Vec<f64>> = vec![Vec::new(); n_classes];
    for (i, (x, &truth)) in all
        .vectors
        .chunks_exact(dims)
        .zip(all.classes)
        .enumerate()
        .step_by(stride)
    {
        if counts[truth] < 2 {
            continue;
        }
        exponents.iter_mut().for_each(Vec::clear);
        for (j, (p, &class)) in all.vectors.chunks_exact(dims).zip(all.classes).enumerate() {
            if j != i {
                let d2: f64 = x.iter().zip(p).map(|(a, b)| (a - b) * (a - b)).sum();
                exponents[class].push(-d2 * inv_two_var);
            }
        }
        // log of the mean kernel term per class
        scores.extend(
            exponents
                .iter()
                .map(|e| log_sum_exp(e) - (e.len() as f64).ln()),
        );
        truths.push(truth);
    }
    fit_temperature(&scores, &truths, n_classes)
}

/// The chosen point of a validation curve: the highest accuracy, and among those the highest mean log
/// posterior of the true class (the lowest log-loss). Ties left after both go to the larger sigma (the
/// grid is ascending: the last one).
///
/// Accuracy alone leaves wide plateaus (it moves in steps of one validation vector), and their largest
/// σ was the old choice. The log-loss picks the sharpest σ of the plateau: on the simulated data set
/// every Parzen row of `reproduce`'s comparison gained 0.1-3 points (glcm 91.8 -> 94.6 %).
fn best_point(curve: &[SigmaPoint]) -> Option<SigmaPoint> {
    let key = |point: &SigmaPoint| {
        (
            point.accuracy,
            point.mean_log_posterior.unwrap_or(f64::NEG_INFINITY),
        )
    };
    curve.iter().copied().reduce(|best, point| {
        if key(&point) >= key(&best) {
            point
        } else {
            best
        }
    })
}

/// Median over the rows of the distance to the nearest other row. `O(n² d)`, fine for training sets.
pub fn median_nearest_neighbour_distance(vectors: &[f64], dims: usize) -> f64 {
    let rows: Vec<&[f64]> = vectors.chunks_exact(dims).collect();
    let mut nearest: Vec<f64> = rows
        .iter()
        .enumerate()
        .map(|(i, a)| {
            rows.iter()
                .enumerate()
                .filter(|&(j, _)| j != i)
                .map(|(_, b)| squared_distance(a, b))
                .fold(f64::INFINITY, f64::min)
                .sqrt()
        })
        .filter(|d| d.is_finite())
        .collect();
    if nearest.is_empty() {
        return 0.0;
    }
    nearest.sort_by(f64::total_cmp);
    let mid = nearest.len() / 2;
    if nearest.len() % 2 == 1 {
        nearest[mid]
    } else {
        0.5 * (nearest[mid - 1] + nearest[mid])
    }
}

/// Stable grouping by class: returns the rows class by class (input order within a class) and the starts.
fn group_by_class(
    data: LabeledVectors<'_>,
    n_classes: usize,
    dims: usize,
) -> (Vec<f64>, Vec<usize>) {
    let mut vectors = Vec::with_capacity(data.vectors.len());
    let mut class_starts = Vec::with_capacity(n_classes + 1);
    for class in 0..n_classes {
        class_starts.push(vectors.len() / dims);
        for (row, _) in data
            .vectors
            .chunks_exact(dims)
            .zip(data.classes)
            .filter(|&(_, &c)| c == class)
        {
            vectors.extend_from_slice(row);
        }
    }
    class_starts.push(vectors.len() / dims);
    (vectors, class_starts)
}

/// `|a - b|²` with four independent partial sums (vectorisable).
fn squared_distance(a: &[f64], b: &[f64]) -> f64 {
    const LANES: usize = 4;
    let mut partial = [0.0; LANES];
    let a_chunks = a.chunks_exact(LANES);
    let b_chunks = b.chunks_exact(LANES);
    let tail: f64 = a_chunks
        .remainder()
        .iter()
        .zip(b_chunks.remainder())
        .map(|(x, y)| (x - y) * (x - y))
        .sum();
    for (x, y) in a_chunks.zip(b_chunks) {
        for lane in 0..LANES {
            let d = x[lane] - y[lane];
            partial[lane] += d * d;
        }
    }
    partial.iter().sum::<f64>() + tail
}

/// The Parzen window as a registered classifier family (`pwe`).
#[derive(Debug)]
pub struct PweFamily;

impl ClassifierFamily for PweFamily {
    const NAME: &'static str = "pwe";
    type Config = ParzenConfig;
    type Model = ParzenModel;
    type Scratch = ParzenScratch;

    fn check(config: &ParzenConfig) -> Result<()> {
        config.check()
    }

    /// σ searched on validation needs it; a fixed σ does not.
    fn needs_validation(config: &ParzenConfig) -> bool {
        matches!(config.sigma, SigmaChoice::Search(_))
    }

    fn fit(config: &ParzenConfig, data: FitData<'_>) -> Result<ParzenModel> {
        ParzenModel::fit(
            data.train,
            data.validation,
            data.n_classes,
            data.dims,
            config,
        )
    }

    fn dims(model: &ParzenModel) -> usize {
        model.dims()
    }

    fn n_classes(model: &ParzenModel) -> usize {
        model.n_classes()
    }

    fn describe(model: &ParzenModel) -> String {
        format!("sigma {:.4e}", model.sigma())
    }

    fn scratch(model: &ParzenModel) -> ParzenScratch {
        model.scratch()
    }

    fn classify_into(
        model: &ParzenModel,
        x: &[f64],
        scratch: &mut ParzenScratch,
        posteriors: &mut [f64],
    ) -> Result<usize> {
        model.classify_into(x, scratch, posteriors)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn two_blobs() -> (Vec<f64>, Vec<usize>) {
        // class 0 around (0, 0), class 1 around (10, 0)
        let vectors = vec![
            0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 10.0, 0.0, 11.0, 0.0, 10.0, 1.0,
        ];
        (vectors, vec![0, 0, 0, 1, 1, 1])
    }

    #[test]
    fn sum_of_squares_matches_the_plain_sum() {
        for len in 0..12 {
            let values: Vec<f64> = (0..len).map(|i| i as f64 * 0.5 - 2.0).collect();
            let plain: f64 = values.iter().map(|v| v * v).sum();
            assert_eq!(sum_of_squares(&values), plain, "{len}");
        }
    }

    #[test]
    fn scores_match_the_definition() {
        let (vectors, classes) = two_blobs();
        let train = LabeledVectors {
            vectors: &vectors,
            classes: &classes,
        };
        let none = LabeledVectors {
            vectors: &[],
            classes: &[],
        };
        let config = ParzenConfig {
            sigma: SigmaChoice::Fixed { sigma: 2.0 },
        };
        let model = ParzenModel::fit(train, none, 2, 2, &config).unwrap();
        let x = [3.0, 0.5];
        let mut scratch = ParzenScratch::default();
        let mut scores = [0.0; 2];
        model
            .log_scores_into(&x, &mut scratch, &mut scores)
            .unwrap();
        for class in 0..2 {
            let naive: f64 = vectors
                .chunks(2)
                .zip(&classes)
                .filter(|&(_, &c)| c == class)
                .map(|(p, _)| {
                    let d2 = (x[0] - p[0]).powi(2) + (x[1] - p[1]).powi(2);
                    (-d2 / 8.0).exp()
                })
                .sum::<f64>()
                / 3.0;
            assert!((scores[class] - naive.ln()).abs() < 1e-12);
        }
        let mut posteriors = [0.0; 2];
        assert_eq!(
            model
                .classify_into(&x, &mut scratch, &mut posteriors)
                .unwrap(),
            0
        );
        let expected = 1.0 / (1.0 + (scores[1] - scores[0]).exp());
        assert!((posteriors[0] - expected).abs() < 1e-12);
        assert!((posteriors.iter().sum::<f64>() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn far_away_points_do_not_underflow() {
        let (vectors, classes) = two_blobs();
        let train = LabeledVectors {
            vectors: &vectors,
            classes: &classes,
        };
        let none = LabeledVectors {
            vectors: &[],
            classes: &[],
        };
        let config = ParzenConfig {
            sigma: SigmaChoice::Fixed { sigma: 0.01 },
        };
        let model = ParzenModel::fit(train, none, 2, 2, &config).unwrap();
        let mut scratch = model.scratch();
        let mut posteriors = [0.0; 2];
        // every kernel value is exp(-huge) = 0 in floating point; log-sum-exp still ranks the classes
        let class = model
            .classify_into(&[1e3, 0.0], &mut scratch, &mut posteriors)
            .unwrap();
        assert_eq!(class, 1);
        assert!(posteriors.iter().all(|p| p.is_finite()));
        assert!((posteriors[1] - 1.0).abs() < 1e-12);
    }

    #[test]
    fn config_checks() {
        assert!(ParzenConfig::default().check().is_ok());
        let zero = ParzenConfig {
            sigma: SigmaChoice::Fixed { sigma: 0.0 },
        };
        assert!(zero.check().is_err());
        let inverted = ParzenConfig {
            sigma: SigmaChoice::Search(SigmaSearch {
                min_factor: 2.0,
                max_factor: 1.0,
                steps: 3,
            }),
        };
        assert!(inverted.check().is_err());
        let factors = SigmaSearch {
            min_factor: 0.5,
            max_factor: 8.0,
            steps: 5,
        }
        .factors();
        for (got, want) in factors.iter().zip([0.5, 1.0, 2.0, 4.0, 8.0]) {
            assert!((got - want).abs() < 1e-12);
        }
    }

    #[test]
    fn sigmas_whose_square_underflows_or_overflows_are_refused() {
        for sigma in [
            1e-160,
            1e160,
            f64::MIN_POSITIVE,
            0.0,
            -1.0,
            f64::INFINITY,
            f64::NAN,
        ] {
            assert!(!is_usable_sigma(sigma), "{sigma}");
            let config = ParzenConfig {
                sigma: SigmaChoice::Fixed { sigma },
            };
            let err = config.check().unwrap_err().to_string();
            assert!(err.contains("pwe sigma"), "{err}");
        }
        for sigma in [1e-150, 1e-3, 1.0, 1e150] {
            assert!(is_usable_sigma(sigma), "{sigma}");
        }
    }

    #[test]
    fn a_sigma_grid_reaching_unusable_widths_is_an_error_not_nan() {
        // Nearest-neighbour distances ~1e-158: the grid's 1/32 x scale has σ² below f64's range, where
        // every score was NaN and the saved validation curve held `null`s that could not be read back.
        let (vectors, classes) = two_blobs();
        let tiny: Vec<f64> = vectors.iter().map(|v| v * 1e-158).collect();
        let data = LabeledVectors {
            vectors: &tiny,
            classes: &classes,
        };
        let err = ParzenModel::fit(data, data, 2, 2, &ParzenConfig::default())
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("pwe sigma") && err.contains("sigma grid"),
            "{err}"
        );
        // The same data at a usable scale trains, and its model survives a JSON round trip.
        let data = LabeledVectors {
            vectors: &vectors,
            classes: &classes,
        };
        let model = ParzenModel::fit(data, data, 2, 2, &ParzenConfig::default()).unwrap();
        assert!(
            model
                .validation_curve()
                .iter()
                .all(|p| p.mean_log_likelihood.is_finite())
        );
        let json = serde_json::to_string(&model).unwrap();
        assert_eq!(serde_json::from_str::<ParzenModel>(&json).unwrap(), model);
    }

    #[test]
    fn median_nearest_neighbour() {
        // 1-D points 0, 1, 3, 7: nearest distances 1, 1, 2, 4 -> median 1.5
        let d = median_nearest_neighbour_distance(&[0.0, 1.0, 3.0, 7.0], 1);
        assert!((d - 1.5).abs() < 1e-12);
    }
}
