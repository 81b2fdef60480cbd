//! `eval --decide-at`: early decisions evaluated on the protocol's draws. In each fold a whole-stance
//! model is trained on the fold's training stances (the method asked for, or the automatic choice),
//! with a classifier for each decision point (on the training stances cut there) and `auto`'s
//! threshold (from inner folds of the training stances only); the held-out stances are then decided at
//! each point (a stance that lifts off before the point: at its lift-off, whole) and by `auto`. Beside
//! each point, the one-frame model at the same offset: the automatic choice trained on the frame
//! `K` after touchdown of the same training stances, tested on the same held-out stances' frame `K`.

use presrs_core::evaluation::Evaluation;
use presrs_core::pipeline::{
    AutoRule, HeldOutStance, LabeledImage, StanceImages, TrainedModel, classify_stances,
    train_early,
};
use serde::Serialize;

use crate::dataset::{Dataset, SampleOptions};
use crate::error::{Context, Error, Result};
use crate::eval::EvalSetup;
use crate::method::Method;
use crate::progress::{Progress, Quiet};
use crate::train::early::stance_images;

/// Accuracy at one decision point, frames after touchdown.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EarlyPoint {
    /// `K`: the stance's first `K + 1` frames.
    pub frames: usize,
    /// `K` times the frame period, when the recordings state one.
    pub ms: Option<f64>,
    /// `K` over the median stance length of the tested stances.
    pub share_of_median_stance: f64,
    /// The whole-stance model's classifier trained for `K`, over every held-out stance (one that lifts
    /// off before frame `K` is decided at its lift-off, whole).
    pub accuracy: f64,
    /// The one-frame model (the automatic choice) on frame `K` after touchdown, over the held-out
    /// stances that have that frame; `None` when not measured.
    pub frame_accuracy: Option<f64>,
    /// Held-out stances with a frame `K` (the one-frame model's test set).
    pub frame_tested: usize,
}

/// `auto`: the first point whose confidence passes the threshold learned in the fold.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EarlyAuto {
    pub accuracy: f64,
    /// Mean decision time after touchdown: frames, ms (with a frame period), share of each stance,
    /// and over the median stance length (a lift-off decision counts as the stance's length).
    pub mean_frames: f64,
    pub mean_ms: Option<f64>,
    pub mean_share_of_stance: f64,
    pub mean_over_median_stance: f64,
    /// Share of the held-out stances decided before their lift-off (at any point, late ones too).
    pub decided_early: f64,
    /// Share of the held-out stances decided by their mid-stance: at a point at most half their own
    /// length after touchdown.
    pub decided_by_mid_stance: f64,
    /// The threshold of each fold's model, in the draws' order.
    pub thresholds: Vec<f64>,
    /// The deadline point of each fold's model (frames after touchdown; `None`: its stances not
    /// confident by then wait for their lift-off), in the draws' order.
    pub deadlines: Vec<Option<usize>>,
    /// `auto`'s accuracy on each fold's held-out stances, and the whole stance's there, in the
    /// draws' order: which fold's rule cost what.
    pub fold_accuracies: Vec<f64>,
    pub fold_whole_accuracies: Vec<f64>,
    /// What one threshold for every fold would have given, chosen in hindsight on the held-out
    /// stances themselves: the thresholds no other beats in both accuracy and mean decision time,
    /// earliest first. A bound on what any threshold rule could reach with these classifiers, not a
    /// result: it tells whether the rule or the point classifiers hold `auto` back.
    pub hindsight: Vec<HindsightThreshold>,
}

/// One rule (threshold and deadline) applied to every held-out stance (see [`EarlyAuto::hindsight`]).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct HindsightThreshold {
    /// `None`: no point decides by its confidence.
    pub threshold: Option<f64>,
    /// `None`: no deadline (the stances no point was confident about decided whole at lift-off).
    pub deadline: Option<usize>,
    pub accuracy: f64,
    pub mean_over_median_stance: f64,
    pub decided_early: f64,
    pub decided_by_mid_stance: f64,
}

impl EarlyAuto {
    /// The most accurate hindsight threshold whose mean decision comes by `share` of the median
    /// stance (`None` when none does).
    pub fn hindsight_best_by(&self, share: f64) -> Option<&HindsightThreshold> {
        self.hindsight
            .iter()
            .filter(|h| h.mean_over_median_stance <= share)
            .max_by(|a, b| a.accuracy.total_cmp(&b.accuracy))
    }
}

/// What [`evaluate_early`] measured.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EarlyEvaluation {
    /// The whole-stance classifier at lift-off, on the same held-out stances.
    pub whole_accuracy: f64,
    pub points: Vec<EarlyPoint>,
    pub auto: EarlyAuto,
    /// Median length of the held-out stances, frames (and ms).
    pub median_stance_frames: usize,
    pub median_stance_ms: Option<f64>,
    /// The frame period the times are in, ms.
    pub frame_period_ms: Option<f64>,
    pub tested: usize,
    pub folds: usize,
    /// Where the one-frame model led the stance model ([`one_frame_lead`](Self::one_frame_lead)).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub frame_ahead: Option<FrameAhead>,
}

/// Where the one-frame model beside the points decided clearly better than the stance model trained
/// for them (see [`EarlyEvaluation::one_frame_lead`]).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FrameAhead {
    /// The points (frames after touchdown) where the one-frame model led.
    pub points: Vec<usize>,
    /// Its largest lead there (a difference of accuracies).
    pub largest_lead: f64,
    /// Its most accurate point, when that is above the whole stance's accuracy: (frames, accuracy).
    pub above_whole: Option<(usize, f64)>,
}

/// How many standard errors of the difference of two accuracies a lead must exceed to be told (the
/// race's bound, [`presrs_core::selection::RACE_Z`]).
pub const LEAD_Z: f64 = presrs_core::selection::RACE_Z;

impl EarlyEvaluation {
    /// The points at which the one-frame model led the stance model by more than [`LEAD_Z`] standard
    /// errors of the difference of the two accuracies over the same held-out stances (points whose
    /// one-frame test set lacks stances that lift off before them are not compared). `None` when it
    /// led at none: the stance's summary then carries the class at least as well as one frame.
    pub fn one_frame_lead(&self) -> Option<FrameAhead> {
        let n = self.tested as f64;
        let mut ahead = FrameAhead {
            points: Vec::new(),
            largest_lead: 0.0,
            above_whole: None,
        };
        for point in &self.points {
            let Some(frame) = point
                .frame_accuracy
                .filter(|_| point.frame_tested == self.tested)
            else {
                continue;
            };
            let stance = point.accuracy;
            let spread = ((frame * (1.0 - frame) + stance * (1.0 - stance)) / n.max(1.0)).sqrt();
            let lead = frame - stance;
            if lead > LEAD_Z * spread {
                ahead.points.push(point.frames);
                ahead.largest_lead = ahead.largest_lead.max(lead);
                let best = ahead.above_whole.map_or(self.whole_accuracy, |(_, a)| a);
                if frame > best {
                    ahead.above_whole = Some((point.frames, frame));
                }
            }
        }
        (!ahead.points.is_empty()).then_some(ahead)
    }

    /// The curve as the HTML report shows it; `note` says how the stances were held out.
    pub fn curve(&self, note: String) -> presrs_report::EarlyCurve {
        presrs_report::EarlyCurve {
            points: self
                .points
                .iter()
                .map(|point| presrs_report::EarlyCurvePoint {
                    frames: point.frames,
                    accuracy: point.accuracy,
                    frame_accuracy: point.frame_accuracy,
                })
                .collect(),
            whole_accuracy: self.whole_accuracy,
            auto: Some(presrs_report::EarlyAutoResult {
                accuracy: self.auto.accuracy,
                mean_frames: self.auto.mean_frames,
                decided_early: self.auto.decided_early,
                decided_by_mid_stance: self.auto.decided_by_mid_stance,
            }),
            median_stance_frames: self.median_stance_frames,
            frame_period_ms: self.frame_period_ms,
            tested: self.tested,
            note,
        }
    }
}

/// The data set read as frames `K` after touchdown, for the one-frame model beside each point.
#[derive(Debug)]
pub struct FrameReadings {
    pub by_point: Vec<(usize, Dataset)>,
}

impl FrameReadings {
    /// `manifest` read with `options` as the frame `K` after touchdown of each stance, for every
    /// decision point `K` of `whole` (the stance reading).
    pub fn load(
        manifest: &std::path::Path,
        options: &SampleOptions,
        whole: &Dataset,
        progress: &dyn Progress,
    ) -> Result<Self> {
        let mut by_point = Vec::new();
        for (k, _) in &whole.stances.points {
            let options = SampleOptions {
                kind: presrs_core::sample::SampleKind::Frame,
                sample: presrs_core::stance::SampleFrame::Offset(*k),
                decision_points: Vec::new(),
                skip_short_stances: true,
                ..options.clone()
            };
            by_point.push((*k, Dataset::load(manifest, &options, progress)?));
        }
        Ok(Self { by_point })
    }
}

/// Evaluates early decisions on `setup`'s draws (its data set read as whole stances, cut at its
/// decision points), with `frames`' one-frame models beside each point (see the module docs).
pub fn evaluate_early(
    setup: &EvalSetup<'_>,
    frames: Option<&FrameReadings>,
    progress: &dyn Progress,
) -> Result<EarlyEvaluation> {
    let dataset = setup.dataset();
    let name = dataset.path().display().to_string();
    if dataset.stances.points.is_empty() {
        return Err(Error::invalid(
            "eval --decide-at needs whole-stance samples (--sample stance) cut at decision points",
        ));
    }
    let method = &setup.options.method;
    let samples = setup.samples();
    let labels: Vec<&str> = samples.iter().map(|s| s.label).collect();
    let all: Vec<usize> = (0..samples.len()).collect();
    let evaluation = Evaluation {
        samples,
        protocol: setup.protocol(),
        repeats: setup.options.repeats,
        seed: setup.options.seed,
        progress: &|| {},
    };
    let draws = evaluation.draws().with_context(|| name.clone())?;
    progress.start("early decisions, fold by fold", Some(draws.len() as u64));
    // Each held-out stance's outcomes, its data-set index and its fold.
    let mut tested: Vec<(HeldOutStance, usize, usize)> = Vec::new();
    let mut rules = Vec::new();
    let mut frame_right = vec![(0usize, 0usize); dataset.stances.points.len()];
    for (fold, draw) in draws.iter().enumerate() {
        let part = |indices: &[usize]| stance_images(dataset, &all, indices, &labels);
        let (train_set, validation, test) =
            (part(&draw.train), part(&draw.validation), part(&draw.test));
        let whole = train_whole(method, dataset, &train_set, &validation, draw.seed)
            .with_context(|| format!("{name}: training a fold"))?;
        let chooser =
            crate::train::early::point_chooser(method, &dataset.sample, draw.seed, &Quiet);
        let choose = chooser
            .as_deref()
            .map(|f| f as presrs_core::pipeline::ChoosePoint<'_>);
        let early = train_early(&whole, &train_set, &validation, choose, draw.seed, None)
            .with_context(|| format!("{name}: training a fold's decision points"))?;
        rules.push(
            early
                .auto
                .map_or(AutoRule::threshold(f64::INFINITY), |auto| auto.rule()),
        );
        let model = whole.with_early(early)?;
        let outcomes = classify_stances(&model, &test)?;
        tested.extend(
            outcomes
                .into_iter()
                .zip(&draw.test)
                .map(|(outcome, &i)| (outcome, i, fold)),
        );
        if let Some(frames) = frames {
            for (slot, (k, reading)) in frames.by_point.iter().enumerate() {
                let (right, count) = frame_model_at(dataset, reading, *k, draw, &labels)?;
                frame_right[slot].0 += right;
                frame_right[slot].1 += count;
            }
        }
        progress.advance(1);
    }
    progress.finish();
    Ok(summarise(
        dataset,
        &tested,
        &rules,
        frames.map(|_| frame_right.as_slice()),
        draws.len(),
    ))
}

/// A fold's whole-stance model: the automatic choice, or the fixed method.
fn train_whole(
    method: &Method,
    dataset: &Dataset,
    train_set: &StanceImages<'_>,
    validation: &StanceImages<'_>,
    seed: u64,
) -> Result<TrainedModel> {
    let grid = train_set
        .whole
        .first()
        .map(|image| image.frame.grid())
        .ok_or_else(|| Error::invalid("a fold with no training stance"))?;
    let model = if method.is_auto() {
        presrs_core::selection::train_auto(
            &train_set.whole,
            &validation.whole,
            &method.auto_choice(&method.candidates_for(
                grid,
                false,
                &dataset.sample,
                crate::method::race_draws_for(train_set.whole.len()),
            )?),
            seed,
        )
    } else {
        presrs_core::pipeline::train(
            &train_set.whole,
            &validation.whole,
            &method.train_config(grid)?,
        )
    };
    Ok(model.and_then(|model| model.with_sample(dataset.sample))?)
}

/// The one-frame model (the automatic choice) trained on frame `K` of the draw's training stances
/// and tested on that frame of its held-out ones: (right, tested).
fn frame_model_at(
    stances: &Dataset,
    reading: &Dataset,
    k: usize,
    draw: &presrs_core::evaluation::Draw,
    labels: &[&str],
) -> Result<(usize, usize)> {
    // A stance's frame sample: the same manifest line, `K` frames after its touchdown.
    let find = |i: usize| {
        let stance = &stances.samples[i];
        reading
            .samples
            .iter()
            .position(|s| s.line == stance.line && s.frame_index == stance.frame_index + k)
    };
    let images = |indices: &[usize]| -> Vec<LabeledImage<'_>> {
        indices
            .iter()
            .filter_map(|&i| {
                let sample = &reading.samples[find(i)?];
                Some(LabeledImage {
                    frame: sample.frame.view(),
                    label: labels[i],
                    condition: sample.condition.as_deref(),
                    group: sample.group.as_deref(),
                })
            })
            .collect()
    };
    let (train_images, validation, test) = (
        images(&draw.train),
        images(&draw.validation),
        images(&draw.test),
    );
    let Some(first) = train_images.first() else {
        return Ok((0, test.len()));
    };
    let method = Method::default();
    let candidates = method.candidates_for(first.frame.grid(), false, &reading.sample, 1)?;
    let model = presrs_core::selection::train_auto(
        &train_images,
        &validation,
        &method.auto_choice(&candidates),
        draw.seed,
    )?;
    let views: Vec<_> = test.iter().map(|image| image.frame).collect();
    let right = model
        .classify_batch(&views)
        .iter()
        .zip(&test)
        .filter(|(result, image)| {
            result
                .as_ref()
                .is_ok_and(|c| model.class_names()[c.class] == image.label)
        })
        .count();
    Ok((right, test.len()))
}

/// The curve, `auto` and the times from every held-out stance's outcomes (with its data-set index).
fn summarise(
    dataset: &Dataset,
    tested: &[(HeldOutStance, usize, usize)],
    rules: &[AutoRule],
    frame_right: Option<&[(usize, usize)]>,
    folds: usize,
) -> EarlyEvaluation {
    let n = tested.len().max(1) as f64;
    let share = |hit: &dyn Fn(&HeldOutStance) -> bool| {
        tested.iter().filter(|(s, _, _)| hit(s)).count() as f64 / n
    };
    let period_ms = tested
        .iter()
        .find_map(|&(_, i, _)| dataset.stances.frame_periods.get(i).copied().flatten())
        .map(|s| s * 1e3);
    let stances: Vec<HeldOutStance> = tested.iter().map(|(s, _, _)| s.clone()).collect();
    let median = presrs_core::pipeline::median_length(&stances);
    let frames: Vec<usize> = dataset.stances.points.iter().map(|(k, _)| *k).collect();
    let points = frames
        .iter()
        .enumerate()
        .map(|(p, &k)| EarlyPoint {
            frames: k,
            ms: period_ms.map(|ms| ms * k as f64),
            share_of_median_stance: k as f64 / median.max(1) as f64,
            accuracy: share(&|s| s.points[p].map_or(s.whole.0, |(class, _)| class) == s.class),
            frame_accuracy: frame_right
                .map(|counts| counts[p].0 as f64 / counts[p].1.max(1) as f64),
            frame_tested: frame_right.map_or(0, |counts| counts[p].1),
        })
        .collect();
    // Each stance decided by its fold's rule.
    let decisions: Vec<_> = tested
        .iter()
        .map(|(stance, _, fold)| {
            let rule = rules
                .get(*fold)
                .copied()
                .unwrap_or(AutoRule::threshold(f64::INFINITY));
            (stance, stance.decide(&frames, rule))
        })
        .collect();
    let mean = |f: &dyn Fn(&HeldOutStance, &presrs_core::pipeline::OfflineDecision) -> f64| {
        decisions.iter().map(|(s, d)| f(s, d)).sum::<f64>() / n
    };
    let mean_frames = mean(&|_, d| d.frame as f64);
    let hindsight = hindsight_frontier(&stances, &frames, median);
    let by_fold =
        |right: &dyn Fn(&HeldOutStance, &presrs_core::pipeline::OfflineDecision) -> bool| {
            (0..rules.len())
                .map(|fold| {
                    let (mut hits, mut count) = (0usize, 0usize);
                    for ((stance, decision), (_, _, f)) in decisions.iter().zip(tested) {
                        if *f == fold {
                            count += 1;
                            hits += usize::from(right(stance, decision));
                        }
                    }
                    hits as f64 / count.max(1) as f64
                })
                .collect::<Vec<f64>>()
        };
    let auto = EarlyAuto {
        accuracy: mean(&|s, d| f64::from(u8::from(d.class == s.class))),
        mean_frames,
        mean_ms: period_ms.map(|ms| ms * mean_frames),
        mean_share_of_stance: mean(&|s, d| d.frame as f64 / s.stance_frames.max(1) as f64),
        mean_over_median_stance: mean_frames / median.max(1) as f64,
        decided_early: mean(&|_, d| f64::from(u8::from(d.point.is_some()))),
        decided_by_mid_stance: mean(&|s, d| f64::from(u8::from(by_mid_stance(s, d)))),
        thresholds: rules.iter().map(|rule| rule.threshold).collect(),
        deadlines: rules.iter().map(|rule| rule.deadline).collect(),
        fold_accuracies: by_fold(&|s, d| d.class == s.class),
        fold_whole_accuracies: by_fold(&|s, _| s.whole.0 == s.class),
        hindsight,
    };
    let mut early = EarlyEvaluation {
        whole_accuracy: share(&|s| s.whole.0 == s.class),
        points,
        auto,
        median_stance_frames: median,
        median_stance_ms: period_ms.map(|ms| ms * median as f64),
        frame_period_ms: period_ms,
        tested: tested.len(),
        folds,
        frame_ahead: None,
    };
    early.frame_ahead = early.one_frame_lead();
    early
}

/// Whether `decision` came by `stance`'s mid-stance: at a point at most half its length after
/// touchdown (a decision at lift-off never does).
fn by_mid_stance(
    stance: &HeldOutStance,
    decision: &presrs_core::pipeline::OfflineDecision,
) -> bool {
    decision.point.is_some() && 2 * decision.frame <= stance.stance_frames
}

/// Every distinct confidence of the points' decisions (and none) tried as one threshold for all
/// held-out stances, with every point (and none) as the deadline; the rules not beaten in both
/// accuracy and mean decision time, earliest first.
fn hindsight_frontier(
    stances: &[HeldOutStance],
    frames: &[usize],
    median: usize,
) -> Vec<HindsightThreshold> {
    let candidates = presrs_core::pipeline::point_confidences(stances);
    let n = stances.len().max(1) as f64;
    let outcome = |(threshold, deadline): (Option<f64>, Option<usize>)| {
        let rule = AutoRule {
            threshold: threshold.unwrap_or(f64::INFINITY),
            deadline,
        };
        let (mut right, mut frames_sum, mut early, mut by_mid) = (0usize, 0usize, 0usize, 0usize);
        for stance in stances {
            let decision = stance.decide(frames, rule);
            right += usize::from(decision.class == stance.class);
            frames_sum += decision.frame;
            early += usize::from(decision.point.is_some());
            by_mid += usize::from(by_mid_stance(stance, &decision));
        }
        HindsightThreshold {
            threshold,
            deadline,
            accuracy: right as f64 / n,
            mean_over_median_stance: frames_sum as f64 / n / median.max(1) as f64,
            decided_early: early as f64 / n,
            decided_by_mid_stance: by_mid as f64 / n,
        }
    };
    let deadlines: Vec<Option<usize>> = std::iter::once(None)
        .chain(frames.iter().copied().map(Some))
        .collect();
    let mut all: Vec<HindsightThreshold> = candidates
        .into_iter()
        .map(Some)
        .chain([None])
        .flat_map(|threshold| deadlines.iter().map(move |&deadline| (threshold, deadline)))
        .map(outcome)
        .collect();
    all.sort_by(|a, b| {
        a.mean_over_median_stance
            .total_cmp(&b.mean_over_median_stance)
            .then(b.accuracy.total_cmp(&a.accuracy))
    });
    let mut frontier: Vec<HindsightThreshold> = Vec::new();
    for candidate in all {
        if frontier
            .last()
            .is_none_or(|best| candidate.accuracy > best.accuracy)
        {
            frontier.push(candidate);
        }
    }
    frontier
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stance(class: usize, points: &[Option<(usize, f64)>], whole: usize) -> HeldOutStance {
        HeldOutStance {
            class,
            stance_frames: 10,
            points: points.to_vec(),
            whole: (whole, 0.9),
        }
    }

    #[test]
    fn the_hindsight_frontier_keeps_only_thresholds_nothing_beats() {
        // Points at frames 2 and 5 of 10-frame stances. A confident early point that is right, one
        // that is wrong at a higher confidence, and a stance only the whole model gets right.
        let tested: Vec<(HeldOutStance, usize, usize)> = [
            stance(0, &[Some((0, 0.8)), Some((0, 0.9))], 0),
            stance(1, &[Some((0, 0.95)), Some((1, 0.7))], 1),
            stance(1, &[Some((1, 0.6)), Some((1, 0.99))], 0),
        ]
        .into_iter()
        .enumerate()
        .map(|(i, s)| (s, i, 0))
        .collect();
        let stances: Vec<HeldOutStance> = tested.iter().map(|(s, _, _)| s.clone()).collect();
        let frontier = hindsight_frontier(&stances, &[2, 5], 10);
        // The earliest (threshold 0.6: every stance at frame 2): the second stance is decided 0
        // (wrong), the others right: 2 of 3 at a mean of 2 frames.
        assert_eq!(frontier[0].threshold, Some(0.6));
        assert!((frontier[0].accuracy - 2.0 / 3.0).abs() < 1e-12);
        assert!((frontier[0].mean_over_median_stance - 0.2).abs() < 1e-12);
        // Every rule's outcome, recomputed by brute force, is matched or beaten by the frontier.
        let rules = [0.5, 0.6, 0.7, 0.8, 0.9, 0.95, 0.99, 2.0]
            .into_iter()
            .flat_map(|threshold| {
                [None, Some(2), Some(5)].map(|deadline| AutoRule {
                    threshold,
                    deadline,
                })
            });
        for rule in rules {
            let decisions: Vec<_> = tested
                .iter()
                .map(|(s, _, _)| (s.class, s.decide(&[2, 5], rule)))
                .collect();
            let accuracy = decisions.iter().filter(|(c, d)| d.class == *c).count() as f64 / 3.0;
            let mean = decisions.iter().map(|(_, d)| d.frame as f64).sum::<f64>() / 3.0 / 10.0;
            assert!(
                frontier
                    .iter()
                    .any(|h| h.accuracy >= accuracy && h.mean_over_median_stance <= mean + 1e-12),
                "{rule:?}: {accuracy} at {mean} beats the frontier {frontier:?}"
            );
        }
        // By mid-stance: a decision at most half the stance's own length after touchdown (frame 5 of
        // 10 is, a point past it or the lift-off is not).
        assert_eq!(frontier[0].decided_by_mid_stance, 1.0);
        let late = stance(0, &[Some((0, 0.5)), Some((0, 0.9))], 0);
        let by = |t: f64| AutoRule::threshold(t);
        assert!(by_mid_stance(&late, &late.decide(&[2, 5], by(0.8))));
        assert!(!by_mid_stance(&late, &late.decide(&[2, 6], by(0.8))));
        assert!(!by_mid_stance(&late, &late.decide(&[2, 5], by(0.95))));
        // Earliest first, each more accurate than the one before.
        for pair in frontier.windows(2) {
            assert!(pair[0].mean_over_median_stance <= pair[1].mean_over_median_stance);
            assert!(pair[0].accuracy < pair[1].accuracy);
        }
    }

    fn evaluation(whole: f64, points: &[(usize, f64, Option<f64>, usize)]) -> EarlyEvaluation {
        EarlyEvaluation {
            whole_accuracy: whole,
            points: points
                .iter()
                .map(
                    |&(frames, accuracy, frame_accuracy, frame_tested)| EarlyPoint {
                        frames,
                        ms: None,
                        share_of_median_stance: frames as f64 / 20.0,
                        accuracy,
                        frame_accuracy,
                        frame_tested,
                    },
                )
                .collect(),
            auto: EarlyAuto {
                accuracy: 0.0,
                mean_frames: 0.0,
                mean_ms: None,
                mean_share_of_stance: 0.0,
                mean_over_median_stance: 0.0,
                decided_early: 0.0,
                decided_by_mid_stance: 0.0,
                thresholds: Vec::new(),
                deadlines: Vec::new(),
                fold_accuracies: Vec::new(),
                fold_whole_accuracies: Vec::new(),
                hindsight: Vec::new(),
            },
            median_stance_frames: 20,
            median_stance_ms: None,
            frame_period_ms: None,
            tested: 240,
            folds: 3,
            frame_ahead: None,
        }
    }

    /// The one-frame model is told ahead where it leads past 2 standard errors of the difference on
    /// the same stances (not by a stance or two, not on a smaller test set), with its largest lead,
    /// and its best point when that is above the whole stance.
    #[test]
    fn the_one_frame_model_is_ahead_only_past_the_noise_on_the_same_stances() {
        let early = evaluation(
            0.917,
            &[
                (2, 0.858, Some(0.988), 240),
                (4, 0.912, Some(1.0), 240),
                (6, 0.90, Some(0.91), 240),
                (8, 0.60, Some(0.95), 100),
                (9, 0.95, None, 0),
            ],
        );
        let ahead = early.one_frame_lead().unwrap();
        assert_eq!(ahead.points, vec![2, 4]);
        assert!((ahead.largest_lead - 0.130).abs() < 1e-12);
        assert_eq!(ahead.above_whole, Some((4, 1.0)));
        // 0.90 against 0.91 on 240 stances is noise; behind is never ahead
        let close = evaluation(
            0.95,
            &[(6, 0.90, Some(0.91), 240), (7, 0.9, Some(0.5), 240)],
        );
        assert_eq!(close.one_frame_lead(), None);
        // ahead but under the whole stance: no point above it
        let under = evaluation(0.99, &[(2, 0.70, Some(0.90), 240)]);
        assert_eq!(under.one_frame_lead().unwrap().above_whole, None);
    }
}
