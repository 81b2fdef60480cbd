//! Steady state allocates nothing: a [`Session`] classifying frames one at a time and an
//! [`OnlineClassifier`] fed a 100 Hz stream (after its first frame) make no heap allocation, for every
//! feature family and classifier, with and without the preprocessing steps.
//!
//! The counting allocator is process-wide, so this file holds a single test: nothing else runs in this
//! test binary while it measures.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::alloc::System;

use presrs_core::Frame;
use presrs_core::classifier::ClassifierKind;
use presrs_core::features::FeatureKind;
use presrs_core::online::{Calibration, DecideAt, OnlineClassifier, OnlineParams};
use presrs_core::pipeline::{LabeledImage, TrainConfig, TrainedModel, train};
use presrs_core::preprocess::Preprocess;
use presrs_core::stance::{ValidSegmentParams, segment};
use presrs_core::testing::{
    SYNTHETIC_CLASSES, stance_model_with_points, stance_stream, synthetic_frame, synthetic_stream,
};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use stats_alloc::{INSTRUMENTED_SYSTEM, Region, StatsAlloc};

#[global_allocator]
static GLOBAL: &StatsAlloc<System> = &INSTRUMENTED_SYSTEM;

fn labelled(count: usize, rng: &mut ChaCha8Rng) -> Vec<(Frame, &'static str)> {
    (0..count)
        .map(|i| (synthetic_frame(i % 4, rng), SYNTHETIC_CLASSES[i % 4]))
        .collect()
}

fn images<'a>(set: &'a [(Frame, &'static str)]) -> Vec<LabeledImage<'a>> {
    set.iter()
        .map(|(frame, label)| LabeledImage::new(frame.view(), label))
        .collect()
}

fn model(
    features: FeatureKind,
    classifier: ClassifierKind,
    preprocess: Preprocess,
) -> TrainedModel {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let train_set = labelled(4 * 13, &mut rng);
    let validation_set = labelled(4 * 7, &mut rng);
    let config = TrainConfig {
        features: features.default_config(),
        classifier: classifier.default_config(),
        preprocess,
        ..TrainConfig::default()
    }
    .check()
    .unwrap();
    train(&images(&train_set), &images(&validation_set), &config).unwrap()
}

/// The detector's levels as a trained model's online profile would carry them.
fn calibration(frames: &[Frame]) -> Calibration {
    let totals: Vec<f64> = frames.iter().map(|f| f.view().total()).collect();
    let segmentation = segment(&totals, &ValidSegmentParams::default()).unwrap();
    Calibration::from_segmentations([&segmentation]).unwrap()
}

/// Allocations, reallocations and deallocations made while `work` runs.
fn count(work: impl FnOnce()) -> (usize, usize, usize) {
    let region = Region::new(GLOBAL);
    work();
    let change = region.change();
    (
        change.allocations,
        change.reallocations,
        change.deallocations,
    )
}

#[test]
fn steady_state_classification_does_not_allocate() {
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    let frames: Vec<Frame> = (0..64).map(|i| synthetic_frame(i % 4, &mut rng)).collect();
    let live = synthetic_stream(12, &mut rng);
    let fill = Preprocess {
        normalise_load: true,
        fill_absent: true,
        intensity: presrs_core::preprocess::Intensity::Log1p,
    };
    let mut cases = Vec::new();
    for classifier in ClassifierKind::all() {
        cases.push((FeatureKind::FFT1D, classifier, Preprocess::NONE));
    }
    for features in [
        FeatureKind::FFT2D,
        FeatureKind::FFT2D_POLAR,
        FeatureKind::GLCM,
    ] {
        cases.push((features, ClassifierKind::PWE, Preprocess::NONE));
    }
    cases.push((FeatureKind::FFT1D, ClassifierKind::PWE, fill));

    for (features, classifier, preprocess) in cases {
        let name = format!("{features:?} + {classifier:?} ({preprocess:?})");
        let model = model(features, classifier, preprocess);

        // One image at a time through a session: the first call may size nothing more (buffers are
        // made with the session), so every call is counted after one warm-up.
        let mut session = model.session();
        session.classify(&frames[0].view()).unwrap();
        let mut correct = 0;
        let counts = count(|| {
            for (i, frame) in frames.iter().enumerate() {
                let prediction = session.classify(&frame.view()).unwrap();
                correct += usize::from(prediction.class == i % 4);
            }
        });
        assert_eq!(counts, (0, 0, 0), "{name}: session allocations");
        assert!(
            correct > 32,
            "{name}: only {correct}/64 right: not a real run"
        );

        // The online classifier, calibrated from training data (a model's online profile): its first
        // frame fixes the grid and sizes the held-frame buffer; every later frame, through touchdowns,
        // classifications and lift-offs, allocates nothing.
        let online = OnlineParams {
            sample_offset: 6,
            fusion_offsets: vec![4, 5, 6, 7, 8],
            ..OnlineParams::default()
        };
        let mut classifier = OnlineClassifier::new(
            &model,
            &ValidSegmentParams::default(),
            &online,
            Some(calibration(&live)),
        )
        .unwrap();
        classifier.push(&live[0].view()).unwrap();
        let mut events = 0;
        let counts = count(|| {
            for frame in &live[1..] {
                events += classifier.push(&frame.view()).unwrap().events.len();
            }
        });
        assert_eq!(counts, (0, 0, 0), "{name}: online allocations");
        assert!(
            events >= 3 * 10,
            "{name}: only {events} events: the stream was not segmented"
        );

        // Uncalibrated, it calibrates on its warm-up frames (that allocates, once); after them, nothing.
        let mut classifier =
            OnlineClassifier::new(&model, &ValidSegmentParams::default(), &online, None).unwrap();
        let warmup = online.warmup_frames + 1;
        for frame in &live[..warmup] {
            classifier.push(&frame.view()).unwrap();
        }
        assert!(
            !classifier.segmenter().warming_up(),
            "{name}: still warming up"
        );
        let mut events = 0;
        let counts = count(|| {
            for frame in &live[warmup..] {
                events += classifier.push(&frame.view()).unwrap().events.len();
            }
        });
        assert_eq!(
            counts,
            (0, 0, 0),
            "{name}: online allocations after warm-up"
        );
        assert!(events > 0, "{name}: no events after warm-up");
    }

    whole_stance_models_do_not_allocate_per_frame();
}

/// A whole-stance model online: its first frame sizes the stance buffer; every later frame (kept,
/// touchdowns, decisions at lift-off, at `decide_at` (a point, `auto`) and at the cut, lift-offs)
/// allocates nothing.
fn whole_stance_models_do_not_allocate_per_frame() {
    let lens: Vec<usize> = (0..24).map(|i| 10 + (i * 7) % 6).collect();
    let (train_frames, stances) = stance_stream(&lens, 3);
    let model = stance_model_with_points(&train_frames, &stances, 12, &[4]).unwrap();
    let test_lens: Vec<usize> = (0..10).map(|i| 9 + (i * 5) % 8).collect();
    let (live, _) = stance_stream(&test_lens, 4);
    for decide_at in [None, Some(DecideAt::Frames(4)), Some(DecideAt::AUTO)] {
        let online = OnlineParams {
            decide_at,
            ..OnlineParams::default()
        };
        let mut classifier = OnlineClassifier::new(
            &model,
            &ValidSegmentParams::default(),
            &online,
            Some(calibration(&live)),
        )
        .unwrap();
        // The first stance is decided before counting: a session's MiniRocket scratch is a clone,
        // which loses the spare capacity of its offsets, and grows it once on its first sample.
        let first_stance_end = 20 + test_lens[0] + 10;
        for frame in &live[..first_stance_end] {
            classifier.push(&frame.view()).unwrap();
        }
        let mut decisions = 1;
        let counts = count(|| {
            for frame in &live[first_stance_end..] {
                let step = classifier.push(&frame.view()).unwrap();
                decisions += step
                    .events
                    .iter()
                    .filter(|e| matches!(e, presrs_core::online::OnlineEvent::Decision(_)))
                    .count();
            }
        });
        assert_eq!(
            counts,
            (0, 0, 0),
            "whole stance ({decide_at:?}): allocations"
        );
        assert_eq!(
            decisions, 10,
            "whole stance ({decide_at:?}): one decision a stance"
        );
    }
}
