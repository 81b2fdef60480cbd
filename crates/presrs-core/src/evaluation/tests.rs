//! The evaluation's tests: protocols, draws, perturbations, automatic choice and views.

use std::collections::BTreeMap;

use rand::SeedableRng;

use super::*;
use crate::error::CoreError;
use crate::frame::{Frame, FrameView};
use crate::pipeline::{CheckedTrainConfig, LabeledImage, TrainConfig, train};
use crate::split::ValidationSize;
use crate::testing::{SYNTHETIC_CLASSES, synthetic_frame};

fn data() -> Vec<(Frame, &'static str, &'static str)> {
    data_seeded(11)
}

/// 48 synthetic images of each condition, the classes in turn; the noise from `seed`.
fn data_seeded(seed: u64) -> Vec<(Frame, &'static str, &'static str)> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut out = Vec::new();
    for condition in ["G1", "G2", "G3"] {
        for i in 0..48 {
            out.push((
                synthetic_frame(i % 4, &mut rng),
                SYNTHETIC_CLASSES[i % 4],
                condition,
            ));
        }
    }
    out
}

/// The paper's protocol on the synthetic data: trained on G2, 10 per class with 3 validating.
fn g2_protocol() -> Protocol {
    Protocol::TrainCondition {
        condition: Some("G2".into()),
        per_class: Some(10),
        validation: ValidationSize::Count(3),
    }
}

/// The paper's pipeline with `dims` principal components.
fn paper_config_with_dims(dims: usize) -> CheckedTrainConfig {
    TrainConfig {
        dims,
        ..TrainConfig::default()
    }
    .check()
    .unwrap()
}

/// `protocol` on `samples`, `repeats` times from `seed`, without a progress callback.
fn evaluation<'e, 's>(
    samples: &'e [LabeledImage<'s>],
    protocol: &'e Protocol,
    repeats: usize,
    seed: u64,
) -> Evaluation<'e, 's> {
    Evaluation {
        samples,
        protocol,
        repeats,
        seed,
        progress: &|| {},
    }
}

fn samples<'a>(data: &'a [(Frame, &'static str, &'static str)]) -> Vec<LabeledImage<'a>> {
    data.iter()
        .map(|(frame, label, condition)| LabeledImage {
            frame: frame.view(),
            label,
            condition: Some(condition),
            group: Some(condition),
        })
        .collect()
}

#[test]
fn paper_protocol_counts_and_reproducibility() {
    let data = data();
    let samples = samples(&data);
    let protocol = g2_protocol();
    let config = paper_config_with_dims(20);
    let a = evaluation(&samples, &protocol, 2, 5)
        .run(Models::Config(&config))
        .unwrap();
    let b = evaluation(&samples, &protocol, 2, 5)
        .run(Models::Config(&config))
        .unwrap();
    // everything but the wall times is reproducible
    let strip = |report: &EvalReport| {
        report
            .repeats
            .iter()
            .map(|r| RepeatResult {
                train_seconds: 0.0,
                ..r.clone()
            })
            .collect::<Vec<_>>()
    };
    assert_eq!(strip(&a), strip(&b));
    assert_eq!(a.confusion, b.confusion);
    let first = &a.repeats[0];
    assert_eq!((first.n_train, first.n_validation), (28, 12));
    assert_eq!(first.n_test, samples.len() - 40);
    assert_eq!(a.per_condition.len(), 3);
    // the confusion matrix counts every tested sample of every repeat
    let total: u64 = a.confusion.counts.iter().flatten().sum();
    assert_eq!(total as usize, 2 * first.n_test);
    // the synthetic classes are easy: well above chance
    assert!(a.overall.mean > 0.8, "{:?}", a.overall);
    let correct: u64 = (0..4).map(|i| a.confusion.counts[i][i]).sum();
    assert!((correct as f64 / total as f64 - a.overall.mean).abs() < 1e-12);
}

#[test]
fn labels_never_trained_by_protocol() {
    let frame = Frame::zeros(crate::frame::Grid::new(2, 2));
    // (label, condition = group): wood in every trial, carpet only in t1, grass only in G1's t2.
    let rows = [
        ("wood", "t1"),
        ("carpet", "t1"),
        ("wood", "t2"),
        ("grass", "t2"),
        ("wood", "t3"),
    ];
    let samples: Vec<LabeledImage<'_>> = rows
        .iter()
        .map(|&(label, group)| LabeledImage {
            frame: frame.view(),
            label,
            condition: Some(group),
            group: Some(group),
        })
        .collect();
    let loo = Protocol::LeaveOneOut {
        column: "trial".into(),
        per_class: None,
        validation: ValidationSize::Count(0),
    };
    let missing = labels_never_trained(&samples, &loo);
    let expected: BTreeMap<String, Vec<String>> = [
        ("t1".to_owned(), vec!["carpet".to_owned()]),
        ("t2".to_owned(), vec!["grass".to_owned()]),
    ]
    .into();
    assert_eq!(missing, expected);
    let on_t1 = Protocol::TrainCondition {
        condition: Some("t1".into()),
        per_class: None,
        validation: ValidationSize::Count(0),
    };
    assert_eq!(
        labels_never_trained(&samples, &on_t1),
        [("all".to_owned(), vec!["grass".to_owned()])].into()
    );
    let on_all = Protocol::TrainCondition {
        condition: None,
        per_class: None,
        validation: ValidationSize::Count(0),
    };
    assert!(labels_never_trained(&samples, &on_all).is_empty());
}

/// Training on every sample of every condition leaves none to test: an error that says what to change.
#[test]
fn a_training_set_of_every_sample_is_refused_with_a_way_out() {
    let data = data();
    let samples = samples(&data);
    let protocol = Protocol::TrainCondition {
        condition: None,
        per_class: None,
        validation: ValidationSize::Count(3),
    };
    let config = paper_config_with_dims(10);
    let err = evaluation(&samples, &protocol, 1, 3)
        .run(Models::Config(&config))
        .unwrap_err();
    assert!(
        matches!(&err, CoreError::NotEnoughData(reason)
            if reason.contains("the training set took every sample (draw fewer per class")),
        "{err}"
    );
}

#[test]
fn leave_one_out_tests_each_value_once() {
    let data = data();
    let samples = samples(&data);
    let protocol = Protocol::LeaveOneOut {
        column: "condition".into(),
        per_class: Some(8),
        validation: ValidationSize::Count(3),
    };
    let config = paper_config_with_dims(10);
    let report = evaluation(&samples, &protocol, 1, 3)
        .run(Models::Config(&config))
        .unwrap();
    assert_eq!(
        report.per_condition.keys().collect::<Vec<_>>(),
        ["G1", "G2", "G3"]
    );
    assert_eq!(report.repeats[0].n_test, samples.len());
    assert_eq!(report.repeats[0].sigmas.len(), 3);
    // Issue #35: the counts are summed over the three folds (each draws 8 per class, 3 of them
    // validating), and the words say so, per fold.
    let first = &report.repeats[0];
    assert_eq!(first.folds, 3);
    assert_eq!((first.n_train, first.n_validation), (3 * 4 * 5, 3 * 4 * 3));
    let text = first.counts_text();
    assert!(
        text.starts_with("3 folds, per fold (on average) 20 training + 12 validation images"),
        "{text}"
    );
    assert!(
        text.contains(&format!("{} tested in all", samples.len())),
        "{text}"
    );
    let g2 = evaluation(&samples, &g2_protocol(), 1, 3)
        .run(Models::Config(&config))
        .unwrap();
    assert_eq!(g2.repeats[0].folds, 1);
    assert!(g2.repeats[0].counts_text().ends_with(" tested"));
}

#[test]
fn draws_are_the_sets_the_evaluation_trains_and_tests_on() {
    let data = data();
    let samples = samples(&data);
    let config = paper_config_with_dims(10);
    for protocol in [
        Protocol::LeaveOneOut {
            column: "condition".into(),
            per_class: Some(8),
            validation: ValidationSize::Count(3),
        },
        g2_protocol(),
    ] {
        let evaluation = evaluation(&samples, &protocol, 2, 5);
        let seen = std::sync::Mutex::new(Vec::new());
        let reports = evaluation
            .run_with(&[&samples], &[None], &|fold| {
                seen.lock().unwrap().push((
                    fold.seed,
                    fold.fold,
                    fold.held_out.map(str::to_owned),
                    fold.train.to_vec(),
                    fold.validation.to_vec(),
                ));
                let images = |set: &[usize]| -> Vec<LabeledImage<'_>> {
                    set.iter().map(|&i| samples[i]).collect()
                };
                let model = train(&images(fold.train), &images(fold.validation), &config)?;
                Ok(FoldModel { model, view: 0 })
            })
            .unwrap();
        let draws = evaluation.draws().unwrap();
        let mut seen = seen.into_inner().unwrap();
        // (folds train in parallel: in the draws' order by repeat seed, then place in the repeat)
        seen.sort_by_key(|(seed, fold, ..)| (*seed, *fold));
        assert_eq!(draws.len(), seen.len());
        for (draw, (seed, _, held_out, train_set, validation_set)) in draws.iter().zip(&seen) {
            assert_eq!(
                (draw.seed, &draw.held_out, &draw.train, &draw.validation),
                (*seed, held_out, train_set, validation_set)
            );
            // the test set is every sample outside the training pool's draw (leave-one-out: the
            // held-out value's samples)
            for &i in &draw.test {
                assert!(!draw.train.contains(&i) && !draw.validation.contains(&i));
                if let Some(held_out) = &draw.held_out {
                    assert_eq!(samples[i].group, Some(held_out.as_str()));
                }
            }
        }
        for (repeat, result) in reports.0[0].repeats.iter().enumerate() {
            let of_repeat = draws.iter().filter(|d| d.repeat == repeat);
            let n_test: usize = of_repeat.map(|d| d.test.len()).sum();
            assert_eq!(n_test, result.n_test);
        }
        assert_eq!(draws.last().unwrap().repeat, 1);
    }
}

#[test]
fn perturbing_test_images_only_changes_the_tested_accuracy() {
    let data = data();
    let samples = samples(&data);
    let protocol = g2_protocol();
    let config = paper_config_with_dims(20);
    let plain = evaluation(&samples, &protocol, 1, 5)
        .run(Models::Config(&config))
        .unwrap();
    let identity = |_: usize, frame: FrameView<'_>, _: u64| Ok(frame.to_frame());
    let same = evaluation(&samples, &protocol, 1, 5)
        .run_each(Models::Config(&config), &[Some(&identity)])
        .unwrap()
        .reports
        .remove(0);
    assert_eq!(same.confusion, plain.confusion);
    assert_eq!(same.repeats[0].sigmas, plain.repeats[0].sigmas);
    // Blank test images (every sensel dead): the same trained models, chance-level answers.
    let blank = |_: usize, frame: FrameView<'_>, _: u64| Ok(Frame::zeros(frame.grid()));
    let dead = evaluation(&samples, &protocol, 1, 5)
        .run_each(Models::Config(&config), &[Some(&blank)])
        .unwrap()
        .reports
        .remove(0);
    assert_eq!(dead.repeats[0].sigmas, plain.repeats[0].sigmas);
    assert_eq!(dead.repeats[0].n_test, plain.repeats[0].n_test);
    assert!(plain.overall.mean > 0.8, "{}", plain.overall.mean);
    assert!(dead.overall.mean < 0.5, "{}", dead.overall.mean);
}

#[test]
fn several_perturbations_at_once_match_one_at_a_time() {
    let data = data();
    let samples = samples(&data);
    let protocol = g2_protocol();
    let config = paper_config_with_dims(20);
    let noise = crate::perturb::Perturbation::Noise(20.0);
    let noisy = |i: usize, frame: FrameView<'_>, seed: u64| Ok(noise.apply(frame, seed, i as u64));
    let blank = |_: usize, frame: FrameView<'_>, _: u64| Ok(Frame::zeros(frame.grid()));
    let perturbs: [Option<&TestTransform<'_>>; 3] = [None, Some(&noisy), Some(&blank)];
    let calls = std::sync::atomic::AtomicUsize::new(0);
    let tick = || {
        calls.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    };
    let each = Evaluation {
        progress: &tick,
        ..evaluation(&samples, &protocol, 2, 5)
    }
    .run_each(Models::Config(&config), &perturbs)
    .unwrap()
    .reports;
    assert_eq!(
        calls.into_inner(),
        2,
        "one model per repeat, whatever the perturbations"
    );
    for (report, perturb) in each.iter().zip(perturbs) {
        let alone = evaluation(&samples, &protocol, 2, 5)
            .run_each(Models::Config(&config), &[perturb])
            .unwrap()
            .reports
            .remove(0);
        assert_eq!(report.confusion, alone.confusion);
        assert_eq!(report.overall, alone.overall);
        assert_eq!(report.per_condition, alone.per_condition);
    }
    assert!(each[2].overall.mean < each[0].overall.mean);
}

#[test]
fn a_perturbed_image_that_cannot_be_classified_is_a_wrong_answer_not_an_abort() {
    let data = data();
    let samples = samples(&data);
    let protocol = g2_protocol();
    let config = paper_config_with_dims(20);
    let huge = crate::perturb::Perturbation::Load(1e308);
    let heavy = |i: usize, frame: FrameView<'_>, seed: u64| Ok(huge.apply(frame, seed, i as u64));
    // Every other test image is made unclassifiable (values saturated at f64::MAX); the rest stay.
    let half = |i: usize, frame: FrameView<'_>, seed: u64| {
        Ok(if i % 2 == 0 {
            huge.apply(frame, seed, i as u64)
        } else {
            frame.to_frame()
        })
    };
    let perturbs: [Option<&TestTransform<'_>>; 3] = [None, Some(&heavy), Some(&half)];
    let reports = evaluation(&samples, &protocol, 1, 5)
        .run_each(Models::Config(&config), &perturbs)
        .unwrap()
        .reports;
    let (plain, heavy, half) = (&reports[0], &reports[1], &reports[2]);
    let n_test = plain.repeats[0].n_test as u64;
    let counted = |r: &EvalReport| r.confusion.counts.iter().flatten().sum::<u64>();
    let hits = |r: &EvalReport| (0..4).map(|i| r.confusion.counts[i][i]).sum::<u64>();
    assert_eq!(plain.unclassified, 0);
    assert_eq!(
        heavy.unclassified, n_test,
        "no image that large can be classified"
    );
    assert_eq!(counted(heavy), 0);
    assert_eq!(heavy.overall.mean, 0.0);
    let even = samples.len() as u64 / 2;
    assert!(half.unclassified > 0 && half.unclassified <= even);
    assert_eq!(counted(half) + half.unclassified, n_test);
    // The unclassified images count as wrong answers: accuracy over every tested image.
    let accuracy = hits(half) as f64 / n_test as f64;
    assert!((half.overall.mean - accuracy).abs() < 1e-12);
    assert!(half.overall.mean < plain.overall.mean);
}

#[test]
fn automatic_choice_trains_every_fold_on_its_own_and_records_each_selection() {
    let data = data();
    let samples = samples(&data);
    let protocol = Protocol::LeaveOneOut {
        column: "condition".into(),
        per_class: Some(8),
        validation: ValidationSize::Count(3),
    };
    let candidates = [paper_config_with_dims(5), paper_config_with_dims(10)];
    let run = evaluation(&samples, &protocol, 2, 7)
        .run_each(
            Models::Auto(crate::selection::AutoChoice::new(
                &candidates,
                crate::selection::ValidateBy::Auto,
            )),
            &[None],
        )
        .unwrap();
    // one model per held-out value and repeat, each with its selection
    assert_eq!(run.selections.len(), 3 * 2);
    for selection in &run.selections {
        assert_eq!(selection.scores.len(), candidates.len());
        assert!(selection.chosen().is_some());
    }
    // the same draws as a fixed configuration: every sample tested once per repeat
    let report = &run.reports[0];
    assert_eq!(report.repeats[0].n_test, samples.len());
    let total: u64 = report.confusion.counts.iter().flatten().sum();
    assert_eq!(total as usize, 2 * samples.len());
    // `run` is `run_each` on the images as they are
    let alone = evaluation(&samples, &protocol, 2, 7)
        .run(Models::Auto(crate::selection::AutoChoice::new(
            &candidates,
            crate::selection::ValidateBy::Auto,
        )))
        .unwrap();
    assert_eq!(alone.confusion, report.confusion);
    assert_eq!(alone.per_condition, report.per_condition);
}

/// Each fold's model may read another view of the same units: a fold tested in view `k` scores what
/// an evaluation of view `k` alone scores on that fold (the same draws), and views of other units
/// are refused.
#[test]
fn each_fold_is_tested_in_the_view_its_model_reads() {
    let (plain, other) = (data(), data_seeded(12));
    let (plain, other) = (samples(&plain), samples(&other));
    let protocol = Protocol::LeaveOneOut {
        column: "condition".into(),
        per_class: Some(8),
        validation: ValidationSize::Count(3),
    };
    let config = paper_config_with_dims(10);
    let views: [&[LabeledImage<'_>]; 2] = [&plain, &other];
    let (report, first) = evaluation(&plain, &protocol, 2, 3)
        .run_views(&views, &|fold| {
            let view = usize::from(fold.held_out == Some("G1"));
            let images = |set: &[usize]| -> Vec<LabeledImage<'_>> {
                set.iter().map(|&i| views[view][i]).collect()
            };
            let model = train(&images(fold.train), &images(fold.validation), &config)?;
            Ok(FoldModel { model, view })
        })
        .unwrap();
    let alone = |samples: &[LabeledImage<'_>]| {
        evaluation(samples, &protocol, 2, 3)
            .run(Models::Config(&config))
            .unwrap()
    };
    let (plain_alone, other_alone) = (alone(&plain), alone(&other));
    assert_eq!(report.per_condition["G1"], other_alone.per_condition["G1"]);
    for held_out in ["G2", "G3"] {
        assert_eq!(
            report.per_condition[held_out],
            plain_alone.per_condition[held_out]
        );
    }
    assert_ne!(
        plain_alone.per_condition["G1"],
        other_alone.per_condition["G1"]
    );
    assert_eq!(first.unwrap().held_out.as_deref(), Some("G1"));
    // another unit order, or fewer units: refused before any training
    let mut swapped = other.clone();
    swapped.swap(0, 1);
    let fewer = &other[1..];
    for bad in [&swapped[..], fewer] {
        let err = evaluation(&plain, &protocol, 1, 3)
            .run_views(&[&plain, bad], &|_| {
                unreachable!("trained on mismatched views")
            })
            .unwrap_err();
        assert!(err.to_string().contains("in reading 1"), "{err}");
    }
}

#[test]
fn mean_std_and_confusion_metrics() {
    let m = MeanStd::of(&[1.0, 0.0]);
    assert!((m.mean - 0.5).abs() < 1e-15 && (m.std - 0.5f64.sqrt()).abs() < 1e-15);
    let c = Confusion {
        labels: vec!["a".into(), "b".into()],
        counts: vec![vec![3, 1], vec![0, 4]],
    };
    assert_eq!(c.recall(), vec![0.75, 1.0]);
    assert_eq!(c.precision(), vec![1.0, 0.8]);
    assert_eq!(c.row_normalised()[0], vec![0.75, 0.25]);
}
