//! Gaussian class-conditional densities: maximum likelihood (MLE, one full covariance per class, i.e.
//! quadratic discriminant) and linear discriminant analysis (LDA, one covariance shared by the classes).
//!
//! With 13-20 samples per class and tens of PCA dimensions the sample covariance is singular, so it is
//! shrunk toward a scaled identity with the Ledoit-Wolf estimate of the shrinkage
//! (`Σ = (1 - s) S + s μ I`, `μ = tr S / d`, `s` as in scikit-learn's `ledoit_wolf_shrinkage`), or a fixed
//! `s`. Scores are log densities with equal priors; posteriors are their softmax at a temperature fitted on
//! five-fold cross-validated scores of the training + validation vectors
//! (`calibration::cross_validated_scores`; the validation set scored by a model of the training vectors
//! where a class is too small to fold), so the confidence is not the near-0/1 of a 50-dimensional
//! Gaussian. The final model is fitted on training + validation vectors.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt;
use faer::linalg::triangular_solve::solve_lower_triangular_in_place;
use faer::{Mat, MatMut, MatRef, Par};
use serde::{Deserialize, Serialize};

use super::calibration::{cross_validated_scores, fit_temperature};
use super::common::LabeledVectors;
use super::common::{
    accuracy_of_scores, check_vectors, merged, require_per_class, softmax_in_place,
};
use super::family::{ClassifierFamily, FitData};
use crate::error::{CoreError, Result, check_len};

/// How the covariances are shrunk.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(tag = "mode", rename_all = "snake_case", deny_unknown_fields)]
pub enum Shrinkage {
    /// The Ledoit-Wolf estimate (the default).
    #[default]
    LedoitWolf,
    /// A fixed weight in `[0, 1]` on the scaled identity.
    Fixed { weight: f64 },
}

/// Parameters of the Gaussian classifiers.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GaussianConfig {
    #[serde(default)]
    pub shrinkage: Shrinkage,
}

impl GaussianConfig {
    pub fn check(&self) -> Result<()> {
        match self.shrinkage {
            Shrinkage::Fixed { weight } if !(0.0..=1.0).contains(&weight) => {
                Err(CoreError::Param {
                    name: "gaussian shrinkage",
                    reason: format!("a fixed shrinkage weight must be in [0, 1], got {weight}"),
                })
            }
            _ => Ok(()),
        }
    }
}

/// The Ledoit-Wolf shrinkage weight of centred data `x` (`n x d`, row-major), as scikit-learn computes
/// it, and the empirical covariance `S = xᵀx / n` (`d x d`). Errors unless `d >= 1` and `x` holds
/// `n >= 1` whole rows.
pub fn ledoit_wolf(x: &[f64], d: usize) -> Result<(f64, Vec<f64>)> {
    if d == 0 || x.is_empty() || x.len() % d != 0 {
        return Err(CoreError::Shape {
            what: "ledoit-wolf data",
            expected: "at least one row of at least one value".into(),
            got: format!("{} values in rows of {d}", x.len()),
        });
    }
    let n = x.len() / d;
    let mut emp = vec![0.0; d * d];
    for row in x.chunks_exact(d) {
        for i in 0..d {
            for j in 0..=i {
                emp[i * d + j] += row[i] * row[j];
            }
        }
    }
    for i in 0..d {
        for j in 0..=i {
            emp[i * d + j] /= n as f64;
            emp[j * d + i] = emp[i * d + j];
        }
    }
    let nf = n as f64;
    let trace: f64 = (0..d).map(|i| emp[i * d + i]).sum();
    let mu = trace / d as f64;
    // beta_ = Σ_ij ((x²)ᵀ x²)_ij = Σ_ij Σ_k x_ki² x_kj² = Σ_k (Σ_i x_ki²)²
    let beta_raw: f64 = x
        .chunks_exact(d)
        .map(|row| row.iter().map(|v| v * v).sum::<f64>().powi(2))
        .sum();
    // delta_ = Σ_ij (xᵀx)_ij² / n²  = Σ_ij S_ij²
    let delta_raw: f64 = emp.iter().map(|v| v * v).sum();
    let beta = (beta_raw / nf - delta_raw) / (d as f64 * nf);
    let delta = (delta_raw - 2.0 * mu * trace + d as f64 * mu * mu) / d as f64;
    let beta = beta.min(delta);
    let shrinkage = if beta == 0.0 || delta <= 0.0 {
        0.0
    } else {
        beta / delta
    };
    Ok((shrinkage, emp))
}

/// The lower Cholesky factor `L` (`L Lᵀ = a`) of the symmetric `a` (`d x d`, row-major; its lower
/// triangle is read), row-major with the upper triangle zero, by faer's LLᵀ, sequential so that the
/// result does not depend on the thread count; `None` unless `a` is positive definite with a finite
/// factor.
fn cholesky_lower(a: &[f64], d: usize) -> Option<Vec<f64>> {
    let mut factor = Mat::from_fn(d, d, |i, j| a[i * d + j]);
    let par = Par::Seq;
    let mut scratch = MemBuffer::new(llt::factor::cholesky_in_place_scratch::<f64>(
        d,
        par,
        Default::default(),
    ));
    llt::factor::cholesky_in_place(
        factor.as_mut(),
        Default::default(),
        par,
        MemStack::new(&mut scratch),
        Default::default(),
    )
    .ok()?;
    let lower: Vec<f64> = (0..d)
        .flat_map(|i| (0..d).map(move |j| (i, j)))
        .map(|(i, j)| if j <= i { factor[(i, j)] } else { 0.0 })
        .collect();
    // faer stops at a pivot that is not positive; a NaN or infinite entry is refused here.
    let positive = (0..d).all(|i| lower[i * d + i] > 0.0);
    (positive && lower.iter().all(|v| v.is_finite())).then_some(lower)
}

#[cfg(test)]
#[path = "gaussian_linalg_tests.rs"]
mod linalg_tests;

/// Shrinks the covariance of centred `x` and factors it; returns (L, log det Σ, shrinkage weight).
pub(crate) fn shrunk_factor(
    x: &[f64],
    d: usize,
    shrinkage: Shrinkage,
) -> Result<(Vec<f64>, f64, f64)> {
    let (lw, mut cov) = ledoit_wolf(x, d)?;
    let weight = match shrinkage {
        Shrinkage::LedoitWolf => lw,
        Shrinkage::Fixed { weight } => weight,
    };
    let mu = (0..d).map(|i| cov[i * d + i]).sum::<f64>() / d as f64;
    for value in cov.iter_mut() {
        *value *= 1.0 - weight;
    }
    for i in 0..d {
        cov[i * d + i] += weight * mu;
    }
    // A degenerate covariance (e.g. no spread, or no shrinkage with too few samples) gets a small ridge.
    let mut ridge = 1e-10 * mu.max(1e-300);
    let mut ridged = cov.clone();
    let factor = loop {
        if let Some(factor) = cholesky_lower(&ridged, d) {
            break factor;
        }
        if ridge > 1e300 {
            return Err(CoreError::NotEnoughData(
                "the class covariance cannot be made positive definite".into(),
            ));
        }
        ridged.copy_from_slice(&cov);
        for i in 0..d {
            ridged[i * d + i] += ridge;
        }
        ridge *= 100.0;
    };
    // det Σ = det L² = (Π L_ii)².
    let log_det = 2.0 * (0..d).map(|i| factor[i * d + i].ln()).sum::<f64>();
    Ok((factor, log_det, weight))
}

/// A trained Gaussian classifier (MLE or LDA). Deserialising checks that the parts fit together: `dims`
/// and `n_classes` at least 1; with `g` covariances (1 when `shared`, else `n_classes`): `n_classes x
/// dims` `means`, `g` lower Cholesky factors of `dims x dims` with positive diagonals in `factors`, `g`
/// `log_dets` and `g` `shrinkage` weights in `[0, 1]`; every value finite and the `temperature`
/// positive. A file that breaks one of these is an error naming the field.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "GaussianFields", into = "GaussianFields")]
pub struct GaussianModel {
    dims: usize,
    n_classes: usize,
    /// One covariance shared by the classes (LDA) or one per class (MLE).
    shared: bool,
    /// Class means, `n_classes x dims`.
    means: Vec<f64>,
    /// Lower Cholesky factors, `dims x dims` each (one, or one per class).
    factors: Vec<f64>,
    log_dets: Vec<f64>,
    /// The shrinkage weight of each covariance.
    shrinkage: Vec<f64>,
    /// Softmax temperature of the posteriors (fitted on cross-validated scores, see the module docs).
    temperature: f64,
    /// Accuracy of the training-only model on the validation vectors (None without validation data).
    validation_accuracy: Option<f64>,
}

/// The serialised form of [`GaussianModel`], checked on load (see there).
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct GaussianFields {
    dims: usize,
    n_classes: usize,
    shared: bool,
    means: Vec<f64>,
    factors: Vec<f64>,
    log_dets: Vec<f64>,
    shrinkage: Vec<f64>,
    temperature: f64,
    validation_accuracy: Option<f64>,
}

impl From<GaussianModel> for GaussianFields {
    fn from(model: GaussianModel) -> Self {
        Self {
            dims: model.dims,
            n_classes: model.n_classes,
            shared: model.shared,
            means: model.means,
            factors: model.factors,
            log_dets: model.log_dets,
            shrinkage: model.shrinkage,
            temperature: model.temperature,
            validation_accuracy: model.validation_accuracy,
        }
    }
}

impl TryFrom<GaussianFields> for GaussianModel {
    type Error = CoreError;

    fn try_from(fields: GaussianFields) -> Result<Self> {
        let bad = |reason: String| {
            Err(CoreError::Param {
                name: "gaussian model",
                reason,
            })
        };
        let d = fields.dims;
        if d == 0 || fields.n_classes == 0 {
            return bad(format!(
                "`dims` and `n_classes` must be at least 1, got {d} and {}",
                fields.n_classes
            ));
        }
        let groups = if fields.shared { 1 } else { fields.n_classes };
        let lengths = [
            ("means", fields.means.len(), fields.n_classes.checked_mul(d)),
            (
                "factors",
                fields.factors.len(),
                d.checked_mul(d).and_then(|dd| dd.checked_mul(groups)),
            ),
            ("log_dets", fields.log_dets.len(), Some(groups)),
            ("shrinkage", fields.shrinkage.len(), Some(groups)),
        ];
        for (field, got, expected) in lengths {
            if Some(got) != expected {
                let expected =
                    expected.map_or_else(|| "more than fit in memory".into(), |e| e.to_string());
                return bad(format!(
                    "`{field}` holds {got} values, expected {expected} ({} classes of {d} dims, {})",
                    fields.n_classes,
                    if fields.shared {
                        "one shared covariance"
                    } else {
                        "one covariance per class"
                    }
                ));
            }
        }
        for (field, values) in [
            ("means", &fields.means),
            ("factors", &fields.factors),
            ("log_dets", &fields.log_dets),
        ] {
            if values.iter().any(|v| !v.is_finite()) {
                return bad(format!("`{field}` holds non-finite values"));
            }
        }
        if let Some(weight) = fields.shrinkage.iter().find(|w| !(0.0..=1.0).contains(*w)) {
            return bad(format!(
                "`shrinkage` weights must be in [0, 1], got {weight}"
            ));
        }
        // The forward substitution divides by the diagonal of each factor.
        for (group, factor) in fields.factors.chunks_exact(d * d).enumerate() {
            if let Some(i) = (0..d).find(|&i| factor[i * d + i] <= 0.0) {
                return bad(format!(
                    "`factors`: Cholesky factor {group} has the non-positive diagonal entry {} at {i}",
                    factor[i * d + i]
                ));
            }
        }
        if !(fields.temperature.is_finite() && fields.temperature > 0.0) {
            return bad(format!(
                "`temperature` must be positive and finite, got {}",
                fields.temperature
            ));
        }
        Ok(Self {
            dims: d,
            n_classes: fields.n_classes,
            shared: fields.shared,
            means: fields.means,
            factors: fields.factors,
            log_dets: fields.log_dets,
            shrinkage: fields.shrinkage,
            temperature: fields.temperature,
            validation_accuracy: fields.validation_accuracy,
        })
    }
}

impl GaussianModel {
    /// Fits class means and shrunk covariances on `data` (every class needs two vectors).
    fn fit_on(
        data: &LabeledVectors<'_>,
        n_classes: usize,
        dims: usize,
        shared: bool,
        shrinkage: Shrinkage,
    ) -> Result<Self> {
        require_per_class(data, n_classes, 2)?;
        let mut means = vec![0.0; n_classes * dims];
        let mut counts = vec![0usize; n_classes];
        for (x, &class) in data.vectors.chunks_exact(dims).zip(data.classes) {
            counts[class] += 1;
            for (m, v) in means[class * dims..(class + 1) * dims].iter_mut().zip(x) {
                *m += v;
            }
        }
        for (class, &count) in counts.iter().enumerate() {
            for m in &mut means[class * dims..(class + 1) * dims] {
                *m /= count as f64;
            }
        }
        let centred_of = |wanted: Option<usize>| -> Vec<f64> {
            let mut out = Vec::new();
            for (x, &class) in data.vectors.chunks_exact(dims).zip(data.classes) {
                if wanted.is_none_or(|w| w == class) {
                    out.extend(x.iter().zip(&means[class * dims..]).map(|(v, m)| v - m));
                }
            }
            out
        };
        let mut factors = Vec::new();
        let mut log_dets = Vec::new();
        let mut weights = Vec::new();
        let groups: Vec<Option<usize>> = if shared {
            vec![None]
        } else {
            (0..n_classes).map(Some).collect()
        };
        for group in groups {
            let (factor, log_det, weight) = shrunk_factor(&centred_of(group), dims, shrinkage)?;
            factors.extend(factor);
            log_dets.push(log_det);
            weights.push(weight);
        }
        Ok(Self {
            dims,
            n_classes,
            shared,
            means,
            factors,
            log_dets,
            shrinkage: weights,
            temperature: 1.0,
            validation_accuracy: None,
        })
    }

    /// Trains (see the module documentation). `shared`: LDA; otherwise MLE.
    pub fn fit(
        train: LabeledVectors<'_>,
        validation: LabeledVectors<'_>,
        n_classes: usize,
        dims: usize,
        shared: bool,
        config: &GaussianConfig,
    ) -> Result<Self> {
        config.check()?;
        check_vectors(&train, "gaussian training vectors", dims, n_classes)?;
        check_vectors(&validation, "gaussian validation vectors", dims, n_classes)?;
        let (vectors, classes) = merged(&train, &validation);
        let all = LabeledVectors {
            vectors: &vectors,
            classes: &classes,
        };
        let (temperature, validation_accuracy) = if validation.classes.is_empty() {
            (1.0, None)
        } else {
            let first = Self::fit_on(&train, n_classes, dims, shared, config.shrinkage)?;
            let scores = first.scores_of(validation.vectors)?;
            let cross_validated = cross_validated_scores(
                &all,
                n_classes,
                dims,
                |part| Self::fit_on(part, n_classes, dims, shared, config.shrinkage),
                |model, x, out| {
                    let mut scratch = model.scratch();
                    model.log_scores_into(x, &mut scratch, out)
                },
            )?;
            let temperature = match cross_validated {
                Some(cv) => fit_temperature(&cv, &classes, n_classes)?,
                None => fit_temperature(&scores, validation.classes, n_classes)?,
            };
            (
                temperature,
                Some(accuracy_of_scores(&scores, validation.classes, n_classes)),
            )
        };
        let mut model = Self::fit_on(&all, n_classes, dims, shared, config.shrinkage)?;
        model.temperature = temperature;
        model.validation_accuracy = validation_accuracy;
        Ok(model)
    }

    fn scores_of(&self, vectors: &[f64]) -> Result<Vec<f64>> {
        let mut scratch = self.scratch();
        let mut scores = vec![0.0; vectors.len() / self.dims * self.n_classes];
        for (x, out) in vectors
            .chunks_exact(self.dims)
            .zip(scores.chunks_exact_mut(self.n_classes))
        {
            self.log_scores_into(x, &mut scratch, out)?;
        }
        Ok(scores)
    }

    pub fn dims(&self) -> usize {
        self.dims
    }

    pub fn n_classes(&self) -> usize {
        self.n_classes
    }

    pub fn is_shared(&self) -> bool {
        self.shared
    }

    /// The shrinkage weight of each covariance (one for LDA).
    pub fn shrinkage(&self) -> &[f64] {
        &self.shrinkage
    }

    pub fn temperature(&self) -> f64 {
        self.temperature
    }

    pub fn validation_accuracy(&self) -> Option<f64> {
        self.validation_accuracy
    }

    pub fn scratch(&self) -> GaussianScratch {
        GaussianScratch {
            diff: vec![0.0; self.dims],
        }
    }

    /// Log density of `x` under each class (up to a common constant) into `out`. Does not allocate.
    pub fn log_scores_into(
        &self,
        x: &[f64],
        scratch: &mut GaussianScratch,
        out: &mut [f64],
    ) -> Result<()> {
        let d = self.dims;
        check_len("gaussian input", d, x.len())?;
        check_len("gaussian class scores", self.n_classes, out.len())?;
        scratch.diff.resize(d, 0.0);
        for (class, score) in out.iter_mut().enumerate() {
            let group = if self.shared { 0 } else { class };
            let factor =
                MatRef::from_row_major_slice(&self.factors[group * d * d..][..d * d], d, d);
            let mean = &self.means[class * d..(class + 1) * d];
            for ((z, v), m) in scratch.diff.iter_mut().zip(x).zip(mean) {
                *z = v - m;
            }
            // z = L⁻¹ (x - μ) by faer's forward substitution; the quadratic form is |z|².
            let z = MatMut::from_column_major_slice_mut(&mut scratch.diff, d, 1);
            solve_lower_triangular_in_place(factor, z, Par::Seq);
            let quad: f64 = scratch.diff.iter().map(|z| z * z).sum();
            *score = -0.5 * (quad + self.log_dets[group]);
        }
        Ok(())
    }

    /// Posteriors into `posteriors`; returns the most likely class. Does not allocate.
    pub fn classify_into(
        &self,
        x: &[f64],
        scratch: &mut GaussianScratch,
        posteriors: &mut [f64],
    ) -> Result<usize> {
        self.log_scores_into(x, scratch, posteriors)?;
        Ok(softmax_in_place(posteriors, self.temperature))
    }
}

/// Reusable buffers of [`GaussianModel::classify_into`].
#[derive(Clone, Debug, Default)]
pub struct GaussianScratch {
    diff: Vec<f64>,
}

/// The Gaussian classifiers as registered families: `SHARED_COVARIANCE` false is maximum likelihood with
/// one shrunk covariance per class ([`MleFamily`], `mle`), true is linear discriminant analysis with one
/// shared shrunk covariance ([`LdaFamily`], `lda`).
#[derive(Debug)]
pub struct GaussianFamily<const SHARED_COVARIANCE: bool>;

/// Gaussian maximum likelihood (one shrunk covariance per class), `mle`.
pub type MleFamily = GaussianFamily<false>;

/// Linear discriminant analysis (one shared shrunk covariance), `lda`.
pub type LdaFamily = GaussianFamily<true>;

impl<const SHARED_COVARIANCE: bool> ClassifierFamily for GaussianFamily<SHARED_COVARIANCE> {
    const NAME: &'static str = if SHARED_COVARIANCE { "lda" } else { "mle" };
    type Config = GaussianConfig;
    type Model = GaussianModel;
    type Scratch = GaussianScratch;

    fn check(config: &GaussianConfig) -> Result<()> {
        config.check()
    }

    fn fit(config: &GaussianConfig, data: FitData<'_>) -> Result<GaussianModel> {
        GaussianModel::fit(
            data.train,
            data.validation,
            data.n_classes,
            data.dims,
            SHARED_COVARIANCE,
            config,
        )
    }

    fn dims(model: &GaussianModel) -> usize {
        model.dims()
    }

    fn n_classes(model: &GaussianModel) -> usize {
        model.n_classes()
    }

    fn describe(model: &GaussianModel) -> String {
        gaussian_describe(model)
    }

    fn scratch(model: &GaussianModel) -> GaussianScratch {
        model.scratch()
    }

    fn classify_into(
        model: &GaussianModel,
        x: &[f64],
        scratch: &mut GaussianScratch,
        posteriors: &mut [f64],
    ) -> Result<usize> {
        model.classify_into(x, scratch, posteriors)
    }
}

/// The shrinkage and temperature training chose, in words.
fn gaussian_describe(model: &GaussianModel) -> String {
    let s = model.shrinkage();
    let mean = s.iter().sum::<f64>() / s.len().max(1) as f64;
    format!(
        "Ledoit-Wolf shrinkage {mean:.3}, temperature {:.3e}",
        model.temperature()
    )
}
