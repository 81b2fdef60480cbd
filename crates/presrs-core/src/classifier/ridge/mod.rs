//! Ridge classifier: one-vs-rest ridge regression on standardised features, the regularisation chosen by
//! exact leave-one-out, as scikit-learn's `RidgeClassifierCV` (the classifier MiniRocket is used with).
//! Two families: `ridge` standardises the features, `ridge_raw` only centres them (scikit-learn's
//! `RidgeClassifierCV` alone, as the MiniRocket paper and aeon's peer use it): with ~10,000 features of
//! one kind (MiniRocket's proportions, all in [0, 1]) standardising gives the rare, noisy features the
//! weight of the common ones, and on `jiku-walk` cost 5.6 points; which one a data set needs is the
//! automatic choice's to validate.
//!
//! The training and validation vectors together are standardised (each feature less its mean, over its
//! population standard deviation; a feature indistinguishable from a constant, by scikit-learn's
//! `StandardScaler` test, keeps scale 1; `ridge_raw`: every scale 1). Each class `c` gets a target column `+1` for its vectors and
//! `-1` for the others (scikit-learn's `LabelBinarizer(pos_label=1, neg_label=-1)`); with two classes a
//! single column, `+1` for the second class, whose decision `s` gives the scores `(-s, s)`. Ridge
//! regression with an unpenalised intercept is fitted for every `α` of [`RidgeConfig::alphas`], and the
//! `α` with the smallest mean squared leave-one-out residual over every vector and target wins (ties to
//! the earlier in the list, as scikit-learn). The leave-one-out residuals are exact, not estimated: ridge
//! is a linear smoother, so all of them, for every `α`, come from one eigendecomposition of the Gram
//! matrix `Z Zᵀ` (`n <= p`) or of `Zᵀ Z` (`n > p`) (`loo.rs`). The predicted class has the largest
//! decision `w_c · z + b_c` (the first on ties; with two classes the second class when `s > 0`).
//!
//! Posteriors are `softmax(scores / T)`, `T` fitted by [`fit_temperature`](super::calibration::fit_temperature)
//! on the leave-one-out decisions of the chosen `α` (`Y` less the leave-one-out residuals): each is the
//! decision of the model fitted on all the other vectors, so they are held-out scores of (nearly) the final
//! model, for every vector, and free once `α` is chosen (no refit, unlike the five folds of mle/lda/svm).
//! Without calibration ([`FitData::calibrate`] false) `T = 1`.

use serde::{Deserialize, Serialize};

use crate::classifier::calibration::{is_usable_temperature, unit_temperature};
use crate::classifier::common::softmax_in_place;
use crate::classifier::family::{ClassifierFamily, FitData, FitRows};
use crate::error::{CoreError, Result, check_len};
use crate::kernels::matrix_vector;

mod direct;
mod fit;
mod loo;

/// Parameters of the ridge classifier.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RidgeConfig {
    /// The candidate regularisations (positive, finite; in any order: ties go to the earlier one). The
    /// default is 10 values log-spaced from 1e-3 to 1e3 (numpy's `logspace(-3, 3, 10)`, what aeon and
    /// the MiniRocket paper use).
    #[serde(default = "default_alphas")]
    pub alphas: Vec<f64>,
    /// `α` and the temperature fixed, as chosen on a subsample ([`RidgePin`]): the fit on every vector
    /// searches nothing (`alphas` is not read) and solves one system.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pinned: Option<RidgePin>,
}

/// What ridge's leave-one-out chose on a subsample of large data (the automatic choice's scoring
/// subsample), fixed for the fit on every vector ([`ClassifierFamily::pinned`]): the leave-one-out needs
/// an eigendecomposition of `O(min(n, p)³)` on one core, one `α` only a Cholesky solve (`direct.rs`).
/// `α` is the prior's scale (the noise variance over the coefficients' prior variance), which does not
/// depend on how many vectors there are, so the subsample's choice carries to the whole.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RidgePin {
    pub alpha: f64,
    pub temperature: f64,
    /// The subsample's leave-one-out curve and accuracy at `alpha`, kept in the model as measured.
    pub loo_errors: Vec<(f64, f64)>,
    pub loo_accuracy: f64,
    /// How many vectors that leave-one-out ran on.
    pub loo_samples: usize,
}

/// `logspace(-3, 3, 10)`.
fn default_alphas() -> Vec<f64> {
    (0..10)
        // numpy's arithmetic: `i * step + start`, the last value exactly `stop`
        .map(|i| {
            let exponent = if i == 9 {
                3.0
            } else {
                f64::from(i) * (6.0 / 9.0) - 3.0
            };
            10f64.powf(exponent)
        })
        .collect()
}

impl Default for RidgeConfig {
    fn default() -> Self {
        Self {
            alphas: default_alphas(),
            pinned: None,
        }
    }
}

impl RidgeConfig {
    pub fn check(&self) -> Result<()> {
        if self.alphas.is_empty() {
            return Err(CoreError::Param {
                name: "ridge alphas",
                reason: "give at least one regularisation alpha".into(),
            });
        }
        if let Some(alpha) = self.alphas.iter().find(|a| !(a.is_finite() && **a > 0.0)) {
            return Err(CoreError::Param {
                name: "ridge alphas",
                reason: format!("every alpha must be positive and finite, got {alpha}"),
            });
        }
        if let Some(pin) = &self.pinned {
            let usable = is_usable_temperature(pin.alpha)
                && is_usable_temperature(pin.temperature)
                && (0.0..=1.0).contains(&pin.loo_accuracy);
            if !usable {
                return Err(CoreError::Param {
                    name: "ridge pinned",
                    reason: format!(
                        "alpha and temperature must be positive and finite and loo_accuracy in \
                         [0, 1], got {pin:?}"
                    ),
                });
            }
        }
        Ok(())
    }
}

/// How the features are scaled before the regression.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Scaling {
    /// Each feature less its mean over its standard deviation (`ridge`).
    Standardised,
    /// Each feature less its mean, in its own units (`ridge_raw`).
    Centred,
}

/// A trained ridge classifier. Deserialising checks that the parts fit together: `dims >= 1`,
/// `n_classes >= 2`, `dims` `means` and `scales` (scales positive), `n_classes x dims` `coefficients`
/// and `n_classes` `intercepts`, every value finite, `alpha` and `temperature` positive. A file that
/// breaks one of these is an error naming the field.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "RidgeFields", into = "RidgeFields")]
pub struct RidgeModel {
    dims: usize,
    n_classes: usize,
    /// The chosen regularisation.
    alpha: f64,
    /// The standardisation: `z = (x - means) / scales`.
    means: Vec<f64>,
    scales: Vec<f64>,
    /// One row per class, on the standardised features (`n_classes x dims`, row-major).
    coefficients: Vec<f64>,
    intercepts: Vec<f64>,
    temperature: f64,
    /// `(α, mean squared leave-one-out residual)` for every candidate whose residuals were finite.
    loo_errors: Vec<(f64, f64)>,
    /// The share of training vectors whose leave-one-out decision at the chosen `α` was right.
    loo_accuracy: f64,
    /// How many vectors the leave-one-out curve and accuracy are of: every training vector, or for a
    /// model whose `α` was pinned ([`RidgePin`]) the subsample's (`None` in files written before it
    /// was recorded).
    loo_samples: Option<usize>,
}

/// The serialised form of [`RidgeModel`], checked on load (see there).
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct RidgeFields {
    dims: usize,
    n_classes: usize,
    alpha: f64,
    means: Vec<f64>,
    scales: Vec<f64>,
    coefficients: Vec<f64>,
    intercepts: Vec<f64>,
    #[serde(default = "unit_temperature")]
    temperature: f64,
    loo_errors: Vec<(f64, f64)>,
    loo_accuracy: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    loo_samples: Option<usize>,
}

impl From<RidgeModel> for RidgeFields {
    fn from(model: RidgeModel) -> Self {
        Self {
            dims: model.dims,
            n_classes: model.n_classes,
            alpha: model.alpha,
            means: model.means,
            scales: model.scales,
            coefficients: model.coefficients,
            intercepts: model.intercepts,
            temperature: model.temperature,
            loo_errors: model.loo_errors,
            loo_accuracy: model.loo_accuracy,
            loo_samples: model.loo_samples,
        }
    }
}

impl TryFrom<RidgeFields> for RidgeModel {
    type Error = CoreError;

    fn try_from(fields: RidgeFields) -> Result<Self> {
        check_fields(&fields)?;
        Ok(Self {
            dims: fields.dims,
            n_classes: fields.n_classes,
            alpha: fields.alpha,
            means: fields.means,
            scales: fields.scales,
            coefficients: fields.coefficients,
            intercepts: fields.intercepts,
            temperature: fields.temperature,
            loo_errors: fields.loo_errors,
            loo_accuracy: fields.loo_accuracy,
            loo_samples: fields.loo_samples,
        })
    }
}

/// The checks of [`RidgeModel`]'s documentation.
fn check_fields(fields: &RidgeFields) -> Result<()> {
    let bad = |reason: String| {
        Err(CoreError::Param {
            name: "ridge model",
            reason,
        })
    };
    let (d, classes) = (fields.dims, fields.n_classes);
    if d == 0 || classes < 2 {
        return bad(format!(
            "`dims` must be at least 1 and `n_classes` at least 2, got {d} and {classes}"
        ));
    }
    let lengths = [
        ("means", fields.means.len(), Some(d)),
        ("scales", fields.scales.len(), Some(d)),
        (
            "coefficients",
            fields.coefficients.len(),
            classes.checked_mul(d),
        ),
        ("intercepts", fields.intercepts.len(), Some(classes)),
    ];
    for (field, got, expected) in lengths {
        if Some(got) != expected {
            let expected =
                expected.map_or_else(|| "more than fit in memory".into(), |e| e.to_string());
            return bad(format!(
                "`{field}` holds {got} values, expected {expected} ({classes} classes of {d} dims)"
            ));
        }
    }
    let loo: Vec<f64> = fields
        .loo_errors
        .iter()
        .flat_map(|&(a, e)| [a, e])
        .collect();
    for (field, values) in [
        ("means", &fields.means),
        ("coefficients", &fields.coefficients),
        ("intercepts", &fields.intercepts),
        ("loo_errors", &loo),
    ] {
        if values.iter().any(|v| !v.is_finite()) {
            return bad(format!("`{field}` holds non-finite values"));
        }
    }
    if let Some(scale) = fields.scales.iter().find(|s| !(s.is_finite() && **s > 0.0)) {
        return bad(format!("`scales` must be positive and finite, got {scale}"));
    }
    for (field, value) in [("alpha", fields.alpha), ("temperature", fields.temperature)] {
        if !is_usable_temperature(value) {
            return bad(format!(
                "`{field}` must be positive and finite, got {value}"
            ));
        }
    }
    if !(0.0..=1.0).contains(&fields.loo_accuracy) {
        return bad(format!(
            "`loo_accuracy` must be in [0, 1], got {}",
            fields.loo_accuracy
        ));
    }
    Ok(())
}

impl RidgeModel {
    pub fn dims(&self) -> usize {
        self.dims
    }

    pub fn n_classes(&self) -> usize {
        self.n_classes
    }

    /// The regularisation the leave-one-out chose.
    pub fn alpha(&self) -> f64 {
        self.alpha
    }

    /// The feature means of the standardisation.
    pub fn means(&self) -> &[f64] {
        &self.means
    }

    /// The feature scales of the standardisation (population standard deviations, 1 for constants).
    pub fn scales(&self) -> &[f64] {
        &self.scales
    }

    /// The coefficients of class `c` on the standardised features (row `c`, `dims` long).
    pub fn coefficients(&self, class: usize) -> Option<&[f64]> {
        self.coefficients.chunks_exact(self.dims).nth(class)
    }

    /// One intercept per class.
    pub fn intercepts(&self) -> &[f64] {
        &self.intercepts
    }

    /// The posteriors' temperature (see the module documentation).
    pub fn temperature(&self) -> f64 {
        self.temperature
    }

    /// `(α, mean squared leave-one-out residual)` for every candidate (with finite residuals), in the
    /// order of the configuration.
    pub fn loo_errors(&self) -> &[(f64, f64)] {
        &self.loo_errors
    }

    /// The share of training vectors whose leave-one-out decision was right, at the chosen `α`.
    pub fn loo_accuracy(&self) -> f64 {
        self.loo_accuracy
    }

    /// How many vectors the leave-one-out figures are of: every training vector, or when `α` was chosen
    /// on a subsample, its vectors (`None` for a model file written before it was recorded).
    pub fn loo_samples(&self) -> Option<usize> {
        self.loo_samples
    }

    /// `config` with this model's `α` and temperature pinned ([`RidgePin`]).
    pub fn pinned(&self, config: &RidgeConfig) -> RidgeConfig {
        RidgeConfig {
            alphas: config.alphas.clone(),
            pinned: Some(RidgePin {
                alpha: self.alpha,
                temperature: self.temperature,
                loo_errors: self.loo_errors.clone(),
                loo_accuracy: self.loo_accuracy,
                loo_samples: self.loo_samples.unwrap_or(0),
            }),
        }
    }

    pub fn scratch(&self) -> RidgeScratch {
        RidgeScratch {
            standardised: vec![0.0; self.dims],
        }
    }

    /// The decision of every class (`w_c · z + b_c`) into `out`; does not allocate once `scratch` is
    /// sized.
    pub fn decisions_into(
        &self,
        x: &[f64],
        scratch: &mut RidgeScratch,
        out: &mut [f64],
    ) -> Result<()> {
        check_len("ridge input", self.dims, x.len())?;
        check_len("ridge class scores", self.n_classes, out.len())?;
        scratch.standardised.resize(self.dims, 0.0);
        let rows = x.iter().zip(&self.means).zip(&self.scales);
        for (z, ((v, m), s)) in scratch.standardised.iter_mut().zip(rows) {
            *z = (v - m) / s;
        }
        matrix_vector(&self.coefficients, self.dims, &scratch.standardised, out);
        for (score, b) in out.iter_mut().zip(&self.intercepts) {
            *score += b;
        }
        Ok(())
    }

    /// Posteriors into `posteriors`; returns the predicted class. Does not allocate once `scratch` is
    /// sized.
    pub fn classify_into(
        &self,
        x: &[f64],
        scratch: &mut RidgeScratch,
        posteriors: &mut [f64],
    ) -> Result<usize> {
        self.decisions_into(x, scratch, posteriors)?;
        Ok(softmax_in_place(posteriors, self.temperature))
    }
}

/// Reusable buffers of [`RidgeModel::classify_into`].
#[derive(Clone, Debug, Default)]
pub struct RidgeScratch {
    standardised: Vec<f64>,
}

/// The ridge classifier as a registered family (`ridge`).
#[derive(Debug)]
pub struct RidgeFamily;

impl ClassifierFamily for RidgeFamily {
    const NAME: &'static str = "ridge";
    /// Only with the random-convolution features (`presrs::method` adds it to their candidates).
    const JOINS_AUTO: bool = false;
    /// Ridge standardises every feature itself and is regularised: MiniRocket's ~10,000 features go in
    /// whole (the PCA's 51 components cost 15 points on `icub20`; `docs/methods.md`).
    const TAKES_ALL_FEATURES: bool = true;
    type Config = RidgeConfig;
    type Model = RidgeModel;
    type Scratch = RidgeScratch;

    fn check(config: &RidgeConfig) -> Result<()> {
        config.check()
    }

    fn fit(config: &RidgeConfig, data: FitData<'_>) -> Result<RidgeModel> {
        RidgeModel::fit(config, data, Scaling::Standardised)
    }

    const READS_SINGLE: bool = true;

    fn fit_single(config: &RidgeConfig, data: FitData<'_, f32>) -> Result<RidgeModel> {
        RidgeModel::fit(config, data, Scaling::Standardised)
    }

    const READS_ROWS: bool = true;

    fn fit_rows(config: &RidgeConfig, data: FitRows<'_>) -> Result<RidgeModel> {
        RidgeModel::fit_views(config, data, Scaling::Standardised)
    }

    const PINS: bool = true;

    fn pinned(config: &RidgeConfig, model: &RidgeModel) -> Option<RidgeConfig> {
        Some(model.pinned(config))
    }

    fn dims(model: &RidgeModel) -> usize {
        model.dims()
    }

    fn n_classes(model: &RidgeModel) -> usize {
        model.n_classes()
    }

    fn describe(model: &RidgeModel) -> String {
        let over = model
            .loo_samples()
            .map_or_else(String::new, |n| format!(" over {n} vectors"));
        format!(
            "alpha {:.3e} (leave-one-out accuracy {:.3}{over}), temperature {:.3e}",
            model.alpha(),
            model.loo_accuracy(),
            model.temperature()
        )
    }

    fn scratch(model: &RidgeModel) -> RidgeScratch {
        model.scratch()
    }

    fn classify_into(
        model: &RidgeModel,
        x: &[f64],
        scratch: &mut RidgeScratch,
        posteriors: &mut [f64],
    ) -> Result<usize> {
        model.classify_into(x, scratch, posteriors)
    }
}

/// The ridge classifier on centred, unscaled features, as a registered family (`ridge_raw`): the same
/// model (its scales are 1), fitted without dividing the features by their spread.
#[derive(Debug)]
pub struct RidgeRawFamily;

impl ClassifierFamily for RidgeRawFamily {
    const NAME: &'static str = "ridge_raw";
    /// Only with the random-convolution features, as `ridge`.
    const JOINS_AUTO: bool = false;
    const TAKES_ALL_FEATURES: bool = true;
    type Config = RidgeConfig;
    type Model = RidgeModel;
    type Scratch = RidgeScratch;

    fn check(config: &RidgeConfig) -> Result<()> {
        config.check()
    }

    fn fit(config: &RidgeConfig, data: FitData<'_>) -> Result<RidgeModel> {
        RidgeModel::fit(config, data, Scaling::Centred)
    }

    const READS_SINGLE: bool = true;

    fn fit_single(config: &RidgeConfig, data: FitData<'_, f32>) -> Result<RidgeModel> {
        RidgeModel::fit(config, data, Scaling::Centred)
    }

    const READS_ROWS: bool = true;

    fn fit_rows(config: &RidgeConfig, data: FitRows<'_>) -> Result<RidgeModel> {
        RidgeModel::fit_views(config, data, Scaling::Centred)
    }

    const PINS: bool = true;

    fn pinned(config: &RidgeConfig, model: &RidgeModel) -> Option<RidgeConfig> {
        Some(model.pinned(config))
    }

    fn dims(model: &RidgeModel) -> usize {
        model.dims()
    }

    fn n_classes(model: &RidgeModel) -> usize {
        model.n_classes()
    }

    fn describe(model: &RidgeModel) -> String {
        RidgeFamily::describe(model)
    }

    fn scratch(model: &RidgeModel) -> RidgeScratch {
        model.scratch()
    }

    fn classify_into(
        model: &RidgeModel,
        x: &[f64],
        scratch: &mut RidgeScratch,
        posteriors: &mut [f64],
    ) -> Result<usize> {
        model.classify_into(x, scratch, posteriors)
    }
}
