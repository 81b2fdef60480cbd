//! Fitting the ridge classifier: the standardisation, the ±1 targets, the leave-one-out choice of `α` and
//! the temperature (see the documentation of the `ridge` module).

use faer::{Mat, MatRef, Par};

use super::direct::{self, Rows, Standardisation};
use super::loo::{Decomposition, Spectrum, centre_columns};
use super::{RidgeConfig, RidgeModel, Scaling};
use crate::classifier::calibration::fit_temperature;
use crate::classifier::common::LabeledVectors;
use crate::classifier::common::{accuracy_of_scores, check_vectors};
use crate::classifier::family::{FitData, FitRows};
use crate::error::{CoreError, Result};
use crate::linalg::column_standardisation;

impl RidgeModel {
    /// Trains on the training and validation vectors together (see the module documentation); with
    /// `scaling` [`Scaling::Centred`] the features are only centred (each scale 1), as scikit-learn's
    /// `RidgeClassifierCV` alone.
    pub(super) fn fit<T: Copy + Into<f64> + Sync>(
        config: &RidgeConfig,
        data: FitData<'_, T>,
        scaling: Scaling,
    ) -> Result<Self> {
        let (dims, n_classes) = (data.dims, data.n_classes);
        check_vectors(&data.train, "ridge training vectors", dims, n_classes)?;
        check_vectors(
            &data.validation,
            "ridge validation vectors",
            dims,
            n_classes,
        )?;
        let rows = Rows {
            parts: vec![data.train.vectors, data.validation.vectors],
            dims,
        };
        let classes: Vec<usize> = [data.train, data.validation]
            .iter()
            .flat_map(|s| s.classes.iter().copied())
            .collect();
        Self::fit_rows(config, &rows, &classes, n_classes, data.calibrate, scaling)
    }

    /// [`fit`](Self::fit) on rows held elsewhere (a feature table's), read in place.
    pub(super) fn fit_views(
        config: &RidgeConfig,
        data: FitRows<'_>,
        scaling: Scaling,
    ) -> Result<Self> {
        let (dims, n_classes) = (data.dims, data.n_classes);
        for (rows, classes, what) in [
            (data.train, data.train_classes, "ridge training vectors"),
            (
                data.validation,
                data.validation_classes,
                "ridge validation vectors",
            ),
        ] {
            if rows.len() != classes.len() {
                return Err(CoreError::Shape {
                    what,
                    expected: format!("{} rows", classes.len()),
                    got: format!("{} rows", rows.len()),
                });
            }
            for (row, class) in rows.iter().zip(classes.chunks_exact(1)) {
                let one = LabeledVectors {
                    vectors: row,
                    classes: class,
                };
                check_vectors(&one, what, dims, n_classes)?;
            }
        }
        let rows = Rows {
            parts: data.train.iter().chain(data.validation).copied().collect(),
            dims,
        };
        let classes: Vec<usize> = data
            .train_classes
            .iter()
            .chain(data.validation_classes)
            .copied()
            .collect();
        Self::fit_rows(config, &rows, &classes, n_classes, data.calibrate, scaling)
    }

    /// [`fit`](Self::fit) on checked rows (`classes` one per row).
    fn fit_rows<T: Copy + Into<f64> + Sync>(
        config: &RidgeConfig,
        rows: &Rows<'_, T>,
        classes: &[usize],
        n_classes: usize,
        calibrate: bool,
        scaling: Scaling,
    ) -> Result<Self> {
        config.check()?;
        let dims = rows.dims;
        require_every_class(classes, n_classes)?;
        let (means, mut scales) = column_standardisation(|| rows.iter(), dims);
        if scaling == Scaling::Centred {
            scales.fill(1.0);
        }
        let targets = targets(classes, n_classes);
        let standardisation = Standardisation {
            means: &means,
            scales: &scales,
        };
        if let Some(pin) = &config.pinned {
            let (target_means, centred) = centre_columns(targets.as_ref());
            let columns = direct::solve(rows, &standardisation, centred.as_ref(), pin.alpha)?;
            let (coefficients, intercepts) = class_rows(columns.as_ref(), &target_means, n_classes);
            return Ok(Self {
                dims,
                n_classes,
                alpha: pin.alpha,
                means,
                scales,
                coefficients,
                intercepts,
                temperature: pin.temperature,
                loo_errors: pin.loo_errors.clone(),
                loo_accuracy: pin.loo_accuracy,
                loo_samples: Some(pin.loo_samples),
            });
        }
        // The Gram product and its eigendecomposition are most of the time; faer spreads the product
        // over the cores. With no more vectors than features (the Gram mode) the product is summed
        // over panels of standardised columns, without a standardised copy of every vector.
        let all: Vec<&[T]> = rows.iter().collect();
        let standardised = match Decomposition::for_shape(all.len(), dims) {
            Decomposition::Gram => None,
            Decomposition::Covariance => Some(standardise(rows, &means, &scales)),
        };
        let spectrum = match &standardised {
            None => Spectrum::from_gram(
                direct::gram_system(&all, dims, &standardisation),
                dims,
                targets.as_ref(),
            )?,
            Some(standardised) => Spectrum::new(
                MatRef::from_row_major_slice(standardised, classes.len(), dims),
                targets.as_ref(),
                Par::rayon(0),
            )?,
        };
        let choice = choose_alpha(&spectrum, &config.alphas)?;
        // The leave-one-out decisions: each target less its leave-one-out residual.
        let held_out = Mat::from_fn(targets.nrows(), targets.ncols(), |i, t| {
            targets[(i, t)] - choice.residuals[(i, t)]
        });
        let scores = class_scores(held_out.as_ref(), n_classes);
        let temperature = if calibrate {
            fit_temperature(&scores, classes, n_classes)?
        } else {
            1.0
        };
        let columns = match spectrum.dual(choice.alpha) {
            Some(dual) if standardised.is_none() => {
                direct::primal_of(&all, dims, &standardisation, dual.as_ref())
            }
            _ => spectrum
                .coefficients(choice.alpha)
                .ok_or_else(|| CoreError::Param {
                    name: "ridge",
                    reason: "internal: a covariance spectrum without its features".into(),
                })?,
        };
        let (coefficients, intercepts) =
            class_rows(columns.as_ref(), spectrum.target_means(), n_classes);
        Ok(Self {
            dims,
            n_classes,
            alpha: choice.alpha,
            means,
            scales,
            coefficients,
            intercepts,
            temperature,
            loo_errors: choice.curve,
            loo_accuracy: accuracy_of_scores(&scores, classes, n_classes),
            loo_samples: Some(classes.len()),
        })
    }
}

/// Each class's coefficients (`n_classes x p`, row-major) and intercept from the target columns'
/// coefficients (`p x k`) and means: two classes share one column, the first class's decision its
/// negation.
fn class_rows(
    columns: MatRef<'_, f64>,
    target_means: &[f64],
    n_classes: usize,
) -> (Vec<f64>, Vec<f64>) {
    let dims = columns.nrows();
    let mut coefficients = Vec::with_capacity(n_classes * dims);
    let mut intercepts = Vec::with_capacity(n_classes);
    for class in 0..n_classes {
        let (column, sign) = if columns.ncols() == 1 {
            (0, if class == 0 { -1.0 } else { 1.0 })
        } else {
            (class, 1.0)
        };
        coefficients.extend((0..dims).map(|j| sign * columns[(j, column)]));
        intercepts.push(sign * target_means[column]);
    }
    (coefficients, intercepts)
}

/// Errors unless there are two classes or more and every one has a vector.
fn require_every_class(classes: &[usize], n_classes: usize) -> Result<()> {
    if n_classes < 2 {
        return Err(CoreError::NotEnoughData(format!(
            "the ridge classifier needs at least 2 classes, got {n_classes}"
        )));
    }
    let mut counts = vec![0usize; n_classes];
    classes.iter().for_each(|&c| counts[c] += 1);
    if let Some(empty) = counts.iter().position(|&count| count == 0) {
        return Err(CoreError::NotEnoughData(format!(
            "class {empty} has no training vector; the ridge classifier needs one of every class"
        )));
    }
    Ok(())
}

/// `rows`, standardised, row-major.
fn standardise<T: Copy + Into<f64>>(rows: &Rows<'_, T>, means: &[f64], scales: &[f64]) -> Vec<f64> {
    let mut out = Vec::with_capacity(rows.len() * rows.dims);
    for row in rows.iter() {
        out.extend(
            row.iter()
                .zip(means)
                .zip(scales)
                .map(|((&v, m), s)| (v.into() - m) / s),
        );
    }
    out
}

/// The `±1` targets (`n x k`): one column per class, or for two classes one column, `+1` for the
/// second (scikit-learn's `LabelBinarizer(pos_label=1, neg_label=-1)`).
fn targets(classes: &[usize], n_classes: usize) -> Mat<f64> {
    let columns = if n_classes == 2 { 1 } else { n_classes };
    Mat::from_fn(classes.len(), columns, |i, t| {
        let positive = if n_classes == 2 { 1 } else { t };
        if classes[i] == positive { 1.0 } else { -1.0 }
    })
}

/// Per-class scores (`n x n_classes`, row-major) of decisions `n x k`: the columns, or `(-s, s)` for
/// one column of two classes.
fn class_scores(decisions: MatRef<'_, f64>, n_classes: usize) -> Vec<f64> {
    let mut scores = Vec::with_capacity(decisions.nrows() * n_classes);
    for i in 0..decisions.nrows() {
        if decisions.ncols() == 1 {
            scores.extend([-decisions[(i, 0)], decisions[(i, 0)]]);
        } else {
            scores.extend((0..decisions.ncols()).map(|t| decisions[(i, t)]));
        }
    }
    scores
}

/// The chosen regularisation, the residuals it left and the whole curve.
struct AlphaChoice {
    alpha: f64,
    residuals: Mat<f64>,
    /// `(α, mean squared leave-one-out residual)` for every `α` whose residuals are finite.
    curve: Vec<(f64, f64)>,
}

/// The `α` of `alphas` with the smallest mean squared leave-one-out residual over every vector and target
/// (scikit-learn's criterion without a scorer), the first of equals; an `α` whose residuals are not
/// finite (a vector the others cannot predict at all, at a vanishing `α`) is never chosen.
fn choose_alpha(spectrum: &Spectrum<'_>, alphas: &[f64]) -> Result<AlphaChoice> {
    let mut best: Option<(f64, f64, Mat<f64>)> = None;
    let mut curve = Vec::with_capacity(alphas.len());
    for &alpha in alphas {
        let residuals = spectrum.leave_one_out(alpha);
        let count = (residuals.nrows() * residuals.ncols()).max(1) as f64;
        let error = residuals
            .col_iter()
            .flat_map(|c| c.iter().map(|r| r * r))
            .sum::<f64>()
            / count;
        if !error.is_finite() {
            continue;
        }
        curve.push((alpha, error));
        if best
            .as_ref()
            .is_none_or(|(_, smallest, _)| error < *smallest)
        {
            best = Some((alpha, error, residuals));
        }
    }
    let Some((alpha, _, residuals)) = best else {
        return Err(CoreError::Param {
            name: "ridge alphas",
            reason: format!(
                "the leave-one-out residuals are not finite for any alpha of {alphas:?}; try larger alphas"
            ),
        });
    };
    Ok(AlphaChoice {
        alpha,
        residuals,
        curve,
    })
}
