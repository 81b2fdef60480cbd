//! The evaluation engine: train on one part of a dataset, test on the rest, repeat with new seeds.
//!
//! Two protocols (see `docs/interface.md`):
//! - [`Protocol::TrainCondition`], the paper's: draw `per_class` random images per class from one
//!   condition (a gait), `validation` of them for hyper-parameters, and test on every other sample of every
//!   condition. Accuracy is reported per tested condition (the training condition's held-out remainder
//!   included) and overall (over every tested sample).
//! - [`Protocol::LeaveOneOut`]: for every value of a grouping column, train on all samples with another
//!   value and test on the held-out ones (leave-one-subject-out, leave-one-gait-out).
//!
//! Every repeat draws with its own seed (`seed + repeat`), so a run is reproducible and repeats differ.
//! Results are means and standard deviations over the repeats; the confusion matrix sums all repeats.

use std::collections::BTreeMap;
use std::time::Instant;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{CoreError, Result};
use crate::frame::{Frame, FrameView};
use crate::metrics::ratio;
use crate::pipeline::{CheckedTrainConfig, LabeledImage, Selection, train};
use crate::reliability::Reliability;
use crate::split::{ValidationSize, per_class_shortfall, stratified_split_capped};

// The summaries an [`EvalReport`] is made of, nameable from here as before they moved to the leaf module.
pub use crate::metrics::{Confusion, MeanStd};

/// How training and test sets are formed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Protocol {
    /// Train on a random draw (from `condition` only, when given); test on everything else.
    TrainCondition {
        condition: Option<String>,
        per_class: Option<usize>,
        validation: ValidationSize,
    },
    /// Hold out each value of the samples' `group` in turn.
    LeaveOneOut {
        /// The column's name (for reports).
        column: String,
        per_class: Option<usize>,
        validation: ValidationSize,
    },
}

impl Protocol {
    /// Models one repeat trains on `samples`: one per held-out group with leave-one-out, else one.
    pub fn models_per_repeat(&self, samples: &[LabeledImage<'_>]) -> usize {
        match self {
            Self::LeaveOneOut { .. } => samples
                .iter()
                .filter_map(|s| s.group)
                .collect::<std::collections::BTreeSet<_>>()
                .len(),
            Self::TrainCondition { .. } => 1,
        }
    }
}

/// What one repeat found.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RepeatResult {
    pub seed: u64,
    pub overall_accuracy: f64,
    pub per_condition: BTreeMap<String, f64>,
    /// The Parzen σ of each model trained in this repeat (one per held-out value for leave-one-out).
    pub sigmas: Vec<f64>,
    /// Training, validation and test images, summed over the repeat's folds (see `folds`).
    pub n_train: usize,
    pub n_validation: usize,
    pub n_test: usize,
    pub train_seconds: f64,
    /// Models trained in this repeat: one, or one per held-out value with leave-one-out. An image
    /// trains in every fold but the one that holds it out, so `n_train` and `n_validation` may exceed
    /// the images there are; `n_test` counts each tested image once per repeat.
    #[serde(default = "one_fold")]
    pub folds: usize,
}

/// Repeats stored before `folds` was recorded trained one model (the paper's protocol) or did not say.
fn one_fold() -> usize {
    1
}

impl RepeatResult {
    /// The image counts in words: `13 training + 7 validation images, 60 tested` for one model, and per
    /// fold (on average) with the total tested for several.
    pub fn counts_text(&self) -> String {
        if self.folds <= 1 {
            return format!(
                "{} training + {} validation images, {} tested",
                self.n_train, self.n_validation, self.n_test
            );
        }
        let per_fold = |n: usize| n as f64 / self.folds as f64;
        format!(
            "{} folds, per fold (on average) {:.0} training + {:.0} validation images and {:.0} \
             tested; {} tested in all (summed over the folds: {} training + {} validation)",
            self.folds,
            per_fold(self.n_train),
            per_fold(self.n_validation),
            per_fold(self.n_test),
            self.n_test,
            self.n_train,
            self.n_validation
        )
    }
}

/// The result of an evaluation ([`Evaluation::run`]): every repeat, and their summary.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EvalReport {
    pub protocol: Protocol,
    pub repeats: Vec<RepeatResult>,
    pub overall: MeanStd,
    /// Accuracy per tested condition (or held-out value), mean and spread over repeats.
    pub per_condition: BTreeMap<String, MeanStd>,
    pub confusion: Confusion,
    /// Median wall time of one classification (crop + features + PCA + classifier), nanoseconds.
    pub median_classify_ns: u64,
    /// Perturbed test images the model could not classify (e.g. values beyond what its features can
    /// represent), over all repeats. Each counts as a wrong answer in the accuracies and is missing from
    /// the confusion matrix (it has no predicted class). An unperturbed image that cannot be classified
    /// is an error instead: that is bad data, not a fault the evaluation injected.
    #[serde(default)]
    pub unclassified: u64,
    /// The confidences of every classified test image against whether it was right, over all repeats:
    /// how far the model's confidences can be trusted.
    #[serde(default)]
    pub reliability: Reliability,
}

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
                    let model = train(&images(fold.train), &images(fold.validation), config)?;
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

    /// Evaluates every configuration of `configs` with the same draws (so every combination sees the same
    /// training sets). A combination that cannot be trained (e.g. too few samples per class for its
    /// classifier) is reported with its error instead of stopping the comparison.
    pub fn compare(&self, configs: &[CheckedTrainConfig]) -> Result<Vec<ComparisonRow>> {
        let mut rows = Vec::with_capacity(configs.len());
        for config in configs {
            let inner = config.config();
            let report = match self.run(Models::Config(config)) {
                // a parameter error is the caller's mistake, not this combination's limitation
                Err(err @ CoreError::Param { .. }) => return Err(err),
                other => other,
            };
            let train_seconds = match &report {
                Ok(report) => {
                    let per_model: Vec<f64> = report
                        .repeats
                        .iter()
                        .map(|r| {
                            let models = match self.protocol {
                                Protocol::TrainCondition { .. } => 1,
                                Protocol::LeaveOneOut { .. } => r.per_condition.len().max(1),
                            };
                            r.train_seconds / models as f64
                        })
                        .collect();
                    MeanStd::of(&per_model)
                }
                Err(_) => MeanStd::default(),
            };
            rows.push(ComparisonRow {
                features: inner.features.name(),
                classifier: inner.classifier.kind().as_str().to_owned(),
                config: inner.clone(),
                report: report.map_err(|err| err.to_string()),
                train_seconds,
            });
        }
        Ok(rows)
    }

    /// The engine behind every run: the folds of each repeat, each fold's model from `trainer`, its
    /// test images classified under each of `perturbs`. Also returns the first model trained.
    fn run_with(
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
    folds
        .par_iter()
        .enumerate()
        .map(|(k, fold)| {
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
        })
        .collect()
}

/// What became of one test image: its predicted class, confidence and classification time in
/// nanoseconds; `Ok(None)` for a perturbed image the model could not classify.
type TestOutcome = Result<Option<(usize, f64, u64)>>;

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

/// What one perturbation's tests have found so far.
struct Tally {
    confusion: Confusion,
    times_ns: Vec<u64>,
    results: Vec<RepeatResult>,
    unclassified: u64,
    reliability: Reliability,
}

impl Tally {
    fn new(labels: Vec<String>, repeats: usize) -> Self {
        Self {
            confusion: Confusion::new(labels),
            times_ns: Vec::new(),
            results: Vec::with_capacity(repeats),
            unclassified: 0,
            reliability: Reliability::default(),
        }
    }

    /// Adds the `outcomes` of one fold's test images (`fold.test`, in order): the confusion, the
    /// times, the reliability, and `correct`, the hits and tests by condition (or held-out value).
    fn add_fold(
        &mut self,
        correct: &mut BTreeMap<String, (u64, u64)>,
        fold: &Fold,
        samples: &[LabeledImage<'_>],
        model: &crate::pipeline::TrainedModel,
        outcomes: Vec<TestOutcome>,
    ) -> Result<()> {
        let confusion = &mut self.confusion;
        for (&i, outcome) in fold.test.iter().zip(outcomes) {
            let Some((predicted, confidence, ns)) = outcome? else {
                // A wrong answer, with no predicted class for the confusion matrix.
                self.unclassified += 1;
                correct.entry(fold.key_of(&samples[i])).or_default().1 += 1;
                continue;
            };
            self.times_ns.push(ns);
            let predicted_label = &model.class_names()[predicted];
            let truth = confusion
                .labels
                .binary_search_by(|l| l.as_str().cmp(samples[i].label));
            let guess = confusion.labels.binary_search(predicted_label);
            if let (Ok(t), Ok(g)) = (truth, guess) {
                confusion.counts[t][g] += 1;
            }
            let key = fold.key_of(&samples[i]);
            let entry = correct.entry(key).or_default();
            entry.1 += 1;
            let right = predicted_label == samples[i].label;
            if right {
                entry.0 += 1;
            }
            self.reliability.add(confidence, right);
        }
        Ok(())
    }

    /// Ends a repeat: `result` with the accuracies of `correct` (hits and tests by condition) is its
    /// result. An error if nothing was tested.
    fn add_repeat(
        &mut self,
        result: &RepeatResult,
        correct: BTreeMap<String, (u64, u64)>,
    ) -> Result<()> {
        let (hits, total) = correct
            .values()
            .fold((0, 0), |(c, t), &(c1, t1)| (c + c1, t + t1));
        if total == 0 {
            return Err(CoreError::NotEnoughData(
                "no sample is left to test on: the training set took every sample (draw fewer \
                 per class, or train on one condition and test on the others)"
                    .into(),
            ));
        }
        let mut result = result.clone();
        result.overall_accuracy = ratio(hits, total);
        result.per_condition = correct
            .into_iter()
            .map(|(key, (c, t))| (key, ratio(c, t)))
            .collect();
        self.results.push(result);
        Ok(())
    }

    fn into_report(self, protocol: &Protocol) -> EvalReport {
        let mut report = report_of(protocol, self.results, self.confusion, self.times_ns);
        report.unclassified = self.unclassified;
        report.reliability = self.reliability;
        report
    }
}

/// The report of one evaluation's repeats.
fn report_of(
    protocol: &Protocol,
    results: Vec<RepeatResult>,
    confusion: Confusion,
    mut times_ns: Vec<u64>,
) -> EvalReport {
    let overall = MeanStd::of(
        &results
            .iter()
            .map(|r| r.overall_accuracy)
            .collect::<Vec<_>>(),
    );
    let mut keys: Vec<&String> = results
        .iter()
        .flat_map(|r| r.per_condition.keys())
        .collect();
    keys.sort();
    keys.dedup();
    let per_condition = keys
        .into_iter()
        .map(|key| {
            let values: Vec<f64> = results
                .iter()
                .filter_map(|r| r.per_condition.get(key).copied())
                .collect();
            (key.clone(), MeanStd::of(&values))
        })
        .collect();
    times_ns.sort_unstable();
    let median_classify_ns = times_ns.get(times_ns.len() / 2).copied().unwrap_or(0);
    EvalReport {
        protocol: protocol.clone(),
        repeats: results,
        overall,
        per_condition,
        confusion,
        median_classify_ns,
        unclassified: 0,
        reliability: Reliability::default(),
    }
}

/// One combination of a comparison ([`Evaluation::compare`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ComparisonRow {
    /// The feature family (or `a+b` for a combination).
    pub features: String,
    pub classifier: String,
    pub config: crate::pipeline::TrainConfig,
    /// The evaluation, or why this combination could not be trained.
    pub report: std::result::Result<EvalReport, String>,
    /// Training time per trained model, seconds (mean and spread over repeats).
    pub train_seconds: MeanStd,
}

/// The classes whose training pool holds fewer images than the protocol's `per_class`, with how many
/// it holds, by held-out value (leave-one-out) or as `"all"` (a training condition): their draws are
/// capped to what there is. Empty when every draw is as asked.
pub fn per_class_capped(
    samples: &[LabeledImage<'_>],
    protocol: &Protocol,
) -> BTreeMap<String, BTreeMap<String, usize>> {
    let shortfall = |keep: &dyn Fn(&LabeledImage<'_>) -> bool, per_class: Option<usize>| {
        let labels: Vec<&str> = samples
            .iter()
            .filter(|s| keep(s))
            .map(|s| s.label)
            .collect();
        per_class_shortfall(&labels, per_class)
    };
    let mut out = BTreeMap::new();
    match protocol {
        Protocol::TrainCondition {
            condition,
            per_class,
            ..
        } => {
            let short = shortfall(
                &|s| condition.as_deref().is_none_or(|c| s.condition == Some(c)),
                *per_class,
            );
            if !short.is_empty() {
                out.insert("all".to_owned(), short);
            }
        }
        Protocol::LeaveOneOut { per_class, .. } => {
            let values: std::collections::BTreeSet<&str> =
                samples.iter().filter_map(|s| s.group).collect();
            for value in values {
                let short = shortfall(&|s| s.group != Some(value), *per_class);
                if !short.is_empty() {
                    out.insert(value.to_owned(), short);
                }
            }
        }
    }
    out
}

/// The labels a protocol tests that its training sets can never hold, by held-out value (leave-one-out)
/// or as `"all"` (a training condition): such samples are wrong whatever the model, e.g. a group that is
/// one terrain's only trial. Empty when every tested label can be trained. Sorted.
pub fn labels_never_trained(
    samples: &[LabeledImage<'_>],
    protocol: &Protocol,
) -> BTreeMap<String, Vec<String>> {
    let labels_where = |keep: &dyn Fn(&LabeledImage<'_>) -> bool| {
        samples
            .iter()
            .filter(|s| keep(s))
            .map(|s| s.label)
            .collect::<std::collections::BTreeSet<_>>()
    };
    let mut out = BTreeMap::new();
    match protocol {
        Protocol::TrainCondition {
            condition: Some(condition),
            ..
        } => {
            let trainable = labels_where(&|s| s.condition == Some(condition.as_str()));
            let missing: Vec<String> = labels_where(&|_| true)
                .difference(&trainable)
                .map(|&l| l.to_owned())
                .collect();
            if !missing.is_empty() {
                out.insert("all".to_owned(), missing);
            }
        }
        Protocol::TrainCondition {
            condition: None, ..
        } => {}
        Protocol::LeaveOneOut { .. } => {
            let values: std::collections::BTreeSet<&str> =
                samples.iter().filter_map(|s| s.group).collect();
            for value in values {
                let trainable = labels_where(&|s| s.group != Some(value));
                let missing: Vec<String> = labels_where(&|s| s.group == Some(value))
                    .difference(&trainable)
                    .map(|&l| l.to_owned())
                    .collect();
                if !missing.is_empty() {
                    out.insert(value.to_owned(), missing);
                }
            }
        }
    }
    out
}

/// One fold of one repeat of an evaluation ([`Evaluation::draws`]): indices into its samples.
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
struct Fold {
    train: Vec<usize>,
    validation: Vec<usize>,
    test: Vec<usize>,
    /// Leave-one-out reports by held-out value; the other protocol by condition.
    by_group: bool,
}

impl Fold {
    /// With leave-one-out, the held-out value (that of the first test sample).
    fn held_out<'s>(&self, samples: &[LabeledImage<'s>]) -> Option<&'s str> {
        self.by_group
            .then(|| self.test.first().and_then(|&i| samples[i].group))
            .flatten()
    }

    fn key_of(&self, sample: &LabeledImage<'_>) -> String {
        let key = if self.by_group {
            sample.group
        } else {
            sample.condition
        };
        key.unwrap_or("all").to_owned()
    }
}

fn folds(samples: &[LabeledImage<'_>], protocol: &Protocol, seed: u64) -> Result<Vec<Fold>> {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::Frame;
    use crate::pipeline::TrainConfig;
    use crate::testing::{SYNTHETIC_CLASSES, synthetic_frame};
    use rand::SeedableRng;

    fn data() -> Vec<(Frame, &'static str, &'static str)> {
        data_seeded(11)
    }

    /// 48 synthetic images of each condition, the classes in turn; the noise from `seed`.
    fn data_seeded(seed: u64) -> Vec<(Frame, &'static str, &'static str)> {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let mut out = Vec::new();
        for condition in ["G1", "G2", "G3"] {
            for i in 0..48 {
                out.push((
                    synthetic_frame(i % 4, &mut rng),
                    SYNTHETIC_CLASSES[i % 4],
                    condition,
                ));
            }
        }
        out
    }

    /// The paper's protocol on the synthetic data: trained on G2, 10 per class with 3 validating.
    fn g2_protocol() -> Protocol {
        Protocol::TrainCondition {
            condition: Some("G2".into()),
            per_class: Some(10),
            validation: ValidationSize::Count(3),
        }
    }

    /// The paper's pipeline with `dims` principal components.
    fn paper_config_with_dims(dims: usize) -> CheckedTrainConfig {
        TrainConfig {
            dims,
            ..TrainConfig::default()
        }
        .check()
        .unwrap()
    }

    /// `protocol` on `samples`, `repeats` times from `seed`, without a progress callback.
    fn evaluation<'e, 's>(
        samples: &'e [LabeledImage<'s>],
        protocol: &'e Protocol,
        repeats: usize,
        seed: u64,
    ) -> Evaluation<'e, 's> {
        Evaluation {
            samples,
            protocol,
            repeats,
            seed,
            progress: &|| {},
        }
    }

    fn samples<'a>(data: &'a [(Frame, &'static str, &'static str)]) -> Vec<LabeledImage<'a>> {
        data.iter()
            .map(|(frame, label, condition)| LabeledImage {
                frame: frame.view(),
                label,
                condition: Some(condition),
                group: Some(condition),
            })
            .collect()
    }

    #[test]
    fn paper_protocol_counts_and_reproducibility() {
        let data = data();
        let samples = samples(&data);
        let protocol = g2_protocol();
        let config = paper_config_with_dims(20);
        let a = evaluation(&samples, &protocol, 2, 5)
            .run(Models::Config(&config))
            .unwrap();
        let b = evaluation(&samples, &protocol, 2, 5)
            .run(Models::Config(&config))
            .unwrap();
        // everything but the wall times is reproducible
        let strip = |report: &EvalReport| {
            report
                .repeats
                .iter()
                .map(|r| RepeatResult {
                    train_seconds: 0.0,
                    ..r.clone()
                })
                .collect::<Vec<_>>()
        };
        assert_eq!(strip(&a), strip(&b));
        assert_eq!(a.confusion, b.confusion);
        let first = &a.repeats[0];
        assert_eq!((first.n_train, first.n_validation), (28, 12));
        assert_eq!(first.n_test, samples.len() - 40);
        assert_eq!(a.per_condition.len(), 3);
        // the confusion matrix counts every tested sample of every repeat
        let total: u64 = a.confusion.counts.iter().flatten().sum();
        assert_eq!(total as usize, 2 * first.n_test);
        // the synthetic classes are easy: well above chance
        assert!(a.overall.mean > 0.8, "{:?}", a.overall);
        let correct: u64 = (0..4).map(|i| a.confusion.counts[i][i]).sum();
        assert!((correct as f64 / total as f64 - a.overall.mean).abs() < 1e-12);
    }

    #[test]
    fn labels_never_trained_by_protocol() {
        let frame = Frame::zeros(crate::frame::Grid::new(2, 2));
        // (label, condition = group): wood in every trial, carpet only in t1, grass only in G1's t2.
        let rows = [
            ("wood", "t1"),
            ("carpet", "t1"),
            ("wood", "t2"),
            ("grass", "t2"),
            ("wood", "t3"),
        ];
        let samples: Vec<LabeledImage<'_>> = rows
            .iter()
            .map(|&(label, group)| LabeledImage {
                frame: frame.view(),
                label,
                condition: Some(group),
                group: Some(group),
            })
            .collect();
        let loo = Protocol::LeaveOneOut {
            column: "trial".into(),
            per_class: None,
            validation: ValidationSize::Count(0),
        };
        let missing = labels_never_trained(&samples, &loo);
        let expected: BTreeMap<String, Vec<String>> = [
            ("t1".to_owned(), vec!["carpet".to_owned()]),
            ("t2".to_owned(), vec!["grass".to_owned()]),
        ]
        .into();
        assert_eq!(missing, expected);
        let on_t1 = Protocol::TrainCondition {
            condition: Some("t1".into()),
            per_class: None,
            validation: ValidationSize::Count(0),
        };
        assert_eq!(
            labels_never_trained(&samples, &on_t1),
            [("all".to_owned(), vec!["grass".to_owned()])].into()
        );
        let on_all = Protocol::TrainCondition {
            condition: None,
            per_class: None,
            validation: ValidationSize::Count(0),
        };
        assert!(labels_never_trained(&samples, &on_all).is_empty());
    }

    /// Training on every sample of every condition leaves none to test: an error that says what to change.
    #[test]
    fn a_training_set_of_every_sample_is_refused_with_a_way_out() {
        let data = data();
        let samples = samples(&data);
        let protocol = Protocol::TrainCondition {
            condition: None,
            per_class: None,
            validation: ValidationSize::Count(3),
        };
        let config = paper_config_with_dims(10);
        let err = evaluation(&samples, &protocol, 1, 3)
            .run(Models::Config(&config))
            .unwrap_err();
        assert!(
            matches!(&err, CoreError::NotEnoughData(reason)
                if reason.contains("the training set took every sample (draw fewer per class")),
            "{err}"
        );
    }

    #[test]
    fn leave_one_out_tests_each_value_once() {
        let data = data();
        let samples = samples(&data);
        let protocol = Protocol::LeaveOneOut {
            column: "condition".into(),
            per_class: Some(8),
            validation: ValidationSize::Count(3),
        };
        let config = paper_config_with_dims(10);
        let report = evaluation(&samples, &protocol, 1, 3)
            .run(Models::Config(&config))
            .unwrap();
        assert_eq!(
            report.per_condition.keys().collect::<Vec<_>>(),
            ["G1", "G2", "G3"]
        );
        assert_eq!(report.repeats[0].n_test, samples.len());
        assert_eq!(report.repeats[0].sigmas.len(), 3);
        // Issue #35: the counts are summed over the three folds (each draws 8 per class, 3 of them
        // validating), and the words say so, per fold.
        let first = &report.repeats[0];
        assert_eq!(first.folds, 3);
        assert_eq!((first.n_train, first.n_validation), (3 * 4 * 5, 3 * 4 * 3));
        let text = first.counts_text();
        assert!(
            text.starts_with("3 folds, per fold (on average) 20 training + 12 validation images"),
            "{text}"
        );
        assert!(
            text.contains(&format!("{} tested in all", samples.len())),
            "{text}"
        );
        let g2 = evaluation(&samples, &g2_protocol(), 1, 3)
            .run(Models::Config(&config))
            .unwrap();
        assert_eq!(g2.repeats[0].folds, 1);
        assert!(g2.repeats[0].counts_text().ends_with(" tested"));
    }

    #[test]
    fn draws_are_the_sets_the_evaluation_trains_and_tests_on() {
        let data = data();
        let samples = samples(&data);
        let config = paper_config_with_dims(10);
        for protocol in [
            Protocol::LeaveOneOut {
                column: "condition".into(),
                per_class: Some(8),
                validation: ValidationSize::Count(3),
            },
            g2_protocol(),
        ] {
            let evaluation = evaluation(&samples, &protocol, 2, 5);
            let seen = std::sync::Mutex::new(Vec::new());
            let reports = evaluation
                .run_with(&[&samples], &[None], &|fold| {
                    seen.lock().unwrap().push((
                        fold.seed,
                        fold.fold,
                        fold.held_out.map(str::to_owned),
                        fold.train.to_vec(),
                        fold.validation.to_vec(),
                    ));
                    let images = |set: &[usize]| -> Vec<LabeledImage<'_>> {
                        set.iter().map(|&i| samples[i]).collect()
                    };
                    let model = train(&images(fold.train), &images(fold.validation), &config)?;
                    Ok(FoldModel { model, view: 0 })
                })
                .unwrap();
            let draws = evaluation.draws().unwrap();
            let mut seen = seen.into_inner().unwrap();
            // (folds train in parallel: in the draws' order by repeat seed, then place in the repeat)
            seen.sort_by_key(|(seed, fold, ..)| (*seed, *fold));
            assert_eq!(draws.len(), seen.len());
            for (draw, (seed, _, held_out, train_set, validation_set)) in draws.iter().zip(&seen) {
                assert_eq!(
                    (draw.seed, &draw.held_out, &draw.train, &draw.validation),
                    (*seed, held_out, train_set, validation_set)
                );
                // the test set is every sample outside the training pool's draw (leave-one-out: the
                // held-out value's samples)
                for &i in &draw.test {
                    assert!(!draw.train.contains(&i) && !draw.validation.contains(&i));
                    if let Some(held_out) = &draw.held_out {
                        assert_eq!(samples[i].group, Some(held_out.as_str()));
                    }
                }
            }
            for (repeat, result) in reports.0[0].repeats.iter().enumerate() {
                let of_repeat = draws.iter().filter(|d| d.repeat == repeat);
                let n_test: usize = of_repeat.map(|d| d.test.len()).sum();
                assert_eq!(n_test, result.n_test);
            }
            assert_eq!(draws.last().unwrap().repeat, 1);
        }
    }

    #[test]
    fn perturbing_test_images_only_changes_the_tested_accuracy() {
        let data = data();
        let samples = samples(&data);
        let protocol = g2_protocol();
        let config = paper_config_with_dims(20);
        let plain = evaluation(&samples, &protocol, 1, 5)
            .run(Models::Config(&config))
            .unwrap();
        let identity = |_: usize, frame: FrameView<'_>, _: u64| Ok(frame.to_frame());
        let same = evaluation(&samples, &protocol, 1, 5)
            .run_each(Models::Config(&config), &[Some(&identity)])
            .unwrap()
            .reports
            .remove(0);
        assert_eq!(same.confusion, plain.confusion);
        assert_eq!(same.repeats[0].sigmas, plain.repeats[0].sigmas);
        // Blank test images (every sensel dead): the same trained models, chance-level answers.
        let blank = |_: usize, frame: FrameView<'_>, _: u64| Ok(Frame::zeros(frame.grid()));
        let dead = evaluation(&samples, &protocol, 1, 5)
            .run_each(Models::Config(&config), &[Some(&blank)])
            .unwrap()
            .reports
            .remove(0);
        assert_eq!(dead.repeats[0].sigmas, plain.repeats[0].sigmas);
        assert_eq!(dead.repeats[0].n_test, plain.repeats[0].n_test);
        assert!(plain.overall.mean > 0.8, "{}", plain.overall.mean);
        assert!(dead.overall.mean < 0.5, "{}", dead.overall.mean);
    }

    #[test]
    fn several_perturbations_at_once_match_one_at_a_time() {
        let data = data();
        let samples = samples(&data);
        let protocol = g2_protocol();
        let config = paper_config_with_dims(20);
        let noise = crate::perturb::Perturbation::Noise(20.0);
        let noisy =
            |i: usize, frame: FrameView<'_>, seed: u64| Ok(noise.apply(frame, seed, i as u64));
        let blank = |_: usize, frame: FrameView<'_>, _: u64| Ok(Frame::zeros(frame.grid()));
        let perturbs: [Option<&TestTransform<'_>>; 3] = [None, Some(&noisy), Some(&blank)];
        let calls = std::sync::atomic::AtomicUsize::new(0);
        let tick = || {
            calls.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        };
        let each = Evaluation {
            progress: &tick,
            ..evaluation(&samples, &protocol, 2, 5)
        }
        .run_each(Models::Config(&config), &perturbs)
        .unwrap()
        .reports;
        assert_eq!(
            calls.into_inner(),
            2,
            "one model per repeat, whatever the perturbations"
        );
        for (report, perturb) in each.iter().zip(perturbs) {
            let alone = evaluation(&samples, &protocol, 2, 5)
                .run_each(Models::Config(&config), &[perturb])
                .unwrap()
                .reports
                .remove(0);
            assert_eq!(report.confusion, alone.confusion);
            assert_eq!(report.overall, alone.overall);
            assert_eq!(report.per_condition, alone.per_condition);
        }
        assert!(each[2].overall.mean < each[0].overall.mean);
    }

    #[test]
    fn a_perturbed_image_that_cannot_be_classified_is_a_wrong_answer_not_an_abort() {
        let data = data();
        let samples = samples(&data);
        let protocol = g2_protocol();
        let config = paper_config_with_dims(20);
        let huge = crate::perturb::Perturbation::Load(1e308);
        let heavy =
            |i: usize, frame: FrameView<'_>, seed: u64| Ok(huge.apply(frame, seed, i as u64));
        // Every other test image is made unclassifiable (values saturated at f64::MAX); the rest stay.
        let half = |i: usize, frame: FrameView<'_>, seed: u64| {
            Ok(if i % 2 == 0 {
                huge.apply(frame, seed, i as u64)
            } else {
                frame.to_frame()
            })
        };
        let perturbs: [Option<&TestTransform<'_>>; 3] = [None, Some(&heavy), Some(&half)];
        let reports = evaluation(&samples, &protocol, 1, 5)
            .run_each(Models::Config(&config), &perturbs)
            .unwrap()
            .reports;
        let (plain, heavy, half) = (&reports[0], &reports[1], &reports[2]);
        let n_test = plain.repeats[0].n_test as u64;
        let counted = |r: &EvalReport| r.confusion.counts.iter().flatten().sum::<u64>();
        let hits = |r: &EvalReport| (0..4).map(|i| r.confusion.counts[i][i]).sum::<u64>();
        assert_eq!(plain.unclassified, 0);
        assert_eq!(
            heavy.unclassified, n_test,
            "no image that large can be classified"
        );
        assert_eq!(counted(heavy), 0);
        assert_eq!(heavy.overall.mean, 0.0);
        let even = samples.len() as u64 / 2;
        assert!(half.unclassified > 0 && half.unclassified <= even);
        assert_eq!(counted(half) + half.unclassified, n_test);
        // The unclassified images count as wrong answers: accuracy over every tested image.
        let accuracy = hits(half) as f64 / n_test as f64;
        assert!((half.overall.mean - accuracy).abs() < 1e-12);
        assert!(half.overall.mean < plain.overall.mean);
    }

    #[test]
    fn automatic_choice_trains_every_fold_on_its_own_and_records_each_selection() {
        let data = data();
        let samples = samples(&data);
        let protocol = Protocol::LeaveOneOut {
            column: "condition".into(),
            per_class: Some(8),
            validation: ValidationSize::Count(3),
        };
        let candidates = [paper_config_with_dims(5), paper_config_with_dims(10)];
        let run = evaluation(&samples, &protocol, 2, 7)
            .run_each(
                Models::Auto(crate::selection::AutoChoice::new(
                    &candidates,
                    crate::selection::ValidateBy::Auto,
                )),
                &[None],
            )
            .unwrap();
        // one model per held-out value and repeat, each with its selection
        assert_eq!(run.selections.len(), 3 * 2);
        for selection in &run.selections {
            assert_eq!(selection.scores.len(), candidates.len());
            assert!(selection.chosen().is_some());
        }
        // the same draws as a fixed configuration: every sample tested once per repeat
        let report = &run.reports[0];
        assert_eq!(report.repeats[0].n_test, samples.len());
        let total: u64 = report.confusion.counts.iter().flatten().sum();
        assert_eq!(total as usize, 2 * samples.len());
        // `run` is `run_each` on the images as they are
        let alone = evaluation(&samples, &protocol, 2, 7)
            .run(Models::Auto(crate::selection::AutoChoice::new(
                &candidates,
                crate::selection::ValidateBy::Auto,
            )))
            .unwrap();
        assert_eq!(alone.confusion, report.confusion);
        assert_eq!(alone.per_condition, report.per_condition);
    }

    /// Each fold's model may read another view of the same units: a fold tested in view `k` scores what
    /// an evaluation of view `k` alone scores on that fold (the same draws), and views of other units
    /// are refused.
    #[test]
    fn each_fold_is_tested_in_the_view_its_model_reads() {
        let (plain, other) = (data(), data_seeded(12));
        let (plain, other) = (samples(&plain), samples(&other));
        let protocol = Protocol::LeaveOneOut {
            column: "condition".into(),
            per_class: Some(8),
            validation: ValidationSize::Count(3),
        };
        let config = paper_config_with_dims(10);
        let views: [&[LabeledImage<'_>]; 2] = [&plain, &other];
        let (report, first) = evaluation(&plain, &protocol, 2, 3)
            .run_views(&views, &|fold| {
                let view = usize::from(fold.held_out == Some("G1"));
                let images = |set: &[usize]| -> Vec<LabeledImage<'_>> {
                    set.iter().map(|&i| views[view][i]).collect()
                };
                let model = train(&images(fold.train), &images(fold.validation), &config)?;
                Ok(FoldModel { model, view })
            })
            .unwrap();
        let alone = |samples: &[LabeledImage<'_>]| {
            evaluation(samples, &protocol, 2, 3)
                .run(Models::Config(&config))
                .unwrap()
        };
        let (plain_alone, other_alone) = (alone(&plain), alone(&other));
        assert_eq!(report.per_condition["G1"], other_alone.per_condition["G1"]);
        for held_out in ["G2", "G3"] {
            assert_eq!(
                report.per_condition[held_out],
                plain_alone.per_condition[held_out]
            );
        }
        assert_ne!(
            plain_alone.per_condition["G1"],
            other_alone.per_condition["G1"]
        );
        assert_eq!(first.unwrap().held_out.as_deref(), Some("G1"));
        // another unit order, or fewer units: refused before any training
        let mut swapped = other.clone();
        swapped.swap(0, 1);
        let fewer = &other[1..];
        for bad in [&swapped[..], fewer] {
            let err = evaluation(&plain, &protocol, 1, 3)
                .run_views(&[&plain, bad], &|_| {
                    unreachable!("trained on mismatched views")
                })
                .unwrap_err();
            assert!(err.to_string().contains("in reading 1"), "{err}");
        }
    }

    #[test]
    fn mean_std_and_confusion_metrics() {
        let m = MeanStd::of(&[1.0, 0.0]);
        assert!((m.mean - 0.5).abs() < 1e-15 && (m.std - 0.5f64.sqrt()).abs() < 1e-15);
        let c = Confusion {
            labels: vec!["a".into(), "b".into()],
            counts: vec![vec![3, 1], vec![0, 4]],
        };
        assert_eq!(c.recall(), vec![0.75, 1.0]);
        assert_eq!(c.precision(), vec![1.0, 0.8]);
        assert_eq!(c.row_normalised()[0], vec![0.75, 0.25]);
    }
}
