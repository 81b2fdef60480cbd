//! Helpers shared by the classifiers: input checks, and the softmax at a temperature that turns scores into
//! posteriors (the temperature is fitted in [`super::calibration`]).

use crate::error::{CoreError, Result};

/// Reduced vectors with their class indices, `n x dims` row-major; in double precision, or in single
/// (`LabeledVectors<'_, f32>`) for a family that reads it
/// ([`ClassifierFamily::READS_SINGLE`](super::ClassifierFamily::READS_SINGLE)).
#[derive(Debug)]
pub struct LabeledVectors<'a, T = f64> {
    pub vectors: &'a [T],
    pub classes: &'a [usize],
}

impl<T> Clone for LabeledVectors<'_, T> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<T> Copy for LabeledVectors<'_, T> {}

/// Checks shapes, class indices and finiteness of `data`.
pub(crate) fn check_vectors<T: Copy + Into<f64>>(
    data: &LabeledVectors<'_, T>,
    what: &'static str,
    dims: usize,
    n_classes: usize,
) -> Result<()> {
    if dims == 0 {
        return Err(CoreError::Param {
            name: what,
            reason: "vectors are empty".into(),
        });
    }
    if data.vectors.len() != data.classes.len() * dims {
        return Err(CoreError::Shape {
            what,
            expected: format!("{} vectors of {dims}", data.classes.len()),
            got: format!("{} values", data.vectors.len()),
        });
    }
    if let Some(&class) = data.classes.iter().find(|&&c| c >= n_classes) {
        return Err(CoreError::Param {
            name: what,
            reason: format!("class index {class} but only {n_classes} classes"),
        });
    }
    if data.vectors.iter().any(|&v| !v.into().is_finite()) {
        return Err(CoreError::Param {
            name: what,
            reason: "contains NaN or infinite values".into(),
        });
    }
    Ok(())
}

/// The fraction of the vectors of `validation` (`dims` each) whose class `classify` returns; 0 for none.
pub(crate) fn validation_accuracy(
    validation: &LabeledVectors<'_>,
    dims: usize,
    mut classify: impl FnMut(&[f64]) -> Result<usize>,
) -> Result<f64> {
    let mut correct = 0usize;
    for (x, &class) in validation
        .vectors
        .chunks_exact(dims)
        .zip(validation.classes)
    {
        if classify(x)? == class {
            correct += 1;
        }
    }
    Ok(correct as f64 / validation.classes.len().max(1) as f64)
}

/// Errors unless every class has at least `min` vectors in `data`.
pub(crate) fn require_per_class(
    data: &LabeledVectors<'_>,
    n_classes: usize,
    min: usize,
) -> Result<()> {
    for class in 0..n_classes {
        let count = data.classes.iter().filter(|&&c| c == class).count();
        if count < min {
            return Err(CoreError::NotEnoughData(format!(
                "class {class} has {count} training vector(s); at least {min} needed"
            )));
        }
    }
    Ok(())
}

/// Training and validation vectors together (what final models are fitted on).
pub(crate) fn merged(
    train: &LabeledVectors<'_>,
    validation: &LabeledVectors<'_>,
) -> (Vec<f64>, Vec<usize>) {
    (
        [train.vectors, validation.vectors].concat(),
        [train.classes, validation.classes].concat(),
    )
}

/// Softmax of `scores / temperature` in place; returns the arg-max (first on ties).
pub(crate) fn softmax_in_place(scores: &mut [f64], temperature: f64) -> usize {
    // The differences from the top score are divided, not the scores: a tiny temperature (a model file
    // may hold any positive one) would take large scores to ±inf, and inf - inf to NaN posteriors; the
    // differences only go to -inf, whose exponential is 0.
    let best = argmax(scores);
    let top = scores[best];
    let mut total = 0.0;
    for score in scores.iter_mut() {
        *score = ((*score - top) / temperature).exp();
        total += *score;
    }
    for score in scores.iter_mut() {
        *score /= total;
    }
    best
}

/// Fraction of rows of `scores` (`n x n_classes`) whose arg-max is the true class.
pub(crate) fn accuracy_of_scores(scores: &[f64], classes: &[usize], n_classes: usize) -> f64 {
    if classes.is_empty() {
        return 0.0;
    }
    let correct = scores
        .chunks_exact(n_classes)
        .zip(classes)
        .filter(|(row, class)| argmax(row) == **class)
        .count();
    correct as f64 / classes.len() as f64
}

pub(crate) fn argmax(values: &[f64]) -> usize {
    let mut best = 0;
    for (i, &v) in values.iter().enumerate() {
        if v > values[best] {
            best = i;
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn softmax_matches_the_definition_and_survives_extreme_temperatures() {
        let scores = [-3.0, 1.5, 0.25, 1.5];
        for temperature in [0.7, 1.0, 40.0] {
            let mut posteriors = scores;
            let best = softmax_in_place(&mut posteriors, temperature);
            assert_eq!(best, 1, "the first of the tied maxima");
            let total: f64 = scores.iter().map(|s| (s / temperature).exp()).sum();
            for (p, s) in posteriors.iter().zip(&scores) {
                assert!((p - (s / temperature).exp() / total).abs() < 1e-12);
            }
        }
        // Large scores and a tiny temperature: one-hot (split over the tie), never NaN.
        let large = [-1e300, 2e300, 1e300, 2e300];
        for temperature in [1e-300, f64::MIN_POSITIVE, 5e-324] {
            let mut posteriors = large;
            assert_eq!(softmax_in_place(&mut posteriors, temperature), 1);
            assert_eq!(
                posteriors,
                [0.0, 0.5, 0.0, 0.5],
                "temperature {temperature:e}"
            );
        }
    }
}
