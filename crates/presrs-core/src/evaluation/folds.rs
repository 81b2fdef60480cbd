//! The folds of one repeat: the training, validation and test sets a protocol draws with a seed, and
//! [`Draw`], their public record.

use serde::Serialize;

use super::protocol::Protocol;
use crate::error::{CoreError, Result};
use crate::pipeline::LabeledImage;
use crate::split::{ValidationSize, stratified_split_capped};

/// One fold of one repeat of an evaluation ([`Evaluation::draws`](super::run::Evaluation::draws)):
/// indices into its samples.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Draw {
    /// The repeat, from 0.
    pub repeat: usize,
    /// The repeat's seed (the evaluation's seed + repeat).
    pub seed: u64,
    /// With leave-one-out, the held-out value.
    pub held_out: Option<String>,
    pub train: Vec<usize>,
    pub validation: Vec<usize>,
    pub test: Vec<usize>,
}

/// One train/test partition.
pub(super) struct Fold {
    pub(super) train: Vec<usize>,
    pub(super) validation: Vec<usize>,
    pub(super) test: Vec<usize>,
    /// Leave-one-out reports by held-out value; the other protocol by condition.
    pub(super) by_group: bool,
}

impl Fold {
    /// With leave-one-out, the held-out value (that of the first test sample).
    pub(super) fn held_out<'s>(&self, samples: &[LabeledImage<'s>]) -> Option<&'s str> {
        self.by_group
            .then(|| self.test.first().and_then(|&i| samples[i].group))
            .flatten()
    }

    pub(super) fn key_of(&self, sample: &LabeledImage<'_>) -> String {
        let key = if self.by_group {
            sample.group
        } else {
            sample.condition
        };
        key.unwrap_or("all").to_owned()
    }
}

/// The folds of one repeat of `protocol` on `samples`, drawn with `seed`.
pub(super) fn folds(
    samples: &[LabeledImage<'_>],
    protocol: &Protocol,
    seed: u64,
) -> Result<Vec<Fold>> {
    match protocol {
        Protocol::TrainCondition {
            condition,
            per_class,
            validation,
        } => condition_fold(samples, condition.as_deref(), *per_class, *validation, seed),
        Protocol::LeaveOneOut {
            column,
            per_class,
            validation,
        } => leave_one_out_folds(samples, column, *per_class, *validation, seed),
    }
}

/// The one fold of [`Protocol::TrainCondition`]: training and validation drawn from the samples of
/// `condition` (of all without one), every other sample tested.
fn condition_fold(
    samples: &[LabeledImage<'_>],
    condition: Option<&str>,
    per_class: Option<usize>,
    validation: ValidationSize,
    seed: u64,
) -> Result<Vec<Fold>> {
    let pool: Vec<usize> = (0..samples.len())
        .filter(|&i| condition.is_none_or(|c| samples[i].condition == Some(c)))
        .collect();
    if pool.is_empty() {
        return Err(CoreError::NotEnoughData(format!(
            "no sample has the training condition {:?}",
            condition.unwrap_or("")
        )));
    }
    let labels: Vec<&str> = pool.iter().map(|&i| samples[i].label).collect();
    let split = stratified_split_capped(&labels, per_class, validation, seed)?;
    let in_pool = |indices: &[usize]| indices.iter().map(|&k| pool[k]).collect::<Vec<_>>();
    let (train, validation) = (in_pool(&split.train), in_pool(&split.validation));
    let mut used = vec![false; samples.len()];
    for &i in train.iter().chain(&validation) {
        used[i] = true;
    }
    let test = (0..samples.len()).filter(|&i| !used[i]).collect();
    Ok(vec![Fold {
        train,
        validation,
        test,
        by_group: false,
    }])
}

/// The folds of [`Protocol::LeaveOneOut`]: one per distinct group (`column`), each testing that
/// group's samples after training on a draw from the others.
fn leave_one_out_folds(
    samples: &[LabeledImage<'_>],
    column: &str,
    per_class: Option<usize>,
    validation: ValidationSize,
    seed: u64,
) -> Result<Vec<Fold>> {
    let mut values: Vec<&str> = Vec::new();
    for sample in samples {
        let value = sample.group.ok_or_else(|| {
            CoreError::NotEnoughData(format!(
                "a sample has no value in the leave-one-out column `{column}`"
            ))
        })?;
        values.push(value);
    }
    let mut distinct = values.clone();
    distinct.sort_unstable();
    distinct.dedup();
    if distinct.len() < 2 {
        return Err(CoreError::NotEnoughData(format!(
            "leave-one-out needs at least two values in column `{column}`, found {}",
            distinct.len()
        )));
    }
    distinct
        .iter()
        .enumerate()
        .map(|(k, held_out)| {
            let pool: Vec<usize> = (0..samples.len())
                .filter(|&i| values[i] != *held_out)
                .collect();
            let labels: Vec<&str> = pool.iter().map(|&i| samples[i].label).collect();
            let split = stratified_split_capped(
                &labels,
                per_class,
                validation,
                seed.wrapping_add(k as u64 * 7919),
            )
            .map_err(|err| CoreError::NotEnoughData(format!("holding out {held_out:?}: {err}")))?;
            Ok(Fold {
                train: split.train.iter().map(|&j| pool[j]).collect(),
                validation: split.validation.iter().map(|&j| pool[j]).collect(),
                test: (0..samples.len())
                    .filter(|&i| values[i] == *held_out)
                    .collect(),
                by_group: true,
            })
        })
        .collect()
}
