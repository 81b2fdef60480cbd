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
//! A scheme under which a held-out fold holds a class its training part lacks is not used (every
//! candidate would score 0 on that class, and the choice would be blind): `auto` goes on to the next
//! (condition, then splits), a scheme asked for falls back to splits, and [`Selection::fallback`] records
//! it for the callers to say.
//!
//! More than [`MAX_INNER_FOLDS`] groups (or conditions) are merged, whole, into that many folds.
//!
//! The candidate with the highest mean fold accuracy wins; ties go to the earlier candidate (callers list
//! the paper's fft1d + Parzen window first). The winner is then trained on the given training and validation
//! images and the [`Selection`] (every candidate's scores) is stored in the model.
//!
//! Candidates that share their features (crop, preprocessing, feature family) are scored together: the
//! features of every image once, each fold's PCA once, then every classifier on them (`scoring`). A
//! time budget ([`AutoChoice::budget`]) stops before a feature group that would end past it; callers list
//! the cheap and likely candidates first. With [`RACE_MIN_FOLDS`] folds or more, candidates race: every
//! feature group is scored on the first [`RACE_FOLDS`] folds, those clearly behind the best of all there
//! are not scored on the others ([`CandidateScore::dropped_early`]; never chosen), and the rest finish,
//! the most promising groups first, so that a budget cuts the least promising.

pub(crate) mod folds;
pub(crate) mod record;
mod scoring;
pub(crate) mod subsample;
#[cfg(test)]
mod tests;
pub(crate) mod validate_by;

use std::time::Duration;

use serde::{Deserialize, Serialize};

use crate::error::{CoreError, Result};
use crate::pipeline::config::CheckedTrainConfig;
use crate::pipeline::extract::LabeledImage;
use crate::pipeline::model::TrainedModel;
use crate::pipeline::train::train_searching;

pub use record::{CandidateScore, Selection, SelectionCost, ValidationFallback};
pub use subsample::SCORING_SAMPLES;
pub use validate_by::ValidateBy;

/// At most this many folds when validating by group or condition: more values are merged, whole, into
/// this many folds (as scikit-learn's `GroupKFold`, 5 folds by default). Each fold costs a training of
/// every candidate, and five folds of whole groups are as honest as one per group.
pub const MAX_INNER_FOLDS: usize = 5;

/// Folds scored first, before the rest, when there are at least [`RACE_MIN_FOLDS`].
pub const RACE_FOLDS: usize = 2;
/// The fewest folds for which candidates race (with fewer, every candidate is scored on every fold).
pub const RACE_MIN_FOLDS: usize = 4;
/// How many standard errors behind the best a candidate must be on the first folds to be dropped.
pub const RACE_Z: f64 = 2.0;

/// What an automatic choice chooses among, and how.
#[derive(Clone, Copy, Debug)]
pub struct AutoChoice<'c> {
    /// In order of preference: ties go to the earlier (unless to `preferred_on_tie`), and a budget cuts
    /// from the end.
    pub candidates: &'c [CheckedTrainConfig],
    pub by: ValidateBy,
    /// Time for scoring the candidates; `None`: no limit (every candidate is scored, and the choice is
    /// deterministic in the seed).
    pub budget: Option<Duration>,
    /// Numbers of principal components the best [`REFINED`] candidates are scored again with, once
    /// every candidate has been scored (empty: the candidates' own only).
    pub refine_dims: &'c [usize],
    pub rule: ChoiceRule,
    /// The most samples the candidates are scored on: with more, a stratified subsample of this many
    /// (seeded; [`SelectionCost::scored_on`] says how many), and the winner is trained on every
    /// sample. `None`: every sample.
    pub scoring_samples: Option<usize>,
    /// Told each stage as it begins, for a progress display.
    pub on_stage: Option<StageObserver<'c>>,
    /// The candidate (an index into `candidates`) that wins a tie for the best score, under either
    /// [`ChoiceRule`], where the order would otherwise decide: a prior for when the validation cannot
    /// rank the best candidates. `None`: the rule alone decides.
    pub preferred_on_tie: Option<usize>,
}

/// Receives the automatic choice's stages as they begin, in words (`features: rocket`, `training the
/// winner, rocket + ridge, on 8442 samples`): what a progress display shows. Called from worker
/// threads too.
#[derive(Clone, Copy)]
pub struct StageObserver<'c>(pub &'c (dyn Fn(&str) + Sync));

impl StageObserver<'_> {
    /// Tells the observer, if there is one, that `stage` begins.
    pub(crate) fn tell(observer: Option<Self>, stage: impl FnOnce() -> String) {
        if let Some(Self(observer)) = observer {
            observer(&stage());
        }
    }
}

impl std::fmt::Debug for StageObserver<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("StageObserver")
    }
}

/// How the winner is picked from the candidates' fold accuracies. Under both, a tie for the best
/// goes to the preferred candidate when there is one ([`AutoChoice::preferred_on_tie`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ChoiceRule {
    /// The highest mean (ties to the earlier candidate).
    #[default]
    Best,
    /// The earliest candidate (the search lists the paper's method first, the costlier families last,
    /// and on whole samples the peers' pairing first) whose mean is within one standard error of the
    /// best's: differences inside that are noise, and the highest of a dozen noisy scores is more
    /// often a lucky candidate than a better one. The standard error is its folds' spread over the
    /// square root of their number, but never below the binomial standard error of an accuracy
    /// measured on all the held-out samples, `sqrt(p (1 - p) / n)`: three to five folds that happen
    /// to agree say little of their spread, and no accuracy is known better than its samples allow.
    /// With fewer than [`ONE_SE_MIN_FOLDS`] folds, the best (one difference is no estimate of the
    /// spread).
    OneStandardError,
}

/// The fewest validation folds whose spread the one-standard-error rule trusts (with two, the standard
/// error is one difference: a tolerance as noisy as the scores it is meant to see through).
pub const ONE_SE_MIN_FOLDS: usize = 3;

impl ChoiceRule {
    pub const NAMES: [&'static str; 2] = ["best", "one-se"];
}

impl std::str::FromStr for ChoiceRule {
    type Err = String;

    fn from_str(text: &str) -> std::result::Result<Self, String> {
        match text.trim().to_ascii_lowercase().as_str() {
            "best" => Ok(Self::Best),
            "one-se" | "1se" => Ok(Self::OneStandardError),
            _ => Err(format!(
                "unknown choice rule {text:?} (known: {})",
                Self::NAMES.join(", ")
            )),
        }
    }
}

/// The earliest scored candidate within one standard error of `best`'s mean (the folds' or, if larger,
/// the binomial one of `held_out` samples); `best` itself when it was scored on fewer than
/// [`ONE_SE_MIN_FOLDS`] folds.
fn one_standard_error(scores: &[CandidateScore], best: usize, held_out: usize) -> usize {
    if scores[best].per_fold.len() < ONE_SE_MIN_FOLDS {
        return best;
    }
    let folds = scores[best].per_fold.len() as f64;
    let mean = scores[best].accuracy.mean;
    let binomial = (mean * (1.0 - mean) / held_out.max(1) as f64).sqrt();
    let threshold = mean - (scores[best].accuracy.std / folds.sqrt()).max(binomial);
    scores
        .iter()
        .position(|score| score.is_contender() && score.accuracy.mean >= threshold)
        .unwrap_or(best)
}

/// `preferred` when it scored as well as `best` (within [`record::TIE_TOLERANCE`]), else `best`.
fn preferred_if_tied(scores: &[CandidateScore], best: usize, preferred: Option<usize>) -> usize {
    let (Some(p), Some(top)) = (preferred, scores.get(best)) else {
        return best;
    };
    match scores.get(p) {
        Some(candidate)
            if candidate.is_contender()
                && top.is_contender()
                && candidate.accuracy.mean >= top.accuracy.mean - record::TIE_TOLERANCE =>
        {
            p
        }
        _ => best,
    }
}

/// The winner by `rule` from `scores`, whose highest mean is `best`'s: a tie for it to `preferred` (see
/// [`preferred_if_tied`]), else `best` or, under one standard error, the earliest close candidate.
fn choose(
    scores: &[CandidateScore],
    best: usize,
    rule: ChoiceRule,
    preferred: Option<usize>,
    held_out: usize,
) -> usize {
    let tied = preferred_if_tied(scores, best, preferred);
    match rule {
        _ if tied != best || !scores[best].is_contender() => tied,
        ChoiceRule::Best => best,
        ChoiceRule::OneStandardError => one_standard_error(scores, best, held_out),
    }
}

/// How many of the best candidates are scored again with other numbers of principal components.
pub const REFINED: usize = 3;

impl<'c> AutoChoice<'c> {
    /// Every candidate scored, validated as `by` says, the winner the best (`with_rule` for another
    /// rule).
    pub fn new(candidates: &'c [CheckedTrainConfig], by: ValidateBy) -> Self {
        Self {
            candidates,
            by,
            budget: None,
            refine_dims: &[],
            rule: ChoiceRule::Best,
            scoring_samples: Some(SCORING_SAMPLES),
            on_stage: None,
            preferred_on_tie: None,
        }
    }

    /// With candidate `index` (of `candidates`) winning a tie for the best score.
    pub fn with_preferred_on_tie(self, index: Option<usize>) -> Self {
        Self {
            preferred_on_tie: index.filter(|&i| i < self.candidates.len()),
            ..self
        }
    }

    /// With the candidates scored on at most this many samples (`None`: every sample).
    pub fn with_scoring_samples(self, scoring_samples: Option<usize>) -> Self {
        Self {
            scoring_samples,
            ..self
        }
    }

    /// With `observer` told each stage as it begins.
    pub fn with_stages(self, observer: StageObserver<'c>) -> Self {
        Self {
            on_stage: Some(observer),
            ..self
        }
    }

    /// With the winner picked by `rule`.
    pub fn with_rule(self, rule: ChoiceRule) -> Self {
        Self { rule, ..self }
    }

    /// With a time budget.
    pub fn with_budget(self, budget: Option<Duration>) -> Self {
        Self { budget, ..self }
    }

    /// The time budget (`None`: every candidate is scored).
    pub fn budget(&self) -> Option<Duration> {
        self.budget
    }

    /// With the best candidates scored again with these numbers of principal components.
    pub fn with_refined_dims(self, refine_dims: &'c [usize]) -> Self {
        Self {
            refine_dims,
            ..self
        }
    }
}

/// Scores the candidates on folds of `images` (training + validation images together), made as
/// `choice.by` says from the images' `group` and `condition`, and picks the best. With more images
/// than [`AutoChoice::scoring_samples`], the folds are made of a stratified subsample of that many
/// (deterministic in `seed`). With a budget, feature groups that would end past it are not scored
/// (see [`CandidateScore::skipped`]); without one, every candidate is scored and the result is
/// deterministic in `seed`. The selection's [`Selection::cost`] says on how many images it scored and
/// how long that took.
pub fn select(
    images: &[LabeledImage<'_>],
    choice: &AutoChoice<'_>,
    seed: u64,
) -> Result<Selection> {
    let started = std::time::Instant::now();
    let subsample = choice
        .scoring_samples
        .and_then(|at_most| subsample::stratified_subsample(images, at_most, seed));
    let subset: Vec<LabeledImage<'_>> = subsample.iter().flatten().map(|&i| images[i]).collect();
    let scored = if subsample.is_some() {
        &subset[..]
    } else {
        images
    };
    StageObserver::tell(choice.on_stage, || {
        let of = if scored.len() < images.len() {
            format!(" (a stratified subsample of {})", images.len())
        } else {
            String::new()
        };
        format!(
            "scoring {} candidates on {} samples{of}",
            choice.candidates.len(),
            scored.len()
        )
    });
    let (mut selection, features_seconds) = select_on(scored, choice, seed, started)?;
    selection.cost = Some(SelectionCost {
        samples: images.len(),
        scored_on: scored.len(),
        features_seconds,
        scoring_seconds: started.elapsed().as_secs_f64(),
        final_fit_seconds: 0.0,
        budget_seconds: choice.budget.map(|budget| budget.as_secs_f64()),
        searched_on: None,
    });
    Ok(selection)
}

/// [`select`] on the images it scores on, from `started`; also gives the seconds spent computing
/// features.
fn select_on(
    images: &[LabeledImage<'_>],
    choice: &AutoChoice<'_>,
    seed: u64,
    started: std::time::Instant,
) -> Result<(Selection, f64)> {
    let AutoChoice {
        candidates,
        by,
        budget,
        refine_dims,
        rule: _,
        scoring_samples: _,
        on_stage,
        preferred_on_tie,
    } = *choice;
    if candidates.is_empty() {
        return Err(CoreError::Param {
            name: "candidates",
            reason: "the automatic choice needs at least one candidate".into(),
        });
    }
    let folds::Folds {
        folds,
        method,
        fallback,
        ..
    } = folds::make_folds(images, by, seed)?;
    // Each candidate's folds in order, classifiers in parallel: the scores, and so the choice, do not
    // depend on the number of threads.
    // One race for the candidates and their refinements: a refinement clearly behind the best
    // candidate is dropped too.
    let mut race = scoring::Race::of(&folds);
    let budget = budget.map(|total| scoring::Budget { started, total });
    let mut tables = scoring::Tables::new(on_stage);
    let mut scores =
        scoring::score_candidates(images, &folds, candidates, budget, &mut race, &mut tables)?;
    let variants = dims_variants(&scores, refine_dims)?;
    tables.retain(&variants);
    match budget {
        Some(budget) if budget.spent() => {
            scores.extend(variants.iter().map(|v| scoring::skipped(v, budget.total)))
        }
        _ => scores.extend(scoring::score_candidates(
            images,
            &folds,
            &variants,
            budget,
            &mut race,
            &mut tables,
        )?),
    }
    let mut chosen = 0;
    for (i, score) in scores.iter().enumerate() {
        if score.is_contender()
            && (!scores[chosen].is_contender()
                || score.accuracy.mean > scores[chosen].accuracy.mean)
        {
            chosen = i;
        }
    }
    let held_out = folds.iter().map(|fold| fold.test.len()).sum();
    chosen = choose(&scores, chosen, choice.rule, preferred_on_tie, held_out);
    if !scores[chosen].is_contender() {
        // Every candidate failed (or, in a race, failed on a later fold after the others were
        // dropped); the first failure's reason stands for them.
        let failed = scores
            .iter()
            .find(|score| score.error.is_some())
            .unwrap_or(&scores[chosen]);
        let error = failed.error.as_deref().unwrap_or("dropped early");
        let name = format!("{} + {}", failed.features, failed.classifier);
        return Err(CoreError::NotEnoughData(if scores.len() == 1 {
            format!("{name} could not be trained ({error})")
        } else {
            format!(
                "none of the {} candidates could be trained ({name}: {error})",
                scores.len()
            )
        }));
    }
    let selection = Selection {
        method,
        chosen,
        scores,
        fallback,
        cost: None,
    };
    Ok((selection, tables.seconds()))
}

/// The best [`REFINED`] scored candidates (by mean accuracy, ties to the earlier) with each of `dims`
/// they do not already have, best first.
fn dims_variants(scores: &[CandidateScore], dims: &[usize]) -> Result<Vec<CheckedTrainConfig>> {
    if dims.is_empty() {
        return Ok(Vec::new());
    }
    let mut ranked: Vec<&CandidateScore> =
        scores.iter().filter(|score| score.is_contender()).collect();
    // (a stable sort: ties keep the candidates' order)
    ranked.sort_by(|a, b| b.accuracy.mean.total_cmp(&a.accuracy.mean));
    let mut variants = Vec::new();
    // (a candidate without a PCA step has no dims to refine, and leaves its place to the next)
    let refinable = ranked
        .into_iter()
        .filter(|score| score.config.pca_dims().is_some());
    for score in refinable.take(REFINED) {
        for &d in dims.iter().filter(|&&d| d != score.config.dims) {
            variants.push(
                crate::pipeline::TrainConfig {
                    dims: d,
                    ..score.config.clone()
                }
                .check()?,
            );
        }
    }
    Ok(variants)
}

/// A fixed method trained as [`train`](crate::pipeline::train) trains it, except on large data: with
/// more than `at_most` images (training and validation), a classifier that pins its hyper-parameters
/// ([`ClassifierConfig::pins`](crate::classifier::ClassifierConfig::pins): ridge's `alpha`, the SVM's
/// `C` and `gamma`) has them searched on a stratified subsample of `at_most` (drawn with `seed`, as the
/// automatic choice draws its own) and only the choice fitted on every image, as the automatic choice's
/// winner is. Returns the subsample's size when the search ran on one
/// ([`TrainingSummary::searched_on`](crate::pipeline::TrainingSummary::searched_on) records it too).
pub fn train_fixed(
    train_images: &[LabeledImage<'_>],
    validation_images: &[LabeledImage<'_>],
    config: &CheckedTrainConfig,
    at_most: Option<usize>,
    seed: u64,
) -> Result<(TrainedModel, Option<usize>)> {
    let subsample = at_most
        .filter(|_| config.config().classifier.pins())
        .and_then(|at_most| {
            let all: Vec<LabeledImage<'_>> = train_images
                .iter()
                .chain(validation_images)
                .copied()
                .collect();
            subsample::stratified_subsample(&all, at_most, seed)
        });
    let (model, _) = train_searching(
        train_images,
        validation_images,
        config,
        subsample.as_deref(),
    )?;
    let searched_on = model.summary().searched_on;
    Ok((model, searched_on))
}

/// [`select`] on training + validation images, then [`train`](crate::pipeline::train) of the winner
/// on them; the model records the selection. When the candidates were scored on a subsample, a winner
/// whose classifier pins its hyper-parameters ([`ClassifierConfig::pins`](crate::classifier::ClassifierConfig::pins))
/// has them searched on that subsample's vectors and only the choice fitted on every image
/// ([`SelectionCost::searched_on`]); on smaller data the model is `train`'s.
pub fn train_auto(
    train_images: &[LabeledImage<'_>],
    validation_images: &[LabeledImage<'_>],
    choice: &AutoChoice<'_>,
    seed: u64,
) -> Result<TrainedModel> {
    let candidates = choice.candidates;
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
    let mut selection = select(&all, choice, seed)?;
    // (the winner may be a candidate refined with other dims: its configuration is in its score)
    let config = selection.scores[selection.chosen].config.clone().check()?;
    // On large data the winner's hyper-parameters are searched on the subsample the candidates were
    // scored on (the same draw), and only the choice is fitted on every sample.
    let subsample = choice
        .scoring_samples
        .and_then(|at_most| subsample::stratified_subsample(&all, at_most, seed));
    let searches_on_subsample = subsample.is_some() && config.config().classifier.pins();
    StageObserver::tell(choice.on_stage, || {
        let search = match &subsample {
            Some(rows) if searches_on_subsample => format!(
                " (its hyper-parameters searched on the stratified subsample of {})",
                rows.len()
            ),
            _ => String::new(),
        };
        format!(
            "training the winner, {} + {}, on {} samples{search}",
            config.config().features.name(),
            config.config().classifier.kind().as_str(),
            all.len()
        )
    });
    let fitting = std::time::Instant::now();
    let (model, searched) = train_searching(
        train_images,
        validation_images,
        &config,
        subsample.as_deref(),
    )?;
    if let Some(cost) = selection.cost.as_mut() {
        cost.final_fit_seconds = fitting.elapsed().as_secs_f64();
        cost.searched_on = searched.then(|| subsample.as_ref().map_or(0, Vec::len));
    }
    Ok(model.with_selection(selection))
}
