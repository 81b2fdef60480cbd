//! Novelty: how far a sample lies from every class the model was trained on, and whether it is too far
//! to be one of them (`unknown`).
//!
//! The score is read in the model's own feature space, the vectors its classifier sees (principal
//! components; a classifier of thousands of raw features, ridge on random convolutions, has its
//! vectors reduced to principal components of their own first, [`NoveltyModel::with_reduction`]):
//! their discriminant space ([`Discriminant`], Fisher's directions with the pooled
//! within-class covariance the identity). Two numbers are read there. The distance to the nearest
//! training vector (of any class): a class's training vectors need not lie around its mean (a terrain
//! pressed at two angles makes two clusters), and a sample between two clusters, or beside a class's
//! cloud, is far from every training vector while near a mean. And the posterior of the nearest class
//! mean (Gaussian classes with that covariance, equal priors: linear discriminant analysis's
//! confidence), low for a sample between classes even when a training vector lies near it. The score
//! is `1 - posterior x credibility of the distance`, the chance-like evidence of both, with no constant
//! to tune (the credibility, defined below, of the distance among held-out ones).
//!
//! Both are calibrated on training vectors held out from the space and from the neighbours (their
//! group held out, as a new recording is): each held-out vector's distance and posterior in the space
//! of the other folds, its distance's credibility among the other held-out distances. A sample is
//! `unknown` when its score exceeds the threshold, the quantile of the held-out scores that leaves
//! [`DEFAULT_REJECTION`] of them out. No unknown class is needed, and `eval --leave-class-out` measures
//! what it does with a class never seen (`docs/methods.md`). Models written before the posterior
//! joined the score keep the distance alone as their score.
//!
//! The held-out scores give each score its credibility, its conformal p-value: the share of held-out
//! known vectors scoring at least as high. A decision's reported confidence is its posterior capped by
//! it ([`Novelty::capped`]): a classifier is sure of the class it names among those it knows, and says
//! nothing of whether the sample is one of them; a sample more novel than 90 % of known ones is never
//! reported at 0.9.

mod calibration;
mod contact;
mod discriminant;
mod labelled;
#[cfg(test)]
mod tests;

use serde::{Deserialize, Serialize};

pub(crate) use calibration::assign_folds;
pub use calibration::{CalibrationFolds, MIN_GROUPS};
pub use contact::{ContactCheck, NoveltyContact};
pub use discriminant::Discriminant;
use discriminant::{nearest, nearest_posterior};
pub use labelled::LabelledVectors;

use crate::error::{CoreError, Result};
use crate::projection::Pca;

/// The label of a decision whose sample is none of the model's classes.
pub const UNKNOWN_LABEL: &str = "unknown";

/// The share of held-out known training vectors the threshold rejects.
pub const DEFAULT_REJECTION: f64 = 0.05;

/// A novelty score and its verdict.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Novelty {
    /// The novelty score (larger: more novel): `1 - posterior x credibility of the distance`, in
    /// [0, 1] (the module documentation); for models written before, the distance to the nearest
    /// training vector in the discriminant space.
    pub score: f64,
    /// The score above which a sample is `unknown`.
    pub threshold: f64,
    /// `score > threshold`: the sample is none of the trained classes.
    pub unknown: bool,
    /// The share of held-out known training vectors scoring at least `score` (its conformal p-value,
    /// `(k + 1) / (n + 1)`); absent for models stored before the held-out scores were kept.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub credibility: Option<f64>,
}

impl Novelty {
    /// The verdict on `score` against `threshold` (without a credibility).
    pub fn of(score: f64, threshold: f64) -> Self {
        Self {
            score,
            threshold,
            unknown: score > threshold,
            credibility: None,
        }
    }

    /// A classifier's `posterior` for its class, capped by the credibility: the confidence reported.
    pub fn capped(&self, posterior: f64) -> f64 {
        self.credibility.map_or(posterior, |c| posterior.min(c))
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
    /// Principal components the classifier's vectors are reduced to before the space, when the
    /// classifier reads too many values for a covariance (absent: the space reads them as they are).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    reduction: Option<Pca>,
    space: Discriminant,
    /// The training vectors in the discriminant space, `n x axes` (row-major): the neighbours.
    neighbours: Vec<f64>,
    threshold: f64,
    /// The share of held-out training vectors the threshold was set to reject.
    rejection: f64,
    folds: CalibrationFolds,
    /// How many held-out distances set the scales and the threshold.
    calibration_vectors: usize,
    /// Those distances, sorted: a distance's credibility is read against them (absent from files
    /// written before they were kept: no credibility then).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    calibration: Vec<f64>,
    /// The held-out vectors' scores, `1 - posterior x credibility`, sorted: the threshold is their
    /// quantile and a score's credibility is read against them. Absent from files written before the
    /// posterior joined the score: their score is the distance, read against `calibration`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    combined: Vec<f64>,
    /// The contact's geometry appended to the classifier's vector before the space (frame models whose
    /// training data showed it separates their classes better; absent otherwise).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    contact: Option<NoveltyContact>,
    /// What leaving classes out inside the training data measured of the contact part (frame models;
    /// absent otherwise and from files written before the check).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    contact_check: Option<ContactCheck>,
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
        if fields.neighbours.is_empty() || fields.neighbours.len() % axes != 0 {
            return Err(bad(format!(
                "{} neighbour values are not whole vectors of {axes} coordinates",
                fields.neighbours.len()
            )));
        }
        let finite = space
            .axes
            .iter()
            .chain(&space.offset)
            .chain(&fields.neighbours)
            .all(|v| v.is_finite());
        if !(finite && fields.threshold.is_finite() && fields.threshold > 0.0) {
            return Err(bad(
                "the directions and the neighbours must be finite, the threshold positive".into(),
            ));
        }
        let sorted = fields.calibration.windows(2).all(|w| w[0] <= w[1]);
        if !(sorted && fields.calibration.iter().all(|v| v.is_finite())) {
            return Err(bad(
                "the held-out calibration distances must be finite and sorted".into(),
            ));
        }
        let sorted = fields.combined.windows(2).all(|w| w[0] <= w[1]);
        if !(sorted && fields.combined.iter().all(|v| (0.0..=1.0).contains(v))) {
            return Err(bad(
                "the held-out scores must be sorted and in [0, 1]".into()
            ));
        }
        if let Some(contact) = &fields.contact {
            contact.check()?;
            if fields.reduction.is_some() || space.dims <= contact.measures() {
                return Err(bad(format!(
                    "a contact part of {} measures needs a space of more values, read as they are (not \
                     after a reduction), got {}",
                    contact.measures(),
                    space.dims
                )));
            }
        }
        if let Some(pca) = &fields.reduction
            && pca.n_components() != space.dims
        {
            return Err(bad(format!(
                "a reduction to {} components before a space of {} values does not fit",
                pca.n_components(),
                space.dims
            )));
        }
        if !fields.combined.is_empty() && fields.calibration.is_empty() {
            return Err(bad(
                "held-out scores without the held-out distances they were read against".into(),
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
    reduced: Vec<f64>,
    joined: Vec<f64>,
    projected: Vec<f64>,
    distances: Vec<f64>,
}

impl NoveltyModel {
    /// Fits the space on `data`'s vectors (the classifier's training and validation vectors), keeps
    /// their projections as the neighbours, and calibrates the threshold on held-out
    /// nearest-neighbour distances (folds by the vectors' groups: at least [`MIN_GROUPS`] of them, and
    /// classes found in two or more) so that `rejection` of them are above it. An error saying what is
    /// missing otherwise.
    pub fn fit(data: LabelledVectors<'_>, rejection: f64) -> Result<Self> {
        let vectors = data.vectors();
        let space = Discriminant::fit(vectors, data.classes(), data.n_classes(), data.dims())?;
        let neighbours = space.project_rows(vectors)?;
        let held_out = calibration::held_out_distances(data)?;
        let mut distances = held_out.distances.clone();
        distances.sort_by(f64::total_cmp);
        let mut combined = calibration::held_out_scores(&held_out, &distances);
        combined.sort_by(f64::total_cmp);
        let threshold = calibration::quantile(&combined, 1.0 - rejection);
        if !(threshold.is_finite() && threshold > 0.0) {
            return Err(CoreError::NotEnoughData(
                "no held-out score to calibrate the novelty score on".into(),
            ));
        }
        Self::try_from(NoveltyFields {
            reduction: None,
            space,
            neighbours,
            threshold,
            rejection,
            folds: held_out.folds,
            calibration_vectors: distances.len(),
            calibration: distances,
            combined,
            contact: None,
            contact_check: None,
        })
    }

    /// [`fit`](Self::fit) on `data`'s vectors joined with the contact part fitted on their `raw`
    /// measures (of `config`, `n x measures`): a score that reads both
    /// ([`score_parts_into`](Self::score_parts_into)).
    pub fn fit_with_contact(
        config: &crate::features::contact::ContactConfig,
        data: LabelledVectors<'_>,
        raw: &[f64],
        rejection: f64,
    ) -> Result<Self> {
        let (vectors, dims) = (data.vectors(), data.dims());
        let contact = NoveltyContact::fit(config, raw, vectors, dims)?;
        let joined = contact.joined(vectors, dims, raw)?;
        let joined_data = data.with_vectors(&joined, dims + contact.measures())?;
        let mut model = Self::fit(joined_data, rejection)?;
        model.fields.contact = Some(contact);
        Self::try_from(model.fields)
    }

    /// This score with what the check of its contact part measured.
    pub fn with_contact_check(mut self, check: Option<ContactCheck>) -> Self {
        self.fields.contact_check = check;
        self
    }

    /// The contact part, when the score reads one: its raw measures of the prepared image are given
    /// to [`score_parts_into`](Self::score_parts_into).
    pub fn contact(&self) -> Option<&NoveltyContact> {
        self.fields.contact.as_ref()
    }

    /// This model reading vectors that `pca` reduces to the ones it was fitted on (`NoveltyModel::fit`
    /// on the projections): for a classifier of too many values for a covariance.
    pub fn with_reduction(mut self, pca: Pca) -> Result<Self> {
        self.fields.reduction = Some(pca);
        Self::try_from(self.fields)
    }

    /// Buffers sized for this model.
    pub fn scratch(&self) -> NoveltyScratch {
        NoveltyScratch {
            reduced: vec![0.0; self.fields.space.dims()],
            joined: if self.fields.contact.is_some() {
                vec![0.0; self.fields.space.dims()]
            } else {
                Vec::new()
            },
            projected: vec![0.0; self.fields.space.n_axes()],
            distances: vec![0.0; self.fields.space.n_classes()],
        }
    }

    /// The novelty of `x` (a vector the classifier sees), for a score without a contact part (an
    /// error otherwise). Does not allocate once `scratch` is sized.
    pub fn score_into(&self, x: &[f64], scratch: &mut NoveltyScratch) -> Result<Novelty> {
        self.score_parts_into(x, None, scratch)
    }

    /// The novelty of `x` (a vector the classifier sees) and, when the score has a contact part
    /// ([`contact`](Self::contact)), the raw contact measures of the same image (an error without
    /// them). Does not allocate once `scratch` is sized.
    pub fn score_parts_into(
        &self,
        x: &[f64],
        contact: Option<&[f64]>,
        scratch: &mut NoveltyScratch,
    ) -> Result<Novelty> {
        let space = &self.fields.space;
        let x = match (&self.fields.contact, contact) {
            (Some(part), Some(raw)) => {
                scratch.joined.resize(space.dims(), 0.0);
                part.join_into(x, raw, &mut scratch.joined)?;
                &scratch.joined[..]
            }
            (Some(_), None) => {
                return Err(CoreError::Param {
                    name: "novelty",
                    reason:
                        "this score reads the contact's geometry beside the classifier's vector, \
                             and none was given"
                            .into(),
                });
            }
            (None, _) => x,
        };
        let x = match &self.fields.reduction {
            Some(pca) => {
                scratch.reduced.resize(space.dims(), 0.0);
                pca.project_into(x, &mut scratch.reduced)?;
                &scratch.reduced[..]
            }
            None => x,
        };
        scratch.projected.resize(space.n_axes(), 0.0);
        scratch.distances.resize(space.n_classes(), 0.0);
        space.distances_into(x, &mut scratch.projected, &mut scratch.distances)?;
        let distance = nearest(&self.fields.neighbours, &scratch.projected);
        if self.fields.combined.is_empty() {
            return Ok(self.verdict(distance));
        }
        let posterior = nearest_posterior(&scratch.distances);
        let credibility = conformal_p_value(&self.fields.calibration, distance).unwrap_or(1.0);
        Ok(self.verdict(1.0 - posterior * credibility))
    }

    /// The verdict on `score` (as [`score_into`](Self::score_into) gives, or a mean of such scores),
    /// with its credibility.
    pub fn verdict(&self, score: f64) -> Novelty {
        Novelty {
            credibility: self.credibility(score),
            ..Novelty::of(score, self.fields.threshold)
        }
    }

    /// The conformal p-value of `score`: `(k + 1) / (n + 1)` where `k` of the `n` held-out known
    /// scores are at least `score`; `None` without them (an older file).
    pub fn credibility(&self, score: f64) -> Option<f64> {
        if self.fields.combined.is_empty() {
            conformal_p_value(&self.fields.calibration, score)
        } else {
            conformal_p_value(&self.fields.combined, score)
        }
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

    /// Length of the vectors scored (the classifier's).
    pub fn dims(&self) -> usize {
        match (&self.fields.reduction, &self.fields.contact) {
            (Some(pca), _) => pca.n_features(),
            (None, Some(contact)) => self.fields.space.dims() - contact.measures(),
            (None, None) => self.fields.space.dims(),
        }
    }

    /// Number of classes.
    pub fn n_classes(&self) -> usize {
        self.fields.space.n_classes()
    }

    /// In words, for `describe` and reports.
    pub fn describe(&self) -> String {
        let score = if self.fields.combined.is_empty() {
            "distance to the nearest training sample"
        } else {
            "1 - the nearest class's posterior x the credibility of the distance to the nearest training \
             sample"
        };
        let reduced = match (&self.fields.reduction, &self.fields.contact) {
            (Some(pca), _) => format!(" (of {} principal components)", pca.n_components()),
            (None, Some(contact)) => format!(
                " (of the classifier's values and {} measures of the contact's geometry)",
                contact.measures()
            ),
            (None, None) => String::new(),
        };
        format!(
            "{score} in a {}-direction discriminant space{reduced}; unknown above {:.3} ({:.0} % of {} \
             held-out training samples, folds by {})",
            self.fields.space.n_axes(),
            self.fields.threshold,
            100.0 * self.fields.rejection,
            self.fields.calibration_vectors,
            match self.fields.folds {
                CalibrationFolds::Group => "group",
                CalibrationFolds::Split => "stratified split",
            }
        ) + &self.fields.contact_check.map_or(String::new(), |check| {
            format!(
                "; the contact's geometry {}: leaving {} classes out inside the training data, AUROC \
                 {:.3} without it, {:.3} with it",
                if check.taken { "joined" } else { "not joined" },
                check.classes,
                check.without,
                check.with
            )
        })
    }
}

/// `(k + 1) / (n + 1)` where `k` of the `n` `sorted` values are at least `score`; `None` without
/// values or for a NaN score.
fn conformal_p_value(sorted: &[f64], score: f64) -> Option<f64> {
    if sorted.is_empty() || score.is_nan() {
        return None;
    }
    let at_least = sorted.len() - sorted.partition_point(|&d| d < score);
    Some((at_least + 1) as f64 / (sorted.len() + 1) as f64)
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
