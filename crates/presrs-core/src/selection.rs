//! Automatic choice of the feature family and classifier, by validation inside the training data only.
//!
//! Every candidate [`TrainConfig`](crate::pipeline::TrainConfig) is scored on folds made from the training + validation images alone:
//! - when those images carry conditions (e.g. gaits) with at least two distinct values, **leave one
//!   condition out**: train on the other conditions (their own 35 % validating the classifier's
//!   hyper-parameters), test on the held-out one — what users need is accuracy on conditions the model has
//!   not seen;
//! - otherwise three seeded stratified splits: 70 % to train (of which 35 % validate), 30 % to test.
//!
//! The candidate with the highest mean fold accuracy wins; ties go to the earlier candidate (callers list
//! the paper's fft1d + Parzen window first). The winner is then trained on the given training and validation
//! images and the [`Selection`] (every candidate's scores) is stored in the model.

use std::collections::BTreeMap;

use crate::error::{CoreError, Result};
use crate::metrics::MeanStd;
use crate::pipeline::{CheckedTrainConfig, LabeledImage, TrainedModel, train};
use crate::split::{ValidationSize, stratified_split};

// The record of a selection is plain data kept in the trained model (`pipeline`); the procedure lives
// here. Re-exported so `select`'s result type is nameable beside it.
pub use crate::pipeline::{CandidateScore, Selection};

struct InnerFold {
    name: String,
    train: Vec<usize>,
    validation: Vec<usize>,
    test: Vec<usize>,
}

/// Scores `candidates` on folds of `images` (training + validation images together); `conditions` (one per
/// image, else an error) enables leave-one-condition-out. Deterministic in `seed`.
pub fn select(
    images: &[LabeledImage<'_>],
    conditions: Option<&[&str]>,
    candidates: &[CheckedTrainConfig],
    seed: u64,
) -> Result<Selection> {
    if candidates.is_empty() {
        return Err(CoreError::Param {
            name: "candidates",
            reason: "the automatic choice needs at least one candidate".into(),
        });
    }
    check_conditions(conditions, images.len())?;
    let labels: Vec<&str> = images.iter().map(|i| i.label).collect();
    let mut distinct: Vec<&str> = conditions.map(<[&str]>::to_vec).unwrap_or_default();
    distinct.sort_unstable();
    distinct.dedup();
    let mut folds = Vec::new();
    let method;
    if let (Some(conditions), true) = (conditions, distinct.len() >= 2) {
        method = format!(
            "leave one condition out inside the training data ({})",
            distinct.join(", ")
        );
        for (k, held_out) in distinct.iter().enumerate() {
            let pool: Vec<usize> = (0..images.len())
                .filter(|&i| conditions[i] != *held_out)
                .collect();
            let pool_labels: Vec<&str> = pool.iter().map(|&i| labels[i]).collect();
            let split = stratified_split(
                &pool_labels,
                None,
                ValidationSize::Fraction(0.35),
                seed.wrapping_add(k as u64),
            )?;
            folds.push(InnerFold {
                name: (*held_out).to_owned(),
                train: split.train.iter().map(|&j| pool[j]).collect(),
                validation: split.validation.iter().map(|&j| pool[j]).collect(),
                test: (0..images.len())
                    .filter(|&i| conditions[i] == *held_out)
                    .collect(),
            });
        }
    } else {
        method = "three stratified 70/30 splits of the training data".to_owned();
        for k in 0..3u64 {
            let outer = stratified_split(
                &labels,
                None,
                ValidationSize::Fraction(0.3),
                seed.wrapping_add(k),
            )?;
            let inner_labels: Vec<&str> = outer.train.iter().map(|&i| labels[i]).collect();
            let inner = stratified_split(
                &inner_labels,
                None,
                ValidationSize::Fraction(0.35),
                seed.wrapping_add(1000 + k),
            )?;
            folds.push(InnerFold {
                name: format!("split {k}"),
                train: inner.train.iter().map(|&j| outer.train[j]).collect(),
                validation: inner.validation.iter().map(|&j| outer.train[j]).collect(),
                test: outer.validation.clone(),
            });
        }
    }
    let mut scores = Vec::with_capacity(candidates.len());
    for candidate in candidates {
        let config = candidate.config();
        let mut per_fold = BTreeMap::new();
        let mut error = None;
        for fold in &folds {
            let pick = |indices: &[usize]| indices.iter().map(|&i| images[i]).collect::<Vec<_>>();
            match train(&pick(&fold.train), &pick(&fold.validation), candidate) {
                Ok(model) => {
                    let mut session = model.session();
                    let mut correct = 0usize;
                    for &i in &fold.test {
                        if session.classify(&images[i].frame)?.label == images[i].label {
                            correct += 1;
                        }
                    }
                    per_fold.insert(
                        fold.name.clone(),
                        correct as f64 / fold.test.len().max(1) as f64,
                    );
                }
                Err(err) => {
                    error = Some(err.to_string());
                    break;
                }
            }
        }
        let accuracy = if error.is_some() {
            MeanStd::default()
        } else {
            MeanStd::of(&per_fold.values().copied().collect::<Vec<_>>())
        };
        scores.push(CandidateScore {
            features: config.features.name(),
            classifier: config.classifier.kind().as_str().to_owned(),
            config: config.clone(),
            accuracy,
            per_fold,
            error,
        });
    }
    let mut chosen = 0;
    for (i, score) in scores.iter().enumerate() {
        if score.error.is_none()
            && (scores[chosen].error.is_some()
                || score.accuracy.mean > scores[chosen].accuracy.mean)
        {
            chosen = i;
        }
    }
    if let Some(error) = &scores[chosen].error {
        // Every candidate failed; the first one's reason stands for them.
        let name = format!(
            "{} + {}",
            scores[chosen].features, scores[chosen].classifier
        );
        return Err(CoreError::NotEnoughData(if scores.len() == 1 {
            format!("{name} could not be trained ({error})")
        } else {
            format!(
                "none of the {} candidates could be trained ({name}: {error})",
                scores.len()
            )
        }));
    }
    Ok(Selection {
        method,
        chosen,
        scores,
    })
}

/// [`select`] on training + validation images, then [`train`] of the winner on them; the model records
/// the selection. `conditions`: one per training image then one per validation image.
pub fn train_auto(
    train_images: &[LabeledImage<'_>],
    validation_images: &[LabeledImage<'_>],
    conditions: Option<&[&str]>,
    candidates: &[CheckedTrainConfig],
    seed: u64,
) -> Result<TrainedModel> {
    // The winner is trained on the given split: a candidate that cannot be trained without validation
    // images is refused now, not after every candidate has been scored.
    if validation_images.is_empty()
        && let Some(config) = candidates
            .iter()
            .map(CheckedTrainConfig::config)
            .find(|config| config.classifier.needs_validation())
    {
        return Err(CoreError::NotEnoughData(format!(
            "the candidate {} + {} chooses its parameters on validation images, and there are none: \
             keep some for validation, or leave it out of the candidates (or give it a fixed sigma)",
            config.features.name(),
            config.classifier.kind().as_str()
        )));
    }
    let all: Vec<LabeledImage<'_>> = train_images
        .iter()
        .chain(validation_images)
        .copied()
        .collect();
    check_conditions(conditions, all.len())?;
    let selection = select(&all, conditions, candidates, seed)?;
    let config = candidates[selection.chosen].clone();
    let model = train(train_images, validation_images, &config)?;
    Ok(model.with_selection(selection))
}

/// Errors unless `conditions`, when given, has one entry per image.
fn check_conditions(conditions: Option<&[&str]>, n_images: usize) -> Result<()> {
    match conditions {
        Some(conditions) if conditions.len() != n_images => Err(CoreError::Shape {
            what: "conditions",
            expected: format!("one per image ({n_images})"),
            got: conditions.len().to_string(),
        }),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::{Frame, Grid};
    use crate::pipeline::TrainConfig;

    /// Four images of `frame`, labelled a, b, a, b.
    fn blank_images(frame: &Frame) -> Vec<LabeledImage<'_>> {
        ["a", "b", "a", "b"]
            .iter()
            .map(|label| LabeledImage::new(frame.view(), label))
            .collect()
    }

    #[test]
    fn conditions_must_match_the_images() {
        let frame = Frame::zeros(Grid::new(44, 44));
        let images = blank_images(&frame);
        let candidates = [TrainConfig::default().check().unwrap()];
        // Fewer conditions than images indexed past their end; more were silently ignored.
        for conditions in [&["x", "y"][..], &["x", "y", "x", "y", "x"][..]] {
            let err = select(&images, Some(conditions), &candidates, 1).unwrap_err();
            assert!(
                matches!(
                    err,
                    CoreError::Shape {
                        what: "conditions",
                        ..
                    }
                ),
                "{err}"
            );
        }
    }

    /// When every candidate fails, the error names the first and gives its reason, once.
    #[test]
    fn every_candidate_failing_names_the_first_and_its_reason() {
        let frame = Frame::zeros(Grid::new(44, 44));
        let labels = ["a", "b"].repeat(6);
        let images: Vec<_> = labels
            .iter()
            .map(|label| LabeledImage::new(frame.view(), label))
            .collect();
        // Identical images: the Parzen window cannot scale σ to their distances.
        let pwe = TrainConfig::default().check().unwrap();
        let err = select(&images, None, std::slice::from_ref(&pwe), 1).unwrap_err();
        let text = err.to_string();
        assert!(
            text.starts_with(
                "not enough data: fft1d + pwe could not be trained (not enough data: "
            ),
            "{text}"
        );
        let err = select(&images, None, &[pwe.clone(), pwe], 1).unwrap_err();
        let text = err.to_string();
        assert!(
            text.starts_with(
                "not enough data: none of the 2 candidates could be trained (fft1d + pwe: "
            ),
            "{text}"
        );
    }

    /// Without validation images, a candidate that needs them (the Parzen window choosing σ) is refused
    /// before any candidate is scored; with a fixed σ the same candidate trains.
    #[test]
    fn candidates_needing_validation_images_are_refused_up_front() {
        let frame = Frame::zeros(Grid::new(44, 44));
        let images = blank_images(&frame);
        let candidates = [TrainConfig::default().check().unwrap()];
        let err = train_auto(&images, &[], None, &candidates, 1).unwrap_err();
        assert!(
            matches!(&err, CoreError::NotEnoughData(reason) if reason.contains("fft1d + pwe")),
            "{err}"
        );
        let fixed = TrainConfig {
            classifier: crate::classifier::ClassifierConfig::Pwe(crate::classifier::ParzenConfig {
                sigma: crate::classifier::SigmaChoice::Fixed { sigma: 1.0 },
            }),
            ..TrainConfig::default()
        };
        let trained = train_auto(&images, &[], None, &[fixed.check().unwrap()], 1);
        assert!(trained.is_ok(), "{:?}", trained.err());
    }
}
