//! The folds an automatic choice validates its candidates on, made from the training data alone.

use super::ValidateBy;
use crate::error::{CoreError, Result};
use crate::pipeline::LabeledImage;
use crate::split::{ValidationSize, stratified_split};

/// Which field of an image its folds are made by.
type Key = for<'x> fn(&LabeledImage<'x>) -> Option<&'x str>;

/// One fold: the candidate is trained on `train` (its hyper-parameters validated on `validation`) and
/// scored on `test` (indices into the images).
pub(super) struct InnerFold {
    pub name: String,
    pub train: Vec<usize>,
    pub validation: Vec<usize>,
    pub test: Vec<usize>,
}

/// The folds of `images` as `by` says (resolved from the images' groups and conditions), with the
/// validation described in words. Deterministic in `seed`.
pub(super) fn make_folds(
    images: &[LabeledImage<'_>],
    by: ValidateBy,
    seed: u64,
) -> Result<(Vec<InnerFold>, String)> {
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
    if by == ValidateBy::Split {
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
        return Ok((
            folds,
            "three stratified 70/30 splits of the training data".to_owned(),
        ));
    }
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
    let method = format!("leave one {what} out inside the training data ({listed})");
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
    Ok((folds, method))
}
