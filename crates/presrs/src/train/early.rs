//! Early decisions at training: which decision points a whole-stance model is trained for
//! (`train --decide-at 8,16,32,whole` or `auto`), the data set's stances cut there as images, and the
//! points' classifiers and `auto`'s threshold added to the model ([`presrs_core::pipeline::train_early`]).

use presrs_core::TrainedModel;
use presrs_core::error::CoreError;
use presrs_core::pipeline::{LabeledImage, StanceImages, train_early};
use presrs_core::sample::SampleKind;
use presrs_core::selection::{StageObserver, ValidateBy};
use presrs_core::split::Split;
use presrs_io::message::{Message, Opt};

use crate::dataset::Dataset;
use crate::error::{Context, Error, Result};
use crate::method::Method;
use crate::progress::Progress;

/// Shares of the median training stance at which `--decide-at auto` puts its decision points: over
/// most of the stance, as TEASER and ECTS place theirs. `auto`'s decision is due by mid-stance on
/// average, so the late points serve as its deadline for the unsure stances while the confident ones
/// are decided early; the last is at 80 %, which most stances reach before their lift-off
/// (`bench/real/RESULTS.md`, "Early decisions, sixth run").
pub const AUTO_POINT_SHARES: [f64; 8] = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8];

/// The decision points a model is trained for, as asked.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum DecisionPoints {
    /// The whole stance only (lift-off).
    #[default]
    Whole,
    /// These frames after touchdown (and the whole stance).
    Frames(Vec<usize>),
    /// Points at [`AUTO_POINT_SHARES`] of the median training stance (and the whole stance).
    Auto,
}

impl std::str::FromStr for DecisionPoints {
    type Err = String;

    /// `auto`, or frames after touchdown separated by commas, where `whole` (the whole stance, always
    /// trained) may stand among them: `8,16,32,whole`.
    fn from_str(text: &str) -> std::result::Result<Self, String> {
        if text.trim() == "auto" {
            return Ok(Self::Auto);
        }
        let mut frames = Vec::new();
        for part in text.split(',').map(str::trim).filter(|p| !p.is_empty()) {
            if part == "whole" {
                continue;
            }
            frames.push(part.parse::<usize>().map_err(|_| {
                format!(
                    "expected auto, or frames after touchdown and `whole` separated by commas \
                     (8,16,32,whole), got {part:?}"
                )
            })?);
        }
        frames.sort_unstable();
        frames.dedup();
        Ok(if frames.is_empty() {
            Self::Whole
        } else {
            Self::Frames(frames)
        })
    }
}

impl DecisionPoints {
    /// The frames after touchdown, `auto`'s from the training stances' lengths `stance_frames`.
    pub fn resolve(&self, stance_frames: &[usize]) -> Vec<usize> {
        match self {
            Self::Whole => Vec::new(),
            Self::Frames(frames) => frames.clone(),
            Self::Auto => {
                let median = presrs_core::online::typical_stance_frames(stance_frames).unwrap_or(0);
                let mut frames: Vec<usize> = AUTO_POINT_SHARES
                    .iter()
                    .map(|share| ((share * median as f64).round() as usize).max(2))
                    .collect();
                frames.dedup();
                frames
            }
        }
    }
}

/// The stances `part` (indices into `pool`, itself indices into `dataset`'s samples; `labels` by pool
/// index) as images: whole, cut at each point, and their lengths.
pub fn stance_images<'d>(
    dataset: &'d Dataset,
    pool: &[usize],
    part: &[usize],
    labels: &[&'d str],
) -> StanceImages<'d> {
    let image = |frame: &'d presrs_core::Frame, j: usize| {
        let sample = &dataset.samples[pool[j]];
        LabeledImage {
            frame: frame.view(),
            label: labels[j],
            condition: sample.condition.as_deref(),
            group: sample.group.as_deref(),
        }
    };
    StanceImages {
        whole: part
            .iter()
            .map(|&j| image(&dataset.samples[pool[j]].frame, j))
            .collect(),
        cuts: dataset
            .stances
            .points
            .iter()
            .map(|(k, cuts)| (*k, part.iter().map(|&j| image(&cuts[pool[j]], j)).collect()))
            .collect(),
        stance_frames: part
            .iter()
            .map(|&j| dataset.stances.stance_frames[pool[j]])
            .collect(),
    }
}

/// A decision point's classifier chosen as a whole-stance model of `method` is when `method` leaves
/// a choice (features or classifier `auto`): the automatic choice among its candidates for the stances
/// cut at the point, validated on the cut validation stances, its stages told to `progress` (named by
/// the point). `None` for a fixed method (the points take the whole-stance model's).
pub fn point_chooser<'m>(
    method: &'m Method,
    sample: &'m SampleKind,
    seed: u64,
    progress: &'m dyn Progress,
) -> Option<PointChooser<'m>> {
    let choose = move |k: usize, train: &[LabeledImage<'_>], validation: &[LabeledImage<'_>]| {
        let grid = train
            .first()
            .map(|image| image.frame.grid())
            .ok_or_else(|| CoreError::Param {
                name: "decision point",
                reason: "no training stance reaches the point".into(),
            })?;
        // One MiniRocket draw: each point is a race of its own, so draws would multiply by the points.
        let candidates = method
            .candidates_for(grid, false, sample, 1)
            .map_err(|err| CoreError::Param {
                name: "decision point",
                reason: err.to_string(),
            })?;
        let tell = |stage: &str| progress.stage(&format!("decision point {k} frames: {stage}"));
        presrs_core::selection::train_auto(
            train,
            validation,
            &method
                .auto_choice(&candidates)
                .with_stages(StageObserver(&tell)),
            seed,
        )
    };
    method
        .is_auto()
        .then(|| Box::new(choose) as PointChooser<'m>)
}

/// What [`point_chooser`] gives: a [`presrs_core::pipeline::ChoosePoint`] that owns its closure.
pub type PointChooser<'m> = Box<
    dyn Fn(
            usize,
            &[LabeledImage<'_>],
            &[LabeledImage<'_>],
        ) -> presrs_core::error::Result<TrainedModel>
        + 'm,
>;

/// `model` with the early decisions of the data set's decision points, trained on the draw `split` of
/// the samples at `pool` (indices into the data set; `labels` by pool index), each point's method
/// chosen as the model's was (`method`, [`point_chooser`]), each stage told to `progress`. Unchanged
/// when the data set holds no cuts.
pub fn with_early_decisions(
    model: TrainedModel,
    (dataset, method): (&Dataset, &Method),
    (pool, split, labels): (&[usize], &Split, &[&str]),
    seed: u64,
    progress: &dyn Progress,
) -> Result<TrainedModel> {
    if dataset.stances.points.is_empty() {
        return Ok(model);
    }
    if dataset.stances.stance_frames.len() != dataset.samples.len() {
        return Err(Error::invalid(
            "decision points before lift-off need whole-stance samples read from movies",
        ));
    }
    let train_set = stance_images(dataset, pool, &split.train, labels);
    let validation = stance_images(dataset, pool, &split.validation, labels);
    let chooser = point_chooser(method, &dataset.sample, seed, progress);
    let choose = chooser
        .as_deref()
        .map(|f| f as presrs_core::pipeline::ChoosePoint<'_>);
    let tell = |stage: &str| progress.stage(stage);
    let on_stage = Some(StageObserver(&tell));
    let early = train_early(&model, &train_set, &validation, choose, seed, on_stage).with_context(
        || {
            format!(
                "{}: cannot train the decision points",
                dataset.path().display()
            )
        },
    )?;
    model
        .with_early(early)
        .with_context(|| format!("{}: decision points", dataset.path().display()))
}

/// The warning for a model whose `auto` rule was learned on stances held out other than by group
/// (`None` otherwise): validation inside the same walkers, surfaces or sessions cannot see how a new
/// one's stances differ, and the early points are where they differ most; a rule it calls safe may
/// decide a new walker's stances early, confidently and wrongly (on `jiku-walk`, leave one walker out,
/// 0-12 points under the whole stance; `bench/real/RESULTS.md`, "Early decisions, seventh run").
pub fn rule_validation_warning(model: &TrainedModel) -> Option<Message> {
    let auto = model.early()?.auto.as_ref()?;
    let by = auto.validated_by?;
    if by == ValidateBy::Group {
        return None;
    }
    Some(
        Message::from(format!(
            "auto's rule for early decisions was learned on training stances held out by {}, not by \
             leaving groups out (that needs 3 or more groups, each class in more than one): it \
             cannot see how the stances of a new walker, surface or session differ, and the early \
             points are where they differ most, so on such stances it may decide early, \
             confidently and wrongly; give each stance's walker or session as its `group` in the \
             manifest to learn it by leaving groups out, or train without ",
            by.describe()
        ))
        .opt(Opt::DecideAt)
        .text(" to decide at lift-off"),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decision_points_are_frames_and_whole_or_auto() {
        assert_eq!(
            "16, 8,whole,32".parse::<DecisionPoints>(),
            Ok(DecisionPoints::Frames(vec![8, 16, 32]))
        );
        assert_eq!("whole".parse::<DecisionPoints>(), Ok(DecisionPoints::Whole));
        assert_eq!("auto".parse::<DecisionPoints>(), Ok(DecisionPoints::Auto));
        assert!("8,soon".parse::<DecisionPoints>().is_err());
        assert_eq!(
            DecisionPoints::Auto.resolve(&[40, 60, 61]),
            vec![6, 12, 18, 24, 30, 36, 42, 48]
        );
        // Short stances: every point at least 2 frames, each once.
        assert_eq!(
            DecisionPoints::Auto.resolve(&[14, 14, 15]),
            vec![2, 3, 4, 6, 7, 8, 10, 11]
        );
        assert_eq!(DecisionPoints::Auto.resolve(&[5, 5]), vec![2, 3, 4]);
    }
}
