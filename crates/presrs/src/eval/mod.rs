//! Evaluation protocols on a data set: the set-up (labels, held-out column, draws), a fixed method or
//! the automatic choice, every method side by side, and accuracy with perturbed test images. Progress
//! goes to a [`Progress`]; errors name the manifest.

pub mod document;
pub mod early;
pub mod novelty;
pub mod race;

use std::collections::BTreeMap;

use presrs_core::evaluation::{
    ComparisonRow, Draw, EvalReport, Evaluated, Evaluation, Models, Protocol, TestTransform,
};
use presrs_core::perturb::Perturbation;
use presrs_core::pipeline::LabeledImage;
use presrs_core::reliability::Reliability;
use presrs_core::split::ValidationSize;
use presrs_core::{CheckedTrainConfig, CoreError};
use serde::Serialize;

use crate::dataset::Dataset;
use crate::error::{Context, Error, Result};
use crate::method::{ClassifierChoice, Method};
use crate::progress::Progress;
use presrs_io::message::{Message, Opt, Warnings};

/// Which images train and which test.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Holdout {
    /// Train on a random draw (from this condition only, when given), test on every other sample: the
    /// paper's protocol.
    TrainCondition(Option<String>),
    /// Hold out each value of this manifest column in turn (`group`, `condition`, `path`, or an extra
    /// column; not `label`).
    LeaveOneOut(String),
}

impl Holdout {
    /// The protocol in a few words: `trained on G2`, `leave one group out`, `random draw`.
    pub fn describe(&self) -> String {
        match self {
            Self::LeaveOneOut(column) => format!("leave one {column} out"),
            Self::TrainCondition(Some(condition)) => format!("trained on {condition}"),
            Self::TrainCondition(None) => "random draw".to_owned(),
        }
    }
}

impl Holdout {
    /// The protocol when none is asked for (`presrs report`'s; `presrs eval` and `presrs.evaluate`
    /// without a per-class draw): trained on G2 on data with a G2 condition (the simulator's, the
    /// paper's protocol); else leave one group out when every sample has a group and there are two or
    /// more (a person, a trial, a session: the same one never in training and test); else a random
    /// draw from every condition.
    pub fn default_for(dataset: &Dataset) -> Self {
        let has = |condition: &str| {
            dataset
                .samples
                .iter()
                .any(|s| s.condition.as_deref() == Some(condition))
        };
        if has("G2") {
            return Self::TrainCondition(Some("G2".to_owned()));
        }
        let groups: std::collections::BTreeSet<&str> = dataset
            .samples
            .iter()
            .filter_map(|s| s.group.as_deref())
            .collect();
        if groups.len() >= 2 && dataset.samples.iter().all(|s| s.group.is_some()) {
            Self::LeaveOneOut("group".to_owned())
        } else {
            Self::TrainCondition(None)
        }
    }

    /// The protocol of `presrs eval` and `presrs.evaluate`, decided before any training: as asked
    /// (`leave_one_out` or `train_condition`); else, with a per-class draw, a random draw tested on the
    /// rest; else (a draw of every image would leave none to test on) [`default_for`](Self::default_for).
    pub fn resolve(
        dataset: &Dataset,
        leave_one_out: Option<String>,
        train_condition: Option<String>,
        per_class: Option<usize>,
    ) -> Self {
        match (leave_one_out, train_condition) {
            (Some(column), _) => Self::LeaveOneOut(column),
            (None, Some(condition)) => Self::TrainCondition(Some(condition)),
            (None, None) if per_class.is_some() => Self::TrainCondition(None),
            (None, None) => Self::default_for(dataset),
        }
    }
}

/// How an evaluation is run.
#[derive(Clone, Debug, PartialEq)]
pub struct EvalOptions {
    pub holdout: Holdout,
    /// Images drawn per class for training + validation (`None`: all available).
    pub per_class: Option<usize>,
    pub validation: ValidationSize,
    /// Repeats with seeds `seed`, `seed + 1`, ...
    pub repeats: usize,
    pub seed: u64,
    pub method: Method,
}

impl Default for EvalOptions {
    fn default() -> Self {
        Self {
            holdout: Holdout::TrainCondition(None),
            per_class: None,
            validation: ValidationSize::Fraction(0.35),
            repeats: 10,
            seed: 1,
            method: Method::default(),
        }
    }
}

/// A data set ready to evaluate: its labelled samples, the protocol, and what the set-up found.
#[derive(Debug)]
pub struct EvalSetup<'d> {
    dataset: &'d Dataset,
    samples: Vec<LabeledImage<'d>>,
    protocol: Protocol,
    options: EvalOptions,
    /// Test labels no training set can hold, by held-out value (`labels_never_trained`).
    pub never_trained: BTreeMap<String, Vec<String>>,
    /// What the user should know before the run (labels that cannot be recognised).
    pub warnings: Warnings,
}

/// The outcome of [`EvalSetup::evaluate`].
#[derive(Clone, Debug)]
pub struct EvalOutcome {
    pub report: EvalReport,
    /// The automatic choice of every trained model (empty for a fixed method).
    pub selections: Vec<presrs_core::selection::Selection>,
    /// What the user should know (fewer principal components than asked).
    pub warnings: Warnings,
    /// The first model trained (first repeat, first fold), as a report shows it.
    pub first_model: Option<presrs_core::evaluation::FirstModel>,
    /// With `--sample auto`, every fold's race of the sample kinds, in the draws' order
    /// (`crate::eval::race`); empty otherwise.
    pub sample_races: Vec<crate::train::sample_race::FoldRace>,
}

/// What the automatic choice expected of its chosen candidates, inside the training data: to set next
/// to the test result, to see how honest its validation was.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct InternalEstimate {
    /// Mean and spread over the trained models of the chosen candidate's validation accuracy.
    pub accuracy: presrs_core::metrics::MeanStd,
    /// How the candidates were validated (the first model's words).
    pub validated_by: String,
    /// Models it is the mean of.
    pub models: usize,
}

impl EvalOutcome {
    /// The automatic choice's own estimate, over every trained model (`None` for a fixed method).
    pub fn internal_estimate(&self) -> Option<InternalEstimate> {
        let chosen: Vec<f64> = self
            .selections
            .iter()
            .filter_map(|s| s.chosen().map(|c| c.accuracy.mean))
            .collect();
        let first = self.selections.first()?;
        Some(InternalEstimate {
            accuracy: presrs_core::metrics::MeanStd::of(&chosen),
            validated_by: first.method.clone(),
            models: chosen.len(),
        })
    }
}

/// An error, before any training, when the protocol's draw would take every sample for training and
/// leave none to test on; it names the options that leave some.
fn nothing_to_test(
    dataset: &Dataset,
    samples: &[LabeledImage<'_>],
    protocol: &Protocol,
    options: &EvalOptions,
) -> Result<()> {
    let noop = || {};
    let evaluation = Evaluation {
        samples,
        protocol,
        repeats: 1,
        seed: options.seed,
        progress: &noop,
    };
    // (a draw that fails says why when the evaluation runs)
    let Ok(draws) = evaluation.draws() else {
        return Ok(());
    };
    if draws.iter().any(|draw| !draw.test.is_empty()) {
        return Ok(());
    }
    let drawn = match options.per_class {
        Some(per_class) => Message::new()
            .opt_is(Opt::PerClass, per_class)
            .text(" draws every image of every class"),
        None => Message::from("without ")
            .opt(Opt::PerClass)
            .text(", the draw takes every image"),
    };
    let condition = match &options.holdout {
        Holdout::TrainCondition(Some(condition)) => format!(" of condition {condition}"),
        _ => String::new(),
    };
    Err(Error::data(
        Message::from(format!(
            "{}: no image would be left to test on: ",
            dataset.path().display()
        ))
        .then(drawn)
        .text(format!(
            "{condition} for training; hold each group out in turn with "
        ))
        .opt_text(Opt::LeaveOneOut, "group")
        .text(" (given a group in every row) or another column, train on one condition and test on the others with ")
        .opt(Opt::TrainCondition)
        .text(", or draw fewer images per class with ")
        .opt(Opt::PerClass),
    ))
}

/// Accuracy of one method with the test images perturbed.
#[derive(Clone, Debug, Serialize)]
pub struct PerturbationRow {
    /// `KIND=LEVEL`, or `none` for the unperturbed test images.
    pub perturbation: String,
    /// `configured` (the method asked for) or `paper` (fft1d + pwe, shown next to an automatic choice).
    pub method: &'static str,
    pub accuracy: f64,
    pub accuracy_std: f64,
    /// Perturbed test images (summed over repeats) that could not be classified at all, e.g. values
    /// driven to infinity; each is counted as a wrong answer in `accuracy`.
    pub unclassified: u64,
}

impl<'d> EvalSetup<'d> {
    /// Checks the data set against the options (labels everywhere, the held-out column present and
    /// filled) and finds the labels that no training set can hold.
    pub fn new(dataset: &'d Dataset, options: &EvalOptions) -> Result<Self> {
        let name = dataset.path().display();
        dataset.require_labels("evaluation needs a label for every sample")?;
        let column = match &options.holdout {
            Holdout::LeaveOneOut(column) => Some(column.as_str()),
            Holdout::TrainCondition(_) => None,
        };
        if let Some(column) = column
            && !dataset.manifest.has_column(column)
        {
            return Err(Error::data(
                Message::from(format!("{name}: "))
                    .opt_text(Opt::LeaveOneOut, column)
                    .text(format!(
                        ": the manifest has no such column (columns: {})",
                        dataset.manifest.columns.join(", ")
                    )),
            ));
        }
        // Too few samples of a class for the draws: the real cause of any later complaint about the
        // validation set, so said first (with why files gave none).
        let needs_validation = options.per_class.is_some()
            || matches!(options.validation, ValidationSize::Count(count) if count > 0)
            || options
                .method
                .check_validation_set(options.validation, 0)
                .is_err();
        let training_condition = match &options.holdout {
            Holdout::TrainCondition(condition) => condition.as_deref(),
            Holdout::LeaveOneOut(_) => None,
        };
        let need = presrs_core::split::min_samples_per_class(options.per_class, options.validation);
        if needs_validation && let Some(cause) = dataset.too_few_samples(training_condition, need) {
            return Err(Error::data(
                Message::from(format!("{name}: cannot evaluate: ")).then(cause),
            ));
        }
        let mut samples = Vec::with_capacity(dataset.samples.len());
        for sample in &dataset.samples {
            let label = sample.label.as_deref().ok_or_else(|| {
                Error::data(format!(
                    "{}: field `label` is empty; evaluation needs a label for every sample",
                    sample.origin(dataset.path())
                ))
            })?;
            let group = match column {
                Some(column) => Some(sample.column(column).ok_or_else(|| {
                    Error::data(
                        Message::from(format!(
                            "{}: field `{column}` is empty; ",
                            sample.origin(dataset.path())
                        ))
                        .opt(Opt::LeaveOneOut)
                        .text(" needs a value in every row"),
                    )
                })?),
                // The automatic choice validates by the manifest's groups.
                None => sample.group.as_deref(),
            };
            samples.push(LabeledImage {
                frame: sample.frame.view(),
                label,
                condition: sample.condition.as_deref(),
                group,
            });
        }
        let protocol = match &options.holdout {
            Holdout::LeaveOneOut(column) => Protocol::LeaveOneOut {
                column: column.clone(),
                per_class: options.per_class,
                validation: options.validation,
            },
            Holdout::TrainCondition(condition) => Protocol::TrainCondition {
                condition: condition.clone(),
                per_class: options.per_class,
                validation: options.validation,
            },
        };
        nothing_to_test(dataset, &samples, &protocol, options)?;
        let never_trained = presrs_core::evaluation::labels_never_trained(&samples, &protocol);
        let mut warnings: Warnings = never_trained
            .iter()
            .map(|(held_out, labels)| {
                let tested = match column {
                    Some(column) => format!("with {column} {held_out} held out, its"),
                    None => "the".to_owned(),
                };
                format!(
                    "{name}: {tested} test images labelled {} cannot be recognised: no training image \
                     has that label",
                    labels.join(", ")
                )
            })
            .collect();
        let capped = presrs_core::evaluation::per_class_capped(&samples, &protocol);
        if let Some(per_class) = options.per_class
            && !capped.is_empty()
        {
            let held = column.is_some();
            warnings.push(Message::from(format!("{name}: ")).then(
                crate::train::per_class_warning(
                    per_class,
                    capped.iter().flat_map(|(held_out, classes)| {
                        classes.iter().map(move |(class, &n)| {
                            (held.then_some(held_out.as_str()), class.as_str(), n)
                        })
                    }),
                ),
            ));
        }
        Ok(Self {
            dataset,
            samples,
            protocol,
            options: options.clone(),
            never_trained,
            warnings,
        })
    }

    /// Models trained per repeat: one, or one per held-out value.
    pub fn folds(&self) -> usize {
        self.protocol.models_per_repeat(&self.samples)
    }

    /// The labelled samples as the evaluation engine sees them.
    pub fn samples(&self) -> &[LabeledImage<'d>] {
        &self.samples
    }

    pub fn protocol(&self) -> &Protocol {
        &self.protocol
    }

    /// The data set evaluated.
    pub fn dataset(&self) -> &'d Dataset {
        self.dataset
    }

    /// Evaluates the options' method (a fixed one, or the automatic choice in every fold).
    pub fn evaluate(&self, progress: &dyn Progress) -> Result<EvalOutcome> {
        let method = &self.options.method;
        if self.options.validation == ValidationSize::Count(0) {
            method
                .check_validation_set(self.options.validation, 0)
                .with_context(|| format!("{}: cannot evaluate", self.dataset.path().display()))?;
        }
        let grid = self.samples[0].frame.grid();
        let config = method.train_config(grid)?;
        let candidates = if method.is_auto() {
            method.candidates_for(
                grid,
                false,
                &self.dataset.sample,
                crate::method::race_draws_for(self.samples.len()),
            )?
        } else {
            Vec::new()
        };
        let tell = |stage: &str| progress.stage(stage);
        let models = match models(method, &config, &candidates) {
            Models::Auto(choice) => {
                Models::Auto(choice.with_stages(presrs_core::selection::StageObserver(&tell)))
            }
            fixed => fixed,
        };
        let Evaluated {
            reports,
            selections,
            first_model,
        } = self.run("training", 1, progress, |evaluation| {
            evaluation.run_each(models, &[None])
        })?;
        let report = reports.into_iter().next().ok_or_else(|| {
            Error::data(format!(
                "{}: no evaluation was run",
                self.dataset.path().display()
            ))
        })?;
        let mut warnings = Warnings::new();
        // (one fold per repeat: with leave-one-out, n_train sums the folds)
        if let Some(n_train) = report.repeats.iter().map(|r| r.n_train).min()
            && let Some(dims) = method.dims
            && !matches!(method.classifier, ClassifierChoice::Kind(kind) if kind.takes_all_features())
            && self.folds() == 1
            && dims >= n_train
        {
            warnings.push(Message::new().opt_is(Opt::Dims, dims).text(format!(
                ": models trained on {n_train} images keep at most {} principal components (one \
                 fewer than the training images)",
                n_train.saturating_sub(1)
            )));
        }
        warnings.extend(crate::method::selection_warnings(&selections));
        if !method.is_auto()
            && let Some(first) = &first_model
            && let Some(searched_on) = first.model.summary().searched_on
        {
            warnings.push(Message::from(format!(
                "{}'s hyper-parameters were searched on a stratified subsample of {searched_on} of each \
                 model's training samples (large data), then fitted on all of them, as the automatic \
                 choice's winner is",
                first.model.classifier().kind()
            )));
        }
        Ok(EvalOutcome {
            report,
            selections,
            warnings,
            first_model,
            sample_races: Vec::new(),
        })
    }

    /// Every feature family x classifier with the same draws (the method's crop, dims and
    /// preprocessing).
    pub fn compare(&self, progress: &dyn Progress) -> Result<Vec<ComparisonRow>> {
        let configs = self.options.method.candidates_for(
            self.samples[0].frame.grid(),
            true,
            &self.dataset.sample,
            crate::method::race_draws_for(self.samples.len()),
        )?;
        self.run("comparing", configs.len(), progress, |evaluation| {
            evaluation.compare(&configs)
        })
    }

    /// Accuracy with every test image perturbed by each of `perturbations` (the same seeds, so the same
    /// draws and models as [`evaluate`](Self::evaluate), whose `report` is the unperturbed row); each
    /// model is trained once and tested under every perturbation. Next to an automatic choice the
    /// paper's method is evaluated too, so that both degrade side by side.
    pub fn perturbed(
        &self,
        perturbations: &[Perturbation],
        report: &EvalReport,
        progress: &dyn Progress,
    ) -> Result<Vec<PerturbationRow>> {
        if perturbations.is_empty() {
            return Ok(Vec::new());
        }
        let method = &self.options.method;
        let grid = self.samples[0].frame.grid();
        let (config, paper) = (method.train_config(grid)?, method.paper_config(grid)?);
        let candidates = if method.is_auto() {
            method.candidates_for(
                grid,
                false,
                &self.dataset.sample,
                crate::method::race_draws_for(self.samples.len()),
            )?
        } else {
            Vec::new()
        };
        let models = models(method, &config, &candidates);
        let auto = method.is_auto();
        let transforms: Vec<_> = perturbations.iter().map(Perturbation::transform).collect();
        let mut each: Vec<Option<&TestTransform<'_>>> = vec![None];
        each.extend(transforms.iter().map(|t| Some(t as &TestTransform<'_>)));
        let (configured, paper_reports) = self.run(
            "perturbing",
            1 + usize::from(auto),
            progress,
            |evaluation| {
                let configured = evaluation.run_each(models, &each[1..])?.reports;
                let paper = if auto {
                    evaluation.run_each(Models::Config(&paper), &each)?.reports
                } else {
                    Vec::new()
                };
                Ok((configured, paper))
            },
        )?;
        let row = |perturbation: String, method, r: &EvalReport| PerturbationRow {
            perturbation,
            method,
            accuracy: r.overall.mean,
            accuracy_std: r.overall.std,
            unclassified: r.unclassified,
        };
        let mut rows = vec![row("none".to_owned(), "configured", report)];
        if let Some(plain) = paper_reports.first() {
            rows.push(row("none".to_owned(), "paper", plain));
        }
        for (k, p) in perturbations.iter().enumerate() {
            rows.push(row(p.to_string(), "configured", &configured[k]));
            if let Some(r) = paper_reports.get(k + 1) {
                rows.push(row(p.to_string(), "paper", r));
            }
        }
        Ok(rows)
    }

    /// Runs `f` on the engine with progress counted in trained models (`methods` x folds x repeats),
    /// its errors naming the manifest.
    /// The draws [`evaluate`](Self::evaluate) and [`compare`](Self::compare) make (every repeat's
    /// folds: training, validation and test indices into [`samples`](Self::samples)).
    pub fn draws(&self) -> Result<Vec<Draw>> {
        let noop = || {};
        Evaluation {
            samples: &self.samples,
            protocol: &self.protocol,
            repeats: self.options.repeats,
            seed: self.options.seed,
            progress: &noop,
        }
        .draws()
        .with_context(|| self.dataset.path().display().to_string())
    }

    /// Writes into `dir` (created if needed) the samples as the evaluation sees them and its draws, so
    /// that another implementation can be evaluated on the same images with the same training and test
    /// sets: `images.npy` (samples x rows x cols, f64, absent sensels as 0) and `draws.json` (each
    /// sample's label, condition and group, and every repeat's folds as indices into the samples).
    pub fn export_draws(&self, dir: &std::path::Path) -> Result<()> {
        let grid = self.samples[0].frame.grid();
        let mut images = Vec::with_capacity(self.samples.len() * grid.len());
        for (i, sample) in self.samples.iter().enumerate() {
            let frame = sample.frame;
            if frame.grid() != grid {
                return Err(Error::data(format!(
                    "{}: sample {i} is {}x{}, the first {}x{}: the samples of one export share a size",
                    self.dataset.path().display(),
                    frame.grid().rows,
                    frame.grid().cols,
                    grid.rows,
                    grid.cols
                )));
            }
            frame.extend_absent_as_zero(&mut images);
        }
        let draws = self.draws()?;
        std::fs::create_dir_all(dir)?;
        presrs_io::atomic::write_atomic(&dir.join("images.npy"), |w| {
            presrs_io::npy::write_npy_f64(w, &[self.samples.len(), grid.rows, grid.cols], &images)
        })?;
        let document = DrawsExport {
            format: "presrs-eval-draws",
            presrs_version: env!("CARGO_PKG_VERSION"),
            manifest: self.dataset.path().display().to_string(),
            images: "images.npy",
            labels: self.samples.iter().map(|s| s.label).collect(),
            conditions: self.samples.iter().map(|s| s.condition).collect(),
            groups: self.samples.iter().map(|s| s.group).collect(),
            draws,
        };
        presrs_io::atomic::write_atomic(&dir.join("draws.json"), |w| {
            serde_json::to_writer(&mut *w, &document).map_err(std::io::Error::from)?;
            std::io::Write::write_all(w, b"\n")
        })?;
        Ok(())
    }

    fn run<T>(
        &self,
        task: &str,
        methods: usize,
        progress: &dyn Progress,
        f: impl FnOnce(&Evaluation<'_, 'd>) -> presrs_core::error::Result<T>,
    ) -> Result<T> {
        run_counted(
            &self.samples,
            &self.protocol,
            (self.options.repeats, self.options.seed),
            (task, (methods * self.folds() * self.options.repeats) as u64),
            progress,
            f,
        )
        .with_context(|| self.dataset.path().display().to_string())
    }
}

/// `draws.json` of [`EvalSetup::export_draws`].
#[derive(Serialize)]
struct DrawsExport<'s> {
    format: &'static str,
    presrs_version: &'static str,
    manifest: String,
    images: &'static str,
    labels: Vec<&'s str>,
    conditions: Vec<Option<&'s str>>,
    groups: Vec<Option<&'s str>>,
    draws: Vec<Draw>,
}

/// The models each fold trains: the configuration, or the automatic choice among `candidates`.
fn models<'c>(
    method: &Method,
    config: &'c CheckedTrainConfig,
    candidates: &'c [CheckedTrainConfig],
) -> Models<'c> {
    if method.is_auto() {
        Models::Auto(method.auto_choice(candidates))
    } else {
        Models::Config(config)
    }
}

/// Runs `f` on an evaluation of `samples` under `protocol` (`repeats`, `seed`), reporting one step of
/// `task` (announced with `total` steps) per trained model.
pub fn run_counted<'s, T>(
    samples: &[LabeledImage<'s>],
    protocol: &Protocol,
    (repeats, seed): (usize, u64),
    (task, total): (&str, u64),
    progress: &dyn Progress,
    f: impl FnOnce(&Evaluation<'_, 's>) -> std::result::Result<T, CoreError>,
) -> std::result::Result<T, CoreError> {
    progress.start(task, Some(total));
    let evaluation = Evaluation {
        samples,
        protocol,
        repeats,
        seed,
        progress: &|| progress.advance(1),
    };
    let result = f(&evaluation);
    progress.finish();
    result
}

/// The confidences of the tested images against whether they were right (`null` where no image counts).
#[derive(Clone, Debug, Serialize)]
pub struct CalibrationJson {
    pub mean_confidence: Option<f64>,
    pub mean_confidence_right: Option<f64>,
    pub mean_confidence_wrong: Option<f64>,
    /// Count-weighted mean over ten confidence bins of |accuracy - mean confidence| (0: calibrated).
    pub expected_calibration_error: Option<f64>,
}

impl CalibrationJson {
    pub fn new(reliability: &Reliability) -> Self {
        Self {
            mean_confidence: reliability.mean_confidence(),
            mean_confidence_right: reliability.mean_confidence_right(),
            mean_confidence_wrong: reliability.mean_confidence_wrong(),
            expected_calibration_error: reliability.expected_calibration_error(),
        }
    }
}

/// One line on how far the confidences can be trusted, or `None` when nothing was classified.
pub fn calibration_line(reliability: &Reliability) -> Option<String> {
    let (Some(mean), Some(accuracy), Some(error)) = (
        reliability.mean_confidence(),
        reliability.accuracy(),
        reliability.expected_calibration_error(),
    ) else {
        return None;
    };
    let side = |value: Option<f64>, what: &str| {
        value.map_or_else(String::new, |v| format!(", {v:.2} when {what}"))
    };
    let verdict = if error < 0.05 {
        "calibrated"
    } else if mean < accuracy {
        "under-confident: right more often than it says"
    } else {
        "over-confident: right less often than it says"
    };
    Some(format!(
        "confidence: mean {mean:.2}{}{}; right {:.1} % of the time; calibration error {error:.3} ({verdict})",
        side(reliability.mean_confidence_right(), "right"),
        side(reliability.mean_confidence_wrong(), "wrong"),
        100.0 * accuracy,
    ))
}
