//! The engine: an [`Evaluation`] trains each fold's model, tests it (under each perturbation) and
//! tallies the outcomes, repeat by repeat.

use std::collections::BTreeMap;
use std::time::Instant;

use rayon::prelude::*;

use super::folds::{Draw, Fold, folds};
use super::protocol::Protocol;
use super::report::{EvalReport, RepeatResult};
use super::tally::{Tally, TestOutcome};
use crate::error::{CoreError, Result};
use crate::frame::{Frame, FrameView};
use crate::pipeline::{CheckedTrainConfig, LabeledImage, Selection};

/// A function that trains a fold's model from its sets, and says which reading of the samples it
/// classifies.
pub type Trainer<'f> = dyn Fn(&FoldSets<'_>) -> Result<FoldModel> + Sync + 'f;

/// One fold as its trainer sees it ([`Evaluation::run_views`]): which fold, and its training and
/// validation sets (indices into the samples; the test set is never shown).
#[derive(Clone, Copy, Debug)]
pub struct FoldSets<'f> {
    /// The repeat's seed (the evaluation's seed + repeat).
    pub seed: u64,
    /// The fold's place in its repeat, from 0 (the order of [`Evaluation::draws`]).
    pub fold: usize,
    /// With leave-one-out, the held-out value.
    pub held_out: Option<&'f str>,
    pub train: &'f [usize],
    pub validation: &'f [usize],
}

/// A fold's model and the reading of the samples it classifies: an index into the `views` of
/// [`Evaluation::run_views`] (0 for the evaluation's own samples everywhere else).
#[derive(Clone, Debug)]
pub struct FoldModel {
    pub model: crate::pipeline::TrainedModel,
    pub view: usize,
}

/// Changes a test image before it is classified: `(sample index, image, repeat seed) -> image` (fault
/// injection, see [`crate::perturb`]). Training and validation images are never changed. A changed image
/// the model cannot classify counts as a wrong answer ([`EvalReport::unclassified`]); an error of the
/// transform itself stops the evaluation.
pub type TestTransform<'f> = dyn Fn(usize, FrameView<'_>, u64) -> Result<Frame> + Sync + 'f;

/// How each fold's model is trained.
#[derive(Clone, Copy, Debug)]
pub enum Models<'c> {
    /// With this configuration (the paper's method, or any other).
    Config(&'c CheckedTrainConfig),
    /// Chosen as the [`AutoChoice`](crate::selection::AutoChoice) says by
    /// [`crate::selection::train_auto`], on the fold's training data only (its budget is each model's).
    Auto(crate::selection::AutoChoice<'c>),
}

/// What [`Evaluation::run_each`] found.
#[derive(Clone, Debug)]
pub struct Evaluated {
    /// One report per perturbation, in the order given.
    pub reports: Vec<EvalReport>,
    /// The selection of every automatically chosen model, in training order (empty for
    /// [`Models::Config`]).
    pub selections: Vec<Selection>,
    /// The first model trained (the first repeat's first fold): a report shows it as the model that
    /// was evaluated.
    pub first_model: Option<FirstModel>,
}

/// The first model an evaluation trained, and on what.
#[derive(Clone, Debug)]
pub struct FirstModel {
    pub model: crate::pipeline::TrainedModel,
    /// The repeat's seed.
    pub seed: u64,
    /// The held-out value of its fold (leave-one-out), `None` for the other protocol.
    pub held_out: Option<String>,
    pub n_train: usize,
    pub n_validation: usize,
    pub n_test: usize,
}

/// An evaluation: `protocol` on `samples`, run `repeats` times with the seeds `seed`, `seed + 1`, ...;
/// `progress` is called after each trained model (for a progress bar). The runs differ in how each
/// fold's model is trained ([`Models`]) and in what the test images go through; the draws depend only on
/// the samples, the protocol and the seed, so runs with the same ones pair up.
#[derive(Clone, Copy)]
pub struct Evaluation<'e, 's> {
    pub samples: &'e [LabeledImage<'s>],
    pub protocol: &'e Protocol,
    pub repeats: usize,
    pub seed: u64,
    pub progress: &'e (dyn Fn() + Sync),
}

impl std::fmt::Debug for Evaluation<'_, '_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Evaluation")
            .field("samples", &self.samples.len())
            .field("protocol", self.protocol)
            .field("repeats", &self.repeats)
            .field("seed", &self.seed)
            .finish_non_exhaustive()
    }
}

impl Evaluation<'_, '_> {
    /// Trains every fold's model with `models` and tests it on the images as they are.
    pub fn run(&self, models: Models<'_>) -> Result<EvalReport> {
        self.run_each(models, &[None])?
            .reports
            .pop()
            .ok_or_else(|| CoreError::NotEnoughData("no evaluation was run".into()))
    }

    /// Trains every fold's model once with `models` and tests it under each of `perturbs` (`None`: the
    /// test images as they are), so each report is what [`run`](Self::run) would give with the test images
    /// passed through that perturbation first, at the cost of one training.
    pub fn run_each(
        &self,
        models: Models<'_>,
        perturbs: &[Option<&TestTransform<'_>>],
    ) -> Result<Evaluated> {
        let samples = self.samples;
        let images =
            |set: &[usize]| -> Vec<LabeledImage<'_>> { set.iter().map(|&i| samples[i]).collect() };
        match models {
            Models::Config(config) => {
                let (reports, first_model) = self.run_with(&[samples], perturbs, &|fold| {
                    // (on large data, the classifier's hyper-parameters are searched on a
                    // subsample, as the automatic choice's winner's are)
                    let (model, _) = crate::selection::train_fixed(
                        &images(fold.train),
                        &images(fold.validation),
                        config,
                        Some(crate::selection::SCORING_SAMPLES),
                        fold.seed,
                    )?;
                    Ok(FoldModel { model, view: 0 })
                })?;
                Ok(Evaluated {
                    reports,
                    selections: Vec::new(),
                    first_model,
                })
            }
            Models::Auto(choice) => {
                let selections = std::sync::Mutex::new(Vec::new());
                let (reports, first_model) = self.run_with(&[samples], perturbs, &|fold| {
                    let model = crate::selection::train_auto(
                        &images(fold.train),
                        &images(fold.validation),
                        &choice,
                        fold.seed,
                    )?;
                    if let (Some(selection), Ok(mut list)) = (model.selection(), selections.lock())
                    {
                        list.push(selection.clone());
                    }
                    Ok(FoldModel { model, view: 0 })
                })?;
                Ok(Evaluated {
                    reports,
                    selections: selections.into_inner().unwrap_or_default(),
                    first_model,
                })
            }
        }
    }

    /// Trains every fold's model with `trainer` and tests it on the fold's test units in the reading
    /// its [`FoldModel::view`] names: `views` are readings of the evaluation's samples (the same units
    /// in the same order, so the same labels, conditions and groups; e.g. each stance's frame and its
    /// whole movie), and the draws are the evaluation's own. The test images are as they are.
    pub fn run_views(
        &self,
        views: &[&[LabeledImage<'_>]],
        trainer: &Trainer<'_>,
    ) -> Result<(EvalReport, Option<FirstModel>)> {
        for (k, view) in views.iter().enumerate() {
            self.check_same_units(k, view)?;
        }
        let (mut reports, first_model) = self.run_with(views, &[None], trainer)?;
        let report = reports
            .pop()
            .ok_or_else(|| CoreError::NotEnoughData("no evaluation was run".into()))?;
        Ok((report, first_model))
    }

    /// An error unless `view` (reading `k`) has the samples' units: as many, each with the same label,
    /// condition and group.
    fn check_same_units(&self, k: usize, view: &[LabeledImage<'_>]) -> Result<()> {
        if view.len() != self.samples.len() {
            return Err(CoreError::Shape {
                what: "reading of the evaluated samples",
                expected: format!("{} samples", self.samples.len()),
                got: format!("{} in reading {k}", view.len()),
            });
        }
        let differs =
            self.samples.iter().zip(view).position(|(a, b)| {
                (a.label, a.condition, a.group) != (b.label, b.condition, b.group)
            });
        match differs {
            Some(i) => Err(CoreError::Shape {
                what: "reading of the evaluated samples",
                expected: format!(
                    "sample {i} labelled {} (condition {:?}, group {:?})",
                    self.samples[i].label, self.samples[i].condition, self.samples[i].group
                ),
                got: format!(
                    "{} (condition {:?}, group {:?}) in reading {k}",
                    view[i].label, view[i].condition, view[i].group
                ),
            }),
            None => Ok(()),
        }
    }

    /// The draws [`run`](Self::run) makes, fold by fold and repeat by repeat (indices into `samples`), so
    /// that another implementation can be evaluated on exactly the same training, validation and test
    /// sets.
    pub fn draws(&self) -> Result<Vec<Draw>> {
        let mut out = Vec::new();
        for repeat in 0..self.repeats {
            let repeat_seed = self.seed.wrapping_add(repeat as u64);
            for fold in folds(self.samples, self.protocol, repeat_seed)? {
                let held_out = match (self.protocol, fold.test.first()) {
                    (Protocol::LeaveOneOut { .. }, Some(&i)) => {
                        self.samples[i].group.map(str::to_owned)
                    }
                    _ => None,
                };
                out.push(Draw {
                    repeat,
                    seed: repeat_seed,
                    held_out,
                    train: fold.train,
                    validation: fold.validation,
                    test: fold.test,
                });
            }
        }
        Ok(out)
    }

    /// The engine behind every run: the folds of each repeat, each fold's model from `trainer`, its
    /// test images classified under each of `perturbs`. Also returns the first model trained.
    pub(super) fn run_with(
        &self,
        views: &[&[LabeledImage<'_>]],
        perturbs: &[Option<&TestTransform<'_>>],
        trainer: &Trainer<'_>,
    ) -> Result<(Vec<EvalReport>, Option<FirstModel>)> {
        if self.repeats == 0 {
            return Err(CoreError::Param {
                name: "repeats",
                reason: "at least one repeat is needed".into(),
            });
        }
        if self.samples.is_empty() {
            return Err(CoreError::NotEnoughData("no samples to evaluate on".into()));
        }
        let mut labels: Vec<String> = self.samples.iter().map(|s| s.label.to_owned()).collect();
        labels.sort();
        labels.dedup();
        let mut tallies: Vec<Tally> = perturbs
            .iter()
            .map(|_| Tally::new(labels.clone(), self.repeats))
            .collect();
        let mut first_model = None;
        for repeat in 0..self.repeats {
            let repeat_seed = self.seed.wrapping_add(repeat as u64);
            self.run_repeat(
                repeat_seed,
                views,
                perturbs,
                trainer,
                &mut tallies,
                &mut first_model,
            )?;
        }
        let reports = tallies
            .into_iter()
            .map(|tally| tally.into_report(self.protocol))
            .collect();
        Ok((reports, first_model))
    }

    /// One repeat of [`run_with`](Self::run_with), with the seed `repeat_seed`: its folds trained and
    /// tested, each perturbation's outcomes added to its tally (and the first model kept, if none was).
    fn run_repeat(
        &self,
        repeat_seed: u64,
        views: &[&[LabeledImage<'_>]],
        perturbs: &[Option<&TestTransform<'_>>],
        trainer: &Trainer<'_>,
        tallies: &mut [Tally],
        first_model: &mut Option<FirstModel>,
    ) -> Result<()> {
        let samples = self.samples;
        let folds = folds(samples, self.protocol, repeat_seed)?;
        let mut correct_by_condition: Vec<BTreeMap<String, (u64, u64)>> =
            vec![BTreeMap::new(); perturbs.len()];
        let mut result = RepeatResult {
            seed: repeat_seed,
            overall_accuracy: 0.0,
            per_condition: BTreeMap::new(),
            sigmas: Vec::new(),
            n_train: 0,
            n_validation: 0,
            n_test: 0,
            train_seconds: 0.0,
            folds: folds.len(),
        };
        let trained = train_folds(&folds, samples, trainer, repeat_seed, self.progress);
        for (fold, (model, seconds)) in folds.into_iter().zip(trained) {
            let FoldModel { model, view } = model?;
            let tested = views.get(view).copied().ok_or_else(|| CoreError::Param {
                name: "view",
                reason: format!("a fold's model reads view {view} of {}", views.len()),
            })?;
            result.train_seconds += seconds;
            if first_model.is_none() {
                *first_model = Some(FirstModel::of(&model, &fold, samples, repeat_seed));
            }
            result.sigmas.extend(model.sigma());
            result.n_train += fold.train.len();
            result.n_validation += fold.validation.len();
            result.n_test += fold.test.len();
            for ((perturb, tally), correct) in perturbs
                .iter()
                .zip(tallies.iter_mut())
                .zip(correct_by_condition.iter_mut())
            {
                let outcomes = classify_test_set(&model, &fold.test, tested, *perturb, repeat_seed);
                tally.add_fold(correct, &fold, samples, &model, outcomes)?;
            }
        }
        for (tally, correct) in tallies.iter_mut().zip(correct_by_condition) {
            tally.add_repeat(&result, correct)?;
        }
        Ok(())
    }
}

/// The models of `folds`, trained in parallel (each its own training, deterministic whatever the
/// threads: the cores stay busy through each model's sequential parts), in fold order, each with its
/// training time in seconds; `progress` is called after each.
fn train_folds(
    folds: &[Fold],
    samples: &[LabeledImage<'_>],
    trainer: &Trainer<'_>,
    repeat_seed: u64,
    progress: &(dyn Fn() + Sync),
) -> Vec<(Result<FoldModel>, f64)> {
    let train_one = |(k, fold): (usize, &Fold)| {
        let start = Instant::now();
        let model = trainer(&FoldSets {
            seed: repeat_seed,
            fold: k,
            held_out: fold.held_out(samples),
            train: &fold.train,
            validation: &fold.validation,
        });
        progress();
        (model, start.elapsed().as_secs_f64())
    };
    if folds.iter().any(large_fold) {
        folds.iter().enumerate().map(train_one).collect()
    } else {
        folds.par_iter().enumerate().map(train_one).collect()
    }
}

/// Whether a fold's training data (training + validation) are large: more than an automatic choice
/// scores its candidates on ([`SCORING_SAMPLES`](crate::selection::SCORING_SAMPLES)). Such folds are
/// trained one after the other (each training's own stages, features, products and classifiers, run
/// in parallel): in parallel, two or more trainings of the full features were alive at once, which
/// multiplied the peak memory, and each automatic choice's time budget was spent on half the cores.
fn large_fold(fold: &Fold) -> bool {
    fold.train.len() + fold.validation.len() > crate::selection::SCORING_SAMPLES
}

/// Classifies the images `test` (indices into `samples`), each passed through `perturb` first if given,
/// in parallel; the outcomes in the order of `test`.
fn classify_test_set(
    model: &crate::pipeline::TrainedModel,
    test: &[usize],
    samples: &[LabeledImage<'_>],
    perturb: Option<&TestTransform<'_>>,
    repeat_seed: u64,
) -> Vec<TestOutcome> {
    test.par_iter()
        .map_init(
            || model.session(),
            |session, &i| {
                let perturbed = perturb
                    .map(|p| p(i, samples[i].frame, repeat_seed))
                    .transpose()?;
                let frame = perturbed.as_ref().map_or(samples[i].frame, Frame::view);
                let start = Instant::now();
                match session.classify(&frame) {
                    Ok(prediction) => Ok(Some((
                        prediction.class,
                        prediction.confidence,
                        start.elapsed().as_nanos() as u64,
                    ))),
                    Err(_) if perturbed.is_some() => Ok(None),
                    Err(err) => Err(err),
                }
            },
        )
        .collect()
}

impl FirstModel {
    /// `model`, trained on `fold` in the repeat of seed `seed`.
    fn of(
        model: &crate::pipeline::TrainedModel,
        fold: &Fold,
        samples: &[LabeledImage<'_>],
        seed: u64,
    ) -> Self {
        Self {
            model: model.clone(),
            seed,
            held_out: fold.held_out(samples).map(str::to_owned),
            n_train: fold.train.len(),
            n_validation: fold.validation.len(),
            n_test: fold.test.len(),
        }
    }
}
