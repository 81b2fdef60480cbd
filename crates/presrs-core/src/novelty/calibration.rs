//! The novelty threshold learned inside the training data, without any unknown class: every training
//! vector's distance to its nearest neighbour among the other folds' vectors, in a discriminant space
//! fitted on those folds alone (its group held out, or its fold of a stratified split), so that the
//! distances are those of vectors neither the space nor the neighbours saw, as a new recording's are.

use std::collections::BTreeMap;

use crate::error::Result;
use crate::novelty::discriminant::{Discriminant, nearest};

/// Folds: at most this many; more groups are merged, whole, into this many.
const MAX_FOLDS: usize = 5;

/// How the held-out distances were obtained.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CalibrationFolds {
    /// Leaving out one group (the manifest's `group`) at a time (more than five merged into five).
    Group,
    /// Stratified folds of each class's vectors (fewer than three groups).
    Split,
}

/// The held-out nearest-neighbour distance of every vector that could be held out.
pub(crate) struct HeldOut {
    pub folds: CalibrationFolds,
    pub distances: Vec<f64>,
}

/// Each vector's distance to its nearest neighbour among the other folds' vectors, in their
/// discriminant space.
pub(crate) fn held_out_distances(
    vectors: &[f64],
    classes: &[usize],
    groups: &[Option<&str>],
    n_classes: usize,
    dims: usize,
) -> Result<HeldOut> {
    let (folds, fold_of) = assign_folds(classes, groups);
    let n_folds = fold_of.iter().copied().max().map_or(0, |last| last + 1);
    let mut distances = Vec::with_capacity(classes.len());
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
        let neighbours = space.project_rows(&train)?;
        let mut projected = vec![0.0; space.n_axes()];
        let mut to_classes = vec![0.0; n_classes];
        for (row, &f) in vectors.chunks_exact(dims).zip(&fold_of) {
            if f == fold {
                space.distances_into(row, &mut projected, &mut to_classes)?;
                let distance = nearest(&neighbours, &projected);
                if distance.is_finite() {
                    distances.push(distance);
                }
            }
        }
    }
    Ok(HeldOut { folds, distances })
}

/// The fold of every vector: by group when every vector has one and there are three groups or more
/// (more than [`MAX_FOLDS`] merged, whole, in sorted order), else each class's vectors dealt into
/// [`MAX_FOLDS`] folds in turn.
fn assign_folds(classes: &[usize], groups: &[Option<&str>]) -> (CalibrationFolds, Vec<usize>) {
    let named: Option<Vec<&str>> = groups.iter().copied().collect();
    if let Some(named) = named {
        let distinct: BTreeMap<&str, usize> = named.iter().map(|&g| (g, 0)).collect();
        if distinct.len() >= 3 && named.len() == classes.len() {
            let index: BTreeMap<&str, usize> = distinct
                .keys()
                .enumerate()
                .map(|(i, &g)| (g, i % MAX_FOLDS))
                .collect();
            return (
                CalibrationFolds::Group,
                named.iter().map(|g| index[g]).collect(),
            );
        }
    }
    let mut seen: BTreeMap<usize, usize> = BTreeMap::new();
    let folds = classes
        .iter()
        .map(|&class| {
            let count = seen.entry(class).or_insert(0);
            *count += 1;
            (*count - 1) % MAX_FOLDS
        })
        .collect();
    (CalibrationFolds::Split, folds)
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
