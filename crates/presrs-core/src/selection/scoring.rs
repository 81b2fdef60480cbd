//! Scoring the candidates of an automatic choice on its folds, each feature configuration's features
//! computed once per phase (one group's table kept at a time: a group scored again in the race's second
//! phase or the refinement of the dims computes them again) and each fold's PCA fitted once per number
//! of components, on the table's rows in place, then shared by every classifier that uses them (a
//! classifier that takes every feature, ridge, sees them without a PCA). Gives, candidate for candidate, the scores that training each candidate
//! on each fold with [`crate::pipeline::train`] and classifying the held-out images with a session
//! gives (the test `cached_scores_equal_training_each_candidate_on_each_fold` checks it), at a fraction
//! of the cost.

use std::collections::BTreeMap;
use std::time::{Duration, Instant};

use rayon::prelude::*;

use super::folds::InnerFold;
use super::{RACE_FOLDS, RACE_MIN_FOLDS, RACE_Z, StageObserver};
use crate::classifier::{FitRows, LabeledVectors};
use crate::error::{CoreError, Result};
use crate::metrics::MeanStd;
use crate::pipeline::config::{CheckedTrainConfig, TrainConfig};
use crate::pipeline::extract::{FeatureTable, LabeledImage};
use crate::pipeline::train::{class_indices, class_names_of};
use crate::projection::pca::Pca;
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
            same_features(candidates[group.members[0]].config(), config)
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

/// The features of the feature group scored last (and why any group's could not be computed). One
/// group's table at a time: every group's, kept across the race's two phases and the refinement of the
/// dims, were the scoring's largest memory (four random-convolution groups of 4,000 samples x 10,000
/// `f64`, 1.3 GB), while computing a group's features again costs a few per cent of scoring it
/// (`bench/scale/README.md`). The values do not change: the features are deterministic.
#[derive(Default)]
pub(super) struct Tables<'o> {
    entries: Vec<(TrainConfig, std::result::Result<FeatureTable, String>)>,
    /// Every group whose features were computed, to say when they are computed again.
    computed: Vec<TrainConfig>,
    /// Told when a group's features begin.
    observer: Option<StageObserver<'o>>,
    /// Time spent computing features.
    spent: Duration,
}

impl<'o> Tables<'o> {
    pub(super) fn new(observer: Option<StageObserver<'o>>) -> Self {
        Self {
            entries: Vec::new(),
            computed: Vec::new(),
            observer,
            spent: Duration::ZERO,
        }
    }

    /// Seconds spent computing features so far.
    pub(super) fn seconds(&self) -> f64 {
        self.spent.as_secs_f64()
    }

    /// The features of `images` under `config`'s crop, preprocessing and features: the table kept, or
    /// computed (freeing the table of the group before).
    fn get(
        &mut self,
        images: &[LabeledImage<'_>],
        config: &TrainConfig,
    ) -> &std::result::Result<FeatureTable, String> {
        let position = self
            .entries
            .iter()
            .position(|(key, _)| same_features(key, config));
        let index = position.unwrap_or_else(|| {
            self.entries.retain(|(_, table)| table.is_err());
            let again = self.computed.iter().any(|seen| same_features(seen, config));
            StageObserver::tell(self.observer, || {
                format!(
                    "features: {} of {} samples{}",
                    config.features.name(),
                    images.len(),
                    if again { " (again)" } else { "" }
                )
            });
            if !again {
                self.computed.push(config.clone());
            }
            let started = Instant::now();
            let table = FeatureTable::of(images, config).map_err(|err| err.to_string());
            self.spent += started.elapsed();
            self.entries.push((config.clone(), table));
            self.entries.len() - 1
        });
        &self.entries[index].1
    }

    /// Keeps only the features some of `candidates` use (the memory of the others is freed).
    pub(super) fn retain(&mut self, candidates: &[CheckedTrainConfig]) {
        self.entries.retain(|(key, _)| {
            candidates
                .iter()
                .any(|candidate| same_features(key, candidate.config()))
        });
    }
}

/// Whether two configurations compute the same features.
fn same_features(a: &TrainConfig, b: &TrainConfig) -> bool {
    a.crop == b.crop && a.preprocess == b.preprocess && a.features == b.features
}

/// Each candidate's result on each fold scored so far, in fold order.
type FoldResults = Vec<std::result::Result<f64, String>>;

/// Scores every candidate on `folds`, feature group by feature group. Without a race, each group on
/// every fold, in order. In a `race` (from [`Race::of`], kept across calls), in two phases: every group
/// on the first [`RACE_FOLDS`] folds, in order; then the candidates not clearly behind the best there
/// on the other folds, the groups ordered by their best first-folds accuracy, so that a budget cuts
/// the least promising. With a `budget`, a group whose turn would end past it (judged from the slowest
/// candidate so far) is not scored ([`CandidateScore::skipped`]); the first group of each phase always
/// is. Features are computed once per group and phase, in `tables`.
pub(super) fn score_candidates(
    images: &[LabeledImage<'_>],
    folds: &[InnerFold],
    candidates: &[CheckedTrainConfig],
    budget: Option<Budget>,
    race: &mut Option<Race>,
    tables: &mut Tables<'_>,
) -> Result<Vec<CandidateScore>> {
    let groups = feature_groups(candidates);
    let configs: Vec<&TrainConfig> = candidates.iter().map(|c| c.config()).collect();
    let first_folds = if race.is_some() {
        RACE_FOLDS
    } else {
        folds.len()
    };
    let (first, rest) = folds.split_at(first_folds);
    let mut results: Vec<Option<FoldResults>> = vec![None; candidates.len()];
    let mut clock = Clock::default();
    for (g, group) in groups.iter().enumerate() {
        if g > 0 && clock.would_overrun(budget, group.members.len() * first.len()) {
            continue;
        }
        let scored = clock.time(group.members.len() * first.len(), || {
            score_folds(images, first, &configs, &group.members, tables)
        })?;
        for (&m, result) in group.members.iter().zip(scored) {
            results[m] = Some(result);
        }
    }
    let Some(race) = race.as_mut() else {
        return Ok(finish(candidates, folds, results, budget, &[]));
    };
    // Dropped against the best of every group's first folds, not of those scored before it.
    let mut first_scores: Vec<Option<CandidateScore>> = vec![None; candidates.len()];
    for (m, result) in results.iter().enumerate() {
        if let Some(result) = result {
            let score = fold_scores(configs[m], first.iter().zip(result));
            if score.error.is_none() {
                race.best = race.best.max(score.accuracy.mean);
            }
            first_scores[m] = Some(score);
        }
    }
    let going_on = |m: &usize| {
        first_scores[*m]
            .as_ref()
            .is_some_and(|score| score.error.is_none() && !race.clearly_behind(score.accuracy.mean))
    };
    let best_first = |group: &FeatureGroup| {
        group
            .members
            .iter()
            .filter(|m| going_on(m))
            .map(|&m| first_scores[m].as_ref().map_or(0.0, |s| s.accuracy.mean))
            .fold(f64::NEG_INFINITY, f64::max)
    };
    let mut order: Vec<(&FeatureGroup, Vec<usize>)> = groups
        .iter()
        .map(|group| {
            (
                group,
                group.members.iter().copied().filter(going_on).collect(),
            )
        })
        .filter(|(_, members): &(_, Vec<usize>)| !members.is_empty())
        .collect();
    // (a stable sort: ties keep the candidates' order)
    order.sort_by(|a, b| best_first(b.0).total_cmp(&best_first(a.0)));
    let mut cut = Vec::new();
    for (k, (_, members)) in order.iter().enumerate() {
        if k > 0 && clock.would_overrun(budget, members.len() * rest.len()) {
            cut.extend(members.iter().copied());
            continue;
        }
        let scored = clock.time(members.len() * rest.len(), || {
            score_folds(images, rest, &configs, members, tables)
        })?;
        for (&m, more) in members.iter().zip(scored) {
            if let Some(result) = results[m].as_mut() {
                result.extend(more);
            }
        }
    }
    let mut scores = finish(candidates, folds, results, budget, &cut);
    for (m, score) in scores.iter_mut().enumerate() {
        score.dropped_early = first_scores[m]
            .as_ref()
            .is_some_and(|first| first.error.is_none() && !going_on(&m));
    }
    Ok(scores)
}

/// The time spent scoring so far, and the slowest candidate-fold: what a budget judges by.
#[derive(Default)]
struct Clock {
    slowest: Duration,
}

impl Clock {
    /// Runs `score`, `runs` candidate-folds, and keeps the slowest one's time.
    fn time<T>(&mut self, runs: usize, score: impl FnOnce() -> T) -> T {
        let started = Instant::now();
        let out = score();
        let each = started.elapsed() / runs.max(1) as u32;
        self.slowest = self.slowest.max(each);
        out
    }

    /// Whether `runs` more candidate-folds would end past the budget.
    fn would_overrun(&self, budget: Option<Budget>, runs: usize) -> bool {
        budget.is_some_and(|budget| {
            budget.started.elapsed() + self.slowest * runs as u32 > budget.total
        })
    }
}

/// Every candidate's score from its fold results: those never scored are skipped, those in `cut`
/// were scored on the first folds only before the budget was spent.
fn finish(
    candidates: &[CheckedTrainConfig],
    folds: &[InnerFold],
    results: Vec<Option<FoldResults>>,
    budget: Option<Budget>,
    cut: &[usize],
) -> Vec<CandidateScore> {
    let total = budget.map(|budget| budget.total).unwrap_or_default();
    results
        .into_iter()
        .enumerate()
        .map(|(m, result)| match result {
            None => skipped(&candidates[m], total),
            Some(result) => {
                let mut score = fold_scores(candidates[m].config(), folds.iter().zip(&result));
                if cut.contains(&m) && score.error.is_none() {
                    score.error = Some(format!(
                        "scored on the first {} folds only: the time budget of {} was spent",
                        result.len(),
                        seconds_text(total)
                    ));
                    score.skipped = true;
                }
                score
            }
        })
        .collect()
}

/// The results of the candidates `members` (sharing their features) on each of `folds`: per member,
/// per fold in order (a member whose features cannot be computed fails on each, with the reason).
fn score_folds(
    images: &[LabeledImage<'_>],
    folds: &[InnerFold],
    configs: &[&TrainConfig],
    members: &[usize],
    tables: &mut Tables<'_>,
) -> Result<Vec<FoldResults>> {
    let member_configs: Vec<&TrainConfig> = members.iter().map(|&m| configs[m]).collect();
    let table = match tables.get(images, member_configs[0]) {
        Ok(table) => table,
        Err(reason) => return Ok(vec![vec![Err(reason.clone()); folds.len()]; members.len()]),
    };
    let per_fold = folds
        .par_iter()
        .map(|fold| score_fold(images, fold, table, &member_configs))
        .collect::<Result<Vec<_>>>()?;
    Ok((0..members.len())
        .map(|m| per_fold.iter().map(|fold| fold[m].clone()).collect())
        .collect())
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

/// Every member's accuracy on one fold: one PCA per number of components, shared by the classifiers
/// (those that take every feature share the features as they are).
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
    // The fold's rows as the table holds them: the PCA and the classifiers that take every feature
    // read them in place (two folds are scored at once, each row ~10,000 values).
    let rows_of = |indices: &[usize]| -> Vec<&[f64]> {
        indices.iter().map(|&i| table.exact_row(i)).collect()
    };
    let (train_rows, validation_rows) = (rows_of(&fold.train), rows_of(&fold.validation));
    // `None`: the classifiers that take every feature, without a PCA.
    let mut dims_wanted: Vec<Option<usize>> = configs.iter().map(|c| c.pca_dims()).collect();
    dims_wanted.sort_unstable();
    dims_wanted.dedup();
    let mut results = vec![Err(String::new()); configs.len()];
    for dims in dims_wanted {
        let members: Vec<usize> = (0..configs.len())
            .filter(|&m| configs[m].pca_dims() == dims)
            .collect();
        // Classifiers that take every feature read the table's rows in place when they can.
        let in_place =
            dims.is_none() && members.iter().all(|&m| configs[m].classifier.reads_rows());
        let projected = match dims {
            Some(dims) => Pca::fit_rows(&train_rows, table.n_features, dims).and_then(|pca| {
                let train = project_each(&pca, &train_rows)?;
                let validation = project_each(&pca, &validation_rows)?;
                let test = project_each(&pca, &test_rows_of(table, &fold.test))?;
                Ok((pca.n_components(), train, validation, test))
            }),
            None if in_place => Ok((table.n_features, Vec::new(), Vec::new(), Vec::new())),
            None => Ok((
                table.n_features,
                table.exact_rows(&fold.train),
                table.exact_rows(&fold.validation),
                fast_rows(table, &fold.test),
            )),
        };
        let (dims, train, validation, test) = match projected {
            Ok(projected) => projected,
            Err(err) => {
                for m in members {
                    results[m] = Err(err.to_string());
                }
                continue;
            }
        };
        let test_rows: Vec<&[f64]> = if in_place {
            test_rows_of(table, &fold.test)
        } else {
            test.chunks_exact(dims).collect()
        };
        let scored: Vec<(usize, std::result::Result<f64, String>)> = members
            .par_iter()
            .map(|&m| {
                let fitted = if in_place {
                    configs[m].classifier.fit_rows(FitRows {
                        train: &train_rows,
                        train_classes: &train_classes,
                        validation: &validation_rows,
                        validation_classes: &validation_classes,
                        n_classes: class_names.len(),
                        dims,
                        calibrate: false,
                    })
                } else {
                    configs[m].classifier.fit_with(
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
                    )
                };
                let classifier = match fitted {
                    Ok(classifier) => classifier,
                    Err(err) => return Ok((m, Err(err.to_string()))),
                };
                let mut scratch = classifier.scratch();
                let mut posteriors = vec![0.0; class_names.len()];
                let mut correct = 0usize;
                for (&i, reduced) in fold.test.iter().zip(&test_rows) {
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

/// The held-out images' features as a classification session computes them, in place.
fn test_rows_of<'t>(table: &'t FeatureTable, test: &[usize]) -> Vec<&'t [f64]> {
    test.iter().map(|&i| table.fast_row(i)).collect()
}

/// `rows` projected as training projects them (`pipeline::train::project_rows` on the rows laid end
/// to end).
fn project_each(pca: &Pca, rows: &[&[f64]]) -> Result<Vec<f64>> {
    let dims = pca.n_components();
    let mut reduced = vec![0.0; rows.len() * dims];
    let mut scratch = pca.scratch();
    for (x, out) in rows.iter().zip(reduced.chunks_exact_mut(dims)) {
        pca.project_fast_into(x, &mut scratch, out)?;
    }
    Ok(reduced)
}

/// The held-out images' features as a classification session computes them (without a PCA step).
fn fast_rows(table: &FeatureTable, test: &[usize]) -> Vec<f64> {
    test_rows_of(table, test).concat()
}
