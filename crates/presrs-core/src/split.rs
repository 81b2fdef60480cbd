//! Stratified, seeded selection of training and validation samples.
//!
//! The paper draws 20 random images per terrain from one gait, 13 for training and 7 for validation, and
//! tests on everything else. [`stratified_split`] does that for any labels: per class, shuffle with a seeded
//! RNG, take `per_class` (or all), and put `validation` of those aside.

use std::collections::BTreeMap;

use rand::SeedableRng;
use rand::seq::SliceRandom;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::error::{CoreError, Result};

/// How many of each class's picked samples go to validation. In JSON a plain number: a count (`7`) or a
/// fraction (`0.35`); the tagged form of earlier versions (`{"Count": 7}`) is still read.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged, from = "ValidationSizeJson")]
pub enum ValidationSize {
    /// Exactly this many per class.
    Count(usize),
    /// This fraction of each class's picked samples, rounded to nearest, at least 1 and leaving at least 2
    /// for training (when the class has at least 3).
    Fraction(f64),
}

/// What a [`ValidationSize`] is read from: a number, or the tagged form of earlier versions.
#[derive(Deserialize)]
#[serde(untagged)]
enum ValidationSizeJson {
    Count(usize),
    Fraction(f64),
    Tagged(TaggedValidationSize),
}

/// `{"Count": 7}` or `{"Fraction": 0.35}`.
#[derive(Deserialize)]
enum TaggedValidationSize {
    Count(usize),
    Fraction(f64),
}

impl From<ValidationSizeJson> for ValidationSize {
    fn from(json: ValidationSizeJson) -> Self {
        match json {
            ValidationSizeJson::Count(count)
            | ValidationSizeJson::Tagged(TaggedValidationSize::Count(count)) => Self::Count(count),
            ValidationSizeJson::Fraction(fraction)
            | ValidationSizeJson::Tagged(TaggedValidationSize::Fraction(fraction)) => {
                Self::Fraction(fraction)
            }
        }
    }
}

impl Default for ValidationSize {
    /// The paper's 7 of 20.
    fn default() -> Self {
        Self::Fraction(0.35)
    }
}

impl std::str::FromStr for ValidationSize {
    type Err = CoreError;

    /// `7` (a count per class) or `0.35` (a fraction).
    fn from_str(text: &str) -> Result<Self> {
        let bad = || CoreError::Param {
            name: "validation",
            reason: format!(
                "expected a count per class (e.g. 7) or a fraction in (0, 1) (e.g. 0.35), got {text:?}"
            ),
        };
        if let Ok(count) = text.trim().parse::<usize>() {
            return Ok(Self::Count(count));
        }
        let fraction: f64 = text.trim().parse().map_err(|_| bad())?;
        if fraction > 0.0 && fraction < 1.0 {
            Ok(Self::Fraction(fraction))
        } else {
            Err(bad())
        }
    }
}

/// Indices into the input, by role.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Split {
    pub train: Vec<usize>,
    pub validation: Vec<usize>,
    /// Everything not picked (the test set in the paper's protocol).
    pub rest: Vec<usize>,
    /// Classes that had fewer samples than `per_class` asked for, with the samples they had (all
    /// picked): filled by [`stratified_split_capped`] only.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub capped: BTreeMap<String, usize>,
}

/// The classes of `labels` with fewer than `per_class` samples, with their counts (empty for `None`).
pub fn per_class_shortfall(labels: &[&str], per_class: Option<usize>) -> BTreeMap<String, usize> {
    let Some(per_class) = per_class else {
        return BTreeMap::new();
    };
    let mut counts: BTreeMap<&str, usize> = BTreeMap::new();
    for &label in labels {
        *counts.entry(label).or_insert(0) += 1;
    }
    counts
        .into_iter()
        .filter(|&(_, n)| n < per_class)
        .map(|(label, n)| (label.to_owned(), n))
        .collect()
}

/// [`stratified_split`], except that a class with fewer samples than `per_class` gives every sample it
/// has (listed in [`Split::capped`]) instead of failing. The draw of the other classes is the same.
pub fn stratified_split_capped(
    labels: &[&str],
    per_class: Option<usize>,
    validation: ValidationSize,
    seed: u64,
) -> Result<Split> {
    split_per_class(labels, per_class, validation, seed, true)
}

/// Splits `labels` (one per sample) per class. `per_class: None` picks every sample of every class.
/// Fails when a class has fewer samples than asked for, or too few to train and validate.
pub fn stratified_split(
    labels: &[&str],
    per_class: Option<usize>,
    validation: ValidationSize,
    seed: u64,
) -> Result<Split> {
    split_per_class(labels, per_class, validation, seed, false)
}

fn split_per_class(
    labels: &[&str],
    per_class: Option<usize>,
    validation: ValidationSize,
    seed: u64,
    cap: bool,
) -> Result<Split> {
    let mut classes: Vec<&str> = labels.to_vec();
    classes.sort_unstable();
    classes.dedup();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut split = Split::default();
    for class in classes {
        let mut members: Vec<usize> = (0..labels.len()).filter(|&i| labels[i] == class).collect();
        members.shuffle(&mut rng);
        let mut picked = per_class.unwrap_or(members.len());
        if cap && picked > members.len() {
            split.capped.insert(class.to_owned(), members.len());
            picked = members.len();
        }
        if picked > members.len() {
            return Err(CoreError::NotEnoughData(format!(
                "class {class:?} has {} samples, fewer than the {picked} per class asked for",
                members.len()
            )));
        }
        let n_validation = match validation {
            ValidationSize::Count(count) => count,
            ValidationSize::Fraction(fraction) => {
                let rounded = (fraction * picked as f64).round() as usize;
                if picked >= 3 {
                    rounded.clamp(1, picked - 2)
                } else {
                    0
                }
            }
        };
        // Not `picked < n_validation + 1`: the count comes from the command line and may be usize::MAX.
        if n_validation >= picked {
            return Err(CoreError::NotEnoughData(format!(
                "class {class:?}: {picked} picked samples cannot give {n_validation} for validation and \
                 at least one for training"
            )));
        }
        let n_train = picked - n_validation;
        split.train.extend_from_slice(&members[..n_train]);
        split
            .validation
            .extend_from_slice(&members[n_train..picked]);
        split.rest.extend_from_slice(&members[picked..]);
    }
    split.train.sort_unstable();
    split.validation.sort_unstable();
    split.rest.sort_unstable();
    Ok(split)
}

/// The fewest samples a class needs for a draw of `per_class` with `validation`: `per_class` when given,
/// else one validation image and at least one training image (a count `c` of validation images needs
/// `c + 1`; a fraction gives one only from 3 samples on: one for validation, two to train).
pub fn min_samples_per_class(per_class: Option<usize>, validation: ValidationSize) -> usize {
    per_class.unwrap_or(match validation {
        ValidationSize::Count(count) => count.saturating_add(1),
        ValidationSize::Fraction(_) => 3,
    })
}

/// The classes of `classes` (every label expected, e.g. all those of a manifest, some perhaps without
/// a sample) with fewer than `need` samples in `labels`, with their counts, in the order of `classes`.
pub fn classes_short_of(labels: &[&str], classes: &[&str], need: usize) -> Vec<(String, usize)> {
    classes
        .iter()
        .map(|&class| {
            let count = labels.iter().filter(|&&label| label == class).count();
            (class.to_owned(), count)
        })
        .filter(|&(_, count)| count < need)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn labels() -> Vec<&'static str> {
        let mut labels = Vec::new();
        for class in ["wood", "carpet", "clay", "grass"] {
            labels.extend(std::iter::repeat_n(class, 30));
        }
        labels
    }

    #[test]
    fn paper_split_is_13_plus_7_per_class_and_disjoint() {
        let labels = labels();
        let split = stratified_split(&labels, Some(20), ValidationSize::default(), 7).unwrap();
        assert_eq!(split.train.len(), 52);
        assert_eq!(split.validation.len(), 28);
        assert_eq!(split.rest.len(), 40);
        for class in ["wood", "carpet", "clay", "grass"] {
            assert_eq!(
                split.train.iter().filter(|&&i| labels[i] == class).count(),
                13
            );
            assert_eq!(
                split
                    .validation
                    .iter()
                    .filter(|&&i| labels[i] == class)
                    .count(),
                7
            );
        }
        let mut all: Vec<usize> = [split.train, split.validation, split.rest].concat();
        all.sort_unstable();
        assert_eq!(all, (0..labels.len()).collect::<Vec<_>>());
    }

    #[test]
    fn same_seed_same_split_other_seed_other_split() {
        let labels = labels();
        let a = stratified_split(&labels, Some(20), ValidationSize::Count(7), 1).unwrap();
        let b = stratified_split(&labels, Some(20), ValidationSize::Count(7), 1).unwrap();
        let c = stratified_split(&labels, Some(20), ValidationSize::Count(7), 2).unwrap();
        assert_eq!(a, b);
        assert_ne!(a, c);
    }

    #[test]
    fn classes_short_of_samples_are_named_with_their_counts() {
        let labels = ["grass", "grass", "gravel", "grass"];
        let short = classes_short_of(&labels, &["brick", "grass", "gravel"], 3);
        assert_eq!(
            short,
            vec![("brick".to_owned(), 0), ("gravel".to_owned(), 1)]
        );
        assert_eq!(
            min_samples_per_class(None, ValidationSize::Fraction(0.35)),
            3
        );
        assert_eq!(min_samples_per_class(None, ValidationSize::Count(7)), 8);
        assert_eq!(
            min_samples_per_class(Some(20), ValidationSize::Count(7)),
            20
        );
    }

    #[test]
    fn too_few_samples_is_an_error() {
        let labels = labels();
        assert!(stratified_split(&labels, Some(31), ValidationSize::Count(7), 1).is_err());
        assert!(stratified_split(&labels, Some(5), ValidationSize::Count(5), 1).is_err());
        assert!(matches!(
            stratified_split(&labels, Some(5), ValidationSize::Count(usize::MAX), 1),
            Err(CoreError::NotEnoughData(_))
        ));
        assert!(matches!(
            stratified_split(&labels, None, ValidationSize::Count(usize::MAX), 1),
            Err(CoreError::NotEnoughData(_))
        ));
        assert!("1.5".parse::<ValidationSize>().is_err());
        assert_eq!(
            "7".parse::<ValidationSize>().unwrap(),
            ValidationSize::Count(7)
        );
    }

    /// A class short of `per_class` gives all it has and is listed; the others draw as the strict split.
    #[test]
    fn capped_split_takes_what_a_short_class_has() {
        let full = labels();
        let labels = &full[..100]; // grass keeps 10 of its 30
        assert!(stratified_split(labels, Some(20), ValidationSize::Count(7), 3).is_err());
        let capped =
            stratified_split_capped(labels, Some(20), ValidationSize::Count(7), 3).unwrap();
        assert_eq!(capped.capped, BTreeMap::from([("grass".to_owned(), 10)]));
        assert_eq!(per_class_shortfall(labels, Some(20)), capped.capped);
        assert!(per_class_shortfall(labels, None).is_empty());
        let grass = |indices: &[usize]| indices.iter().filter(|&&i| labels[i] == "grass").count();
        assert_eq!((grass(&capped.train), grass(&capped.validation)), (3, 7));
        assert_eq!(capped.train.len(), 3 * 13 + 3);
        // Enough samples: the capped split is the strict one.
        assert_eq!(
            stratified_split_capped(&full, Some(20), ValidationSize::Count(7), 3).unwrap(),
            stratified_split(&full, Some(20), ValidationSize::Count(7), 3).unwrap()
        );
    }
}
