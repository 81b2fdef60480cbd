//! Automatic choice of the feature family and classifier, by validation inside the training data only.
//!
//! Every candidate [`TrainConfig`](crate::pipeline::TrainConfig) is scored on folds made from the training + validation images alone,
//! as [`ValidateBy`] says (by default the most honest the data allow):
//! - **leave one group out** (the images' `group`, e.g. a person or a trial): train on the other groups
//!   (their own 35 % validating the classifier's hyper-parameters), test on the held-out one — what users
//!   of grouped data need is accuracy on groups the model has not seen; the default with 3 or more groups;
//! - **leave one condition out** (e.g. a gait), the same way; the default with fewer groups and 2 or more
//!   conditions;
//! - otherwise three seeded stratified splits: 70 % to train (of which 35 % validate), 30 % to test.
//!
//! The candidate with the highest mean fold accuracy wins; ties go to the earlier candidate (callers list
//! the paper's fft1d + Parzen window first). The winner is then trained on the given training and validation
//! images and the [`Selection`] (every candidate's scores) is stored in the model.

use std::collections::BTreeMap;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{CoreError, Result};
use crate::metrics::MeanStd;
use crate::pipeline::{CheckedTrainConfig, LabeledImage, TrainedModel, train};
use crate::split::{ValidationSize, stratified_split};

// The record of a selection is plain data kept in the trained model (`pipeline`); the procedure lives
// here. Re-exported so `select`'s result type is nameable beside it.
pub use crate::pipeline::{CandidateScore, Selection};

/// How the automatic choice validates its candidates inside the training data.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ValidateBy {
    /// Group when the images span 3 or more groups, else condition when they span 2 or more, else
    /// stratified splits.
    #[default]
    Auto,
    /// Leave one group out (at least two groups needed).
    Group,
    /// Leave one condition out (at least two conditions needed).
    Condition,
    /// Three stratified 70/30 splits.
    Split,
}

impl ValidateBy {
    pub const NAMES: [&'static str; 4] = ["auto", "group", "condition", "split"];

    pub fn as_str(self) -> &'static str {
        match self {
            Self::Auto => "auto",
            Self::Group => "group",
            Self::Condition => "condition",
            Self::Split => "split",
        }
    }

    /// What `Auto` means for images with these distinct groups and conditions (counts).
    pub fn resolve(self, groups: usize, conditions: usize) -> Self {
        match self {
            Self::Auto if groups >= 3 => Self::Group,
            Self::Auto if conditions >= 2 => Self::Condition,
            Self::Auto => Self::Split,
            other => other,
        }
    }
}

impl std::fmt::Display for ValidateBy {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

impl std::str::FromStr for ValidateBy {
    type Err = String;

    fn from_str(text: &str) -> std::result::Result<Self, String> {
        match text.trim().to_ascii_lowercase().as_str() {
            "auto" => Ok(Self::Auto),
            "group" => Ok(Self::Group),
            "condition" => Ok(Self::Condition),
            "split" => Ok(Self::Split),
            _ => Err(format!(
                "unknown validation {text:?} (known: {})",
                Self::NAMES.join(", ")
            )),
        }
    }
}

/// Which field of an image its folds are made by.
type Key = for<'x> fn(&LabeledImage<'x>) -> Option<&'x str>;

struct InnerFold {
    name: String,
    train: Vec<usize>,
    validation: Vec<usize>,
    test: Vec<usize>,
}

/// Scores `candidates` on folds of `images` (training + validation images together), made as `by` says
/// from the images' `group` and `condition`. Deterministic in `seed`.
pub fn select(
    images: &[LabeledImage<'_>],
    by: ValidateBy,
    candidates: &[CheckedTrainConfig],
    seed: u64,
) -> Result<Selection> {
    if candidates.is_empty() {
        return Err(CoreError::Param {
            name: "candidates",
            reason: "the automatic choice needs at least one candidate".into(),
        });
    }
    let labels: Vec<&str> = images.iter().map(|i| i.label).collect();
    let distinct = |key: Key| -> Option<Vec<&str>> {
        let keys: Option<Vec<&str>> = images.iter().map(key).collect();
        let mut keys = keys?;
        keys.sort_unstable();
        keys.dedup();
        Some(keys)
    };
    let groups = distinct(|i| i.group).unwrap_or_default();
    let conditions = distinct(|i| i.condition).unwrap_or_default();
    let by = by.resolve(groups.len(), conditions.len());
    let mut folds = Vec::new();
    let method;
    if by == ValidateBy::Split {
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
    } else {
        let (what, distinct, key): (&str, &[&str], Key) = if by == ValidateBy::Group {
            ("group", &groups, |i| i.group)
        } else {
            ("condition", &conditions, |i| i.condition)
        };
        if distinct.len() < 2 {
            return Err(CoreError::NotEnoughData(format!(
                "validating by {what} needs at least two {what}s in the training data, with a value for every image; found {}",
                distinct.len()
            )));
        }
        const LISTED: usize = 8;
        let mut listed = distinct[..distinct.len().min(LISTED)].join(", ");
        if distinct.len() > LISTED {
            listed.push_str(&format!(", ... {} in all", distinct.len()));
        }
        method = format!("leave one {what} out inside the training data ({listed})");
        for (k, held_out) in distinct.iter().enumerate() {
            let held = |i: usize| key(&images[i]) == Some(*held_out);
            let pool: Vec<usize> = (0..images.len()).filter(|&i| !held(i)).collect();
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
                test: (0..images.len()).filter(|&i| held(i)).collect(),
            });
        }
    }
    // Candidates are scored in parallel (rayon; each one's folds in order): the scores, and so the
    // choice, do not depend on the number of threads.
    let scores: Vec<CandidateScore> = candidates
        .par_iter()
        .map(|candidate| score_candidate(images, &folds, candidate))
        .collect::<Result<_>>()?;
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

/// One candidate's accuracy on every fold (in fold order; the first fold it cannot be trained on ends
/// it, with the reason).
fn score_candidate(
    images: &[LabeledImage<'_>],
    folds: &[InnerFold],
    candidate: &CheckedTrainConfig,
) -> Result<CandidateScore> {
    let config = candidate.config();
    let mut per_fold = BTreeMap::new();
    let mut error = None;
    for fold in folds {
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
    Ok(CandidateScore {
        features: config.features.name(),
        classifier: config.classifier.kind().as_str().to_owned(),
        config: config.clone(),
        accuracy,
        per_fold,
        error,
    })
}

/// [`select`] on training + validation images, then [`train`] of the winner on them; the model records
/// the selection.
pub fn train_auto(
    train_images: &[LabeledImage<'_>],
    validation_images: &[LabeledImage<'_>],
    by: ValidateBy,
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
    let selection = select(&all, by, candidates, seed)?;
    let config = candidates[selection.chosen].clone();
    let model = train(train_images, validation_images, &config)?;
    Ok(model.with_selection(selection))
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

    /// Images of the four synthetic classes, each with a group (of 4) and a condition (of 2).
    fn grouped(frames: &[Frame]) -> Vec<LabeledImage<'_>> {
        const GROUPS: [&str; 4] = ["g0", "g1", "g2", "g3"];
        frames
            .iter()
            .enumerate()
            .map(|(i, frame)| LabeledImage {
                frame: frame.view(),
                label: crate::testing::SYNTHETIC_CLASSES[i % 4],
                condition: Some(["c0", "c1"][(i / 4) % 2]),
                group: Some(GROUPS[(i / 8) % 4]),
            })
            .collect()
    }

    /// The folds follow `ValidateBy`: auto is leave-one-group-out with 3 or more groups, else by
    /// condition, else splits; a validation the data cannot give is an error that says why.
    #[test]
    fn validation_follows_the_groups_then_the_conditions() {
        use rand::SeedableRng;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let frames: Vec<Frame> = (0..64)
            .map(|i| crate::testing::synthetic_frame(i % 4, &mut rng))
            .collect();
        let images = grouped(&frames);
        let lda = TrainConfig {
            classifier: crate::classifier::ClassifierKind::Lda.default_config(),
            dims: 8,
            ..TrainConfig::default()
        }
        .check()
        .unwrap();
        let candidates = std::slice::from_ref(&lda);
        let folds = |selection: &Selection| -> Vec<String> {
            selection.scores[0].per_fold.keys().cloned().collect()
        };
        let auto = select(&images, ValidateBy::Auto, candidates, 1).unwrap();
        assert_eq!(folds(&auto), ["g0", "g1", "g2", "g3"]);
        assert!(
            auto.method.starts_with("leave one group out"),
            "{}",
            auto.method
        );
        let by_condition = select(&images, ValidateBy::Condition, candidates, 1).unwrap();
        assert_eq!(folds(&by_condition), ["c0", "c1"]);
        let split = select(&images, ValidateBy::Split, candidates, 1).unwrap();
        assert_eq!(folds(&split), ["split 0", "split 1", "split 2"]);
        // Two groups only: auto falls back to the conditions; without either, to splits.
        let two: Vec<LabeledImage<'_>> = images
            .iter()
            .filter(|i| matches!(i.group, Some("g0" | "g1")))
            .copied()
            .collect();
        let auto = select(&two, ValidateBy::Auto, candidates, 1).unwrap();
        assert_eq!(folds(&auto), ["c0", "c1"]);
        let plain: Vec<LabeledImage<'_>> = images
            .iter()
            .map(|i| LabeledImage::new(i.frame, i.label))
            .collect();
        let auto = select(&plain, ValidateBy::Auto, candidates, 1).unwrap();
        assert_eq!(folds(&auto), ["split 0", "split 1", "split 2"]);
        let err = select(&plain, ValidateBy::Group, candidates, 1).unwrap_err();
        assert!(
            matches!(&err, CoreError::NotEnoughData(reason) if reason.contains("validating by group")),
            "{err}"
        );
        assert_eq!("Group".parse::<ValidateBy>(), Ok(ValidateBy::Group));
        assert!(
            "person"
                .parse::<ValidateBy>()
                .unwrap_err()
                .contains("known: auto")
        );
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
        let err = select(&images, ValidateBy::Auto, std::slice::from_ref(&pwe), 1).unwrap_err();
        let text = err.to_string();
        assert!(
            text.starts_with(
                "not enough data: fft1d + pwe could not be trained (not enough data: "
            ),
            "{text}"
        );
        let err = select(&images, ValidateBy::Auto, &[pwe.clone(), pwe], 1).unwrap_err();
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
        let err = train_auto(&images, &[], ValidateBy::Auto, &candidates, 1).unwrap_err();
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
        let trained = train_auto(&images, &[], ValidateBy::Auto, &[fixed.check().unwrap()], 1);
        assert!(trained.is_ok(), "{:?}", trained.err());
    }
}
