//! Temperature scaling of class scores (Guo et al., "On Calibration of Modern Neural Networks", 2017): the
//! posteriors become `softmax(scores / T)` with one `T > 0` fitted on scores of held-out vectors
//! (five-fold cross-validated scores of every training and validation vector for the Gaussian classifiers
//! and the SVM, [`cross_validated_scores`]; leave-one-out scores for the Parzen window and k-NN),
//! so that a reported confidence of 0.9 is right about nine times in ten. `T` does not change which class
//! scores highest. Every classifier fits its temperature here.
//!
//! Why the Parzen window needs it: its kernel width is chosen for accuracy, and the most accurate width is
//! often a wide one (near the nearest-class-mean limit), whose posteriors are all close to `1 / classes`:
//! on the simulated data set every image got a confidence of about 0.28 of four classes while 89 % of the
//! validation images were right. Calibrated, the paper's protocol there reports 0.95 on average when right
//! and 0.70 when wrong (99.2 % right).
//!
//! `T` minimises the held-out log-loss. When every held-out vector's true class scores highest that loss
//! has no minimum (it falls as `T -> 0`, every confidence -> 1); then the targets are smoothed by Laplace's
//! rule of succession: `n` vectors without an error cannot show an error rate below about `1 / (n + 2)`,
//! so the true class's target is `(n + 1) / (n + 2)` and the rest is shared by the other classes. (Smoothing
//! every fit was tried: with 28 validation images it capped the confidence near 0.97 and left every
//! classifier under-confident, calibration error 0.06-0.11 against 0.004-0.06 without it.)

use super::common::LabeledVectors;
use crate::error::{CoreError, Result};

/// The range `T` is searched in, relative to the median spread (largest less smallest score) of the rows:
/// wide enough for any score scale met in practice.
pub const TEMPERATURE_RANGE: (f64, f64) = (1e-6, 1e6);

/// The label smoothing `ε` for `n` validation vectors of `n_classes` classes: the target of the true class,
/// `1 - ε + ε / n_classes`, is Laplace's `(n + 1) / (n + 2)`.
pub fn laplace_smoothing(n: usize, n_classes: usize) -> f64 {
    if n_classes < 2 {
        return 0.0;
    }
    let k = n_classes as f64;
    k / ((k - 1.0) * (n as f64 + 2.0))
}

/// Mean over the rows of the cross-entropy between the smoothed targets and `softmax(scores / T)`;
/// `scores` is `rows x n_classes`, finite.
pub fn smoothed_log_loss(
    scores: &[f64],
    classes: &[usize],
    n_classes: usize,
    epsilon: f64,
    temperature: f64,
) -> f64 {
    mean_over_rows(
        scores,
        classes,
        n_classes,
        epsilon,
        1.0 / temperature,
        |term| -term.target * term.log_p,
    )
}

/// The derivative of the loss in the inverse temperature `β = 1 / T`: mean over rows of
/// `E_p[s] - E_target[s]`, which grows with `β` (the loss is convex in `β`).
fn slope(scores: &[f64], classes: &[usize], n_classes: usize, epsilon: f64, beta: f64) -> f64 {
    mean_over_rows(scores, classes, n_classes, epsilon, beta, |term| {
        (term.log_p.exp() - term.target) * term.shifted
    })
}

/// One class of one row: its score less the row's largest, its log posterior at the inverse temperature,
/// and its smoothed target.
struct Term {
    shifted: f64,
    log_p: f64,
    target: f64,
}

/// The mean over rows of the sum over classes of `per_class(term)`, at the inverse temperature `beta`.
fn mean_over_rows(
    scores: &[f64],
    classes: &[usize],
    n_classes: usize,
    epsilon: f64,
    beta: f64,
    per_class: impl Fn(Term) -> f64,
) -> f64 {
    let rows = classes.len().max(1) as f64;
    let total: f64 = scores
        .chunks_exact(n_classes)
        .zip(classes)
        .map(|(row, &class)| {
            let top = row.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let log_total = row
                .iter()
                .map(|s| (beta * (s - top)).exp())
                .sum::<f64>()
                .ln();
            row.iter()
                .enumerate()
                .map(|(c, &s)| {
                    let shifted = s - top;
                    per_class(Term {
                        shifted,
                        log_p: beta * shifted - log_total,
                        target: epsilon / n_classes as f64
                            + if c == class { 1.0 - epsilon } else { 0.0 },
                    })
                })
                .sum::<f64>()
        })
        .sum();
    total / rows
}

/// Fits `T` to `scores` (`rows x n_classes`, log-scale class scores such as log densities; larger is more
/// likely) and the true `classes`, minimising the log-loss (with [`laplace_smoothing`] when the plain one
/// has no minimum; see the module documentation): bisection on the loss's derivative in `ln(1 / T)` (the
/// loss is convex in `1 / T`, so the derivative changes sign at most once) over [`TEMPERATURE_RANGE`]
/// times the median spread of the rows. Rows holding a non-finite score are left out. Returns 1 for fewer
/// than two classes or no usable rows; an error for mismatched lengths or a class out of range.
pub fn fit_temperature(scores: &[f64], classes: &[usize], n_classes: usize) -> Result<f64> {
    if n_classes < 2 || classes.is_empty() {
        return Ok(1.0);
    }
    if scores.len() != classes.len() * n_classes {
        return Err(CoreError::Param {
            name: "calibration scores",
            reason: format!(
                "{} scores for {} rows of {n_classes} classes",
                scores.len(),
                classes.len()
            ),
        });
    }
    if let Some(&class) = classes.iter().find(|&&c| c >= n_classes) {
        return Err(CoreError::Param {
            name: "calibration classes",
            reason: format!("class {class} of {n_classes}"),
        });
    }
    let mut finite_scores = Vec::with_capacity(scores.len());
    let mut finite_classes = Vec::with_capacity(classes.len());
    let mut spreads = Vec::with_capacity(classes.len());
    for (row, &class) in scores.chunks_exact(n_classes).zip(classes) {
        if row.iter().all(|s| s.is_finite()) {
            finite_scores.extend_from_slice(row);
            finite_classes.push(class);
            let top = row.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let bottom = row.iter().copied().fold(f64::INFINITY, f64::min);
            spreads.push(top - bottom);
        }
    }
    spreads.sort_by(f64::total_cmp);
    let Some(&scale) = spreads.get(spreads.len() / 2) else {
        return Ok(1.0);
    };
    if !(scale > 0.0 && scale.is_finite()) {
        return Ok(1.0);
    }
    let (scores, classes) = (&finite_scores[..], &finite_classes[..]);
    // The plain log-loss first; it has no minimum when every row's true class scores highest (the loss
    // falls as T -> 0), and then the smoothed one.
    Ok(
        minimise_log_loss(scores, classes, n_classes, 0.0, scale).unwrap_or_else(|| {
            let epsilon = laplace_smoothing(classes.len(), n_classes);
            minimise_log_loss(scores, classes, n_classes, epsilon, scale)
                .unwrap_or(scale * TEMPERATURE_RANGE.0)
        }),
    )
}

/// The `T` minimising [`smoothed_log_loss`] at smoothing `epsilon`, searched between `scale` x
/// [`TEMPERATURE_RANGE`] by bisection on the derivative in `ln(1 / T)`; `None` when the loss still falls
/// at the smallest `T` (no minimum in the range).
fn minimise_log_loss(
    scores: &[f64],
    classes: &[usize],
    n_classes: usize,
    epsilon: f64,
    scale: f64,
) -> Option<f64> {
    let slope_at = |log_beta: f64| slope(scores, classes, n_classes, epsilon, log_beta.exp());
    // In ln(1 / T): T from scale x 1e6 (lo) down to scale x 1e-6 (hi).
    let (mut lo, mut hi) = (
        (1.0 / (scale * TEMPERATURE_RANGE.1)).ln(),
        (1.0 / (scale * TEMPERATURE_RANGE.0)).ln(),
    );
    if slope_at(lo) >= 0.0 {
        return Some(scale * TEMPERATURE_RANGE.1);
    }
    if slope_at(hi) <= 0.0 {
        return None;
    }
    // 60 halvings of a range of ln(1e12) ~ 27.6 leave it below 1e-16: T to f64 precision.
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if slope_at(mid) < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some((-0.5 * (lo + hi)).exp())
}

/// `ln Σ exp(scores)`, shifted by the largest score so that nothing overflows (`-inf` for no scores).
pub(crate) fn log_sum_exp(scores: &[f64]) -> f64 {
    let max = scores.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if max == f64::NEG_INFINITY {
        return max;
    }
    max + scores.iter().map(|s| (s - max).exp()).sum::<f64>().ln()
}

/// The temperature of model files written before their classifier was calibrated (serde's default for
/// the field): `T = 1` leaves the scores as they were.
pub fn unit_temperature() -> f64 {
    1.0
}

/// Whether `temperature` can scale posteriors: finite and positive.
pub fn is_usable_temperature(temperature: f64) -> bool {
    temperature.is_finite() && temperature > 0.0
}

/// Folds of [`cross_validated_scores`].
pub const CALIBRATION_FOLDS: usize = 5;

/// Each vector's class scores by a model fitted (`fit`) on the other folds and scored by `score`
/// (`score(model, x, out)`, `out` one score per class): the scores a temperature is fitted on when the
/// final model is fitted on every vector. The `i`-th vector of each class goes to fold `i mod K`, `K` the
/// smaller of [`CALIBRATION_FOLDS`] and the smallest class's count, so every fold's model sees every
/// class; `None` when a class has fewer than two vectors.
///
/// Why not the validation set alone: with the paper's 7 validation images per class, 28 scores fix `T`
/// loosely, and a model fitted on the 13 training images scores them less surely than the final model
/// (fitted on all 20) scores new images; the cross-validated scores use all 80, by models fitted on 16
/// per class.
pub fn cross_validated_scores<M>(
    all: &LabeledVectors<'_>,
    n_classes: usize,
    dims: usize,
    fit: impl Fn(&LabeledVectors<'_>) -> Result<M>,
    score: impl Fn(&M, &[f64], &mut [f64]) -> Result<()>,
) -> Result<Option<Vec<f64>>> {
    let mut counts = vec![0usize; n_classes];
    let rank_in_class: Vec<usize> = all
        .classes
        .iter()
        .map(|&class| {
            counts[class] += 1;
            counts[class] - 1
        })
        .collect();
    let folds = counts
        .iter()
        .copied()
        .min()
        .unwrap_or(0)
        .min(CALIBRATION_FOLDS);
    if folds < 2 || dims == 0 {
        return Ok(None);
    }
    let mut scores = vec![0.0; all.classes.len() * n_classes];
    for fold in 0..folds {
        let (mut vectors, mut classes, mut held_out) = (Vec::new(), Vec::new(), Vec::new());
        let rows = all.vectors.chunks_exact(dims).zip(all.classes);
        for (i, (x, &class)) in rows.enumerate() {
            if rank_in_class[i] % folds == fold {
                held_out.push(i);
            } else {
                vectors.extend_from_slice(x);
                classes.push(class);
            }
        }
        let model = fit(&LabeledVectors {
            vectors: &vectors,
            classes: &classes,
        })?;
        for i in held_out {
            score(
                &model,
                &all.vectors[i * dims..(i + 1) * dims],
                &mut scores[i * n_classes..(i + 1) * n_classes],
            )?;
        }
    }
    Ok(Some(scores))
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    /// Rows whose true class scores `margin` above two others, and a share of rows where a wrong class
    /// does instead.
    fn rows(n: usize, wrong_every: usize, margin: f64) -> (Vec<f64>, Vec<usize>) {
        let mut scores = Vec::new();
        let mut classes = Vec::new();
        for i in 0..n {
            let class = i % 3;
            let winner = if wrong_every > 0 && i % wrong_every == 0 {
                (class + 1) % 3
            } else {
                class
            };
            for c in 0..3 {
                scores.push(if c == winner { margin } else { 0.0 } - 0.01 * c as f64);
            }
            classes.push(class);
        }
        (scores, classes)
    }

    #[test]
    fn the_fitted_temperature_minimises_the_loss_over_a_fine_grid() {
        for (wrong_every, margin) in [(4, 0.05), (10, 0.3), (3, 2.0), (7, 40.0)] {
            let (scores, classes) = rows(60, wrong_every, margin);
            let t = fit_temperature(&scores, &classes, 3).unwrap();
            // Some rows are wrong: the plain log-loss has a minimum.
            let loss = |t: f64| smoothed_log_loss(&scores, &classes, 3, 0.0, t);
            // The oracle: a log grid of 4001 temperatures over the whole range (every row's spread is
            // about the margin).
            let (lo, hi) = (
                (margin * TEMPERATURE_RANGE.0).ln(),
                (margin * TEMPERATURE_RANGE.1).ln(),
            );
            let best_on_grid = (0..=4000)
                .map(|i| (lo + (hi - lo) * i as f64 / 4000.0).exp())
                .map(loss)
                .fold(f64::INFINITY, f64::min);
            assert!(
                loss(t) <= best_on_grid + 1e-12,
                "{wrong_every} {margin}: T {t}"
            );
        }
    }

    #[test]
    fn calibrated_confidence_follows_the_validation_accuracy() {
        // The winner scores 0.05 above two others and is the true class in three rows of four: the raw
        // posterior of the winner is about 0.34, the calibrated one the share of rows it is right in.
        let mut scores = Vec::new();
        let mut classes = Vec::new();
        for i in 0..400 {
            let class = i % 3;
            let winner = if i % 4 == 0 { (class + 1) % 3 } else { class };
            scores.extend((0..3).map(|c| if c == winner { 0.05 } else { 0.0 }));
            classes.push(class);
        }
        let t = fit_temperature(&scores, &classes, 3).unwrap();
        let confidence = 1.0 / (1.0 + 2.0 * (-0.05 / t).exp());
        let expected = 0.75;
        assert!(
            (confidence - expected).abs() < 1e-6,
            "T {t}: {confidence} vs {expected}"
        );
    }

    #[test]
    fn a_perfect_validation_set_gives_a_finite_temperature_and_laplace_confidence() {
        let (scores, classes) = rows(28, 0, 1.0);
        let t = fit_temperature(&scores, &classes, 3).unwrap();
        assert!(t > TEMPERATURE_RANGE.0, "{t}");
        let row = &scores[0..3];
        let top = row.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let confidence = 1.0 / row.iter().map(|s| ((s - top) / t).exp()).sum::<f64>();
        assert!(
            (confidence - 29.0 / 30.0).abs() < 0.01,
            "T {t}: {confidence}"
        );
    }

    #[test]
    fn degenerate_inputs() {
        // Rows with a non-finite score are left out; with none left, T is 1.
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            assert_eq!(fit_temperature(&[0.0, bad], &[0], 2).unwrap(), 1.0);
            let with = fit_temperature(&[0.0, bad, 1.0, 0.0, 0.0, 0.3], &[1, 0, 1], 2).unwrap();
            let without = fit_temperature(&[1.0, 0.0, 0.0, 0.3], &[0, 1], 2).unwrap();
            assert_eq!(with, without);
        }
        assert!(fit_temperature(&[0.0, 1.0], &[2], 2).is_err());
        assert!(fit_temperature(&[0.0, 1.0, 2.0], &[0], 2).is_err());
        assert_eq!(fit_temperature(&[], &[], 3).unwrap(), 1.0);
        assert_eq!(fit_temperature(&[0.0], &[0], 1).unwrap(), 1.0);
    }

    /// Stand-in model: the training vectors (1-D, each vector's value its index) and their classes.
    type Remembered = (Vec<f64>, Vec<usize>);

    fn remember(part: &LabeledVectors<'_>) -> Result<Remembered> {
        Ok((part.vectors.to_vec(), part.classes.to_vec()))
    }

    #[test]
    fn cross_validated_scores_come_from_models_that_did_not_see_the_vector() {
        // Classes of 7, 5 and 9 vectors, interleaved: 5 folds.
        let classes = [[0, 1, 2].repeat(5), vec![0, 0, 2, 2, 2, 2]].concat();
        let vectors: Vec<f64> = (0..classes.len()).map(|i| i as f64).collect();
        let all = LabeledVectors {
            vectors: &vectors,
            classes: &classes,
        };
        let fits = std::cell::Cell::new(0);
        let scores = cross_validated_scores(
            &all,
            3,
            1,
            |part| {
                fits.set(fits.get() + 1);
                remember(part)
            },
            |(seen, seen_classes): &Remembered, x, out| {
                // out[0]: 1 if the model trained on x; out[1]: classes it saw; out[2]: vectors it saw
                out[0] = f64::from(u8::from(seen.contains(&x[0])));
                let mut present = [false; 3];
                seen_classes.iter().for_each(|&c| present[c] = true);
                out[1] = present.iter().filter(|&&p| p).count() as f64;
                out[2] = seen.len() as f64;
                Ok(())
            },
        )
        .unwrap()
        .unwrap();
        let counts = [0, 1, 2].map(|c| classes.iter().filter(|&&k| k == c).count());
        assert_eq!(
            fits.get(),
            CALIBRATION_FOLDS.min(*counts.iter().min().unwrap())
        );
        let mut held_out_per_fold_size = Vec::new();
        for row in scores.chunks_exact(3) {
            assert_eq!(row[0], 0.0, "a vector was scored by a model trained on it");
            assert_eq!(row[1], 3.0, "a fold's model lacked a class");
            held_out_per_fold_size.push(row[2]);
        }
        // Every vector is scored once, by a model of all the others less its fold (about a fifth).
        let n = classes.len() as f64;
        assert!(
            held_out_per_fold_size
                .iter()
                .all(|&seen| seen < n && seen >= 0.7 * n)
        );
    }

    #[test]
    fn cross_validated_scores_need_two_vectors_of_every_class() {
        let (vectors, classes) = (vec![0.0, 1.0, 2.0, 3.0], vec![0, 0, 0, 1]);
        let all = LabeledVectors {
            vectors: &vectors,
            classes: &classes,
        };
        let result =
            cross_validated_scores(&all, 2, 1, remember, |_: &Remembered, _, _| Ok(())).unwrap();
        assert!(result.is_none());
    }
}
