//! The novelty threshold learned inside the training data, without any unknown class: every training
//! vector's distance to its nearest neighbour among the other folds' vectors, in a discriminant space
//! fitted on those folds alone (its group held out), so that the distances are those of vectors neither
//! the space nor the neighbours saw, as a new recording's are. Stratified splits of one recording are
//! refused: their held-out vectors have neighbours from their own recording, and the threshold came
//! out so tight that every stance of a new recording of a known terrain was unknown.

use std::collections::{BTreeMap, BTreeSet};

use crate::error::{CoreError, Result};
use crate::novelty::discriminant::{Discriminant, nearest, nearest_posterior};
use crate::novelty::labelled::LabelledVectors;

/// Folds: at most this many; more groups are merged, whole, into this many.
const MAX_FOLDS: usize = 5;

/// The fewest groups (recordings) the threshold is calibrated on: with one, a held-out vector's
/// neighbours would come from its own recording, and the threshold would reject a new recording. Two
/// suffice (each held out against the other): on tais22 with its five sessions merged into three, so
/// that every training set holds two, the threshold calibrated on those two gave the same AUROC as on
/// the four sessions beneath them, and rejected fewer known samples (bench/real/RESULTS.md).
pub const MIN_GROUPS: usize = 2;

/// How the held-out distances were obtained.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CalibrationFolds {
    /// Leaving out one group (the manifest's `group`, else the recording) at a time (more than five
    /// merged into five).
    Group,
    /// Stratified folds of each class's vectors: models of an earlier version only, whose threshold
    /// was too tight for a new recording; none is calibrated so now.
    Split,
}

/// The held-out nearest-neighbour distance of every vector that could be held out, and the posterior
/// of its nearest class mean there (one per distance).
pub(crate) struct HeldOut {
    pub folds: CalibrationFolds,
    pub distances: Vec<f64>,
    pub posteriors: Vec<f64>,
}

/// Each vector's distance to its nearest neighbour among the other folds' vectors, in their
/// discriminant space, and its posterior there ([`nearest_posterior`]). A vector whose class no other fold holds is skipped: its distance is that of a
/// class never seen, not of a new recording of a known one. An error, saying what to give, when the
/// vectors come from fewer than [`MIN_GROUPS`] groups or no class is in two of them.
pub(crate) fn held_out_distances(data: LabelledVectors<'_>) -> Result<HeldOut> {
    let (vectors, classes, n_classes, dims) = (
        data.vectors(),
        data.classes(),
        data.n_classes(),
        data.dims(),
    );
    let fold_of = assign_folds(data.groups())?;
    let n_folds = fold_of.iter().copied().max().map_or(0, |last| last + 1);
    let mut distances = Vec::with_capacity(classes.len());
    let mut posteriors = Vec::with_capacity(classes.len());
    for fold in 0..n_folds {
        let (mut train, mut train_classes) = (Vec::new(), Vec::new());
        for ((row, &class), &f) in vectors.chunks_exact(dims).zip(classes).zip(&fold_of) {
            if f != fold {
                train.extend_from_slice(row);
                train_classes.push(class);
            }
        }
        // A fold whose rest cannot give a space (one class left) calibrates nothing.
        let Ok(space) = Discriminant::fit(&train, &train_classes, n_classes, dims) else {
            continue;
        };
        let mut seen = vec![false; n_classes];
        for &class in &train_classes {
            seen[class] = true;
        }
        let neighbours = space.project_rows(&train)?;
        let mut projected = vec![0.0; space.n_axes()];
        let mut to_classes = vec![0.0; n_classes];
        for ((row, &class), &f) in vectors.chunks_exact(dims).zip(classes).zip(&fold_of) {
            if f == fold && seen[class] {
                space.distances_into(row, &mut projected, &mut to_classes)?;
                let distance = nearest(&neighbours, &projected);
                if distance.is_finite() {
                    distances.push(distance);
                    posteriors.push(nearest_posterior(&to_classes));
                }
            }
        }
    }
    if distances.is_empty() {
        return Err(CoreError::NotEnoughData(
            "no class is recorded in two groups (recordings): the novelty threshold is learned from how \
             far a new recording of a known terrain lies from the others, so each class needs samples \
             from at least two groups"
                .into(),
        ));
    }
    Ok(HeldOut {
        folds: CalibrationFolds::Group,
        distances,
        posteriors,
    })
}

/// Each held-out vector's score, `1 - posterior x credibility` (unsorted): its distance's credibility
/// read against the other held-out distances (`sorted_distances`, itself among them), as a new
/// sample's is read against all of them: `k / n` where `k` of the `n` are at least as far, itself
/// counted.
pub(crate) fn held_out_scores(held_out: &HeldOut, sorted_distances: &[f64]) -> Vec<f64> {
    let n = sorted_distances.len() as f64;
    held_out
        .distances
        .iter()
        .zip(&held_out.posteriors)
        .map(|(&distance, &posterior)| {
            let at_least =
                sorted_distances.len() - sorted_distances.partition_point(|&d| d < distance);
            1.0 - posterior * at_least as f64 / n
        })
        .collect()
}

/// The fold of every vector by its group, more than [`MAX_FOLDS`] groups merged, whole, in sorted
/// order; an error when a vector has no group or there are fewer than [`MIN_GROUPS`].
pub(crate) fn assign_folds(groups: &[Option<&str>]) -> Result<Vec<usize>> {
    let distinct: BTreeSet<&str> = groups.iter().flatten().copied().collect();
    let missing = groups.iter().filter(|g| g.is_none()).count();
    if missing > 0 || distinct.len() < MIN_GROUPS {
        let have = if missing > 0 {
            format!("{missing} of {} samples have no group", groups.len())
        } else {
            format!("the samples come from {} group(s)", distinct.len())
        };
        return Err(CoreError::NotEnoughData(format!(
            "the novelty threshold is learned by holding out whole groups of the training samples, and \
             {have}: give every sample its group (the trial, recording or subject it came from), from \
             at least {MIN_GROUPS} groups (with one, a held-out sample's neighbours would come from its \
             own recording, and the threshold would call a new recording of a known terrain unknown)"
        )));
    }
    let index: BTreeMap<&str, usize> = distinct
        .iter()
        .enumerate()
        .map(|(i, &g)| (g, i % MAX_FOLDS))
        .collect();
    Ok(groups.iter().flatten().map(|g| index[g]).collect())
}

/// The `q` quantile (0..=1) of `sorted` values, linearly interpolated (numpy's default); NaN if empty.
pub(crate) fn quantile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let position = q.clamp(0.0, 1.0) * (sorted.len() - 1) as f64;
    let below = position.floor() as usize;
    let above = (below + 1).min(sorted.len() - 1);
    let weight = position - below as f64;
    sorted[below] * (1.0 - weight) + sorted[above] * weight
}
