//! Scoring the candidates of an automatic choice on its folds, each feature configuration's features
//! computed once and each fold's PCA fitted once per number of components, then shared by every
//! classifier that uses them. Gives, candidate for candidate, the scores that training each candidate
//! on each fold with [`crate::pipeline::train`] and classifying the held-out images with a session
//! gives (the test `cached_scores_equal_training_each_candidate_on_each_fold` checks it), at a fraction
//! of the cost.

use std::collections::BTreeMap;
use std::time::{Duration, Instant};

use rayon::prelude::*;

use super::folds::InnerFold;
use super::{RACE_FOLDS, RACE_MIN_FOLDS, RACE_Z};
use crate::classifier::LabeledVectors;
use crate::error::{CoreError, Result};
use crate::metrics::MeanStd;
use crate::pca::Pca;
use crate::pipeline::config::{CheckedTrainConfig, TrainConfig};
use crate::pipeline::extract::{FeatureTable, LabeledImage};
use crate::pipeline::train::{class_indices, class_names_of, project_rows};
use crate::selection::record::CandidateScore;

/// Candidates that share crop, preprocessing and features (indices into the candidate list, in order).
struct FeatureGroup {
    members: Vec<usize>,
}

/// The candidates grouped by what their features are computed from, groups in order of their first
/// member (so the first candidate, the paper's method, is always in the first group scored).
fn feature_groups(candidates: &[CheckedTrainConfig]) -> Vec<FeatureGroup> {
    let mut groups: Vec<FeatureGroup> = Vec::new();
    for (index, candidate) in candidates.iter().enumerate() {
        let config = candidate.config();
        let same = |group: &&mut FeatureGroup| {
            let first = candidates[group.members[0]].config();
            first.crop == config.crop
                && first.preprocess == config.preprocess
                && first.features == config.features
        };
        match groups.iter_mut().find(same) {
            Some(group) => group.members.push(index),
            None => groups.push(FeatureGroup {
                members: vec![index],
            }),
        }
    }
    groups
}

/// Scores every candidate on `folds`, feature group by feature group in order. With a `budget`, a group
/// that would end past it (judged from the slowest candidate scored so far) is not scored, nor any
/// after it: its candidates are marked `skipped`. The first group is always scored. In a `race` (from
/// [`Race::of`], kept across calls), candidates clearly behind the best so far on the first folds are
/// not scored on the rest.
pub(super) fn score_candidates(
    images: &[LabeledImage<'_>],
    folds: &[InnerFold],
    candidates: &[CheckedTrainConfig],
    budget: Option<Budget>,
    race: &mut Option<Race>,
) -> Result<Vec<CandidateScore>> {
    let mut scores: Vec<Option<CandidateScore>> = vec![None; candidates.len()];
    let mut slowest_per_candidate = Duration::ZERO;
    let mut out_of_budget = false;
    for (g, group) in feature_groups(candidates).iter().enumerate() {
        if let Some(budget) = budget
            && g > 0
        {
            let expected = slowest_per_candidate * group.members.len() as u32;
            out_of_budget |= budget.started.elapsed() + expected > budget.total;
        }
        if let Some(budget) = budget
            && out_of_budget
        {
            for &index in &group.members {
                scores[index] = Some(skipped(&candidates[index], budget.total));
            }
            continue;
        }
        let group_started = Instant::now();
        let scored = score_group(images, folds, candidates, &group.members, race.as_mut())?;
        slowest_per_candidate =
            slowest_per_candidate.max(group_started.elapsed() / group.members.len().max(1) as u32);
        for (index, score) in group.members.iter().zip(scored) {
            scores[*index] = Some(score);
        }
    }
    Ok(scores.into_iter().flatten().collect())
}

/// The automatic choice's time budget: `total` from `started`, across every call of
/// [`score_candidates`] (the refinement of the dims spends what the candidates left).
#[derive(Clone, Copy, Debug)]
pub(super) struct Budget {
    pub started: Instant,
    pub total: Duration,
}

impl Budget {
    /// Whether the budget is spent.
    pub(super) fn spent(&self) -> bool {
        self.started.elapsed() >= self.total
    }
}

/// A race (Maron and Moore's Hoeffding races, with a normal bound): every candidate is scored on the
/// first [`RACE_FOLDS`] folds; one that is clearly behind the best there, by more than [`RACE_Z`]
/// standard errors of the difference of two accuracies on those folds' held-out images, is not scored
/// on the others (it is `dropped_early`). The bound treats the two accuracies as independent; they are
/// measured on the same images, so it is wide, and only clear losers are dropped.
pub(super) struct Race {
    /// Held-out images in the first folds.
    images: usize,
    /// The best mean accuracy on the first folds so far.
    best: f64,
}

impl Race {
    /// The race of `folds`: none with fewer than [`RACE_MIN_FOLDS`].
    pub(super) fn of(folds: &[InnerFold]) -> Option<Self> {
        (folds.len() >= RACE_MIN_FOLDS).then(|| Self {
            images: folds[..RACE_FOLDS].iter().map(|f| f.test.len()).sum(),
            best: f64::NEG_INFINITY,
        })
    }

    /// Whether a candidate with this mean accuracy on the first folds is clearly behind the best.
    fn clearly_behind(&self, accuracy: f64) -> bool {
        let spread = |p: f64| p * (1.0 - p);
        let n = self.images.max(1) as f64;
        let error = ((spread(self.best) + spread(accuracy)) / n).sqrt();
        self.best - accuracy > RACE_Z * error
    }
}

/// A candidate not scored for lack of time.
pub(super) fn skipped(candidate: &CheckedTrainConfig, budget: Duration) -> CandidateScore {
    let reason = format!(
        "not tried: the time budget of {} was spent",
        seconds_text(budget)
    );
    let mut score = candidate_score(candidate.config(), BTreeMap::new(), Some(reason));
    score.skipped = true;
    score
}

/// A duration in seconds as a reader wants it: whole seconds from 10 s, else to a tenth (`60 s`,
/// `2.5 s`), and below a tenth as given.
pub(super) fn seconds_text(duration: Duration) -> String {
    let seconds = duration.as_secs_f64();
    if seconds >= 10.0 {
        format!("{seconds:.0} s")
    } else if seconds >= 0.1 {
        format!("{seconds:.1} s")
    } else {
        format!("{seconds} s")
    }
}

fn candidate_score(
    config: &TrainConfig,
    per_fold: BTreeMap<String, f64>,
    error: Option<String>,
) -> CandidateScore {
    let accuracy = if error.is_some() {
        MeanStd::default()
    } else {
        MeanStd::of(&per_fold.values().copied().collect::<Vec<_>>())
    };
    CandidateScore {
        features: config.features.name(),
        classifier: config.classifier.kind().as_str().to_owned(),
        config: config.clone(),
        accuracy,
        per_fold,
        error,
        skipped: false,
        dropped_early: false,
    }
}

/// The scores of the candidates `members` (sharing their features) on every fold, or, in a race, on
/// the first folds and then, for those not clearly behind, on the others.
fn score_group(
    images: &[LabeledImage<'_>],
    folds: &[InnerFold],
    candidates: &[CheckedTrainConfig],
    members: &[usize],
    race: Option<&mut Race>,
) -> Result<Vec<CandidateScore>> {
    let configs: Vec<&TrainConfig> = members.iter().map(|&i| candidates[i].config()).collect();
    let table = match FeatureTable::of(images, configs[0]) {
        Ok(table) => table,
        Err(err) => {
            let reason = err.to_string();
            return Ok(configs
                .iter()
                .map(|config| candidate_score(config, BTreeMap::new(), Some(reason.clone())))
                .collect());
        }
    };
    let score_on = |folds: &[InnerFold], configs: &[&TrainConfig]| {
        folds
            .par_iter()
            .map(|fold| score_fold(images, fold, &table, configs))
            .collect::<Result<Vec<_>>>()
    };
    // Without a race every fold is scored at once and nobody is dropped.
    let (first, rest) = folds.split_at(if race.is_some() {
        RACE_FOLDS
    } else {
        folds.len()
    });
    let first_results = score_on(first, &configs)?;
    let mut scores: Vec<CandidateScore> = (0..configs.len())
        .map(|m| {
            fold_scores(
                configs[m],
                first.iter().zip(&first_results).map(|(f, r)| (f, &r[m])),
            )
        })
        .collect();
    let Some(race) = race else {
        return Ok(scores);
    };
    for score in scores.iter().filter(|score| score.error.is_none()) {
        race.best = race.best.max(score.accuracy.mean);
    }
    for score in &mut scores {
        score.dropped_early = score.error.is_none() && race.clearly_behind(score.accuracy.mean);
    }
    let going_on: Vec<usize> = (0..configs.len())
        .filter(|&m| scores[m].is_contender())
        .collect();
    let going_on_configs: Vec<&TrainConfig> = going_on.iter().map(|&m| configs[m]).collect();
    let rest_results = score_on(rest, &going_on_configs)?;
    for (position, &m) in going_on.iter().enumerate() {
        let all = first
            .iter()
            .zip(&first_results)
            .map(|(f, r)| (f, &r[m]))
            .chain(
                rest.iter()
                    .zip(&rest_results)
                    .map(|(f, r)| (f, &r[position])),
            );
        scores[m] = fold_scores(configs[m], all);
    }
    Ok(scores)
}

/// A candidate's score from its result on each fold, in order: as training it fold by fold would, the
/// first fold it fails on ends it.
fn fold_scores<'f>(
    config: &TrainConfig,
    results: impl Iterator<Item = (&'f InnerFold, &'f std::result::Result<f64, String>)>,
) -> CandidateScore {
    let mut accuracies = BTreeMap::new();
    for (fold, result) in results {
        match result {
            Ok(accuracy) => {
                accuracies.insert(fold.name.clone(), *accuracy);
            }
            Err(reason) => return candidate_score(config, accuracies, Some(reason.clone())),
        }
    }
    candidate_score(config, accuracies, None)
}

/// Every member's accuracy on one fold: one PCA per number of components, shared by the classifiers.
/// A candidate that cannot be trained gives its reason; a held-out image that cannot be classified (a
/// non-finite value) is an error of the whole choice, as in classification.
fn score_fold(
    images: &[LabeledImage<'_>],
    fold: &InnerFold,
    table: &FeatureTable,
    configs: &[&TrainConfig],
) -> Result<Vec<std::result::Result<f64, String>>> {
    let pick = |indices: &[usize]| indices.iter().map(|&i| images[i]).collect::<Vec<_>>();
    let train_images = pick(&fold.train);
    let classes = class_names_of(&train_images).and_then(|names| {
        let train = class_indices(&names, &train_images)?;
        let validation = class_indices(&names, &pick(&fold.validation))?;
        Ok((names, train, validation))
    });
    let (class_names, train_classes, validation_classes) = match classes {
        Ok(classes) => classes,
        Err(err) => return Ok(vec![Err(err.to_string()); configs.len()]),
    };
    let train_rows = table.exact_rows(&fold.train);
    let validation_rows = table.exact_rows(&fold.validation);
    let mut dims_wanted: Vec<usize> = configs.iter().map(|config| config.dims).collect();
    dims_wanted.sort_unstable();
    dims_wanted.dedup();
    let mut results = vec![Err(String::new()); configs.len()];
    for dims in dims_wanted {
        let members: Vec<usize> = (0..configs.len())
            .filter(|&m| configs[m].dims == dims)
            .collect();
        let projected = Pca::fit(&train_rows, table.n_features, dims).and_then(|pca| {
            let train = project_rows(&pca, &train_rows)?;
            let validation = project_rows(&pca, &validation_rows)?;
            let test = project_test(&pca, table, &fold.test)?;
            Ok((pca.n_components(), train, validation, test))
        });
        let (dims, train, validation, test) = match projected {
            Ok(projected) => projected,
            Err(err) => {
                for m in members {
                    results[m] = Err(err.to_string());
                }
                continue;
            }
        };
        let scored: Vec<(usize, std::result::Result<f64, String>)> = members
            .par_iter()
            .map(|&m| {
                let fitted = configs[m].classifier.fit_with(
                    LabeledVectors {
                        vectors: &train,
                        classes: &train_classes,
                    },
                    LabeledVectors {
                        vectors: &validation,
                        classes: &validation_classes,
                    },
                    class_names.len(),
                    dims,
                    false,
                );
                let classifier = match fitted {
                    Ok(classifier) => classifier,
                    Err(err) => return Ok((m, Err(err.to_string()))),
                };
                let mut scratch = classifier.scratch();
                let mut posteriors = vec![0.0; class_names.len()];
                let mut correct = 0usize;
                for (&i, reduced) in fold.test.iter().zip(test.chunks_exact(dims)) {
                    if reduced.iter().any(|value| !value.is_finite()) {
                        return Err(CoreError::Param {
                            name: "image",
                            reason: "contains NaN or infinite values".into(),
                        });
                    }
                    let class = classifier.classify_into(reduced, &mut scratch, &mut posteriors)?;
                    if class_names[class] == images[i].label {
                        correct += 1;
                    }
                }
                Ok((m, Ok(correct as f64 / fold.test.len().max(1) as f64)))
            })
            .collect::<Result<_>>()?;
        for (m, result) in scored {
            results[m] = result;
        }
    }
    Ok(results)
}

/// The held-out images projected as a classification session projects them (its features, then the
/// PCA's fixed-point projection).
fn project_test(pca: &Pca, table: &FeatureTable, test: &[usize]) -> Result<Vec<f64>> {
    let dims = pca.n_components();
    let mut reduced = vec![0.0; test.len() * dims];
    let mut scratch = pca.scratch();
    for (&i, out) in test.iter().zip(reduced.chunks_exact_mut(dims)) {
        pca.project_fast_into(table.fast_row(i), &mut scratch, out)?;
    }
    Ok(reduced)
}
