//! Temperature scaling of class scores (Guo et al., "On Calibration of Modern Neural Networks", 2017): the
//! posteriors become `softmax(T · scores)` with one `T > 0` fitted on scores of held-out vectors (the
//! Parzen window uses leave-one-out scores), so that a reported confidence of 0.9 is right about nine
//! times in ten. `T` does not change which class scores highest.
//!
//! Why the Parzen window needs it: its kernel width is chosen for accuracy, and the most accurate width is
//! often a wide one (near the nearest-class-mean limit), whose posteriors are all close to `1 / classes`:
//! on the simulated data set every image got a confidence of about 0.28 of four classes while 89 % of the
//! validation images were right. Calibrated, the paper's protocol there reports 0.93 on average when right
//! and 0.61 when wrong (99.2 % right).
//!
//! `T` minimises the validation log-loss against targets smoothed by Laplace's rule of succession: `n`
//! validation vectors cannot show an error rate below about `1 / (n + 2)`, so the true class's target is
//! `(n + 1) / (n + 2)` and the rest is shared by the other classes. Without it, a validation set classified
//! without error drives `T` to infinity and every confidence to exactly 1.

use crate::error::{CoreError, Result};

/// The range `T` is searched in: wide enough for any score scale met in practice, narrow enough that
/// `T · score` stays finite for finite scores of moderate size.
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

/// Mean over the rows of the cross-entropy between the smoothed targets and `softmax(T · scores)`;
/// `scores` is `rows x n_classes`, finite.
pub fn smoothed_log_loss(
    scores: &[f64],
    classes: &[usize],
    n_classes: usize,
    epsilon: f64,
    temperature: f64,
) -> f64 {
    mean_over_rows(scores, classes, n_classes, epsilon, temperature, |term| {
        -term.target * term.log_p
    })
}

/// The derivative of [`smoothed_log_loss`] in `T`: mean over rows of `E_p[s] - E_target[s]`, which grows
/// with `T` (the loss is convex in `T`).
fn slope(
    scores: &[f64],
    classes: &[usize],
    n_classes: usize,
    epsilon: f64,
    temperature: f64,
) -> f64 {
    mean_over_rows(scores, classes, n_classes, epsilon, temperature, |term| {
        (term.log_p.exp() - term.target) * term.shifted
    })
}

/// One class of one row: its score less the row's largest, its log posterior at the temperature, and its
/// smoothed target.
struct Term {
    shifted: f64,
    log_p: f64,
    target: f64,
}

/// The mean over rows of the sum over classes of `per_class(term)`.
fn mean_over_rows(
    scores: &[f64],
    classes: &[usize],
    n_classes: usize,
    epsilon: f64,
    temperature: f64,
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
                .map(|s| (temperature * (s - top)).exp())
                .sum::<f64>()
                .ln();
            row.iter()
                .enumerate()
                .map(|(c, &s)| {
                    let shifted = s - top;
                    per_class(Term {
                        shifted,
                        log_p: temperature * shifted - log_total,
                        target: epsilon / n_classes as f64
                            + if c == class { 1.0 - epsilon } else { 0.0 },
                    })
                })
                .sum::<f64>()
        })
        .sum();
    total / rows
}

/// Fits `T` to `scores` (`rows x n_classes`, finite log-scale class scores such as log densities) and the true
/// `classes`, minimising [`smoothed_log_loss`] with [`laplace_smoothing`] over [`TEMPERATURE_RANGE`].
/// Bisection on the loss's derivative, in `ln T`: the loss is convex in `T`, so the derivative has at most
/// one sign change. Returns 1 for fewer than two classes or no rows.
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
    if scores.iter().any(|s| !s.is_finite()) {
        return Err(CoreError::Param {
            name: "calibration scores",
            reason: "a score is not finite".into(),
        });
    }
    let epsilon = laplace_smoothing(classes.len(), n_classes);
    let slope_at = |log_t: f64| slope(scores, classes, n_classes, epsilon, log_t.exp());
    let (mut lo, mut hi) = (TEMPERATURE_RANGE.0.ln(), TEMPERATURE_RANGE.1.ln());
    if slope_at(lo) >= 0.0 {
        return Ok(TEMPERATURE_RANGE.0);
    }
    if slope_at(hi) <= 0.0 {
        return Ok(TEMPERATURE_RANGE.1);
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
    Ok((0.5 * (lo + hi)).exp())
}

/// Whether `temperature` can scale posteriors: finite and positive.
pub fn is_usable_temperature(temperature: f64) -> bool {
    temperature.is_finite() && temperature > 0.0
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
            let eps = laplace_smoothing(classes.len(), 3);
            let loss = |t: f64| smoothed_log_loss(&scores, &classes, 3, eps, t);
            // The oracle: a log grid of 4001 temperatures over the whole range.
            let (lo, hi) = (TEMPERATURE_RANGE.0.ln(), TEMPERATURE_RANGE.1.ln());
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
        let confidence = 1.0 / (1.0 + 2.0 * (-0.05 * t).exp());
        let eps = laplace_smoothing(400, 3);
        let expected = 0.75 * (1.0 - eps) + eps / 3.0;
        assert!(
            (confidence - expected).abs() < 1e-6,
            "T {t}: {confidence} vs {expected}"
        );
    }

    #[test]
    fn a_perfect_validation_set_gives_a_finite_temperature_and_laplace_confidence() {
        let (scores, classes) = rows(28, 0, 1.0);
        let t = fit_temperature(&scores, &classes, 3).unwrap();
        assert!(t < TEMPERATURE_RANGE.1, "{t}");
        let row = &scores[0..3];
        let top = row.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let confidence = 1.0 / row.iter().map(|s| (t * (s - top)).exp()).sum::<f64>();
        assert!(
            (confidence - 29.0 / 30.0).abs() < 0.01,
            "T {t}: {confidence}"
        );
    }

    #[test]
    fn degenerate_inputs() {
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            assert!(fit_temperature(&[0.0, bad], &[0], 2).is_err());
        }
        assert!(fit_temperature(&[0.0, 1.0], &[2], 2).is_err());
        assert!(fit_temperature(&[0.0, 1.0, 2.0], &[0], 2).is_err());
        assert_eq!(fit_temperature(&[], &[], 3).unwrap(), 1.0);
        assert_eq!(fit_temperature(&[0.0], &[0], 1).unwrap(), 1.0);
    }
}
