//! Training from a data set: the draw (condition, per class, validation share, seed), a fixed method or
//! the automatic choice, the model file with its provenance, and the online profile.

pub mod early;
pub mod profile;
pub mod sample_race;

use std::borrow::Cow;
use std::collections::BTreeMap;
use std::path::Path;

use presrs_core::TrainedModel;
use presrs_core::online::OnlineProfile;
use presrs_core::pipeline::LabeledImage;
use presrs_core::split::{Split, ValidationSize, min_samples_per_class, stratified_split_capped};
use presrs_core::stance::{ValidSegmentParams, segment};
use presrs_io::message::{Message, Opt, Warnings};
use presrs_io::model_file::{DeadSenselProvenance, ModelFile, Provenance};

use crate::dataset::{
    Dataset, MovieLoad, Sample, SampleKind, SampleOptions, read_movie_loads, sample_labels,
};
use crate::error::{Context, Error, Result};
use crate::method::Method;

/// What to train on and how.
#[derive(Clone, Debug, PartialEq)]
pub struct TrainOptions {
    /// Train only on samples of this condition (the manifest's `condition` column, e.g. a gait).
    pub condition: Option<String>,
    /// Random samples drawn per class (`None`: every sample).
    pub per_class: Option<usize>,
    /// Of those, how many per class validate the hyper-parameters.
    pub validation: ValidationSize,
    /// Seed of the random draw and of the automatic choice's folds.
    pub seed: u64,
    pub method: Method,
    /// Fit the novelty score, so that a sample far from every class is decided `unknown` (false:
    /// `--novelty off`, every decision one of the classes).
    pub novelty: bool,
}

impl Default for TrainOptions {
    fn default() -> Self {
        Self {
            condition: None,
            per_class: None,
            validation: ValidationSize::Fraction(0.35),
            seed: 1,
            method: Method::default(),
            novelty: true,
        }
    }
}

/// A trained model and the draw it was trained on.
#[derive(Clone, Debug)]
pub struct Training {
    pub model: TrainedModel,
    /// Training and validation images per label.
    pub train_counts: BTreeMap<String, usize>,
    pub validation_counts: BTreeMap<String, usize>,
    /// What the user should know (fewer principal components than asked).
    pub warnings: Warnings,
    /// Seconds spent fitting the novelty score after the model (outside the automatic choice's
    /// budget); `None` when none was asked for.
    pub novelty_seconds: Option<f64>,
}

impl Training {
    /// Training images (without the validation ones).
    pub fn n_train(&self) -> usize {
        self.train_counts.values().sum()
    }

    /// Validation images.
    pub fn n_validation(&self) -> usize {
        self.validation_counts.values().sum()
    }

    /// The model file: the model with where it came from (`command` is the command line that made it,
    /// when there is one).
    pub fn model_file(
        &self,
        dataset: &Dataset,
        options: &TrainOptions,
        dead_sensels_corrected: bool,
        command: Option<String>,
    ) -> ModelFile {
        let provenance = Provenance {
            manifest: Some(dataset.path().display().to_string()),
            manifest_sha256: Some(dataset.manifest.sha256.clone()),
            seed: Some(options.seed),
            train_condition: options.condition.clone(),
            train_counts: self.train_counts.clone(),
            validation_counts: self.validation_counts.clone(),
            command,
            created_unix_s: std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .ok()
                .map(|d| d.as_secs()),
            dead_sensels: Some(DeadSenselProvenance {
                corrected: dead_sensels_corrected,
                sensels: dataset.dead_sensels.sensels(),
                recordings: dataset.dead_sensels.recordings.len(),
            }),
        };
        ModelFile::new(self.model.clone(), provenance)
    }
}

/// Trains on `dataset` as `options` say: a stratified draw from the condition's samples, then the fixed
/// method, or the automatic choice validated inside the training data (across its conditions when it
/// spans several).
pub fn train(dataset: &Dataset, options: &TrainOptions) -> Result<Training> {
    train_with_progress(dataset, options, &crate::progress::Quiet)
}

/// [`train`], telling `progress` which stage runs ([`Progress::stage`]: the automatic choice's
/// features, scoring and training the winner, then the novelty score).
///
/// [`Progress::stage`]: crate::progress::Progress::stage
pub fn train_with_progress(
    dataset: &Dataset,
    options: &TrainOptions,
    progress: &dyn crate::progress::Progress,
) -> Result<Training> {
    let name = dataset.path().display().to_string();
    dataset.require_labels("training needs a label for every sample")?;
    let pool: Vec<&Sample> = dataset.of_condition(options.condition.as_deref())?;
    let labels = sample_labels(
        dataset.path(),
        &pool,
        "training needs a label for every sample",
    )?;
    let method = &options.method;
    let split =
        stratified_split_capped(&labels, options.per_class, options.validation, options.seed);
    let validation_check = split
        .as_ref()
        .map(|split| method.check_validation_set(options.validation, split.validation.len()));
    // When the draw or its validation set fails, too few samples of a class is the real cause, if
    // it is one: say that first (with why files gave none).
    if !matches!(validation_check, Ok(Ok(()))) {
        let need = min_samples_per_class(options.per_class, options.validation);
        if let Some(cause) = dataset.too_few_samples_to_train(options.condition.as_deref(), need) {
            return Err(Error::data(
                Message::from(format!("{name}: cannot train: ")).then(cause),
            ));
        }
    }
    let split = split.with_context(|| format!("{name}: cannot draw the training set"))?;
    method
        .check_validation_set(options.validation, split.validation.len())
        .with_context(|| format!("{name}: cannot train"))?;
    let grid = pool[0].frame.grid();
    let (train_images, validation_images) = split_images(&split, |i| LabeledImage {
        frame: pool[i].frame.view(),
        label: labels[i],
        condition: pool[i].condition.as_deref(),
        group: pool[i].group.as_deref(),
    });
    let model = if method.is_auto() {
        let candidates = method.candidates_for(
            grid,
            false,
            &dataset.sample,
            crate::method::race_draws_for(pool.len()),
        )?;
        let tell = |stage: &str| progress.stage(stage);
        presrs_core::selection::train_auto(
            &train_images,
            &validation_images,
            &method
                .auto_choice(&candidates)
                .with_stages(presrs_core::selection::StageObserver(&tell)),
            options.seed,
        )
    } else {
        let config = method.train_config(grid)?;
        progress.stage(&format!(
            "training {} + {} on {} samples",
            config.config().features.name(),
            config.config().classifier.kind().as_str(),
            train_images.len() + validation_images.len()
        ));
        presrs_core::selection::train_fixed(
            &train_images,
            &validation_images,
            &config,
            Some(presrs_core::selection::SCORING_SAMPLES),
            options.seed,
        )
        .map(|(model, _)| model)
    }
    .and_then(|model| model.with_sample(dataset.sample))
    .map(|model| {
        model
            .with_sensor(dataset.sensor)
            .with_sampling(dataset.sampling.clone())
    });
    let model = match model {
        Ok(model) => model,
        // A class with one sample cannot be fitted: when that is the cause, say it by name.
        Err(err) => match dataset.too_few_samples_to_train(options.condition.as_deref(), 2) {
            Some(cause) => {
                return Err(Error::data(
                    Message::from(format!("{name}: cannot train: ")).then(cause),
                ));
            }
            None => return Err(err).with_context(|| format!("{name}: training failed")),
        },
    };
    let pool_indices: Vec<usize> = (0..dataset.samples.len())
        .filter(|&i| {
            options
                .condition
                .as_deref()
                .is_none_or(|condition| dataset.samples[i].condition.as_deref() == Some(condition))
        })
        .collect();
    let model = early::with_early_decisions(
        model,
        (dataset, method),
        (&pool_indices, &split, &labels),
        options.seed,
        progress,
    )?;
    let mut warnings = Warnings::new();
    warnings.extend(early::rule_validation_warning(&model));
    let novelty_started = std::time::Instant::now();
    let model = if options.novelty {
        progress.stage(&format!(
            "fitting the novelty score on {} samples",
            train_images.len() + validation_images.len()
        ));
        let recordings: Vec<&Sample> = split
            .train
            .iter()
            .chain(&split.validation)
            .map(|&i| pool[i])
            .collect();
        with_novelty(
            model,
            (&train_images, &validation_images),
            &recordings,
            &mut warnings,
        )
    } else {
        model
    };
    let novelty_seconds = options
        .novelty
        .then(|| novelty_started.elapsed().as_secs_f64());
    if let Some(per_class) = options.per_class
        && !split.capped.is_empty()
    {
        warnings.push(per_class_warning(
            per_class,
            split
                .capped
                .iter()
                .map(|(class, &n)| (None, class.as_str(), n)),
        ));
    }
    let selections = model.selection().cloned();
    warnings.extend(crate::method::selection_warnings(selections.as_slice()));
    if let Some(dims) = method.dims
        && let Some(kept) = model.pca().map(|pca| pca.n_components())
        && kept < dims
    {
        warnings.push(Message::new().opt_is(Opt::Dims, dims).text(format!(
            ": kept {kept} principal components, the most that {} training images of {} features \
             allow (at most one fewer than the training images, and no more than the features)",
            split.train.len(),
            model.n_features()
        )));
    }
    let count = |indices: &[usize]| {
        let mut counts = BTreeMap::new();
        for &i in indices {
            *counts.entry(labels[i].to_owned()).or_insert(0) += 1;
        }
        counts
    };
    Ok(Training {
        model,
        train_counts: count(&split.train),
        validation_counts: count(&split.validation),
        warnings,
        novelty_seconds,
    })
}

/// `model` with its novelty score fitted on its training and validation images (`samples`, in the
/// same order), calibrated by leaving out their groups ([`calibration_groups`]); without one, and a
/// warning saying why, when it cannot be fitted.
fn with_novelty(
    model: TrainedModel,
    (train_images, validation_images): (&[LabeledImage<'_>], &[LabeledImage<'_>]),
    samples: &[&Sample],
    warnings: &mut Warnings,
) -> TrainedModel {
    let all: Vec<LabeledImage<'_>> = train_images
        .iter()
        .chain(validation_images)
        .copied()
        .collect();
    match with_novelty_by_recordings(model.clone(), &all, samples) {
        Ok(scored) => scored,
        Err(err) => {
            warnings.push(Message::from(format!(
                "no novelty score (the model will never decide unknown): {err}"
            )));
            model
        }
    }
}

/// `model` with its novelty score fitted on `images` (from `samples`, in the same order), calibrated
/// by leaving out their [`calibration_groups`].
pub(crate) fn with_novelty_by_recordings(
    model: TrainedModel,
    images: &[LabeledImage<'_>],
    samples: &[&Sample],
) -> presrs_core::error::Result<TrainedModel> {
    let groups = calibration_groups(samples);
    let groups: Vec<Option<&str>> = groups.iter().map(|g| g.as_deref()).collect();
    model.with_novelty_by(images, &groups, presrs_core::novelty::DEFAULT_REJECTION)
}

/// The groups the novelty threshold is calibrated by leaving out, one per sample: its `group` when
/// every sample has one, else the recording (file) it came from when they come from several (a new
/// recording is what the threshold must accept), else none (samples given in memory).
fn calibration_groups<'a>(samples: &[&'a Sample]) -> Vec<Option<Cow<'a, str>>> {
    if samples.iter().all(|s| s.group.is_some()) {
        return samples
            .iter()
            .map(|s| s.group.as_deref().map(Cow::Borrowed))
            .collect();
    }
    let one_source = samples.windows(2).all(|w| w[0].source == w[1].source);
    samples
        .iter()
        .map(|s| (!one_source).then(|| s.source.to_string_lossy()))
        .collect()
}

/// The one warning line for a per-class count that some classes cannot give: `short` lists (held-out
/// value, class, images it has) and the line names the fewest.
pub fn per_class_warning<'a>(
    per_class: usize,
    short: impl Iterator<Item = (Option<&'a str>, &'a str, usize)>,
) -> Message {
    let short: Vec<_> = short.collect();
    let classes: std::collections::BTreeSet<&str> = short.iter().map(|s| s.1).collect();
    let fewest = short.iter().min_by_key(|s| s.2);
    let fewest = match fewest {
        Some((Some(held_out), class, n)) => {
            format!("; fewest: {n} of class {class} with {held_out} held out")
        }
        Some((None, class, n)) => format!("; fewest: {n} of class {class}"),
        None => String::new(),
    };
    Message::new()
        .opt_is(Opt::PerClass, per_class)
        .text(format!(
            ": capped to the images there are for {} class(es) ({}){fewest}",
            classes.len(),
            classes.into_iter().collect::<Vec<_>>().join(", ")
        ))
}

/// The training and validation images of a draw: `image(i)` is the image at index `i` of what was
/// drawn from.
pub fn split_images<'s>(
    split: &Split,
    image: impl Fn(usize) -> LabeledImage<'s>,
) -> (Vec<LabeledImage<'s>>, Vec<LabeledImage<'s>>) {
    let images = |indices: &[usize]| indices.iter().map(|&i| image(i)).collect();
    (images(&split.train), images(&split.validation))
}

/// Whether `dataset` holds samples taken from movies (a stance's frame past the first): a model trained
/// on it is meant for a stream, so `train` writes an online profile by default.
pub fn trained_on_movies(dataset: &Dataset) -> bool {
    // A stance sample starts at its touchdown: frame 0 of a trial cut to one contact.
    let stances_of_movies =
        matches!(dataset.sample, SampleKind::Stance { .. }) && !dataset.movie_loads.is_empty();
    stances_of_movies || dataset.samples.iter().any(|sample| sample.frame_index > 0)
}

/// The online profile (detector settings, calibration and sample frame) learned by segmenting, offline
/// with `params` (those of training: the profile keeps them), every movie of a data set as it was read
/// for its samples ([`Dataset::movie_loads`]).
pub fn learn_online_profile(
    movies: &[MovieLoad],
    params: &ValidSegmentParams,
) -> Result<OnlineProfile> {
    let segmentations = movies
        .iter()
        .map(|movie| {
            segment(&movie.total_per_frame, params)
                .with_context(|| format!("{}: cannot segment", movie.path.display()))
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(OnlineProfile::learn_with(&segmentations, params))
}

/// [`learn_online_profile`] from every movie the manifest at `manifest` lists, read as a data set's
/// recordings are with `options` (format options, a row's topic, dead sensels, frame period; no sample
/// is taken): `presrs stream --calibrate`.
pub fn manifest_online_profile(
    manifest: &Path,
    options: &SampleOptions,
    params: &ValidSegmentParams,
) -> Result<OnlineProfile> {
    let manifest = presrs_io::manifest::read_manifest(manifest)?;
    learn_online_profile(&read_movie_loads(&manifest, options)?, params)
}
