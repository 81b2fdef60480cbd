//! The causal (online) detector on recordings that are one contact from their first frame to their
//! last, against the offline segmentation of the same movies: without a calibration (the whole movie
//! fits in the warm-up) the stream's one partial stance comes at `finish`; with one sample per file
//! (`BaselineMode::Contact`) the stance starts at frame 0 and frame `k` is decided as it arrives.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::f64::consts::PI;

use presrs_core::online::{
    CausalSegmenter, DecisionKind, OnlineClassifier, OnlineEvent, OnlineParams, SegEvent,
};
use presrs_core::stance::{BaselineMode, SegmentParams, Stance, ValidSegmentParams, segment};
use presrs_core::testing::{bench_fixture, synthetic_frame};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A heel-and-toe double hump from the first frame to the last (never unloading), with noise.
fn one_contact(n: usize, seed: u64) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|t| {
            let x = t as f64 / (n - 1) as f64;
            let noise: f64 = rng.random_range(-20.0..20.0);
            300.0 + 12_000.0 * (PI * x).sin() * (0.6 + 0.4 * (3.0 * PI * x).cos().abs()) + noise
        })
        .collect()
}

/// The stances of every lift-off the segmenter reports over `totals`, `finish` included.
fn causal_stances(seg: &mut CausalSegmenter, totals: &[f64]) -> (Vec<Stance>, Vec<SegEvent>) {
    let mut events = Vec::new();
    for &total in totals {
        events.extend(seg.push(total).unwrap().iter());
    }
    events.extend(seg.finish().unwrap().iter());
    let stances = events
        .iter()
        .filter_map(|e| match e {
            SegEvent::Liftoff(l) => Some(l.stance),
            _ => None,
        })
        .collect();
    (stances, events)
}

#[test]
fn a_one_contact_movie_gives_its_partial_stance_at_finish_as_offline() {
    let params = ValidSegmentParams::default();
    for (n, seed) in [(12, 1), (40, 2), (63, 3), (100, 4), (127, 5)] {
        let totals = one_contact(n, seed);
        let offline = segment(&totals, &params).unwrap();
        assert_eq!(offline.mode, BaselineMode::Contact, "n = {n}");
        let mut seg = CausalSegmenter::new(&params, &OnlineParams::default(), None).unwrap();
        let (online, events) = causal_stances(&mut seg, &totals);
        assert_eq!(online, offline.stances, "n = {n}");
        assert_eq!(online[0].start, 0);
        assert!(online[0].partial);
        // Touchdown before lift-off, not sampled (the frames have passed).
        assert!(matches!(events[0], SegEvent::Touchdown(td) if td.partial));
        assert!(matches!(events[1], SegEvent::Liftoff(l) if !l.sampled));
    }
}

#[test]
fn one_sample_per_file_decides_frame_k_of_the_contact() {
    let contact = SegmentParams {
        baseline: BaselineMode::Contact,
        ..SegmentParams::default()
    }
    .check()
    .unwrap();
    let (model, _) = bench_fixture(3, 0).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    for (n, class) in [(20, 0), (63, 1), (150, 2), (300, 3)] {
        // (`class` only picks the print: the test is of when the decision comes, not of the model.)
        let totals = one_contact(n, n as u64);
        let offline = segment(&totals, &contact).unwrap();
        let mid = offline.stances[0].mid_frame();
        // The segmenter alone: the stance from frame 0, the sample at k = the offline mid frame.
        let online = OnlineParams {
            sample_offset: mid,
            ..OnlineParams::default()
        };
        let mut seg = CausalSegmenter::new(&contact, &online, None).unwrap();
        let (stances, events) = causal_stances(&mut seg, &totals);
        assert_eq!(stances, offline.stances, "n = {n}");
        let samples: Vec<usize> = events
            .iter()
            .filter_map(|e| match e {
                SegEvent::ClassifySample { frame, .. } => Some(*frame),
                _ => None,
            })
            .collect();
        assert_eq!(samples, vec![mid], "n = {n}");

        // The classifier: one decision, on frame k, and the lift-off at the end says it was sampled.
        let print = synthetic_frame(class, &mut rng);
        let peak = totals.iter().copied().fold(f64::MIN, f64::max);
        let frames: Vec<_> = totals
            .iter()
            .map(|&total| {
                let mut frame = print.clone();
                for v in frame.values_mut() {
                    *v = (*v * total / peak).round();
                }
                frame
            })
            .collect();
        let mut classifier = OnlineClassifier::new(&model, &contact, &online, None).unwrap();
        let mut decisions = Vec::new();
        for frame in &frames {
            for event in classifier.push(&frame.view()).unwrap().events {
                if let OnlineEvent::Decision(d) = event {
                    decisions.push(*d);
                }
            }
        }
        let end = classifier.finish().unwrap();
        let liftoff = end
            .events
            .iter()
            .find_map(|e| match e {
                OnlineEvent::Liftoff(l) => Some(*l),
                _ => None,
            })
            .unwrap();
        assert_eq!(decisions.len(), 1, "n = {n}");
        assert_eq!(decisions[0].kind, DecisionKind::Single);
        assert_eq!(decisions[0].sample_frame, mid);
        // (The frames' totals are the print's, not `totals`: only the extent is compared.)
        let stance = liftoff.stance;
        assert_eq!((stance.start, stance.len, stance.partial), (0, n, true));
        assert!(liftoff.sampled);
    }
}
