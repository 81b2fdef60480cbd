//! The trained pipeline: crop -> features -> PCA -> classifier, with training and a reusable classification session.
//!
//! ```text
//! TrainConfig --check--> CheckedTrainConfig --train(train, validation)--> TrainedModel (serde)
//! TrainedModel::session() -> Session::classify(&frame) -> Prediction { class, label, confidence, posteriors }
//! ```
//!
//! Training follows the paper: features of the training images fit the PCA (`dims` components, at most
//! `n_train - 1`), the validation images are projected with that PCA and used to choose the classifier's
//! hyper-parameters (the Parzen σ), and the final classifier stores the reduced training *and* validation
//! vectors. Absent (masked) sensels are read as 0 unless [`Preprocess::fill_absent`] fills them from their
//! neighbours; [`Preprocess::normalise_load`] divides each cropped image by its total load. Both are part
//! of the configuration and the model, so training and classification preprocess alike. Every image, in
//! training and afterwards, must have the same grid once cropped.

use std::collections::BTreeMap;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::classifier::{
    ClassifierConfig, ClassifierModel, ClassifierScratch, LabeledVectors, SigmaPoint,
};
use crate::crop::Crop;
use crate::error::{CoreError, Result, check_len};
use crate::features::{FeatureConfig, FeatureExtractor, Precision};
use crate::frame::{FrameView, Grid};
use crate::metrics::MeanStd;
use crate::pca::{Pca, ProjectionScratch};
use crate::preprocess::{FillScratch, Preprocess, fill_from_neighbours, normalise_load};

/// Everything training needs besides the data. `Default` is the paper's setting.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrainConfig {
    /// The region of each image that is used (applied before the features).
    pub crop: Crop,
    pub features: FeatureConfig,
    /// Number of principal components kept (capped at `n_train - 1` and at the feature count).
    pub dims: usize,
    pub classifier: ClassifierConfig,
    /// Steps after the crop (fill absent sensels, normalise the load); none by default (the paper).
    #[serde(default, skip_serializing_if = "Preprocess::is_none")]
    pub preprocess: Preprocess,
}

impl Default for TrainConfig {
    /// The paper: 38 x 41 foot region of the 44 x 44 array, 1-D |FFT| with N = 2048, 51 components,
    /// Parzen window with σ chosen on the validation set.
    fn default() -> Self {
        Self {
            crop: Crop::PAPER,
            features: FeatureConfig::default(),
            dims: 51,
            classifier: ClassifierConfig::default(),
            preprocess: Preprocess::NONE,
        }
    }
}

impl TrainConfig {
    /// Checks the parameters once; the result is what [`train`] takes.
    pub fn check(self) -> Result<CheckedTrainConfig> {
        if self.dims == 0 {
            return Err(CoreError::Param {
                name: "dims",
                reason: "at least one principal component must be kept".into(),
            });
        }
        self.features.check()?;
        self.classifier.check()?;
        Ok(CheckedTrainConfig(self))
    }
}

/// A [`TrainConfig`] whose parameters have been checked ([`TrainConfig::check`]).
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(transparent)]
pub struct CheckedTrainConfig(TrainConfig);

impl CheckedTrainConfig {
    pub fn config(&self) -> &TrainConfig {
        &self.0
    }

    pub fn into_inner(self) -> TrainConfig {
        self.0
    }
}

impl TryFrom<TrainConfig> for CheckedTrainConfig {
    type Error = CoreError;

    fn try_from(config: TrainConfig) -> Result<Self> {
        config.check()
    }
}

/// A labelled image as the algorithms see it (a borrowed view of a data set's sample): its class name
/// and, for evaluation, the operating condition it was recorded in and its value of the held-out
/// column.
#[derive(Clone, Copy, Debug)]
pub struct LabeledImage<'a> {
    pub frame: FrameView<'a>,
    pub label: &'a str,
    /// The operating condition (e.g. gait) the image was recorded in.
    pub condition: Option<&'a str>,
    /// The image's group (e.g. a person or a trial; with a leave-one-out protocol, the held-out column's
    /// value): the automatic choice validates by leaving one out.
    pub group: Option<&'a str>,
}

impl<'a> LabeledImage<'a> {
    /// An image with its class name (no condition, no group).
    pub fn new(frame: FrameView<'a>, label: &'a str) -> Self {
        Self {
            frame,
            label,
            condition: None,
            group: None,
        }
    }
}

/// How much data a model was trained on.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TrainingSummary {
    pub config: TrainConfig,
    /// Training and validation images per class, in class order.
    pub train_per_class: Vec<usize>,
    pub validation_per_class: Vec<usize>,
}

/// One candidate's validation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CandidateScore {
    pub features: String,
    pub classifier: String,
    pub config: TrainConfig,
    /// Accuracy over the folds (mean and spread); 0 when the candidate failed.
    pub accuracy: MeanStd,
    /// Accuracy of each fold, by held-out condition (or `split k`).
    pub per_fold: BTreeMap<String, f64>,
    /// Why the candidate could not be trained, if it could not.
    pub error: Option<String>,
    /// Not scored: the automatic choice's time budget was spent before its turn (`error` says so).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub skipped: bool,
    /// Scored on the first folds only: it was clearly behind the best there, and the race
    /// ([`crate::selection::RACE_FOLDS`]) left it out of the other folds. Never chosen.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub dropped_early: bool,
}

impl CandidateScore {
    /// Scored on every fold: it can be chosen.
    pub fn is_contender(&self) -> bool {
        self.error.is_none() && !self.dropped_early
    }

    /// The candidate in words: its features (after an intensity transform, if any) + its classifier,
    /// and its principal components (`fft1d (sqrt) + pwe, 51 dims`).
    pub fn name(&self) -> String {
        let intensity = self.config.preprocess.intensity;
        let transform = if intensity.is_none() {
            String::new()
        } else {
            format!(" ({intensity})")
        };
        format!(
            "{}{transform} + {}, {} dims",
            self.features, self.classifier, self.config.dims
        )
    }
}

/// What the automatic choice ([`crate::selection::select`]) did: plain data, stored in the model.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Selection {
    /// How the candidates were validated (in words).
    pub method: String,
    /// Index of the chosen candidate in `scores`.
    pub chosen: usize,
    pub scores: Vec<CandidateScore>,
}

impl Selection {
    pub fn chosen(&self) -> Option<&CandidateScore> {
        self.scores.get(self.chosen)
    }
}

/// Everything needed to classify images: crop, feature parameters, PCA, classifier state and class names.
/// Serialisable; loading re-checks that the parts fit together (the features against the PCA, the PCA
/// against the classifier, the classifier's own arrays, indices and values, the class names), and that
/// the image grid and feature transforms are within [`MAX_MODEL_SENSELS`] and [`MAX_TRANSFORM_LEN`], so
/// a model that loads classifies frames without panicking.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(try_from = "ModelFields", into = "ModelFields")]
pub struct TrainedModel {
    fields: ModelFields,
    /// Built once from `fields` (checked), cloned by every session.
    extractor: FeatureExtractor,
}

/// The serialised form of [`TrainedModel`].
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct ModelFields {
    /// Bumped when the meaning of a field changes.
    format_version: u32,
    crop: Crop,
    /// Steps after the crop (absent from files written before they existed: none).
    #[serde(default, skip_serializing_if = "Preprocess::is_none")]
    preprocess: Preprocess,
    /// The grid of the images after cropping.
    image_grid: Grid,
    features: FeatureConfig,
    pca: Pca,
    classifier: ClassifierModel,
    class_names: Vec<String>,
    summary: TrainingSummary,
    /// The automatic choice that picked `features` and `classifier`, when there was one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    selection: Option<Selection>,
}

const FORMAT_VERSION: u32 = 1;

/// The largest image a model takes once cropped, in sensels (`image_grid` rows x cols): the streaming
/// readers' limit, far above any pressure sensor (the paper's array has 44 x 44). Training on larger
/// images and loading a model that claims them are errors, so a crafted file cannot make loading plan
/// gigantic transforms.
pub const MAX_MODEL_SENSELS: usize = 1 << 20;

/// The most points the feature transforms of one model may hold together: `fft_len` of the 1-D |FFT|,
/// `pad_rows x pad_cols` of the 2-D one, summed over the parts of combined features (also the limit on
/// the polar form's `radial_bins` and `angular_bins`). 4 Mi points are a few hundred MB of plans and
/// buffers; the paper's setting needs 2048.
pub const MAX_TRANSFORM_LEN: usize = 1 << 22;

/// Checks `image_grid` and the transform sizes of `features` against [`MAX_MODEL_SENSELS`] and
/// [`MAX_TRANSFORM_LEN`], before anything is planned or allocated.
fn check_sizes(features: &FeatureConfig, image_grid: Grid) -> Result<()> {
    let Grid { rows, cols } = image_grid;
    if rows == 0
        || cols == 0
        || rows
            .checked_mul(cols)
            .is_none_or(|len| len > MAX_MODEL_SENSELS)
    {
        return Err(CoreError::Param {
            name: "image_grid",
            reason: format!(
                "the images of a model must have 1 to {MAX_MODEL_SENSELS} sensels once cropped, got \
                 {rows}x{cols}"
            ),
        });
    }
    let points = transform_points(features, image_grid)?;
    if points > MAX_TRANSFORM_LEN {
        return Err(CoreError::Param {
            name: "features",
            reason: format!(
                "the feature transforms need {points} points (fft_len, pad_rows x pad_cols, summed over \
                 the parts); at most {MAX_TRANSFORM_LEN} are allowed"
            ),
        });
    }
    Ok(())
}

/// The points of the transforms `features` plans for `image_grid` (saturating).
fn transform_points(features: &FeatureConfig, image_grid: Grid) -> Result<usize> {
    let too_large = |name: &'static str, what: String| CoreError::Param {
        name,
        reason: format!("{what} exceeds the limit of {MAX_TRANSFORM_LEN}"),
    };
    match features {
        FeatureConfig::Fft1d(config) => {
            let len = config.resolved_len(image_grid)?;
            if len > MAX_TRANSFORM_LEN {
                return Err(too_large("fft_len", format!("the transform length {len}")));
            }
            Ok(len)
        }
        FeatureConfig::Fft2d(config) => {
            for (name, bins) in [
                ("radial_bins", config.radial_bins),
                ("angular_bins", config.angular_bins),
            ] {
                if bins > MAX_TRANSFORM_LEN {
                    return Err(too_large(name, format!("{bins} bins")));
                }
            }
            let rows = config.pad_rows.unwrap_or(image_grid.rows);
            let cols = config.pad_cols.unwrap_or(image_grid.cols);
            match rows.checked_mul(cols) {
                Some(points) if points <= MAX_TRANSFORM_LEN => Ok(points),
                _ => Err(too_large(
                    "pad_rows",
                    format!("the {rows} x {cols} transform (pad_rows x pad_cols)"),
                )),
            }
        }
        FeatureConfig::Glcm(_) => Ok(0),
        FeatureConfig::Combined(config) => config.parts.iter().try_fold(0usize, |total, part| {
            Ok(total.saturating_add(transform_points(part, image_grid)?))
        }),
    }
}

impl From<TrainedModel> for ModelFields {
    fn from(model: TrainedModel) -> Self {
        model.fields
    }
}

impl TryFrom<ModelFields> for TrainedModel {
    type Error = CoreError;

    fn try_from(fields: ModelFields) -> Result<Self> {
        let bad = |reason: String| CoreError::Param {
            name: "trained model",
            reason,
        };
        if fields.format_version != FORMAT_VERSION {
            return Err(bad(format!(
                "format version {} is not supported (this build reads {FORMAT_VERSION})",
                fields.format_version
            )));
        }
        // Sizes first, then the feature count against the PCA's (both without allocating), and only
        // then the extractor with its plans and buffers.
        fields.features.check()?;
        check_sizes(&fields.features, fields.image_grid)?;
        let n_features = fields.features.output_len(fields.image_grid)?;
        if n_features != fields.pca.n_features() {
            return Err(bad(format!(
                "{n_features} features per image but the PCA takes {}",
                fields.pca.n_features()
            )));
        }
        let extractor = fields.features.extractor(fields.image_grid)?;
        if extractor.output_len() != n_features {
            return Err(bad(format!(
                "the extractor gives {} features per image, its configuration {n_features}",
                extractor.output_len()
            )));
        }
        if fields.pca.n_components() != fields.classifier.dims() {
            return Err(bad(format!(
                "the PCA gives {} components but the classifier takes {}",
                fields.pca.n_components(),
                fields.classifier.dims()
            )));
        }
        if fields.class_names.len() != fields.classifier.n_classes() {
            return Err(bad(format!(
                "{} class names for {} classes",
                fields.class_names.len(),
                fields.classifier.n_classes()
            )));
        }
        Ok(Self { fields, extractor })
    }
}

/// Trains the pipeline (see the module documentation). Classes are the distinct training labels, sorted;
/// every validation label must be one of them.
pub fn train(
    train: &[LabeledImage<'_>],
    validation: &[LabeledImage<'_>],
    config: &CheckedTrainConfig,
) -> Result<TrainedModel> {
    let config = config.config();
    let first = train
        .first()
        .ok_or_else(|| CoreError::NotEnoughData("no training images".into()))?;
    let class_names = class_names_of(train)?;
    let train_classes = class_indices(&class_names, train)?;
    let validation_classes = class_indices(&class_names, validation)?;

    let preprocessor = preprocessor_for(config, first.frame.grid())?;
    let image_grid = preprocessor.image_grid;
    let n_features = preprocessor.extractor.output_len();
    let train_features = features_of(train, &preprocessor, Precision::Exact)?;
    let validation_features = features_of(validation, &preprocessor, Precision::Exact)?;

    let pca = Pca::fit(&train_features, n_features, config.dims)?;
    let dims = pca.n_components();
    let classifier = config.classifier.fit(
        LabeledVectors {
            vectors: &project_rows(&pca, &train_features)?,
            classes: &train_classes,
        },
        LabeledVectors {
            vectors: &project_rows(&pca, &validation_features)?,
            classes: &validation_classes,
        },
        class_names.len(),
        dims,
    )?;

    let count = |classes: &[usize]| {
        let mut counts = vec![0; class_names.len()];
        for &class in classes {
            counts[class] += 1;
        }
        counts
    };
    let summary = TrainingSummary {
        config: config.clone(),
        train_per_class: count(&train_classes),
        validation_per_class: count(&validation_classes),
    };
    TrainedModel::try_from(ModelFields {
        format_version: FORMAT_VERSION,
        crop: config.crop,
        preprocess: config.preprocess,
        image_grid,
        features: config.features.clone(),
        pca,
        classifier,
        class_names,
        summary,
        selection: None,
    })
}

/// The classes of a training set: its distinct labels, sorted; at least two.
pub(crate) fn class_names_of(train: &[LabeledImage<'_>]) -> Result<Vec<String>> {
    let mut class_names: Vec<String> = train.iter().map(|image| image.label.to_owned()).collect();
    class_names.sort();
    class_names.dedup();
    if class_names.len() < 2 {
        return Err(CoreError::NotEnoughData(format!(
            "training needs at least two classes, got {class_names:?}"
        )));
    }
    Ok(class_names)
}

/// The class index of every image; a label outside `class_names` is an error.
pub(crate) fn class_indices(
    class_names: &[String],
    images: &[LabeledImage<'_>],
) -> Result<Vec<usize>> {
    images
        .iter()
        .map(|image| {
            class_names
                .binary_search_by(|name| name.as_str().cmp(image.label))
                .map_err(|_| CoreError::Param {
                    name: "validation label",
                    reason: format!(
                        "{:?} is not among the training classes {class_names:?}",
                        image.label
                    ),
                })
        })
        .collect()
}

/// The crop, preprocessing and feature extractor of `config` for images of `frame_grid`, with the size
/// limits loading applies checked first (so that every trained model can be read back).
fn preprocessor_for(config: &TrainConfig, frame_grid: Grid) -> Result<Preprocessor> {
    let image_grid = config.crop.output_grid(frame_grid)?;
    check_sizes(&config.features, image_grid)?;
    Ok(Preprocessor::new(
        config.crop,
        config.preprocess,
        image_grid,
        config.features.extractor(image_grid)?,
    ))
}

/// Projects feature rows (`n x pca.n_features()`) with the PCA's fixed-point projection: the one a
/// session uses, so that training and classification see the same vectors.
pub(crate) fn project_rows(pca: &Pca, features: &[f64]) -> Result<Vec<f64>> {
    let n_features = pca.n_features();
    let dims = pca.n_components();
    let mut reduced = vec![0.0; features.len() / n_features * dims];
    let mut scratch = pca.scratch();
    for (x, out) in features
        .chunks_exact(n_features)
        .zip(reduced.chunks_exact_mut(dims))
    {
        pca.project_fast_into(x, &mut scratch, out)?;
    }
    Ok(reduced)
}

/// The features of many images under one configuration: exact (as training computes them) and, when
/// classification computes them otherwise (the 1-D |FFT| in single precision), as classification
/// does. What the automatic choice computes once and reuses over its folds and classifiers.
pub(crate) struct FeatureTable {
    pub n_features: usize,
    /// Row-major `n x n_features`.
    pub exact: Vec<f64>,
    /// As a session computes them, when that differs from `exact`.
    pub fast: Option<Vec<f64>>,
}

impl FeatureTable {
    /// The features of `images` (all of one grid) under `config`'s crop, preprocessing and features.
    pub fn of(images: &[LabeledImage<'_>], config: &TrainConfig) -> Result<Self> {
        let first = images
            .first()
            .ok_or_else(|| CoreError::NotEnoughData("no images".into()))?;
        let preprocessor = preprocessor_for(config, first.frame.grid())?;
        let exact = features_of(images, &preprocessor, Precision::Exact)?;
        let fast = if config.features.has_fast_path() {
            Some(features_of(images, &preprocessor, Precision::Fast)?)
        } else {
            None
        };
        Ok(Self {
            n_features: preprocessor.extractor.output_len(),
            exact,
            fast,
        })
    }

    /// Image `index`'s features as training computes them.
    pub fn exact_row(&self, index: usize) -> &[f64] {
        &self.exact[index * self.n_features..(index + 1) * self.n_features]
    }

    /// Image `index`'s features as a classification session computes them.
    pub fn fast_row(&self, index: usize) -> &[f64] {
        let table = self.fast.as_ref().unwrap_or(&self.exact);
        &table[index * self.n_features..(index + 1) * self.n_features]
    }

    /// The exact rows of `indices`, in order.
    pub fn exact_rows(&self, indices: &[usize]) -> Vec<f64> {
        let mut rows = Vec::with_capacity(indices.len() * self.n_features);
        for &index in indices {
            rows.extend_from_slice(self.exact_row(index));
        }
        rows
    }
}

/// Features of many images (`n x n_features`, row-major), in parallel.
fn features_of(
    images: &[LabeledImage<'_>],
    preprocessor: &Preprocessor,
    precision: Precision,
) -> Result<Vec<f64>> {
    let n_features = preprocessor.extractor.output_len();
    let mut features = vec![0.0; images.len() * n_features];
    features
        .par_chunks_mut(n_features)
        .zip(images.par_iter())
        .enumerate()
        .try_for_each_init(
            || preprocessor.clone(),
            |preprocessor, (index, (out, image))| {
                preprocessor
                    .features_into(&image.frame, out, precision)
                    .map_err(|err| match err {
                        CoreError::Shape {
                            what,
                            expected,
                            got,
                        } => CoreError::Shape {
                            what,
                            expected,
                            got: format!("{got} (image {index}, label {:?})", image.label),
                        },
                        other => other,
                    })
            },
        )?;
    Ok(features)
}

/// Crop + preprocessing + features for one image grid, with its buffers.
#[derive(Clone, Debug)]
struct Preprocessor {
    crop: Crop,
    preprocess: Preprocess,
    image_grid: Grid,
    cropped: Vec<f64>,
    /// The crop of the frame's mask (used when filling absent sensels).
    cropped_present: Vec<bool>,
    fill: FillScratch,
    extractor: FeatureExtractor,
}

impl Preprocessor {
    fn new(
        crop: Crop,
        preprocess: Preprocess,
        image_grid: Grid,
        extractor: FeatureExtractor,
    ) -> Self {
        let len = image_grid.len();
        let fill = preprocess.fill_absent;
        Self {
            crop,
            preprocess,
            image_grid,
            cropped: vec![0.0; len],
            cropped_present: if fill { vec![true; len] } else { Vec::new() },
            fill: if fill {
                FillScratch::new(len)
            } else {
                FillScratch::default()
            },
            extractor,
        }
    }

    /// Crops `frame` (absent sensels read as 0, or filled from their neighbours), normalises its load when
    /// asked, and writes its features into `out`. Does not allocate.
    fn features_into(
        &mut self,
        frame: &FrameView<'_>,
        out: &mut [f64],
        precision: Precision,
    ) -> Result<()> {
        if precision == Precision::Fast
            && let Some(features) = self.fast_f32_features(frame)?
        {
            check_len("feature buffer", features.len(), out.len())?;
            for (dst, &value) in out.iter_mut().zip(features) {
                *dst = f64::from(value);
            }
            return Ok(());
        }
        crop_masked_into(&self.crop, self.image_grid, frame, &mut self.cropped)?;
        if self.preprocess.fill_absent
            && let Some(mask) = frame.present()
        {
            let (row0, col0, grid) = self.crop.window(frame.grid())?;
            let in_cols = frame.grid().cols;
            for (r, dst) in self.cropped_present.chunks_exact_mut(grid.cols).enumerate() {
                let start = (row0 + r) * in_cols + col0;
                dst.copy_from_slice(&mask[start..start + grid.cols]);
            }
            fill_from_neighbours(
                &mut self.cropped,
                self.image_grid,
                Some(&self.cropped_present),
                None,
                &mut self.fill,
            )?;
        }
        self.preprocess.intensity.apply(&mut self.cropped);
        if self.preprocess.normalise_load {
            normalise_load(&mut self.cropped);
        }
        match precision {
            Precision::Exact => self.extractor.extract_into(&self.cropped, out),
            Precision::Fast => self.extractor.extract_fast_into(&self.cropped, out),
        }
    }
}

impl Preprocessor {
    /// The common case of classification: the 1-D |FFT| reads the crop straight from the frame (no
    /// absent sensels, no load normalisation, no intensity transform) and gives its features in f32, as the fixed-point PCA reads
    /// them. `None` when the case does not apply.
    fn fast_f32_features(&mut self, frame: &FrameView<'_>) -> Result<Option<&[f32]>> {
        if let FeatureExtractor::Fft1d(extractor) = &mut self.extractor
            && frame.present().is_none()
            && !self.preprocess.normalise_load
            && self.preprocess.intensity.is_none()
        {
            let start = crop_start(&self.crop, self.image_grid, frame)?;
            return extractor
                .extract_fast_window(frame.values(), start, frame.grid().cols)
                .map(Some);
        }
        Ok(None)
    }
}

/// Where the crop of `frame` starts in its row-major values; the crop must give `expected`.
fn crop_start(crop: &Crop, expected: Grid, frame: &FrameView<'_>) -> Result<usize> {
    let (row0, col0, grid) = crop.window(frame.grid())?;
    if grid != expected {
        return Err(CoreError::Shape {
            what: "image",
            expected: format!("{expected} sensels after the crop {crop}"),
            got: format!("{grid} (from a {} image)", frame.grid()),
        });
    }
    Ok(row0 * frame.grid().cols + col0)
}

/// Copies the crop of `frame` into `out`, zeroing absent sensels; the crop must give `expected`.
fn crop_masked_into(
    crop: &Crop,
    expected: Grid,
    frame: &FrameView<'_>,
    out: &mut [f64],
) -> Result<()> {
    let start = crop_start(crop, expected, frame)?;
    let in_cols = frame.grid().cols;
    let grid = expected;
    let values = frame.values();
    let mask = frame.present();
    for (r, dst) in out.chunks_exact_mut(grid.cols).enumerate() {
        let start = start + r * in_cols;
        let src = &values[start..start + grid.cols];
        match mask {
            None => dst.copy_from_slice(src),
            Some(mask) => {
                for ((d, &s), &here) in dst.iter_mut().zip(src).zip(&mask[start..start + grid.cols])
                {
                    *d = if here { s } else { 0.0 };
                }
            }
        }
    }
    Ok(())
}

/// The features of one image as the pipeline computes them (crop, absent sensels as 0, then `features`).
pub fn extract_features(
    frame: &FrameView<'_>,
    crop: &Crop,
    features: &FeatureConfig,
) -> Result<Vec<f64>> {
    extract_features_with(frame, crop, Preprocess::NONE, features)
}

/// [`extract_features`] with the preprocessing steps `preprocess` after the crop.
pub fn extract_features_with(
    frame: &FrameView<'_>,
    crop: &Crop,
    preprocess: Preprocess,
    features: &FeatureConfig,
) -> Result<Vec<f64>> {
    Ok(extract_features_many(std::slice::from_ref(frame), crop, preprocess, features)?.0)
}

/// [`extract_features_with`] for many images of one grid, row-major `frames.len() x n_features` (the
/// transforms planned once). Equal, image for image, to what `extract_features_with` gives.
pub fn extract_features_many(
    frames: &[FrameView<'_>],
    crop: &Crop,
    preprocess: Preprocess,
    features: &FeatureConfig,
) -> Result<(Vec<f64>, usize)> {
    features.check()?;
    let Some(first) = frames.first() else {
        return Ok((Vec::new(), 0));
    };
    let image_grid = crop.output_grid(first.grid())?;
    let mut preprocessor = Preprocessor::new(
        *crop,
        preprocess,
        image_grid,
        features.extractor(image_grid)?,
    );
    let width = preprocessor.extractor.output_len();
    let mut out = vec![0.0; frames.len() * width];
    for (frame, row) in frames.iter().zip(out.chunks_exact_mut(width)) {
        preprocessor.features_into(frame, row, Precision::Exact)?;
    }
    Ok((out, width))
}

impl TrainedModel {
    /// A classification session with its own buffers (one per thread).
    pub fn session(&self) -> Session<'_> {
        let fields = &self.fields;
        Session {
            model: self,
            preprocessor: Preprocessor::new(
                fields.crop,
                fields.preprocess,
                fields.image_grid,
                self.extractor.clone(),
            ),
            features: vec![0.0; fields.pca.n_features()],
            projection: fields.pca.scratch(),
            reduced: vec![0.0; fields.pca.n_components()],
            scratch: fields.classifier.scratch(),
            posteriors: vec![0.0; fields.class_names.len()],
        }
    }

    /// Classifies many frames in parallel; results in input order, each equal (bit for bit) to what a
    /// [`Session`] gives for that frame. Frames go in blocks of [`BATCH_BLOCK`] per rayon task: the
    /// features of a block are projected together, so the PCA basis is read once per block rather than
    /// once per frame.
    pub fn classify_batch(&self, frames: &[FrameView<'_>]) -> Vec<Result<Classification>> {
        frames
            .par_chunks(BATCH_BLOCK)
            .map_init(
                || BatchSession::new(self),
                |session, block| session.classify_block(block),
            )
            .flatten()
            .collect()
    }

    /// Class names, in class-index order.
    pub fn class_names(&self) -> &[String] {
        &self.fields.class_names
    }

    pub fn crop(&self) -> Crop {
        self.fields.crop
    }

    /// The preprocessing steps after the crop.
    pub fn preprocess(&self) -> Preprocess {
        self.fields.preprocess
    }

    /// The grid of the images after cropping.
    pub fn image_grid(&self) -> Grid {
        self.fields.image_grid
    }

    pub fn features(&self) -> &FeatureConfig {
        &self.fields.features
    }

    pub fn pca(&self) -> &Pca {
        &self.fields.pca
    }

    pub fn classifier(&self) -> &ClassifierModel {
        &self.fields.classifier
    }

    /// The Parzen kernel width, when the classifier is a Parzen window.
    pub fn sigma(&self) -> Option<f64> {
        match &self.fields.classifier {
            ClassifierModel::Pwe(model) => Some(model.sigma()),
            _ => None,
        }
    }

    /// Validation accuracy against σ, when σ was searched (empty otherwise).
    pub fn validation_curve(&self) -> &[SigmaPoint] {
        match &self.fields.classifier {
            ClassifierModel::Pwe(model) => model.validation_curve(),
            _ => &[],
        }
    }

    pub fn summary(&self) -> &TrainingSummary {
        &self.fields.summary
    }

    /// The automatic choice of features and classifier (with every candidate's validation scores), when
    /// the model was trained by [`crate::selection::train_auto`].
    pub fn selection(&self) -> Option<&Selection> {
        self.fields.selection.as_ref()
    }

    /// This model with `selection` recorded.
    pub fn with_selection(mut self, selection: Selection) -> Self {
        self.fields.selection = Some(selection);
        self
    }
}

/// Classifies frames one at a time with reused buffers: no allocation per call.
#[derive(Debug)]
pub struct Session<'m> {
    model: &'m TrainedModel,
    preprocessor: Preprocessor,
    features: Vec<f64>,
    projection: ProjectionScratch,
    reduced: Vec<f64>,
    scratch: ClassifierScratch,
    posteriors: Vec<f64>,
}

/// The result of [`Session::classify`], borrowing the session's buffers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Prediction<'s> {
    pub class: usize,
    pub label: &'s str,
    /// The posterior of `class`.
    pub confidence: f64,
    /// Posterior of every class, in class-index order (equal priors).
    pub posteriors: &'s [f64],
}

impl Prediction<'_> {
    pub fn to_classification(&self) -> Classification {
        Classification {
            class: self.class,
            confidence: self.confidence,
            posteriors: self.posteriors.to_vec(),
        }
    }
}

/// An owned prediction (from [`TrainedModel::classify_batch`]); the label is
/// `model.class_names()[class]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Classification {
    pub class: usize,
    pub confidence: f64,
    pub posteriors: Vec<f64>,
}

impl<'m> Session<'m> {
    pub fn model(&self) -> &'m TrainedModel {
        self.model
    }

    /// Classifies one frame. Errors when the frame's grid does not give the model's grid once cropped,
    /// or when it holds non-finite values.
    pub fn classify(&mut self, frame: &FrameView<'_>) -> Result<Prediction<'_>> {
        self.reduce(frame)?;
        let model = self.model;
        let class = classify_reduced(
            model,
            &self.reduced,
            &mut self.scratch,
            &mut self.posteriors,
        )?;
        Ok(Prediction {
            class,
            label: &model.fields.class_names[class],
            confidence: self.posteriors[class],
            posteriors: &self.posteriors,
        })
    }

    /// The feature vector of `frame` (before PCA), exact: as training computes it.
    pub fn features(&mut self, frame: &FrameView<'_>) -> Result<&[f64]> {
        self.preprocessor
            .features_into(frame, &mut self.features, Precision::Exact)?;
        Ok(&self.features)
    }

    /// The feature vector of `frame` as classification computes it (before PCA): the fast path, with the
    /// 1-D |FFT| in single precision (within ~1e-6 of the largest exact feature).
    pub fn fast_features(&mut self, frame: &FrameView<'_>) -> Result<&[f64]> {
        self.preprocessor
            .features_into(frame, &mut self.features, Precision::Fast)?;
        Ok(&self.features)
    }

    /// The features of `frame` in the precision classification computes them in, f32, when it takes the
    /// common path (1-D |FFT| features, no absent sensels, no load normalisation; `None` otherwise, and
    /// [`fast_features`](Self::fast_features) gives them): the values of `fast_features`, before they
    /// are widened to f64. [`Pca::project_fast_into`] reads them as they are.
    pub fn fast_features_f32(&mut self, frame: &FrameView<'_>) -> Result<Option<&[f32]>> {
        self.preprocessor.fast_f32_features(frame)
    }

    /// The PCA-reduced feature vector of `frame` (what the classifier sees): the
    /// [`fast_features`](Self::fast_features) and the PCA's fixed-point projection.
    pub fn reduce(&mut self, frame: &FrameView<'_>) -> Result<&[f64]> {
        let pca = &self.model.fields.pca;
        match self.preprocessor.fast_f32_features(frame)? {
            // The same values as `fast_features` gives, without widening them to f64 and back.
            Some(features) => {
                pca.project_fast_into(features, &mut self.projection, &mut self.reduced)?;
            }
            None => {
                self.preprocessor
                    .features_into(frame, &mut self.features, Precision::Fast)?;
                pca.project_fast_into(&self.features, &mut self.projection, &mut self.reduced)?;
            }
        }
        Ok(&self.reduced)
    }
}

/// Frames per block of [`TrainedModel::classify_batch`]: their features (64 x 1025 x 8 B = 512 KB) and
/// quantized copies (64 x 2 KB) stay in L2 while the basis is streamed through once.
pub const BATCH_BLOCK: usize = 64;

/// The classifier step shared by [`Session`] and [`BatchSession`]: refuses a non-finite reduced vector
/// (the image held NaN or infinite values), then writes the posteriors and returns the class.
fn classify_reduced(
    model: &TrainedModel,
    reduced: &[f64],
    scratch: &mut ClassifierScratch,
    posteriors: &mut [f64],
) -> Result<usize> {
    if reduced.iter().any(|value| !value.is_finite()) {
        return Err(CoreError::Param {
            name: "image",
            reason: "contains NaN or infinite values".into(),
        });
    }
    model
        .fields
        .classifier
        .classify_into(reduced, scratch, posteriors)
}

/// Buffers for classifying a block of frames together (one per rayon worker in
/// [`TrainedModel::classify_batch`]): a session's, plus the block's features and reduced vectors.
#[derive(Debug)]
struct BatchSession<'m> {
    session: Session<'m>,
    /// Row-major `block x n_features`, in the single precision the projection reads (the fast features
    /// as they are, any others rounded).
    features: Vec<f32>,
    /// Row-major `block x n_components`.
    reduced: Vec<f64>,
}

impl<'m> BatchSession<'m> {
    fn new(model: &'m TrainedModel) -> Self {
        Self {
            session: model.session(),
            features: Vec::new(),
            reduced: Vec::new(),
        }
    }

    fn classify_block(&mut self, frames: &[FrameView<'_>]) -> Vec<Result<Classification>> {
        let session = &mut self.session;
        let model = session.model;
        let pca = &model.fields.pca;
        let (n_features, dims) = (pca.n_features(), pca.n_components());
        self.features.resize(frames.len() * n_features, 0.0);
        self.reduced.resize(frames.len() * dims, 0.0);
        // A frame whose features fail keeps its error; its row is zeroed and its projection ignored.
        let mut failed: Vec<Option<CoreError>> = Vec::with_capacity(frames.len());
        for (frame, row) in frames
            .iter()
            .zip(self.features.chunks_exact_mut(n_features))
        {
            let error = single_features_into(session, frame, row).err();
            if error.is_some() {
                row.fill(0.0);
            }
            failed.push(error);
        }
        if let Err(err) =
            pca.project_fast_many(&self.features, &mut session.projection, &mut self.reduced)
        {
            // Cannot happen (the buffers are sized above); every frame gets the reason all the same.
            let reason = err.to_string();
            return frames
                .iter()
                .map(|_| {
                    Err(CoreError::Param {
                        name: "pca",
                        reason: reason.clone(),
                    })
                })
                .collect();
        }
        failed
            .into_iter()
            .zip(self.reduced.chunks_exact(dims))
            .map(|(error, reduced)| match error {
                Some(err) => Err(err),
                None => {
                    let class = classify_reduced(
                        model,
                        reduced,
                        &mut session.scratch,
                        &mut session.posteriors,
                    )?;
                    Ok(Classification {
                        class,
                        confidence: session.posteriors[class],
                        posteriors: session.posteriors.clone(),
                    })
                }
            })
            .collect()
    }
}

/// The features of `frame` as classification computes them, in f32, into `out`: straight from the fast
/// path, or computed in f64 by the session and rounded.
fn single_features_into(
    session: &mut Session<'_>,
    frame: &FrameView<'_>,
    out: &mut [f32],
) -> Result<()> {
    if let Some(features) = session.preprocessor.fast_f32_features(frame)? {
        check_len("feature buffer", features.len(), out.len())?;
        out.copy_from_slice(features);
        return Ok(());
    }
    session
        .preprocessor
        .features_into(frame, &mut session.features, Precision::Fast)?;
    check_len("feature buffer", session.features.len(), out.len())?;
    #[allow(clippy::cast_possible_truncation)]
    for (dst, &value) in out.iter_mut().zip(&session.features) {
        *dst = value as f32;
    }
    Ok(())
}
