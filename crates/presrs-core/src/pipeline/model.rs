//! The trained model: its stored fields, the checks loading applies (sizes, parts that fit together), and
//! what it tells about itself.

use serde::{Deserialize, Serialize};

use crate::classifier::{ClassifierKind, ClassifierModel, PweFamily, SigmaPoint};
use crate::crop::Crop;
use crate::error::{CoreError, Result};
use crate::features::{FeatureConfig, FeatureExtractor};
use crate::frame::Grid;
use crate::novelty::NoveltyModel;
use crate::pipeline::config::TrainConfig;
use crate::preprocess::Preprocess;
use crate::projection::pca::Pca;
use crate::sample::{SampleKind, Sampling, sensor_mismatch};
use crate::selection::record::Selection;

/// How much data a model was trained on.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TrainingSummary {
    pub config: TrainConfig,
    /// Training and validation images per class, in class order.
    pub train_per_class: Vec<usize>,
    pub validation_per_class: Vec<usize>,
    /// The images the classifier's hyper-parameters were searched on, when not all of them (a
    /// stratified subsample of large data; the choice then fitted on every image).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub searched_on: Option<usize>,
}

/// Everything needed to classify images: crop, feature parameters, PCA, classifier state and class names.
/// Serialisable; loading re-checks that the parts fit together (the features against the PCA, the PCA
/// against the classifier, the classifier's own arrays, indices and values, the class names), and that
/// the image grid and feature transforms are within [`MAX_MODEL_SENSELS`] and [`MAX_TRANSFORM_LEN`], so
/// a model that loads classifies frames without panicking.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(try_from = "ModelFields", into = "ModelFields")]
pub struct TrainedModel {
    pub(crate) fields: ModelFields,
    /// Built once from `fields` (checked), cloned by every session.
    pub(crate) extractor: FeatureExtractor,
}

/// The serialised form of [`TrainedModel`].
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct ModelFields {
    /// Bumped when the meaning of a field changes.
    pub(crate) format_version: u32,
    pub(crate) crop: Crop,
    /// Steps after the crop (absent from files written before they existed: none).
    #[serde(default, skip_serializing_if = "Preprocess::is_none")]
    pub(crate) preprocess: Preprocess,
    /// The grid of the images after cropping.
    pub(crate) image_grid: Grid,
    pub(crate) features: FeatureConfig,
    /// The PCA step; absent when the classifier takes every feature (ridge), which only models written
    /// since that path exist have (older files always hold one, and load and classify as before).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(crate) pca: Option<Pca>,
    pub(crate) classifier: ClassifierModel,
    pub(crate) class_names: Vec<String>,
    pub(crate) summary: TrainingSummary,
    /// The automatic choice that picked `features` and `classifier`, when there was one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(crate) selection: Option<Selection>,
    /// What a sample is, when not one frame (absent from files of one-frame models).
    #[serde(default, skip_serializing_if = "SampleKind::is_frame")]
    pub(crate) sample: SampleKind,
    /// The sensor of a stance or series model: the grid of its training recordings' frames, or of its
    /// series (channels x time, as the model takes them). Absent from one-frame models (their crop
    /// and image grid say it) and from older files, which take any grid as before.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(crate) sensor: Option<Grid>,
    /// How the training samples were taken from their recordings (absent from models trained on
    /// samples made in memory, and from older files).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(crate) sampling: Option<Sampling>,
    /// A whole-stance model's classifiers for decision points before lift-off (absent from files
    /// written before them, and from models trained for the whole stance only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(crate) early: Option<Box<EarlyDecisions>>,
    /// The novelty score and its threshold (absent from files written before it, and from models
    /// trained without it: every decision is then one of the classes, as before).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(crate) novelty: Option<NoveltyModel>,
}

pub(crate) const FORMAT_VERSION: u32 = 1;

// The early decisions a model stores (trained by `crate::pipeline::early`), here beside the model they
// hold and are held by.

/// One decision point: `frames` after touchdown, with the model trained on stances cut there (samples of
/// `frames + 1` frames).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DecisionPoint {
    /// `K`: the stance's first `K + 1` frames.
    pub frames: usize,
    pub model: TrainedModel,
}

/// The threshold `auto` decides with, and what validation measured with it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AutoThreshold {
    /// A point decides when its confidence is at least this (above 1: never, lift-off decides).
    pub threshold: f64,
    /// Validation accuracy of the whole-stance classifier, and of `auto` with this threshold.
    pub whole_accuracy: f64,
    pub auto_accuracy: f64,
    /// Mean frame after touchdown at which `auto` decided in validation, and as a share of each
    /// stance's length (a lift-off decision counts as the whole length).
    pub mean_decision_frame: f64,
    pub mean_decision_share: f64,
    /// Held-out stances the threshold was learned on.
    pub validation_stances: usize,
    /// How those stances were held out (inner folds by group, condition or stratified splits); absent
    /// from models written before it was recorded.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub validated_by: Option<crate::selection::ValidateBy>,
    /// The point (frames after touchdown) at which a stance no point was confident about by then is
    /// decided whatever its confidence (`None`: it waits for its lift-off). Absent from models
    /// written before deadlines.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub deadline: Option<usize>,
}

impl AutoThreshold {
    /// The rule `auto` decides by.
    pub fn rule(&self) -> AutoRule {
        AutoRule {
            threshold: self.threshold,
            deadline: self.deadline,
        }
    }
}

/// How `auto` decides a stance: at the first point whose confidence is at least `threshold`, else at
/// the `deadline` point whatever its confidence, else (no deadline, or the stance lifts off first)
/// whole at its lift-off.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AutoRule {
    pub threshold: f64,
    pub deadline: Option<usize>,
}

impl AutoRule {
    /// `threshold` without a deadline.
    pub fn threshold(threshold: f64) -> Self {
        Self {
            threshold,
            deadline: None,
        }
    }

    /// Whether a point `frames` after touchdown with `confidence` decides.
    pub fn decides(&self, frames: usize, confidence: f64) -> bool {
        confidence >= self.threshold || self.deadline == Some(frames)
    }
}

/// A whole-stance model's classifiers for decision points before lift-off.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EarlyDecisions {
    /// In increasing `frames`, each before the model's length.
    pub points: Vec<DecisionPoint>,
    /// What `auto` decides with (absent: `auto` is refused).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub auto: Option<AutoThreshold>,
    /// Where training the points' classifiers and `auto`'s rule spent its time (absent from models
    /// written before it was recorded).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cost: Option<EarlyCost>,
}

/// Where training the early decisions spent its time: after the whole-stance model, and outside the
/// automatic choice's budget (each point's own choice has the budget of its own).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EarlyCost {
    /// Seconds spent training the points' classifiers on every training stance (each point's method
    /// chosen there when the model's is the automatic choice).
    pub points_seconds: f64,
    /// Seconds spent learning `auto`'s rule: the inner folds, each retraining the whole-stance
    /// classifier and every point's on the fold's other stances.
    pub rule_seconds: f64,
    /// The inner folds of the rule, and the classifiers trained in them.
    pub inner_folds: usize,
    pub inner_models: usize,
    /// The stances the rule was learned from, of all the training stances (fewer: a stratified
    /// subsample, [`RULE_STANCES`](crate::pipeline::RULE_STANCES)).
    pub rule_stances: usize,
    pub stances: usize,
}

impl EarlyCost {
    /// Every second of it.
    pub fn total_seconds(&self) -> f64 {
        self.points_seconds + self.rule_seconds
    }
}

impl EarlyDecisions {
    /// The points' frames after touchdown, increasing.
    pub fn frames(&self) -> Vec<usize> {
        self.points.iter().map(|point| point.frames).collect()
    }

    /// The model of point `frames`.
    pub fn point(&self, frames: usize) -> Option<&TrainedModel> {
        self.points
            .iter()
            .find(|point| point.frames == frames)
            .map(|point| &point.model)
    }

    /// Checks the points against their whole-stance `model`: increasing, before its length, stance
    /// models of its sample and classes, with no points of their own; a threshold that is a number.
    pub(crate) fn check(&self, model: &TrainedModel) -> Result<()> {
        let bad = |reason: String| CoreError::Param {
            name: "early decisions",
            reason,
        };
        let length = model.image_grid().cols;
        let mut last = None;
        for point in &self.points {
            if last.is_some_and(|last| point.frames <= last) || point.frames + 1 >= length {
                return Err(bad(format!(
                    "decision points must increase and come before the model's length ({length} \
                     frames); got {:?}",
                    self.frames()
                )));
            }
            last = Some(point.frames);
            let sub = &point.model;
            let own = match model.sample() {
                SampleKind::Stance { summary, .. } => SampleKind::Stance {
                    summary,
                    length: Some(point.frames + 1),
                },
                other => other,
            };
            if sub.sample() != own
                || sub.class_names() != model.class_names()
                || sub.image_grid() != Grid::new(model.image_grid().rows, point.frames + 1)
                || sub.early().is_some()
            {
                return Err(bad(format!(
                    "the model of point {} does not take the whole-stance model's samples and \
                     classes",
                    point.frames
                )));
            }
        }
        if let Some(auto) = &self.auto
            && (!auto.threshold.is_finite() || auto.threshold < 0.0)
        {
            return Err(bad(format!(
                "threshold {} is not a confidence",
                auto.threshold
            )));
        }
        if let Some(deadline) = self.auto.and_then(|auto| auto.deadline)
            && self.point(deadline).is_none()
        {
            return Err(bad(format!(
                "the deadline {deadline} is not one of the decision points {:?}",
                self.frames()
            )));
        }
        Ok(())
    }
}

/// The largest image a model takes once cropped, in sensels (`image_grid` rows x cols): the streaming
/// readers' limit, far above any pressure sensor (the paper's array has 44 x 44). Training on larger
/// images and loading a model that claims them are errors, so a crafted file cannot make loading plan
/// gigantic transforms.
pub const MAX_MODEL_SENSELS: usize = 1 << 20;

pub use crate::features::MAX_TRANSFORM_LEN;

/// Checks `image_grid` and the transform sizes of `features` against [`MAX_MODEL_SENSELS`] and
/// [`MAX_TRANSFORM_LEN`], before anything is planned or allocated.
pub(crate) fn check_sizes(features: &FeatureConfig, image_grid: Grid) -> Result<()> {
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
    let points = features.transform_points(image_grid)?;
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
        check_projection(&fields, n_features)?;
        let extractor = fields.features.extractor(fields.image_grid)?;
        if extractor.output_len() != n_features {
            return Err(bad(format!(
                "the extractor gives {} features per image, its configuration {n_features}",
                extractor.output_len()
            )));
        }
        if fields.class_names.len() != fields.classifier.n_classes() {
            return Err(bad(format!(
                "{} class names for {} classes",
                fields.class_names.len(),
                fields.classifier.n_classes()
            )));
        }
        check_sample(&fields.sample, fields.image_grid)?;
        check_novelty(&fields)?;
        let model = Self { fields, extractor };
        if let Some(early) = &model.fields.early {
            early.check(&model)?;
        }
        Ok(model)
    }
}

/// The features against the PCA and the PCA against the classifier; without a PCA, the classifier must
/// take every feature (a file that drops the PCA of another classifier is refused).
fn check_projection(fields: &ModelFields, n_features: usize) -> Result<()> {
    let bad = |reason: String| CoreError::Param {
        name: "trained model",
        reason,
    };
    let classifier_dims = fields.classifier.dims();
    match &fields.pca {
        Some(pca) if pca.n_features() != n_features => Err(bad(format!(
            "{n_features} features per image but the PCA takes {}",
            pca.n_features()
        ))),
        Some(pca) if pca.n_components() != classifier_dims => Err(bad(format!(
            "the PCA gives {} components but the classifier takes {classifier_dims}",
            pca.n_components()
        ))),
        Some(_) => Ok(()),
        None if !fields.classifier.kind().takes_all_features() => Err(bad(format!(
            "no PCA, but the {} classifier takes principal components",
            fields.classifier.kind().as_str()
        ))),
        None if classifier_dims != n_features => Err(bad(format!(
            "{n_features} features per image but the classifier takes {classifier_dims}"
        ))),
        None => Ok(()),
    }
}

/// The novelty score reads the classifier's vectors, of the model's classes.
fn check_novelty(fields: &ModelFields) -> Result<()> {
    let Some(novelty) = &fields.novelty else {
        return Ok(());
    };
    let (dims, classes) = (fields.classifier.dims(), fields.class_names.len());
    if novelty.dims() != dims || novelty.n_classes() != classes {
        return Err(CoreError::Param {
            name: "novelty",
            reason: format!(
                "the novelty score reads {} values of {} classes, but the classifier takes {dims} of \
                 {classes}",
                novelty.dims(),
                novelty.n_classes()
            ),
        });
    }
    Ok(())
}

/// A whole-stance model's images are its summary's channels over its length.
fn check_sample(sample: &SampleKind, image_grid: Grid) -> Result<()> {
    if let SampleKind::Stance { summary, length } = sample {
        let expected = Grid::new(summary.channels(), length.unwrap_or(image_grid.cols));
        if expected != image_grid || length.is_none() {
            return Err(CoreError::Param {
                name: "sample",
                reason: format!(
                    "a whole-stance model takes {expected} summaries with a stated length, but its \
                     images are {image_grid}"
                ),
            });
        }
    }
    Ok(())
}

impl TrainedModel {
    /// Class names, in class-index order.
    pub fn class_names(&self) -> &[String] {
        &self.fields.class_names
    }

    pub fn crop(&self) -> Crop {
        self.fields.crop
    }

    /// What a sample is: one frame (the paper's), a whole stance, or a series.
    pub fn sample(&self) -> SampleKind {
        self.fields.sample
    }

    /// This model, stating that its samples are of `sample` (a stance's length fixed to the model's).
    /// Training knows images only; the workflow that made them says what they are.
    pub fn with_sample(mut self, sample: SampleKind) -> Result<Self> {
        let sample = match sample {
            SampleKind::Stance { summary, .. } => SampleKind::Stance {
                summary,
                length: Some(self.fields.image_grid.cols),
            },
            other => other,
        };
        check_sample(&sample, self.fields.image_grid)?;
        self.fields.sample = sample;
        Ok(self)
    }

    /// The sensor a stance or series model was trained on (see [`Self::check_sensor`]); `None` for
    /// one-frame models and files written before it was stored.
    pub fn sensor(&self) -> Option<Grid> {
        self.fields.sensor
    }

    /// This model, stating the sensor its samples came from (ignored for one-frame models, whose
    /// crop and image grid already say what they take).
    pub fn with_sensor(mut self, sensor: Option<Grid>) -> Self {
        if !self.fields.sample.is_frame() {
            self.fields.sensor = sensor;
        }
        self
    }

    /// An error unless `grid` is the sensor this model was trained on: the frames of a stance for a
    /// whole-stance model, the series for a series model (as the model takes it: channels in rows).
    /// Models that do not say (one-frame models, older files) take any grid here.
    pub fn check_sensor(&self, grid: Grid) -> Result<()> {
        match sensor_mismatch(&self.fields.sample, self.fields.sensor, grid) {
            Some(err) => Err(err),
            None => Ok(()),
        }
    }

    /// How the training samples were taken from their recordings, when the model says.
    pub fn sampling(&self) -> Option<&Sampling> {
        self.fields.sampling.as_ref()
    }

    /// This model with `sampling` recorded.
    pub fn with_sampling(mut self, sampling: Option<Sampling>) -> Self {
        self.fields.sampling = sampling;
        self
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

    /// The PCA step, when there is one (`None`: the classifier takes every feature, as ridge does).
    pub fn pca(&self) -> Option<&Pca> {
        self.fields.pca.as_ref()
    }

    /// Features per image (what the PCA, or the classifier without one, takes).
    pub fn n_features(&self) -> usize {
        self.extractor.output_len()
    }

    /// What the classifier sees, in words: `PCA 51 components`, or `no PCA: 9996 standardised
    /// features` (ridge standardises them itself), `no PCA: 9996 features as they are` (`ridge_raw`).
    pub fn describe_projection(&self) -> String {
        match &self.fields.pca {
            Some(pca) => format!("PCA {} components", pca.n_components()),
            None if self.fields.classifier.kind() == ClassifierKind::RIDGE_RAW => {
                format!("no PCA: {} features as they are", self.n_features())
            }
            None => format!("no PCA: {} standardised features", self.n_features()),
        }
    }

    /// Length of the vectors the classifier sees: the principal components kept, or every feature.
    pub fn classifier_dims(&self) -> usize {
        self.fields.classifier.dims()
    }

    pub fn classifier(&self) -> &ClassifierModel {
        &self.fields.classifier
    }

    /// The Parzen kernel width, when the classifier is a Parzen window.
    pub fn sigma(&self) -> Option<f64> {
        let parzen = self.fields.classifier.get::<PweFamily>()?;
        Some(parzen.sigma())
    }

    /// Validation accuracy against σ, when σ was searched (empty otherwise).
    pub fn validation_curve(&self) -> &[SigmaPoint] {
        self.fields
            .classifier
            .get::<PweFamily>()
            .map_or(&[], |parzen| parzen.validation_curve())
    }

    pub fn summary(&self) -> &TrainingSummary {
        &self.fields.summary
    }

    /// The automatic choice of features and classifier (with every candidate's validation scores), when
    /// the model was trained by [`crate::selection::train_auto`].
    pub fn selection(&self) -> Option<&Selection> {
        self.fields.selection.as_ref()
    }

    /// The classifiers for decision points before lift-off, when trained for them.
    pub fn early(&self) -> Option<&EarlyDecisions> {
        self.fields.early.as_deref()
    }

    /// This whole-stance model with classifiers for decision points before lift-off (checked against
    /// it: see [`EarlyDecisions`]).
    pub fn with_early(mut self, early: EarlyDecisions) -> Result<Self> {
        if !matches!(self.fields.sample, SampleKind::Stance { .. }) {
            return Err(CoreError::Param {
                name: "early decisions",
                reason: "decision points before lift-off are for whole-stance models".into(),
            });
        }
        early.check(&self)?;
        self.fields.early = Some(Box::new(early));
        Ok(self)
    }

    /// Whether this model was trained to decide at `decide_at` (see
    /// [`crate::online::DecideAt`]): `K` frames after touchdown is one of its decision points, or (a
    /// whole-stance model) at least its length less one (its whole sample); `auto` needs decision
    /// points and their threshold. `Err` says what it was trained for, in words.
    pub fn trained_for(
        &self,
        decide_at: crate::online::DecideAt,
    ) -> std::result::Result<(), String> {
        use crate::online::DecideAt;
        let SampleKind::Stance { .. } = self.fields.sample else {
            return Err("one frame of each stance, chosen by the sample offset".into());
        };
        let length = self.fields.image_grid.cols;
        let points = self.early().map(EarlyDecisions::frames).unwrap_or_default();
        let fits = match decide_at {
            DecideAt::Frames(k) => k + 1 >= length || points.contains(&k),
            DecideAt::Auto(_) => self
                .early()
                .is_some_and(|e| e.auto.is_some() && !e.points.is_empty()),
        };
        if fits {
            return Ok(());
        }
        let list: Vec<String> = points.iter().map(ToString::to_string).collect();
        let auto = self
            .early()
            .is_some_and(|e| e.auto.is_some() && !e.points.is_empty());
        let whole = format!(
            "the whole stance (at lift-off, or {} frames after touchdown and later)",
            length - 1
        );
        Err(match (list.is_empty(), auto) {
            (true, _) => format!("{whole} only"),
            (false, false) => format!("{} frames after touchdown and {whole}", list.join(", ")),
            (false, true) => format!(
                "{} frames after touchdown (and auto among them) and {whole}",
                list.join(", ")
            ),
        })
    }

    /// The novelty score, when the model has one.
    pub fn novelty(&self) -> Option<&NoveltyModel> {
        self.fields.novelty.as_ref()
    }

    /// This model without its novelty score: every decision one of the classes (`--novelty off`).
    pub fn without_novelty(mut self) -> Self {
        self.fields.novelty = None;
        self
    }

    /// This model with `novelty` (checked against the classifier).
    pub fn with_novelty_model(mut self, novelty: NoveltyModel) -> Result<Self> {
        self.fields.novelty = Some(novelty);
        check_novelty(&self.fields)?;
        Ok(self)
    }

    /// This model with `selection` recorded.
    pub fn with_selection(mut self, selection: Selection) -> Self {
        self.fields.selection = Some(selection);
        self
    }
}

#[cfg(test)]
mod tests {
    use crate::testing::bench_fixture;

    use super::*;

    #[test]
    fn a_model_round_trips_through_serde() {
        let (model, frames) = bench_fixture(3, 8).unwrap();
        let json = serde_json::to_string(&model).unwrap();
        let back: TrainedModel = serde_json::from_str(&json).unwrap();
        assert_eq!(serde_json::to_string(&back).unwrap(), json);
        assert_eq!(back.class_names(), model.class_names());
        for frame in &frames {
            let (mut a, mut b) = (model.session(), back.session());
            let (a, b) = (
                a.classify(&frame.view()).unwrap(),
                b.classify(&frame.view()).unwrap(),
            );
            assert_eq!(a.posteriors, b.posteriors);
        }
    }

    #[test]
    fn loading_refuses_another_version_and_parts_that_do_not_fit() {
        let (model, _) = bench_fixture(3, 0).unwrap();
        let value = serde_json::to_value(&model).unwrap();
        let mut future = value.clone();
        future["format_version"] = serde_json::json!(FORMAT_VERSION + 1);
        let err = serde_json::from_value::<TrainedModel>(future).unwrap_err();
        assert!(err.to_string().contains("format version"), "{err}");
        let mut renamed = value.clone();
        renamed["class_names"] = serde_json::json!(["only one"]);
        let err = serde_json::from_value::<TrainedModel>(renamed).unwrap_err();
        assert!(err.to_string().contains("class names"), "{err}");
        let mut huge = value;
        huge["image_grid"] = serde_json::json!({"rows": MAX_MODEL_SENSELS, "cols": 2});
        let err = serde_json::from_value::<TrainedModel>(huge).unwrap_err();
        assert!(err.to_string().contains("sensels"), "{err}");
    }
}
