//! Early decisions (anytime classification) of a whole-stance model: one classifier per decision point
//! before lift-off, each trained on the training stances cut at its point (the same method as the
//! whole-stance classifier: crop, features, projection and classifier family), and the confidence
//! threshold with which `auto` decides at the first point that passes it, else at a deadline point
//! (the idea of TEASER, Schäfer and Leser 2020, and of ECTS: decide when the prediction is safe, not at
//! a fixed frame).
//!
//! A point `K` is the stance's first `K + 1` frames (frames touchdown to touchdown + K), summarised as
//! the online [`StanceBuffer`](crate::online::StanceBuffer) summarises them, as a sample of its own
//! length, `K + 1` frames (not zero-padded to the whole stance's: the features see only the frames
//! there are). A stance that lifts off before frame `K` is decided at its lift-off, whole, by the
//! whole-stance classifier, online and here alike.
//!
//! **The threshold** is learned from out-of-sample confidences: the training and validation stances (at
//! most [`RULE_STANCES`] of them, a stratified subsample of more) are split into the automatic
//! choice's inner folds (by group, condition or stratified splits), each fold's
//! classifiers are trained on the rest, and each held-out stance is classified at every point and
//! whole. A threshold (among the confidences seen, and "never") is *safe* when its early decisions
//! are safe with a margin for the few stances validation has: over the stances `auto` decides before
//! their lift-off, the Wilson lower bound (z = [`AUTO_BOUND_Z`]) of its accuracy is at most
//! [`AUTO_TOLERANCE`] below the whole-stance classifier's accuracy on the same stances. Of the safe
//! thresholds, `auto` takes the *highest* whose mean decision on the held-out stances comes by
//! [`AUTO_EARLINESS`] of their median length (if none does, the lowest safe one: safety before
//! earliness).
//!
//! Why the highest within the earliness budget rather than the lowest safe one: validation inside
//! the training data is optimistic about early points, because it cannot see the shift to what the
//! training data lack (another person's gait, another surface): on jiku-walk, a fold trained on one
//! walker found its first point safe at any threshold and decided every stance of the other walker at
//! 10 % of the stance, 15 points below the whole stance, where one threshold waiting longer (still
//! within half the stance) loses nothing. Waiting costs nothing until the decision is due, so `auto`
//! spends the earliness it is allowed on confidence. A point estimate of the accuracy alone, without
//! the bound, let one subject's 60 stances set a threshold that was too bold on another subject.
//!
//! **The deadline** is learned after the threshold: of the points at which deciding every stance no
//! point was confident about by then (by that point's classifier, whatever its confidence) keeps the
//! early decisions safe by the same bound, the latest with which the mean decision on the held-out
//! stances still comes by [`AUTO_EARLINESS`] of their median length (else the earliest safe one);
//! none if no point is safe (the stance waits for its lift-off). The budget is on the mean, as for
//! the threshold: the unsure stances may wait past mid-stance for a point that knows more, while
//! the confident ones, decided early, pay for it. The late points are the accurate ones while their
//! confidences sit below the one threshold the earliest points set (docs/methods.md, "Early
//! decisions").

use std::time::Instant;

use crate::error::{CoreError, Result};
use crate::pipeline::extract::LabeledImage;
use crate::pipeline::model::{
    AutoRule, AutoThreshold, DecisionPoint, EarlyCost, EarlyDecisions, TrainedModel,
};
use crate::pipeline::train::train;
use crate::selection::folds::make_folds;
use crate::selection::subsample::{SCORING_SAMPLES, stratified_subsample};
use crate::selection::{StageObserver, ValidateBy};

/// How far below the whole-stance classifier's validation accuracy the lower bound of `auto`'s early
/// decisions' accuracy may fall (two points: the loss the early decision may cost).
pub const AUTO_TOLERANCE: f64 = 0.02;

/// The z of the lower bound on the early decisions' validation accuracy (one-sided, about 84 %).
pub const AUTO_BOUND_Z: f64 = 1.0;

/// When `auto`'s decision is due on average: this share of the median validation stance (by
/// mid-stance on average, while the gait can still change before the next touchdown; the threshold
/// and the deadline both spend this budget).
pub const AUTO_EARLINESS: f64 = 0.5;

/// Stances as images for early decisions: each whole (laid into the model's length), each cut at every
/// point `K` (laid into `K + 1` frames), and each stance's length; all in the same order.
#[derive(Clone, Debug, Default)]
pub struct StanceImages<'a> {
    pub whole: Vec<LabeledImage<'a>>,
    /// Per point (its frames after touchdown), the stances cut there.
    pub cuts: Vec<(usize, Vec<LabeledImage<'a>>)>,
    /// Each stance's length, frames.
    pub stance_frames: Vec<usize>,
}

impl<'a> StanceImages<'a> {
    /// The stances at `indices`, in that order.
    pub fn select(&self, indices: &[usize]) -> Self {
        let pick = |images: &[LabeledImage<'a>]| indices.iter().map(|&i| images[i]).collect();
        Self {
            whole: pick(&self.whole),
            cuts: self
                .cuts
                .iter()
                .map(|(frames, images)| (*frames, pick(images)))
                .collect(),
            stance_frames: indices.iter().map(|&i| self.stance_frames[i]).collect(),
        }
    }

    /// These stances followed by `other`'s (the same points).
    pub fn joined(&self, other: &Self) -> Self {
        let mut all = self.clone();
        all.whole.extend_from_slice(&other.whole);
        for ((_, mine), (_, theirs)) in all.cuts.iter_mut().zip(&other.cuts) {
            mine.extend_from_slice(theirs);
        }
        all.stance_frames.extend_from_slice(&other.stance_frames);
        all
    }

    fn check(&self) -> Result<()> {
        let n = self.whole.len();
        if self.stance_frames.len() != n || self.cuts.iter().any(|(_, cut)| cut.len() != n) {
            return Err(CoreError::Param {
                name: "stance images",
                reason: "every point needs each stance cut there, and each stance its length"
                    .into(),
            });
        }
        Ok(())
    }
}

/// One stance classified at every point and whole, by models that did not train on it.
#[derive(Clone, Debug, PartialEq)]
pub struct HeldOutStance {
    pub class: usize,
    pub stance_frames: usize,
    /// Per point: class and confidence (`None`: the stance lifts off before the point).
    pub points: Vec<Option<(usize, f64)>>,
    pub whole: (usize, f64),
}

/// What `auto` (or a fixed point) decided for one stance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OfflineDecision {
    pub class: usize,
    pub confidence: f64,
    /// Frames after touchdown (the stance's length when decided at lift-off).
    pub frame: usize,
    /// The point that decided (`None`: the whole-stance classifier at lift-off).
    pub point: Option<usize>,
}

impl HeldOutStance {
    /// `auto`'s decision by `rule` over points `frames`: the first point whose confidence is at least
    /// the threshold, else the deadline point (when the stance reaches it), else the whole stance at
    /// its lift-off.
    pub fn decide(&self, frames: &[usize], rule: AutoRule) -> OfflineDecision {
        for (index, (&k, outcome)) in frames.iter().zip(&self.points).enumerate() {
            if let Some((class, confidence)) = *outcome
                && rule.decides(k, confidence)
            {
                return OfflineDecision {
                    class,
                    confidence,
                    frame: k,
                    point: Some(index),
                };
            }
        }
        OfflineDecision {
            class: self.whole.0,
            confidence: self.whole.1,
            frame: self.stance_frames,
            point: None,
        }
    }
}

/// Trains the classifier of decision point `K` (its first argument) on the stances cut there
/// (training, validation): how a whole-stance model from the automatic choice has a method chosen
/// for each point (the method that suits the whole stance need not suit its first frames).
pub type ChoosePoint<'f> =
    &'f dyn Fn(usize, &[LabeledImage<'_>], &[LabeledImage<'_>]) -> Result<TrainedModel>;

/// Trains the early decisions of `whole` (a whole-stance model trained on `train.whole` with
/// `validation.whole` validating): each point's model on the stances cut there, by `choose` when
/// given (a method chosen per point) or else with the whole model's method, and `auto`'s threshold
/// from the inner folds of all those stances, each point retrained there with its own method (see the
/// module docs). `on_stage` is told each point and each inner fold as it begins; the time each part
/// took is in the result's `cost`.
pub fn train_early(
    whole: &TrainedModel,
    train_set: &StanceImages<'_>,
    validation: &StanceImages<'_>,
    choose: Option<ChoosePoint<'_>>,
    seed: u64,
    on_stage: Option<StageObserver<'_>>,
) -> Result<EarlyDecisions> {
    train_set.check()?;
    validation.check()?;
    let started = Instant::now();
    let length = whole.image_grid().cols;
    let trained: Vec<_> = train_set
        .cuts
        .iter()
        .zip(&validation.cuts)
        .filter(|((frames, _), _)| frames + 1 < length)
        .collect();
    let mut points = Vec::new();
    for (i, ((frames, cut), (_, cut_validation))) in trained.iter().enumerate() {
        StageObserver::tell(on_stage, || {
            let how = if choose.is_some() {
                "choosing its method"
            } else {
                "training"
            };
            format!(
                "decision point {frames} frames ({} of {}): {how} on {} cut stances",
                i + 1,
                trained.len(),
                cut.len() + cut_validation.len()
            )
        });
        let model = match choose {
            Some(choose) => choose(*frames, cut, cut_validation)?.with_sample(whole.sample())?,
            None => train_like(whole, cut, cut_validation)?,
        };
        points.push(DecisionPoint {
            frames: *frames,
            model,
        });
    }
    let points_seconds = started.elapsed().as_secs_f64();
    let rule_started = Instant::now();
    let all = train_set.joined(validation);
    let stances = all.whole.len();
    let rule_set = rule_stances(all, RULE_STANCES, seed);
    let (held_out, inner_folds, validated_by) =
        held_out_stances(whole, &rule_set, &points, seed, on_stage)?;
    let kept: Vec<usize> = points.iter().map(|p| p.frames).collect();
    let auto = AutoThreshold {
        validated_by: Some(validated_by),
        ..learn_threshold(&held_out, &kept)
    };
    let cost = EarlyCost {
        points_seconds,
        rule_seconds: rule_started.elapsed().as_secs_f64(),
        inner_folds,
        inner_models: inner_folds * (points.len() + 1),
        rule_stances: rule_set.whole.len(),
        stances,
    };
    let early = EarlyDecisions {
        points,
        auto: Some(auto),
        cost: Some(cost),
    };
    early.check(whole)?;
    Ok(early)
}

/// The most stances `auto`'s rule is learned from: on more, a stratified subsample (by label, group
/// and condition) of this many, as the automatic choice scores its candidates. The rule needs a few
/// thousand held-out stances, not all of a robot's logs, and its inner folds retrain the whole stance
/// and every point once each.
pub const RULE_STANCES: usize = SCORING_SAMPLES;

/// `all`, or a stratified subsample of `at_most` of its stances (seeded) when it holds more.
fn rule_stances(all: StanceImages<'_>, at_most: usize, seed: u64) -> StanceImages<'_> {
    match stratified_subsample(&all.whole, at_most, seed) {
        Some(rows) => all.select(&rows),
        None => all,
    }
}

/// A model trained with `like`'s method (its configuration) and sample kind.
pub fn train_like(
    like: &TrainedModel,
    train_images: &[LabeledImage<'_>],
    validation: &[LabeledImage<'_>],
) -> Result<TrainedModel> {
    let config = like.summary().config.clone().check()?;
    train(train_images, validation, &config)?.with_sample(like.sample())
}

/// Every stance of `all` held out once (the inner folds of the automatic choice) and classified at
/// `points` and whole by models of their methods (`whole`'s, and each point's own) trained on the
/// fold's others; the number of folds, and how they were made. `on_stage` is told each fold as it
/// begins.
pub fn held_out_stances(
    whole: &TrainedModel,
    all: &StanceImages<'_>,
    points: &[DecisionPoint],
    seed: u64,
    on_stage: Option<StageObserver<'_>>,
) -> Result<(Vec<HeldOutStance>, usize, ValidateBy)> {
    let folds = make_folds(&all.whole, ValidateBy::Auto, seed)?;
    let mut held_out = Vec::new();
    let count = folds.folds.len();
    for (i, fold) in folds.folds.iter().enumerate() {
        StageObserver::tell(on_stage, || {
            format!(
                "auto's rule: inner fold {} of {count}, the whole stance and {} points trained on \
                 {} stances",
                i + 1,
                points.len(),
                fold.train.len() + fold.validation.len()
            )
        });
        let train_part = all.select(&fold.train);
        let validation_part = all.select(&fold.validation);
        let test = all.select(&fold.test);
        held_out.extend(classify_held_out(
            whole,
            &train_part,
            &validation_part,
            &test,
            points,
        )?);
    }
    Ok((held_out, count, folds.used))
}

/// `test`'s stances classified at every point of `points` and whole, by models of `like`'s method
/// (whole) and each point's (its own model's) trained on `train_part` (validated on `validation`).
pub fn classify_held_out(
    like: &TrainedModel,
    train_part: &StanceImages<'_>,
    validation: &StanceImages<'_>,
    test: &StanceImages<'_>,
    points: &[DecisionPoint],
) -> Result<Vec<HeldOutStance>> {
    let whole_model = train_like(like, &train_part.whole, &validation.whole)?;
    let class_names = whole_model.class_names().to_vec();
    let whole = batch_outcomes(&whole_model, &test.whole)?;
    let mut per_point = Vec::new();
    for point in points {
        let k = point.frames;
        let model = train_like(&point.model, &cut_at(train_part, k), &cut_at(validation, k))?;
        per_point.push(batch_outcomes(&model, &cut_at(test, k))?);
    }
    test.whole
        .iter()
        .enumerate()
        .map(|(i, image)| {
            let class = class_names
                .iter()
                .position(|name| name == image.label)
                .ok_or_else(|| CoreError::Param {
                    name: "label",
                    reason: format!("held-out class {:?} was not trained on", image.label),
                })?;
            let stance_frames = test.stance_frames[i];
            Ok(HeldOutStance {
                class,
                stance_frames,
                points: stance_points(points, &per_point, i, stance_frames),
                whole: whole[i],
            })
        })
        .collect()
}

/// `test`'s stances classified by `model` (whole) and its decision points (each stance cut at every
/// point its own images hold), for an evaluation of early decisions on stances it did not train on.
pub fn classify_stances(
    model: &TrainedModel,
    test: &StanceImages<'_>,
) -> Result<Vec<HeldOutStance>> {
    test.check()?;
    let early = model.early().ok_or_else(|| CoreError::Param {
        name: "early decisions",
        reason: "the model has no decision points".into(),
    })?;
    let whole = batch_outcomes(model, &test.whole)?;
    let mut per_point = Vec::new();
    for point in &early.points {
        let images = test
            .cuts
            .iter()
            .find(|(frames, _)| *frames == point.frames)
            .map(|(_, images)| images.as_slice())
            .ok_or_else(|| CoreError::Param {
                name: "stance images",
                reason: format!("no stances cut at point {}", point.frames),
            })?;
        per_point.push(batch_outcomes(&point.model, images)?);
    }
    test.whole
        .iter()
        .enumerate()
        .map(|(i, image)| {
            let class = model
                .class_names()
                .iter()
                .position(|name| name == image.label)
                .unwrap_or(usize::MAX);
            let stance_frames = test.stance_frames[i];
            Ok(HeldOutStance {
                class,
                stance_frames,
                points: stance_points(&early.points, &per_point, i, stance_frames),
                whole: whole[i],
            })
        })
        .collect()
}

/// Each image's class and confidence by `model`, in order.
fn batch_outcomes(model: &TrainedModel, images: &[LabeledImage<'_>]) -> Result<Vec<(usize, f64)>> {
    let views: Vec<_> = images.iter().map(|image| image.frame).collect();
    model
        .classify_batch(&views)
        .into_iter()
        .map(|result| result.map(|c| (c.class, c.confidence)))
        .collect()
}

/// Stance `i`'s outcome at every point (`None` where it lifts off before the point).
fn stance_points(
    points: &[DecisionPoint],
    per_point: &[Vec<(usize, f64)>],
    i: usize,
    stance_frames: usize,
) -> Vec<Option<(usize, f64)>> {
    points
        .iter()
        .zip(per_point)
        .map(|(point, outcome)| (point.frames < stance_frames).then(|| outcome[i]))
        .collect()
}

/// The stances of `set` cut at point `k` (none when it holds no such cut).
fn cut_at<'a>(set: &StanceImages<'a>, k: usize) -> Vec<LabeledImage<'a>> {
    set.cuts
        .iter()
        .find(|(frames, _)| *frames == k)
        .map(|(_, images)| images.clone())
        .unwrap_or_default()
}

/// The rule of the module docs over `held_out` stances: of the thresholds whose early decisions'
/// accuracy, at its lower bound, is within [`AUTO_TOLERANCE`] of the whole-stance classifier's on
/// the same stances, the highest whose mean decision comes by [`AUTO_EARLINESS`] of the median
/// stance, else the lowest; then the deadline: of the points at which deciding the stances the
/// threshold leaves keeps the early decisions safe, the latest with which the mean decision still
/// comes by [`AUTO_EARLINESS`] of the median stance, else the earliest.
pub fn learn_threshold(held_out: &[HeldOutStance], frames: &[usize]) -> AutoThreshold {
    let never = 1.0 + f64::EPSILON.sqrt();
    let mut candidates = point_confidences(held_out);
    candidates.push(never);
    let due = AUTO_EARLINESS * median_length(held_out) as f64;
    let safe: Vec<f64> = candidates
        .into_iter()
        .filter(|&t| early_decisions_are_safe(held_out, frames, AutoRule::threshold(t)))
        .collect();
    let threshold = safe
        .iter()
        .rev()
        .copied()
        .find(|&t| mean_decision_frame(held_out, frames, AutoRule::threshold(t)) <= due)
        .or_else(|| safe.first().copied())
        .unwrap_or(never);
    let with_deadline = |k: usize| AutoRule {
        threshold,
        deadline: Some(k),
    };
    let safe_deadlines: Vec<usize> = frames
        .iter()
        .copied()
        .filter(|&k| early_decisions_are_safe(held_out, frames, with_deadline(k)))
        .collect();
    // A later deadline never decides earlier, so the mean decision grows with it: the latest due in
    // time, else the earliest safe one (safety before earliness, as for the threshold).
    let deadline = safe_deadlines
        .iter()
        .rev()
        .copied()
        .find(|&k| mean_decision_frame(held_out, frames, with_deadline(k)) <= due)
        .or_else(|| safe_deadlines.first().copied());
    measure_rule(
        held_out,
        frames,
        AutoRule {
            threshold,
            deadline,
        },
    )
}

/// `rule` with what it gives on `held_out`.
fn measure_rule(held_out: &[HeldOutStance], frames: &[usize], rule: AutoRule) -> AutoThreshold {
    let n = held_out.len().max(1) as f64;
    let decisions: Vec<OfflineDecision> = held_out
        .iter()
        .map(|stance| stance.decide(frames, rule))
        .collect();
    AutoThreshold {
        threshold: rule.threshold,
        whole_accuracy: accuracy(held_out, |stance| stance.whole.0),
        auto_accuracy: accuracy(held_out, |stance| stance.decide(frames, rule).class),
        mean_decision_frame: decisions.iter().map(|d| d.frame as f64).sum::<f64>() / n,
        mean_decision_share: decisions
            .iter()
            .zip(held_out)
            .map(|(d, s)| d.frame as f64 / s.stance_frames.max(1) as f64)
            .sum::<f64>()
            / n,
        validation_stances: held_out.len(),
        validated_by: None,
        deadline: rule.deadline,
    }
}

/// The mean frame after touchdown at which `rule` decides `held_out` (0 without stances).
fn mean_decision_frame(held_out: &[HeldOutStance], frames: &[usize], rule: AutoRule) -> f64 {
    let frames_sum: usize = held_out
        .iter()
        .map(|stance| stance.decide(frames, rule).frame)
        .sum();
    frames_sum as f64 / held_out.len().max(1) as f64
}

/// Whether `auto` by `rule` is safe on `held_out`: no stance decided early, or the lower bound of the
/// early decisions' accuracy within [`AUTO_TOLERANCE`] of the whole stance's on them.
fn early_decisions_are_safe(held_out: &[HeldOutStance], frames: &[usize], rule: AutoRule) -> bool {
    let (mut early, mut right, mut whole_right) = (0usize, 0usize, 0usize);
    for stance in held_out {
        let decision = stance.decide(frames, rule);
        if decision.point.is_some() {
            early += 1;
            right += usize::from(decision.class == stance.class);
            whole_right += usize::from(stance.whole.0 == stance.class);
        }
    }
    if early == 0 {
        return true;
    }
    let whole = whole_right as f64 / early as f64;
    wilson_lower_bound(right, early, AUTO_BOUND_Z) >= whole - AUTO_TOLERANCE - 1e-12
}

/// The Wilson score interval's lower bound of a proportion `right / n` at `z` (0 when `n` is 0).
pub fn wilson_lower_bound(right: usize, n: usize, z: f64) -> f64 {
    if n == 0 {
        return 0.0;
    }
    let n = n as f64;
    let p = right as f64 / n;
    let z2 = z * z;
    let centre = p + z2 / (2.0 * n);
    let spread = z * (p * (1.0 - p) / n + z2 / (4.0 * n * n)).sqrt();
    ((centre - spread) / (1.0 + z2 / n)).max(0.0)
}

/// Every distinct confidence of the points' outcomes of `stances`, ascending: the thresholds that
/// decide differently.
pub fn point_confidences(stances: &[HeldOutStance]) -> Vec<f64> {
    let mut confidences: Vec<f64> = stances
        .iter()
        .flat_map(|stance| stance.points.iter().flatten().map(|&(_, c)| c))
        .collect();
    confidences.sort_by(f64::total_cmp);
    confidences.dedup();
    confidences
}

/// The median of the stances' lengths, frames (the lower middle one; 0 without stances).
pub fn median_length(stances: &[HeldOutStance]) -> usize {
    let mut lengths: Vec<usize> = stances.iter().map(|s| s.stance_frames).collect();
    lengths.sort_unstable();
    lengths
        .get(lengths.len().saturating_sub(1) / 2)
        .copied()
        .unwrap_or(0)
}

/// The share of `stances` whose class `decided` gives right (0 without stances).
fn accuracy(stances: &[HeldOutStance], decided: impl Fn(&HeldOutStance) -> usize) -> f64 {
    if stances.is_empty() {
        return 0.0;
    }
    let right = stances.iter().filter(|s| decided(s) == s.class).count();
    right as f64 / stances.len() as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stance(class: usize, points: &[(usize, f64)], whole: (usize, f64)) -> HeldOutStance {
        HeldOutStance {
            class,
            stance_frames: 20,
            points: points.iter().copied().map(Some).collect(),
            whole,
        }
    }

    /// `auto` decides at the first confident point; the threshold is safe at its lower bound, so a
    /// confident wrong early answer raises it, and so do too few right ones to trust; of the safe
    /// ones it takes the highest whose mean decision comes by half the median stance.
    #[test]
    fn the_threshold_is_the_highest_safe_one_whose_decisions_come_by_mid_stance() {
        let frames = [4, 8];
        // Sixty stances of 20 frames right early at 0.9 and above; one wrong at 0.7.
        let mut stances = vec![stance(0, &[(1, 0.7), (0, 0.95)], (0, 0.99))];
        for i in 0..60 {
            let class = i % 2;
            stances.push(stance(class, &[(class, 0.9), (class, 0.97)], (class, 0.99)));
        }
        let auto = learn_threshold(&stances, &frames);
        // 0.7 decides the first stance wrong at frame 4; 0.9, 0.95 and 0.97 are safe; 0.97 decides
        // the sixty at frame 8 and would leave the first for its lift-off (a mean of 8.2 frames, by
        // mid-stance: 10 frames), 0.99 none before lift-off. The point at 8 is safe as a deadline:
        // it decides the first stance there, right.
        assert_eq!(auto.threshold, 0.97);
        assert_eq!((auto.whole_accuracy, auto.auto_accuracy), (1.0, 1.0));
        assert_eq!(auto.deadline, Some(8));
        assert_eq!(auto.mean_decision_frame, 8.0);
        // With the second point past mid-stance, the highest safe threshold due in time is 0.9.
        let late_points = [4, 12];
        let auto = learn_threshold(&stances, &late_points);
        assert_eq!(auto.threshold, 0.9);
        // The point at 4 as a deadline would decide the first stance wrong: too bold; the one at 12
        // is safe and due in time (it decides no stance the threshold leaves).
        assert_eq!(auto.deadline, Some(12));
        assert_eq!(auto.mean_decision_frame, (12.0 + 60.0 * 4.0) / 61.0);
        let late = stances[0].decide(&frames, AutoRule::threshold(0.99));
        assert_eq!((late.point, late.frame), (None, 20));
        // Three stances right early are too few to be sure of two points: auto waits.
        let few = learn_threshold(&stances[1..4], &frames);
        assert!(few.threshold > 1.0, "{}", few.threshold);
        // A stance that lifts off before a point has no outcome there.
        let short = HeldOutStance {
            points: vec![Some((0, 0.99)), None],
            ..stances[0].clone()
        };
        assert_eq!(
            short.decide(&frames, AutoRule::threshold(0.999)).point,
            None
        );
    }

    #[test]
    fn the_wilson_bound_is_below_the_share_and_tightens_with_more_stances() {
        assert_eq!(wilson_lower_bound(0, 0, 1.0), 0.0);
        let (few, many) = (
            wilson_lower_bound(10, 10, 1.0),
            wilson_lower_bound(100, 100, 1.0),
        );
        assert!(few < many && many < 1.0, "{few} {many}");
        assert!((wilson_lower_bound(100, 100, 1.0) - 100.0 / 101.0).abs() < 1e-12);
        assert!(wilson_lower_bound(50, 100, 1.0) < 0.5);
    }

    /// A model with points writes them and reads them back (deciding alike); a file whose point is
    /// not before the model's length, or whose points do not increase, is refused; a file without
    /// points (written before them) loads as whole-stance only.
    #[test]
    fn decision_points_round_trip_and_are_checked_on_loading() {
        use crate::online::DecideAt;
        use crate::testing::{stance_model_with_points, stance_stream};
        let lens: Vec<usize> = (0..16).map(|i| 10 + (i * 7) % 6).collect();
        let (frames, stances) = stance_stream(&lens, 3);
        let model = stance_model_with_points(&frames, &stances, 16, &[3, 6]).unwrap();
        let json = serde_json::to_value(&model).unwrap();
        let back: TrainedModel = serde_json::from_value(json.clone()).unwrap();
        assert_eq!(back.early().unwrap().frames(), vec![3, 6]);
        assert_eq!(serde_json::to_value(&back).unwrap(), json);
        assert!(back.early().unwrap().auto.is_some());
        for (bad, what) in [
            (serde_json::json!(15), "length"),
            (serde_json::json!(2), "increase"),
        ] {
            let mut broken = json.clone();
            broken["early"]["points"][1]["frames"] = bad;
            let err = serde_json::from_value::<TrainedModel>(broken).unwrap_err();
            assert!(err.to_string().contains(what), "{err}");
        }
        let mut old = json;
        old.as_object_mut().unwrap().remove("early");
        let old: TrainedModel = serde_json::from_value(old).unwrap();
        assert!(old.early().is_none());
        assert!(old.trained_for(DecideAt::Frames(3)).is_err());
        assert!(old.trained_for(DecideAt::AUTO).is_err());
        assert!(
            old.trained_for(DecideAt::Frames(15)).is_ok(),
            "its whole length"
        );
        assert!(model.trained_for(DecideAt::Frames(6)).is_ok());
        let err = model.trained_for(DecideAt::Frames(5)).unwrap_err();
        assert!(
            err.contains("3, 6 frames") && err.contains("auto among them"),
            "{err}"
        );
    }

    /// The deadline decides the stances no point was confident about at the latest safe point due in
    /// time, when validation shows it safe; a point that is wrong too often is no deadline.
    #[test]
    fn the_deadline_is_the_latest_safe_point_due_in_time() {
        let frames = [3, 6, 10];
        // Sixty stances confident and right at every point; sixty unsure: wrong at 3, half wrong at
        // 6, right at 10 but with a confidence (0.65) the early points' mistakes make unsafe.
        let unsure = |i: usize, right_at_ten: bool| {
            let class = i % 2;
            let at_six = if i % 4 < 2 { class } else { 1 - class };
            let at_ten = if right_at_ten { class } else { 1 - class };
            stance(
                class,
                &[(1 - class, 0.6), (at_six, 0.7), (at_ten, 0.65)],
                (class, 0.99),
            )
        };
        let confident = |i: usize| {
            let class = i % 2;
            stance(class, &[(class, 0.99); 3], (class, 0.99))
        };
        let mut stances: Vec<HeldOutStance> = (0..60).map(confident).collect();
        stances.extend((0..60).map(|i| unsure(i, true)));
        let auto = learn_threshold(&stances, &frames);
        // Only 0.99 and above are safe; 0.99 leaves the unsure sixty to their lift-off (a mean of
        // 11.5 frames, past mid-stance), the deadline at 10 decides them right there.
        assert_eq!((auto.threshold, auto.deadline), (0.99, Some(10)));
        assert_eq!(auto.mean_decision_frame, (60.0 * 3.0 + 60.0 * 10.0) / 120.0);
        assert_eq!(auto.auto_accuracy, 1.0);
        let decision = stances[60].decide(&frames, auto.rule());
        assert_eq!((decision.point, decision.frame), (Some(2), 10));
        // Wrong at 10 for every fourth unsure stance, no point is a safe deadline.
        let mut stances: Vec<HeldOutStance> = (0..60).map(confident).collect();
        stances.extend((0..60).map(|i| unsure(i, i % 4 != 1)));
        let auto = learn_threshold(&stances, &frames);
        assert_eq!((auto.threshold, auto.deadline), (0.99, None));
        assert_eq!(auto.mean_decision_frame, (60.0 * 3.0 + 60.0 * 20.0) / 120.0);
    }

    /// A point past mid-stance is a deadline when the confident stances, decided early, keep the mean
    /// decision by mid-stance; of two such points the latest due in time; when none is due in time,
    /// the earliest safe one.
    #[test]
    fn a_deadline_past_mid_stance_is_taken_while_the_mean_comes_by_mid_stance() {
        // Stances of 20 frames (due by frame 10 on average); points at 3, 10 and 14. The unsure
        // stances are wrong at 3 (at 0.7) and right at 10 and 14 with a confidence (0.65) the wrong
        // early answers make unsafe as a threshold.
        let frames = [3, 10, 14];
        let unsure = |i: usize| {
            let class = i % 2;
            stance(
                class,
                &[(1 - class, 0.7), (class, 0.65), (class, 0.65)],
                (class, 0.99),
            )
        };
        let confident = |i: usize| {
            let class = i % 2;
            stance(class, &[(class, 0.99); 3], (class, 0.99))
        };
        let set = |unsure_count: usize| {
            let mut stances: Vec<HeldOutStance> = (0..60).map(confident).collect();
            stances.extend((0..unsure_count).map(unsure));
            stances
        };
        // Sixty confident at frame 3, sixty unsure: the deadline at 14 gives a mean of 8.5 frames.
        let auto = learn_threshold(&set(60), &frames);
        assert_eq!((auto.threshold, auto.deadline), (0.99, Some(14)));
        assert_eq!(auto.mean_decision_frame, (60.0 * 3.0 + 60.0 * 14.0) / 120.0);
        // 120 unsure: 14 would give 10.33 frames, 10 gives 7.67.
        let auto = learn_threshold(&set(120), &frames);
        assert_eq!((auto.threshold, auto.deadline), (0.99, Some(10)));
        assert_eq!(
            auto.mean_decision_frame,
            (60.0 * 3.0 + 120.0 * 10.0) / 180.0
        );
        // Without the point at 10, none is due in time: the earliest safe one, 14.
        let auto = learn_threshold(&set(120), &[3, 14]);
        assert_eq!(auto.deadline, Some(14));
        assert!(auto.mean_decision_frame > 10.0);
    }

    /// On more stances than the cap, the rule's stances are a stratified subsample: every class keeps
    /// its share, each stance comes with its own cuts and length, the same seed draws the same.
    #[test]
    fn the_rule_learns_from_a_stratified_subsample_of_many_stances() {
        use crate::frame::{Frame, Grid};
        let frames: Vec<Frame> = (0..40)
            .map(|i| Frame::new(Grid::new(1, 3), vec![i as f64; 3]).unwrap())
            .collect();
        let labels = ["a", "b"];
        // Thirty stances of class a, ten of b; stance i is i + 10 frames long.
        let image = |i: usize| LabeledImage::new(frames[i].view(), labels[usize::from(i >= 30)]);
        let all = StanceImages {
            whole: (0..40).map(image).collect(),
            cuts: vec![(2, (0..40).map(image).collect())],
            stance_frames: (0..40).map(|i| i + 10).collect(),
        };
        assert_eq!(rule_stances(all.clone(), 40, 1).whole.len(), 40);
        let some = rule_stances(all.clone(), 20, 1);
        assert_eq!(some.whole.len(), 20);
        let count = |label: &str| some.whole.iter().filter(|im| im.label == label).count();
        assert_eq!((count("a"), count("b")), (15, 5));
        for (i, image) in some.whole.iter().enumerate() {
            let original = image.frame.values()[0] as usize;
            assert_eq!(some.stance_frames[i], original + 10);
            assert_eq!(some.cuts[0].1[i].frame.values()[0] as usize, original);
        }
        let again = rule_stances(all, 20, 1);
        assert_eq!(again.stance_frames, some.stance_frames);
    }

    /// When every safe threshold decides after mid-stance, `auto` takes the earliest of them.
    #[test]
    fn past_mid_stance_auto_takes_the_earliest_safe_threshold() {
        // Stances of 20 frames; the only point is at frame 14, right for all at 0.8 or 0.95.
        let stances: Vec<HeldOutStance> = (0..60)
            .map(|i| {
                let class = i % 2;
                let confidence = if i < 30 { 0.8 } else { 0.95 };
                stance(class, &[(class, confidence)], (class, 0.99))
            })
            .collect();
        let auto = learn_threshold(&stances, &[14]);
        assert_eq!(auto.threshold, 0.8);
        assert_eq!(auto.mean_decision_frame, 14.0);
    }

    /// When no point can be trusted, `auto` never decides early.
    #[test]
    fn without_a_safe_point_auto_waits_for_the_lift_off() {
        let stances = vec![
            stance(0, &[(1, 1.0)], (0, 0.9)),
            stance(1, &[(0, 1.0)], (1, 0.9)),
        ];
        let auto = learn_threshold(&stances, &[5]);
        assert!(auto.threshold > 1.0);
        assert_eq!(auto.auto_accuracy, 1.0);
        assert_eq!(auto.mean_decision_share, 1.0);
    }
}
