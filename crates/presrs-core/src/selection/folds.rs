//! The folds an automatic choice validates its candidates on, made from the training data alone.

use super::{MAX_INNER_FOLDS, ValidateBy};
use crate::error::{CoreError, Result};
use crate::pipeline::extract::LabeledImage;
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
    let held_out_sets = whole_groups_in_folds(images, distinct, key);
    let method = if held_out_sets.len() == distinct.len() {
        format!("leave one {what} out inside the training data ({listed})")
    } else {
        format!(
            "{} folds of whole {what}s inside the training data ({listed}; {} {what}s)",
            held_out_sets.len(),
            distinct.len()
        )
    };
    for (k, held_out) in held_out_sets.iter().enumerate() {
        let held = |i: usize| key(&images[i]).is_some_and(|value| held_out.contains(&value));
        let pool: Vec<usize> = (0..images.len()).filter(|&i| !held(i)).collect();
        let pool_labels: Vec<&str> = pool.iter().map(|&i| labels[i]).collect();
        let split = stratified_split(
            &pool_labels,
            None,
            ValidationSize::Fraction(0.35),
            seed.wrapping_add(k as u64),
        )?;
        folds.push(InnerFold {
            name: held_out.join("+"),
            train: split.train.iter().map(|&j| pool[j]).collect(),
            validation: split.validation.iter().map(|&j| pool[j]).collect(),
            test: (0..images.len()).filter(|&i| held(i)).collect(),
        });
    }
    Ok((folds, method))
}

/// The values held out together in each fold: one per fold up to [`MAX_INNER_FOLDS`]; beyond, the
/// values by decreasing number of images (ties by name), each to the fold with the fewest images so
/// far (ties to the first), so that the folds are about equal in size. Each fold's values sorted.
fn whole_groups_in_folds<'a>(
    images: &[LabeledImage<'a>],
    distinct: &[&'a str],
    key: Key,
) -> Vec<Vec<&'a str>> {
    if distinct.len() <= MAX_INNER_FOLDS {
        return distinct.iter().map(|&value| vec![value]).collect();
    }
    let size = |value: &str| images.iter().filter(|i| key(i) == Some(value)).count();
    let mut by_size: Vec<(usize, &str)> = distinct.iter().map(|&v| (size(v), v)).collect();
    by_size.sort_by(|a, b| b.0.cmp(&a.0).then(a.1.cmp(b.1)));
    let mut folds: Vec<(usize, Vec<&str>)> = vec![(0, Vec::new()); MAX_INNER_FOLDS];
    for (count, value) in by_size {
        let smallest = (0..folds.len())
            .min_by_key(|&f| (folds[f].0, f))
            .unwrap_or(0);
        folds[smallest].0 += count;
        folds[smallest].1.push(value);
    }
    let mut folds: Vec<Vec<&str>> = folds.into_iter().map(|(_, values)| values).collect();
    for values in &mut folds {
        values.sort_unstable();
    }
    folds.sort();
    folds
}
