//! The streaming classifier on a synthetic stream: flights of empty frames and stances of the synthetic
//! foot prints under a half-sine load. Events, sample frame, fusion, partial stances, bad frames, and the
//! causal detector against the offline segmentation on noisy drifting series.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::f64::consts::PI;

use presrs_core::online::{
    Calibration, CausalSegmenter, DecisionKind, MAX_OFFSET_FRAMES, OnlineClassifier, OnlineEvent,
    OnlineParams, SegEvent,
};
use presrs_core::stance::{ValidSegmentParams, segment};
use presrs_core::testing::{bench_fixture, synthetic_frame};
use presrs_core::{Frame, Grid};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// `(frames, stances as (start, len, class))`: stances of `len` frames separated by 20-frame flights.
fn stream(lens: &[usize], lead: usize, seed: u64) -> (Vec<Frame>, Vec<(usize, usize, usize)>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let grid = Grid::new(44, 44);
    let mut frames = Vec::new();
    let mut truth = Vec::new();
    let flight = |rng: &mut ChaCha8Rng| {
        let mut f = Frame::zeros(grid);
        // A few noisy sensels, as a real sensor in flight.
        for _ in 0..3 {
            let i = rng.random_range(0..grid.len());
            f.values_mut()[i] = rng.random_range(3.0..6.0);
        }
        f
    };
    for _ in 0..lead {
        frames.push(flight(&mut rng));
    }
    for (i, &len) in lens.iter().enumerate() {
        let class = i % 4;
        truth.push((frames.len(), len, class));
        let print = synthetic_frame(class, &mut rng);
        for j in 0..len {
            let scale = (PI * (j as f64 + 0.5) / len as f64).sin();
            let mut f = print.clone();
            for v in f.values_mut() {
                *v = (*v * scale).round();
            }
            frames.push(f);
        }
        for _ in 0..20 {
            frames.push(flight(&mut rng));
        }
    }
    (frames, truth)
}

fn calibration(frames: &[Frame]) -> Calibration {
    let totals: Vec<f64> = frames.iter().map(|f| f.view().total()).collect();
    let seg = segment(&totals, &ValidSegmentParams::default()).unwrap();
    Calibration::from_segmentations([&seg]).unwrap()
}

#[test]
fn events_in_order_with_the_kth_frame_classified() {
    let (model, _) = bench_fixture(3, 0).unwrap();
    let (frames, truth) = stream(&[14, 14, 15, 13, 14, 14, 16, 14], 10, 1);
    let online = OnlineParams {
        sample_offset: 6,
        fusion_offsets: vec![4, 5, 6, 7, 8],
        ..OnlineParams::default()
    };
    let mut classifier = OnlineClassifier::new(
        &model,
        &ValidSegmentParams::default(),
        &online,
        Some(calibration(&frames)),
    )
    .unwrap();
    let mut log = Vec::new();
    let mut correct = (0, 0);
    for frame in &frames {
        let step = classifier.push(&frame.view()).unwrap();
        for event in step.events {
            if let OnlineEvent::Decision(d) = event {
                let posteriors = step.posteriors(d);
                assert_eq!(posteriors.len(), 4);
                assert!((posteriors.iter().sum::<f64>() - 1.0).abs() < 1e-9);
                assert_eq!(posteriors[d.class], d.confidence);
                let (_, _, class) = truth[d.stance_id as usize];
                match d.kind {
                    DecisionKind::Single => correct.0 += usize::from(d.class == class),
                    DecisionKind::Fused => correct.1 += usize::from(d.class == class),
                    DecisionKind::Stance => panic!("a one-frame model decides no whole stance"),
                }
            }
            log.push(*event);
        }
    }
    let step = classifier.finish().unwrap();
    assert!(step.events.is_empty(), "the stream ends in flight");
    assert_eq!(
        log.len(),
        truth.len() * 4,
        "touchdown, single, fused, lift-off each"
    );
    for (i, chunk) in log.chunks(4).enumerate() {
        let (start, len, _) = truth[i];
        let OnlineEvent::Touchdown(td) = chunk[0] else {
            panic!("{chunk:?}")
        };
        assert_eq!((td.touchdown_frame, td.partial), (start, false));
        assert!(td.frame < start + 3, "confirmed within min_stance frames");
        let OnlineEvent::Decision(single) = chunk[1] else {
            panic!("{chunk:?}")
        };
        assert_eq!(single.kind, DecisionKind::Single);
        assert_eq!(single.sample_frame, start + 6);
        assert_eq!(
            single.frame,
            start + 6,
            "decided on arrival of the sample frame"
        );
        let OnlineEvent::Decision(fused) = chunk[2] else {
            panic!("{chunk:?}")
        };
        assert_eq!((fused.kind, fused.frames_used), (DecisionKind::Fused, 5));
        assert_eq!(fused.frame, start + 8);
        let OnlineEvent::Liftoff(lo) = chunk[3] else {
            panic!("{chunk:?}")
        };
        assert_eq!((lo.stance.start, lo.stance.len), (start, len));
        assert!(lo.sampled);
        assert_eq!(
            lo.frame,
            start + len + 2,
            "max_gap_frames after the last loaded frame"
        );
    }
    assert!(correct.0 >= 6 && correct.1 >= 6, "{correct:?}");
    let stats = classifier.stats();
    assert_eq!(stats.frames, frames.len() as u64);
    assert_eq!((stats.decisions, stats.fused_decisions), (8, 8));
}

#[test]
fn partial_stances_short_stances_and_bad_frames() {
    let (model, _) = bench_fixture(3, 0).unwrap();
    // The stream starts inside a stance (partial: reported, not sampled); the second stance is too short
    // for k = 6 (ends before its sample frame); the third is normal; the stream ends inside a fourth.
    let (mut frames, truth) = stream(&[14, 5, 14, 14], 0, 2);
    let cut = truth[3].0 + 9;
    frames.truncate(cut);
    frames.drain(..4);
    let cal = calibration(&frames);
    let mut classifier = OnlineClassifier::new(
        &model,
        &ValidSegmentParams::default(),
        &OnlineParams::default(),
        Some(cal),
    )
    .unwrap();
    let mut events = Vec::new();
    for (i, frame) in frames.iter().enumerate() {
        if i == 30 {
            // A frame of the wrong size and a frame with NaN: errors, the stream goes on.
            let err = classifier
                .push(&Frame::zeros(Grid::new(4, 4)).view())
                .unwrap_err()
                .to_string();
            assert!(err.contains("4x4") && err.contains("44x44"), "{err}");
            let mut bad = frame.clone();
            bad.values_mut()[0] = f64::NAN;
            assert!(classifier.push(&bad.view()).is_err());
        }
        events.extend_from_slice(classifier.push(&frame.view()).unwrap().events);
    }
    events.extend_from_slice(classifier.finish().unwrap().events);
    let liftoffs: Vec<_> = events
        .iter()
        .filter_map(|e| match e {
            OnlineEvent::Liftoff(l) => Some(*l),
            _ => None,
        })
        .collect();
    assert_eq!(liftoffs.len(), 4, "{events:?}");
    assert!(liftoffs[0].stance.partial && !liftoffs[0].sampled);
    assert!(
        !liftoffs[1].stance.partial && !liftoffs[1].sampled,
        "5-frame stance, k = 6"
    );
    assert!(!liftoffs[2].stance.partial && liftoffs[2].sampled);
    assert!(
        liftoffs[3].stance.partial && liftoffs[3].sampled,
        "cut by the end of the stream"
    );
    let decisions = events
        .iter()
        .filter(|e| matches!(e, OnlineEvent::Decision(_)))
        .count();
    assert_eq!(decisions, 2);
    assert_eq!(classifier.stats().rejected_frames, 2);
}

#[test]
fn a_dropout_at_the_sample_frame_is_decided_from_the_held_copy() {
    let (model, _) = bench_fixture(3, 0).unwrap();
    let (mut frames, truth) = stream(&[14, 14], 5, 3);
    let (start, _, _) = truth[1];
    frames[start + 6] = Frame::zeros(Grid::new(44, 44));
    let mut classifier = OnlineClassifier::new(
        &model,
        &ValidSegmentParams::default(),
        &OnlineParams::default(),
        Some(calibration(&frames)),
    )
    .unwrap();
    let mut decisions = Vec::new();
    for frame in &frames {
        let step = classifier.push(&frame.view()).unwrap();
        for e in step.events {
            if let OnlineEvent::Decision(d) = e {
                decisions.push(*d);
            }
        }
    }
    assert_eq!(decisions.len(), 2);
    let d = decisions[1];
    assert_eq!(
        (d.sample_frame, d.frame),
        (start + 6, start + 7),
        "decided one frame late"
    );
    // The decision is the held (empty) frame's, not a later one's.
    let mut session = model.session();
    let empty = session
        .classify(&Frame::zeros(Grid::new(44, 44)).view())
        .unwrap()
        .class;
    assert_eq!(d.class, empty);
}

#[test]
fn causal_and_offline_agree_on_noisy_drifting_series() {
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    for trial in 0..20 {
        // Stances 12..=16 frames, flights 17..=23, amplitude 1000, noise sigma 5, drift 60 over the series.
        let mut stances = Vec::new();
        let mut t = 15;
        while t < 1500 {
            let len = rng.random_range(12..=16);
            stances.push((t, len));
            t += len + rng.random_range(17..=23);
        }
        let n = t;
        let mut totals: Vec<f64> = (0..n)
            .map(|i| {
                let noise: f64 = (0..12).map(|_| rng.random::<f64>()).sum::<f64>() - 6.0;
                100.0 + 60.0 * i as f64 / n as f64 + 5.0 * noise
            })
            .collect();
        for &(start, len) in &stances {
            for j in 0..len {
                totals[start + j] += 1000.0 * (PI * (j as f64 + 0.5) / len as f64).sin();
            }
        }
        let params = ValidSegmentParams::default();
        let off = segment(&totals, &params).unwrap();
        let cal = Calibration::from_segmentations([&off]).unwrap();
        let mut seg = CausalSegmenter::new(&params, &OnlineParams::default(), Some(cal)).unwrap();
        let mut online = Vec::new();
        for &total in &totals {
            for e in seg.push(total).unwrap().iter() {
                if let SegEvent::Liftoff(l) = e {
                    online.push(l.stance);
                }
            }
        }
        let complete: Vec<_> = off.stances.iter().filter(|s| !s.partial).collect();
        assert_eq!(complete.len(), stances.len(), "trial {trial}");
        let same = complete
            .iter()
            .filter(|s| online.iter().any(|o| o.start == s.start && o.len == s.len))
            .count();
        // The levels differ a little (past-only baseline and noise); the stances may differ by a frame at
        // their low-load edges, rarely.
        assert!(
            same * 100 >= complete.len() * 95,
            "trial {trial}: {same}/{}",
            complete.len()
        );
        assert_eq!(online.len(), complete.len(), "trial {trial}: same count");
    }
}

#[test]
fn sample_and_fusion_offsets_are_bounded() {
    let params = ValidSegmentParams::default();
    for online in [
        OnlineParams {
            sample_offset: usize::MAX,
            ..OnlineParams::default()
        },
        OnlineParams {
            sample_offset: MAX_OFFSET_FRAMES + 1,
            ..OnlineParams::default()
        },
        OnlineParams {
            fusion_offsets: vec![4, usize::MAX],
            ..OnlineParams::default()
        },
    ] {
        let err = CausalSegmenter::new(&params, &online, None).unwrap_err();
        let text = err.to_string();
        assert!(
            text.contains("sample_offset") || text.contains("fusion_offsets"),
            "{text}"
        );
    }
    // The largest offset allowed runs: the stance ends long before its sample frame, so it is reported
    // and not sampled.
    let (frames, truth) = stream(&[14], 5, 4);
    let online = OnlineParams {
        sample_offset: MAX_OFFSET_FRAMES,
        ..OnlineParams::default()
    };
    let mut seg = CausalSegmenter::new(&params, &online, Some(calibration(&frames))).unwrap();
    let mut liftoffs = Vec::new();
    for frame in &frames {
        for e in seg.push(frame.view().total()).unwrap().iter() {
            assert!(!matches!(e, SegEvent::ClassifySample { .. }), "{e:?}");
            if let SegEvent::Liftoff(l) = e {
                liftoffs.push(l);
            }
        }
    }
    assert_eq!(liftoffs.len(), 1);
    assert_eq!(liftoffs[0].stance.start, truth[0].0);
    assert!(!liftoffs[0].sampled);
}

#[test]
fn a_first_frame_the_model_cannot_classify_is_rejected_up_front() {
    let (model, _) = bench_fixture(3, 0).unwrap();
    let (frames, _) = stream(&[14], 5, 5);
    let mut classifier = OnlineClassifier::new(
        &model,
        &ValidSegmentParams::default(),
        &OnlineParams::default(),
        Some(calibration(&frames)),
    )
    .unwrap();
    // The paper's crop (drop 6 rows, 3 columns) does not give the model's 38x41 image from 16x16.
    let err = classifier
        .push(&Frame::zeros(Grid::new(16, 16)).view())
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("16x16") && err.contains("38x41") && err.contains("crop"),
        "{err}"
    );
    assert_eq!(classifier.grid(), None, "the rejected frame sets no grid");
    // The stream goes on with frames the model can classify.
    let mut decisions = 0;
    for frame in &frames {
        let step = classifier.push(&frame.view()).unwrap();
        decisions += step
            .events
            .iter()
            .filter(|e| matches!(e, OnlineEvent::Decision(_)))
            .count();
    }
    assert_eq!(decisions, 1);
    assert_eq!(classifier.stats().rejected_frames, 1);
    assert_eq!(classifier.stats().frames, frames.len() as u64);
}

/// `frame` with `+1e308` and `-1e308` at two neighbouring sensels inside the paper's crop: its total load
/// is unchanged (the pair cancels) but its features overflow, so the model cannot classify it.
fn unclassifiable(frame: &Frame) -> Frame {
    let mut bad = frame.clone();
    bad.values_mut()[3] = 1e308;
    bad.values_mut()[4] = -1e308;
    bad
}

#[test]
fn a_frame_that_cannot_be_classified_keeps_the_events_of_its_frame() {
    let (model, _) = bench_fixture(3, 0).unwrap();
    let (mut frames, truth) = stream(&[14, 14, 14], 10, 6);
    let cal = calibration(&frames);
    // k = 0: the sample is the touchdown frame, held and classified at confirmation, the frame whose
    // events include the touchdown. The second stance's first frames cannot be classified.
    let (start, _, _) = truth[1];
    assert!(frames[start - 1].view().total() < 100.0);
    for frame in &mut frames[start..start + 3] {
        *frame = unclassifiable(frame);
    }
    assert!(model.session().classify(&frames[start].view()).is_err());
    let online = OnlineParams {
        sample_offset: 0,
        fusion_offsets: vec![2, 5],
        ..OnlineParams::default()
    };
    let mut classifier =
        OnlineClassifier::new(&model, &ValidSegmentParams::default(), &online, Some(cal)).unwrap();
    let mut events = Vec::new();
    let mut messages = Vec::new();
    for frame in &frames {
        let step = classifier.push(&frame.view()).unwrap();
        for e in step.events {
            if let OnlineEvent::Failed(f) = e {
                messages.push(step.error(f).unwrap().to_string());
            }
        }
        events.extend_from_slice(step.events);
    }
    events.extend_from_slice(classifier.finish().unwrap().events);
    let of = |id: u64| -> Vec<OnlineEvent> {
        events
            .iter()
            .copied()
            .filter(|e| match e {
                OnlineEvent::Touchdown(td) => td.stance_id == id,
                OnlineEvent::Decision(d) => d.stance_id == id,
                OnlineEvent::Failed(f) => f.stance_id == id,
                OnlineEvent::Liftoff(l) => l.stance_id == id,
            })
            .collect()
    };
    for id in [0, 2] {
        let evs = of(id);
        assert!(matches!(evs[0], OnlineEvent::Touchdown(_)), "{evs:?}");
        assert!(
            matches!(evs.last(), Some(OnlineEvent::Liftoff(l)) if l.sampled),
            "{evs:?}"
        );
        assert!(!evs.iter().any(|e| matches!(e, OnlineEvent::Failed(_))));
    }
    let evs = of(1);
    assert!(
        matches!(evs[0], OnlineEvent::Touchdown(_)),
        "touchdown kept: {evs:?}"
    );
    let single = evs
        .iter()
        .find_map(|e| match e {
            OnlineEvent::Failed(f) if f.kind == DecisionKind::Single => Some(*f),
            _ => None,
        })
        .unwrap();
    assert_eq!(single.sample_frame, start);
    // Fusion frame 2 (the confirmation frame) failed too; frame 5 is fine, so the fused decision comes
    // from it alone.
    assert!(evs.iter().any(
        |e| matches!(e, OnlineEvent::Failed(f) if f.kind == DecisionKind::Fused && f.sample_frame == start + 2)
    ));
    let fused: Vec<_> = evs
        .iter()
        .filter_map(|e| match e {
            OnlineEvent::Decision(d) => Some(*d),
            _ => None,
        })
        .collect();
    assert_eq!(fused.len(), 1, "{evs:?}");
    assert_eq!(
        (fused[0].kind, fused[0].frames_used, fused[0].sample_frame),
        (DecisionKind::Fused, 1, start + 5)
    );
    let Some(OnlineEvent::Liftoff(liftoff)) = evs.last() else {
        panic!("no lift-off: {evs:?}");
    };
    assert!(!liftoff.sampled, "no single decision was made");
    assert!(
        messages.iter().all(|m| m.contains("NaN or infinite")),
        "{messages:?}"
    );
    let stats = classifier.stats();
    assert_eq!(
        (stats.stances, stats.decisions, stats.fused_decisions),
        (3, 2, 3)
    );
    assert_eq!(stats.rejected_frames, 0);
}
