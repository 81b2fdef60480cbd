//! Whole-stance models online: a synthetic stream of stances through the [`OnlineClassifier`], each
//! decision checked against the offline path (the stance's frames summarised, laid into the model's
//! length and classified): at lift-off, `decide_at` frames after touchdown, and for stances longer
//! than the model's length. And the settings that do not fit the kind of model are refused.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use presrs_core::Frame;
use presrs_core::online::{
    Calibration, DecideAt, DecidedAt, Decision, DecisionKind, EarlyReason, OnlineClassifier,
    OnlineEvent, OnlineParams,
};
use presrs_core::pipeline::TrainedModel;
use presrs_core::stance::{Stance, ValidSegmentParams, segment};
use presrs_core::testing::{
    SYNTHETIC_CLASSES, bench_fixture, stance_model, stance_model_with_points, stance_sample,
    stance_stream,
};

const LENGTH: usize = 16;

fn calibration(frames: &[Frame]) -> Calibration {
    let totals: Vec<f64> = frames.iter().map(|f| f.view().total()).collect();
    let seg = segment(&totals, &ValidSegmentParams::default()).unwrap();
    Calibration::from_segmentations([&seg]).unwrap()
}

/// A model of `LENGTH` frames trained on one stream, and another stream to judge (stances of 10 to
/// 15 frames, and with `long` some of 19 to 22).
fn setup(long: bool) -> (TrainedModel, Vec<Frame>) {
    setup_with_points(long, &[])
}

/// [`setup`] with classifiers for the decision points `points`.
fn setup_with_points(long: bool, points: &[usize]) -> (TrainedModel, Vec<Frame>) {
    let lens: Vec<usize> = (0..24).map(|i| 10 + (i * 7) % 6).collect();
    let (frames, stances) = stance_stream(&lens, 3);
    let model = if points.is_empty() {
        stance_model(&frames, &stances, LENGTH).unwrap()
    } else {
        stance_model_with_points(&frames, &stances, LENGTH, points).unwrap()
    };
    let test_lens: Vec<usize> = (0..12)
        .map(|i| {
            if long && i % 3 == 1 {
                19 + i % 4
            } else {
                10 + (i * 5) % 6
            }
        })
        .collect();
    (model, stance_stream(&test_lens, 11).0)
}

/// A decision with its posteriors, and the lift-off of each stance.
#[derive(Debug)]
struct Run {
    decisions: Vec<(Decision, Vec<f64>, usize)>,
    liftoffs: Vec<(Stance, bool, usize)>,
}

fn run(model: &TrainedModel, frames: &[Frame], decide_at: Option<DecideAt>) -> Run {
    let online = OnlineParams {
        decide_at,
        ..OnlineParams::default()
    };
    let params = ValidSegmentParams::default();
    let mut classifier =
        OnlineClassifier::new(model, &params, &online, Some(calibration(frames))).unwrap();
    let mut out = Run {
        decisions: Vec::new(),
        liftoffs: Vec::new(),
    };
    let mut order = 0;
    let mut record = |step: presrs_core::online::Step<'_>, out: &mut Run| {
        for event in step.events {
            order += 1;
            match event {
                OnlineEvent::Decision(d) => {
                    out.decisions.push((*d, step.posteriors(d).to_vec(), order));
                }
                OnlineEvent::Liftoff(l) => out.liftoffs.push((l.stance, l.sampled, order)),
                OnlineEvent::Failed(f) => panic!("{f:?}: {:?}", step.error(f)),
                OnlineEvent::Touchdown(_) => {}
            }
        }
    };
    for frame in frames {
        let step = classifier.push(&frame.view()).unwrap();
        record(step, &mut out);
    }
    let step = classifier.finish().unwrap();
    record(step, &mut out);
    out
}

/// The offline classification of frames `first .. first + count`.
fn offline(
    model: &TrainedModel,
    frames: &[Frame],
    first: usize,
    count: usize,
) -> (usize, Vec<f64>) {
    // In the model's own length: the whole stance's, or a decision point's K + 1 frames.
    let sample = stance_sample(&frames[first..first + count], model.image_grid().cols).unwrap();
    let mut session = model.session();
    let prediction = session.classify(&sample.view()).unwrap();
    (prediction.class, prediction.posteriors.to_vec())
}

#[test]
fn each_stance_is_decided_at_its_liftoff_as_offline() {
    let (model, frames) = setup(false);
    let run = run(&model, &frames, None);
    let totals: Vec<f64> = frames.iter().map(|f| f.view().total()).collect();
    let offline_stances = segment(&totals, &ValidSegmentParams::default()).unwrap();
    assert_eq!(run.liftoffs.len(), 12);
    assert_eq!(run.decisions.len(), 12, "one decision a stance");
    let mut same_as_offline = 0;
    for ((decision, posteriors, at), (stance, sampled, liftoff_at)) in
        run.decisions.iter().zip(&run.liftoffs)
    {
        assert!(sampled);
        assert_eq!(
            *at + 1,
            *liftoff_at,
            "the decision comes just before its lift-off"
        );
        assert_eq!(decision.kind, DecisionKind::Stance);
        let how = decision.stance.unwrap();
        assert_eq!(how.decided_at, DecidedAt::Liftoff);
        assert!(!how.cut);
        assert_eq!(how.waited_for, decision.frame);
        assert_eq!(decision.touchdown_frame, stance.start);
        assert_eq!(decision.frames_used, stance.len);
        assert_eq!(decision.sample_frame, stance.end() - 1);
        let (class, expected) = offline(&model, &frames, stance.start, stance.len);
        assert_eq!(decision.class, class);
        assert_eq!(posteriors, &expected, "to the bit");
        assert_eq!(decision.confidence, expected[class]);
        same_as_offline += usize::from(
            offline_stances
                .stances
                .iter()
                .any(|s| (s.start, s.len) == (stance.start, stance.len)),
        );
    }
    assert_eq!(
        same_as_offline, 12,
        "the detector finds the offline stances"
    );
    let right = run
        .decisions
        .iter()
        .enumerate()
        .filter(|(i, (d, _, _))| model.class_names()[d.class] == SYNTHETIC_CLASSES[i % 4])
        .count();
    // The summaries hardly see the synthetic prints' textures, but more than chance (3 of 12) and
    // more than one class: the decisions are a real model's.
    assert!(right >= 5, "{right} of 12: not a real model");
    let classes: std::collections::BTreeSet<usize> =
        run.decisions.iter().map(|(d, _, _)| d.class).collect();
    assert!(classes.len() >= 3, "{classes:?}");
}

#[test]
fn decide_at_k_decides_on_the_stance_so_far() {
    let k = 7;
    let (model, frames) = setup_with_points(false, &[4, k]);
    let point = model.early().unwrap().point(k).unwrap();
    let run = run(&model, &frames, Some(DecideAt::Frames(k)));
    assert_eq!(run.decisions.len(), 12);
    for ((decision, posteriors, at), (stance, sampled, liftoff_at)) in
        run.decisions.iter().zip(&run.liftoffs)
    {
        assert!(sampled);
        assert!(at < liftoff_at);
        let how = decision.stance.unwrap();
        assert_eq!(how.decided_at, DecidedAt::Offset(k));
        assert_eq!(how.waited_for, stance.start + k);
        assert_eq!(
            decision.frame,
            stance.start + k,
            "decided as frame K arrives"
        );
        assert_eq!(decision.frames_used, k + 1);
        assert!(!how.cut);
        let early = how.early.unwrap();
        assert_eq!((early.reason, early.point), (EarlyReason::Fixed, Some(k)));
        // By the classifier trained on stances cut at K, not the whole-stance one.
        let (class, expected) = offline(point, &frames, stance.start, k + 1);
        assert_eq!(decision.class, class);
        assert_eq!(posteriors, &expected);
    }
    // K past a stance's end (and the model's length: the whole-stance classifier): it is decided at
    // its lift-off, on the whole stance.
    let late = run_late(&model, &frames);
    assert!(late.iter().all(|&d| d == DecidedAt::Liftoff), "{late:?}");
}

/// `auto` decides at the first point whose confidence passes the model's threshold, by that point's
/// classifier (as offline), else at its deadline point by that point's classifier, else at the
/// lift-off by the whole-stance one; each decision says why.
#[test]
fn auto_decides_at_the_first_confident_point_else_at_its_deadline() {
    let points = [3, 6, 9];
    let (model, frames) = setup_with_points(false, &points);
    check_auto(&model, &frames, &points);
    // The same model with a deadline at 6 and a threshold few points pass: stances no point was
    // confident about by 6 are decided there.
    let mut early = model.early().unwrap().clone();
    let auto = early.auto.as_mut().unwrap();
    auto.threshold = 0.999;
    auto.deadline = Some(6);
    let with_deadline = model.clone().with_early(early).unwrap();
    let reasons = check_auto(&with_deadline, &frames, &points);
    assert!(reasons.contains(&EarlyReason::Deadline), "{reasons:?}");
    // A deadline that is not one of the points is refused.
    let mut early = model.early().unwrap().clone();
    early.auto.as_mut().unwrap().deadline = Some(5);
    let err = model.clone().with_early(early).unwrap_err();
    assert!(err.to_string().contains("deadline 5"), "{err}");
}

/// Runs `model` with `auto` over `frames` and checks every decision against the offline rule; the
/// reasons given, in order.
fn check_auto(model: &TrainedModel, frames: &[Frame], points: &[usize]) -> Vec<EarlyReason> {
    let early = model.early().unwrap();
    let rule = early.auto.unwrap().rule();
    let run = run(model, frames, Some(DecideAt::AUTO));
    assert_eq!(run.decisions.len(), 12);
    let mut reasons = Vec::new();
    for ((decision, posteriors, _), (stance, sampled, _)) in run.decisions.iter().zip(&run.liftoffs)
    {
        assert!(sampled);
        let how = decision.stance.unwrap();
        let reason = how.early.unwrap();
        reasons.push(reason.reason);
        // The first point offline whose confidence passes the threshold, or the deadline.
        let first = points.iter().find(|&&k| {
            k < stance.len && {
                let (class, p) = offline(early.point(k).unwrap(), frames, stance.start, k + 1);
                rule.decides(k, p[class])
            }
        });
        match first {
            Some(&k) => {
                let (class, expected) =
                    offline(early.point(k).unwrap(), frames, stance.start, k + 1);
                let why = if expected[class] >= rule.threshold {
                    EarlyReason::Confident
                } else {
                    EarlyReason::Deadline
                };
                assert_eq!(how.decided_at, DecidedAt::Offset(k));
                assert_eq!((reason.reason, reason.point), (why, Some(k)));
                assert_eq!(reason.threshold, Some(rule.threshold));
                assert_eq!((decision.class, posteriors), (class, &expected));
            }
            None => {
                assert_eq!(how.decided_at, DecidedAt::Liftoff);
                assert_eq!(reason.reason, EarlyReason::NotConfident);
                assert_eq!(reason.point, None);
            }
        }
    }
    reasons
}

/// A model decides only at the moments it was trained for: a point it lacks, or `auto` without
/// points, is refused with how to train one; its whole length is always accepted.
#[test]
fn a_moment_the_model_was_not_trained_for_is_refused() {
    let (whole_only, _) = setup(false);
    let (with_points, _) = setup_with_points(false, &[4]);
    let params = ValidSegmentParams::default();
    let at = |decide_at| OnlineParams {
        decide_at: Some(decide_at),
        ..OnlineParams::default()
    };
    for (model, decide_at) in [
        (&whole_only, DecideAt::Frames(4)),
        (&whole_only, DecideAt::AUTO),
        (&with_points, DecideAt::Frames(5)),
    ] {
        let err = OnlineClassifier::new(model, &params, &at(decide_at), None)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("not trained to decide at") && err.contains("--decide-at"),
            "{decide_at}: {err}"
        );
    }
    for (model, decide_at) in [
        (&whole_only, DecideAt::Frames(LENGTH - 1)),
        (&with_points, DecideAt::Frames(4)),
        (&with_points, DecideAt::AUTO),
    ] {
        assert!(
            OnlineClassifier::new(model, &params, &at(decide_at), None).is_ok(),
            "{decide_at}"
        );
    }
}

fn run_late(model: &TrainedModel, frames: &[Frame]) -> Vec<DecidedAt> {
    run(model, frames, Some(DecideAt::Frames(40)))
        .decisions
        .iter()
        .map(|(d, _, _)| d.stance.unwrap().decided_at)
        .collect()
}

#[test]
fn a_stance_longer_than_the_model_is_decided_on_its_first_frames_when_known() {
    let (model, frames) = setup(true);
    let run = run(&model, &frames, None);
    assert_eq!(run.decisions.len(), 12);
    let mut cut = 0;
    for ((decision, posteriors, at), (stance, sampled, liftoff_at)) in
        run.decisions.iter().zip(&run.liftoffs)
    {
        assert!(sampled);
        let how = decision.stance.unwrap();
        let (first, count) = if stance.len > LENGTH {
            cut += 1;
            assert_eq!(how.decided_at, DecidedAt::Length(LENGTH));
            assert!(how.cut);
            // Known longer as its 17th frame arrives, loaded.
            assert_eq!(how.waited_for, stance.start + LENGTH);
            assert!(at < liftoff_at, "before the lift-off");
            (stance.start, LENGTH)
        } else {
            assert_eq!(how.decided_at, DecidedAt::Liftoff);
            (stance.start, stance.len)
        };
        assert_eq!(decision.frames_used, count);
        let (class, expected) = offline(&model, &frames, first, count);
        assert_eq!(decision.class, class);
        assert_eq!(posteriors, &expected);
    }
    assert_eq!(cut, 4);
}

#[test]
fn settings_that_do_not_fit_the_model_are_refused() {
    let (frame_model, _) = bench_fixture(3, 0).unwrap();
    let params = ValidSegmentParams::default();
    let decide = OnlineParams {
        decide_at: Some(DecideAt::Frames(5)),
        ..OnlineParams::default()
    };
    let err = OnlineClassifier::new(&frame_model, &params, &decide, None)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("decide_at") && err.contains("whole-stance"),
        "{err}"
    );
    let (stance_model, frames) = setup(false);
    let fuse = OnlineParams {
        fusion_offsets: vec![3, 4],
        ..OnlineParams::default()
    };
    let err = OnlineClassifier::new(&stance_model, &params, &fuse, None)
        .unwrap_err()
        .to_string();
    assert!(err.contains("fusion"), "{err}");
    // A frame too small for the summary's regions is refused, and the stream can go on.
    let mut classifier =
        OnlineClassifier::new(&stance_model, &params, &OnlineParams::default(), None).unwrap();
    let tiny = Frame::zeros(presrs_core::Grid::new(2, 1));
    assert!(classifier.push(&tiny.view()).is_err());
    assert!(classifier.push(&frames[0].view()).is_ok());
}

/// A stream that ends during the warm-up has its stances found at the end: reported, not decided.
#[test]
fn stances_found_at_the_end_of_a_warmup_are_reported_not_decided() {
    let (model, _) = setup(false);
    let (frames, stances) = stance_stream(&[12, 14], 5);
    assert!(frames.len() < OnlineParams::default().warmup_frames);
    let params = ValidSegmentParams::default();
    let mut classifier =
        OnlineClassifier::new(&model, &params, &OnlineParams::default(), None).unwrap();
    for frame in &frames {
        assert!(classifier.push(&frame.view()).unwrap().events.is_empty());
    }
    let step = classifier.finish().unwrap();
    let liftoffs: Vec<_> = step
        .events
        .iter()
        .filter_map(|e| match e {
            OnlineEvent::Liftoff(l) => Some(l),
            OnlineEvent::Touchdown(_) => None,
            other => panic!("{other:?}"),
        })
        .collect();
    assert_eq!(liftoffs.len(), stances.len());
    assert!(liftoffs.iter().all(|l| !l.sampled));
}
