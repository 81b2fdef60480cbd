//! Novelty: how far a sample lies from every class the model was trained on, and whether it is too far
//! to be one of them (`unknown`).
//!
//! The score is read in the model's own feature space, the vectors its classifier sees (principal
//! components): their discriminant space ([`Discriminant`], Fisher's directions with the pooled
//! within-class covariance the identity), where each class's distance is divided by that class's own
//! scale, the median distance of its training vectors held out from the space (so that a tight class and
//! a loose one are judged alike). The score is the smallest of these ratios; a sample is `unknown` when
//! it exceeds the threshold, the quantile of the same ratios over the held-out training vectors that
//! leaves [`DEFAULT_REJECTION`] of them out. No unknown class is needed: the threshold is learned from
//! known vectors that the space did not see (their group held out, as a new recording is), and
//! `eval --leave-class-out` measures what it does with a class never seen (`docs/methods.md`).

mod calibration;
mod discriminant;
#[cfg(test)]
mod tests;

use serde::{Deserialize, Serialize};

pub use calibration::CalibrationFolds;
pub use discriminant::Discriminant;

use crate::error::{CoreError, Result, check_len};

/// The label of a decision whose sample is none of the model's classes.
pub const UNKNOWN_LABEL: &str = "unknown";

/// The share of held-out known training vectors the threshold rejects.
pub const DEFAULT_REJECTION: f64 = 0.03;

/// A novelty score and its verdict.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Novelty {
    /// The distance to the nearest class in units of that class's own spread (larger: more novel).
    pub score: f64,
    /// The score above which a sample is `unknown`.
    pub threshold: f64,
    /// `score > threshold`: the sample is none of the trained classes.
    pub unknown: bool,
}

impl Novelty {
    /// The verdict on `score` against `threshold`.
    pub fn of(score: f64, threshold: f64) -> Self {
        Self {
            score,
            threshold,
            unknown: score > threshold,
        }
    }
}

/// What a model stores to score novelty (see the module documentation). Loading checks that the parts
/// fit together.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "NoveltyFields", into = "NoveltyFields")]
pub struct NoveltyModel {
    fields: NoveltyFields,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct NoveltyFields {
    space: Discriminant,
    /// Each class's median held-out distance.
    class_scales: Vec<f64>,
    threshold: f64,
    /// The share of held-out training vectors the threshold was set to reject.
    rejection: f64,
    folds: CalibrationFolds,
    /// How many held-out distances set the scales and the threshold.
    calibration_vectors: usize,
}

impl From<NoveltyModel> for NoveltyFields {
    fn from(model: NoveltyModel) -> Self {
        model.fields
    }
}

impl TryFrom<NoveltyFields> for NoveltyModel {
    type Error = CoreError;

    fn try_from(fields: NoveltyFields) -> Result<Self> {
        let bad = |reason: String| CoreError::Param {
            name: "novelty",
            reason,
        };
        let space = &fields.space;
        let axes = space.n_axes();
        if space.dims == 0
            || axes == 0
            || space.axes.len() != axes * space.dims
            || space.class_means.len() % axes != 0
        {
            return Err(bad(format!(
                "a discriminant space of {} directions of {} values with {} class-mean values does not fit",
                axes,
                space.dims,
                space.class_means.len()
            )));
        }
        if fields.class_scales.len() != space.n_classes() {
            return Err(bad(format!(
                "{} class scales for {} classes",
                fields.class_scales.len(),
                space.n_classes()
            )));
        }
        let finite = space
            .axes
            .iter()
            .chain(&space.offset)
            .all(|v| v.is_finite());
        let positive = fields
            .class_scales
            .iter()
            .all(|s| s.is_finite() && *s > 0.0);
        if !finite || !positive || !(fields.threshold.is_finite() && fields.threshold > 0.0) {
            return Err(bad(
                "the directions must be finite, the class scales and the threshold positive".into(),
            ));
        }
        if !(0.0..1.0).contains(&fields.rejection) {
            return Err(bad(format!(
                "rejection {} is outside [0, 1)",
                fields.rejection
            )));
        }
        Ok(Self { fields })
    }
}

/// Reusable buffers of [`NoveltyModel::score_into`].
#[derive(Clone, Debug, Default)]
pub struct NoveltyScratch {
    projected: Vec<f64>,
    distances: Vec<f64>,
}

impl NoveltyModel {
    /// Fits the space on `vectors` (`n x dims`, row-major, the classifier's training and validation
    /// vectors) of `classes`, and calibrates the scales and the threshold on held-out distances (folds
    /// by `groups`, one per vector, when there are three groups or more; else stratified folds) so that
    /// `rejection` of them are above it.
    pub fn fit(
        vectors: &[f64],
        classes: &[usize],
        groups: &[Option<&str>],
        n_classes: usize,
        dims: usize,
        rejection: f64,
    ) -> Result<Self> {
        check_len("novelty groups", classes.len(), groups.len())?;
        let space = Discriminant::fit(vectors, classes, n_classes, dims)?;
        let held_out = calibration::held_out_distances(vectors, classes, groups, n_classes, dims)?;
        let mut per_class: Vec<Vec<f64>> = vec![Vec::new(); n_classes];
        for &(class, distance) in &held_out.distances {
            per_class[class].push(distance);
        }
        let mut pooled: Vec<f64> = held_out.distances.iter().map(|&(_, d)| d).collect();
        pooled.sort_by(f64::total_cmp);
        let fallback = calibration::quantile(&pooled, 0.5);
        let class_scales: Vec<f64> = per_class
            .iter_mut()
            .map(|distances| {
                distances.sort_by(f64::total_cmp);
                let median = calibration::quantile(distances, 0.5);
                if median.is_finite() && median > 0.0 {
                    median
                } else {
                    fallback
                }
            })
            .collect();
        if !class_scales.iter().all(|s| s.is_finite() && *s > 0.0) {
            return Err(CoreError::NotEnoughData(
                "no held-out distance to calibrate the novelty score on".into(),
            ));
        }
        let mut ratios: Vec<f64> = held_out
            .distances
            .iter()
            .map(|&(class, distance)| distance / class_scales[class])
            .collect();
        ratios.sort_by(f64::total_cmp);
        let threshold = calibration::quantile(&ratios, 1.0 - rejection);
        Self::try_from(NoveltyFields {
            space,
            class_scales,
            threshold,
            rejection,
            folds: held_out.folds,
            calibration_vectors: ratios.len(),
        })
    }

    /// Buffers sized for this model.
    pub fn scratch(&self) -> NoveltyScratch {
        NoveltyScratch {
            projected: vec![0.0; self.fields.space.n_axes()],
            distances: vec![0.0; self.fields.space.n_classes()],
        }
    }

    /// The novelty of `x` (a vector the classifier sees). Does not allocate once `scratch` is sized.
    pub fn score_into(&self, x: &[f64], scratch: &mut NoveltyScratch) -> Result<Novelty> {
        let space = &self.fields.space;
        scratch.projected.resize(space.n_axes(), 0.0);
        scratch.distances.resize(space.n_classes(), 0.0);
        space.distances_into(x, &mut scratch.projected, &mut scratch.distances)?;
        let score = scratch
            .distances
            .iter()
            .zip(&self.fields.class_scales)
            .map(|(distance, scale)| distance / scale)
            .fold(f64::INFINITY, f64::min);
        Ok(Novelty::of(score, self.fields.threshold))
    }

    /// [`score_into`](Self::score_into) with buffers of its own.
    pub fn score(&self, x: &[f64]) -> Result<Novelty> {
        self.score_into(x, &mut self.scratch())
    }

    /// The score above which a sample is `unknown`.
    pub fn threshold(&self) -> f64 {
        self.fields.threshold
    }

    /// The share of held-out training vectors the threshold was set to reject.
    pub fn rejection(&self) -> f64 {
        self.fields.rejection
    }

    /// How the held-out distances were obtained.
    pub fn folds(&self) -> CalibrationFolds {
        self.fields.folds
    }

    /// Length of the vectors scored.
    pub fn dims(&self) -> usize {
        self.fields.space.dims()
    }

    /// Number of classes.
    pub fn n_classes(&self) -> usize {
        self.fields.class_scales.len()
    }

    /// In words, for `describe` and reports.
    pub fn describe(&self) -> String {
        format!(
            "distance in a {}-direction discriminant space over each class's spread; unknown above {:.3} \
             ({:.0} % of {} held-out training samples, folds by {})",
            self.fields.space.n_axes(),
            self.fields.threshold,
            100.0 * self.fields.rejection,
            self.fields.calibration_vectors,
            match self.fields.folds {
                CalibrationFolds::Group => "group",
                CalibrationFolds::Split => "stratified split",
            }
        )
    }
}

/// The area under the ROC curve of a score that should be larger for `positives` than for `negatives`:
/// the chance that a random positive scores above a random negative, ties counting one half (the
/// Mann-Whitney statistic over the pair count). `None` when either side is empty or a score is NaN.
pub fn auroc(positives: &[f64], negatives: &[f64]) -> Option<f64> {
    if positives.is_empty()
        || negatives.is_empty()
        || positives.iter().chain(negatives).any(|v| v.is_nan())
    {
        return None;
    }
    let mut all: Vec<(f64, bool)> = positives
        .iter()
        .map(|&v| (v, true))
        .chain(negatives.iter().map(|&v| (v, false)))
        .collect();
    all.sort_by(|a, b| a.0.total_cmp(&b.0));
    // Mid-ranks over ties, then the positives' rank sum.
    let mut rank_sum = 0.0;
    let mut start = 0;
    while start < all.len() {
        let mut end = start + 1;
        while end < all.len() && all[end].0 == all[start].0 {
            end += 1;
        }
        let mid_rank = (start + end + 1) as f64 / 2.0;
        rank_sum += mid_rank * all[start..end].iter().filter(|(_, p)| *p).count() as f64;
        start = end;
    }
    let (p, n) = (positives.len() as f64, negatives.len() as f64);
    Some((rank_sum - p * (p + 1.0) / 2.0) / (p * n))
}
