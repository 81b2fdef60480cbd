//! The folds an automatic choice validates its candidates on, made from the training data alone.

use std::collections::BTreeSet;

use super::MAX_INNER_FOLDS;
use crate::error::{CoreError, Result};
use crate::pipeline::extract::LabeledImage;
use crate::selection::record::ValidationFallback;
use crate::selection::validate_by::ValidateBy;
use crate::split::{ValidationSize, stratified_split};

/// Which field of an image its folds are made by.
type Key = for<'x> fn(&LabeledImage<'x>) -> Option<&'x str>;

/// One fold: the candidate is trained on `train` (its hyper-parameters validated on `validation`) and
/// scored on `test` (indices into the images).
pub(crate) struct InnerFold {
    pub name: String,
    pub train: Vec<usize>,
    pub validation: Vec<usize>,
    pub test: Vec<usize>,
}

/// The folds an automatic choice scores its candidates on, and how they were made.
pub(crate) struct Folds {
    pub folds: Vec<InnerFold>,
    /// The validation in words.
    pub method: String,
    /// The scheme passed over, if one was.
    pub fallback: Option<ValidationFallback>,
    /// The scheme the folds were made by.
    pub used: ValidateBy,
}

/// The folds of `images` as `by` says (resolved from the images' groups and conditions), with the
/// validation described in words. A scheme under which a held-out fold holds a class that its training
/// part lacks is not used: `auto` goes on to the next it would choose (condition, then splits), a
/// scheme asked for falls back to stratified splits, and [`Folds::fallback`] says so. Deterministic
/// in `seed`.
pub(crate) fn make_folds(images: &[LabeledImage<'_>], by: ValidateBy, seed: u64) -> Result<Folds> {
    let groups = distinct(images, |i| i.group);
    let conditions = distinct(images, |i| i.condition);
    let wanted = by.resolve(groups.len(), conditions.len());
    let mut tried = wanted;
    let mut fallback: Option<ValidationFallback> = None;
    loop {
        if tried == ValidateBy::Split {
            let folds = split_folds(images, seed)?;
            let method = "three stratified 70/30 splits of the training data".to_owned();
            return Ok(Folds {
                folds,
                method,
                fallback: fallback.map(|f| ValidationFallback { used: tried, ..f }),
                used: tried,
            });
        }
        let (folds, method) = if tried == ValidateBy::Group {
            held_out_folds(images, "group", &groups, |i| i.group, seed)?
        } else {
            held_out_folds(images, "condition", &conditions, |i| i.condition, seed)?
        };
        let unseen = classes_unseen_in_training(images, &folds);
        if unseen.is_empty() {
            return Ok(Folds {
                folds,
                method,
                fallback: fallback.map(|f| ValidationFallback { used: tried, ..f }),
                used: tried,
            });
        }
        fallback.get_or_insert(ValidationFallback {
            wanted,
            used: ValidateBy::Split,
            unseen,
        });
        tried = if tried == ValidateBy::Group && by == ValidateBy::Auto && conditions.len() >= 2 {
            ValidateBy::Condition
        } else {
            ValidateBy::Split
        };
    }
}

/// The distinct values of `key` over `images`, sorted; empty when an image has none.
fn distinct<'a>(images: &[LabeledImage<'a>], key: Key) -> Vec<&'a str> {
    let keys: Option<Vec<&str>> = images.iter().map(key).collect();
    let mut keys = keys.unwrap_or_default();
    keys.sort_unstable();
    keys.dedup();
    keys
}

/// The classes some fold tests on and does not train on, each with the first such fold's name.
fn classes_unseen_in_training(
    images: &[LabeledImage<'_>],
    folds: &[InnerFold],
) -> Vec<(String, String)> {
    let mut unseen: Vec<(String, String)> = Vec::new();
    for fold in folds {
        let trained: BTreeSet<&str> = fold.train.iter().map(|&i| images[i].label).collect();
        let tested: BTreeSet<&str> = fold.test.iter().map(|&i| images[i].label).collect();
        for class in tested.difference(&trained) {
            if !unseen.iter().any(|(c, _)| c == class) {
                unseen.push(((*class).to_owned(), fold.name.clone()));
            }
        }
    }
    unseen
}

/// Three seeded stratified splits: 70 % to train (of which 35 % validate), 30 % to test.
fn split_folds(images: &[LabeledImage<'_>], seed: u64) -> Result<Vec<InnerFold>> {
    let labels: Vec<&str> = images.iter().map(|i| i.label).collect();
    let mut folds = Vec::new();
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
    Ok(folds)
}

/// One fold per value of `key` (`what`: group or condition) with its images held out, or
/// [`MAX_INNER_FOLDS`] folds of whole values; the rest of the images, stratified, train (65 %) and
/// validate (35 %).
fn held_out_folds(
    images: &[LabeledImage<'_>],
    what: &str,
    distinct: &[&str],
    key: Key,
    seed: u64,
) -> Result<(Vec<InnerFold>, String)> {
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
    let labels: Vec<&str> = images.iter().map(|i| i.label).collect();
    let mut folds = Vec::new();
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
