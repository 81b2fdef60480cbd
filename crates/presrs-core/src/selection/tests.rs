use super::*;
use std::collections::BTreeMap;

use crate::frame::{Frame, Grid};
use crate::pipeline::TrainConfig;
use crate::pipeline::train::train;

/// `count` synthetic frames of four classes (frame `i` of class `i % 4`), seeded.
fn four_class_frames(count: usize, seed: u64) -> Vec<Frame> {
    use rand::SeedableRng;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    (0..count)
        .map(|i| crate::testing::synthetic_frame(i % 4, &mut rng))
        .collect()
}

/// Four images of `frame`, labelled a, b, a, b.
fn blank_images(frame: &Frame) -> Vec<LabeledImage<'_>> {
    ["a", "b", "a", "b"]
        .iter()
        .map(|label| LabeledImage::new(frame.view(), label))
        .collect()
}

/// Images of the four synthetic classes, each with a group (of 4) and a condition (of 2).
fn grouped(frames: &[Frame]) -> Vec<LabeledImage<'_>> {
    const GROUPS: [&str; 4] = ["g0", "g1", "g2", "g3"];
    frames
        .iter()
        .enumerate()
        .map(|(i, frame)| LabeledImage {
            frame: frame.view(),
            label: crate::testing::SYNTHETIC_CLASSES[i % 4],
            condition: Some(["c0", "c1"][(i / 4) % 2]),
            group: Some(GROUPS[(i / 8) % 4]),
        })
        .collect()
}

/// The folds follow `ValidateBy`: auto is leave-one-group-out with 3 or more groups, else by
/// condition, else splits; a validation the data cannot give is an error that says why.
#[test]
fn validation_follows_the_groups_then_the_conditions() {
    let frames = four_class_frames(64, 3);
    let images = grouped(&frames);
    let lda = TrainConfig {
        classifier: crate::classifier::ClassifierKind::LDA.default_config(),
        dims: 8,
        ..TrainConfig::default()
    }
    .check()
    .unwrap();
    let candidates = std::slice::from_ref(&lda);
    let folds = |selection: &Selection| -> Vec<String> {
        selection.scores[0].per_fold.keys().cloned().collect()
    };
    let auto = select(&images, &AutoChoice::new(candidates, ValidateBy::Auto), 1).unwrap();
    assert_eq!(folds(&auto), ["g0", "g1", "g2", "g3"]);
    assert!(
        auto.method.starts_with("leave one group out"),
        "{}",
        auto.method
    );
    let by_condition = select(
        &images,
        &AutoChoice::new(candidates, ValidateBy::Condition),
        1,
    )
    .unwrap();
    assert_eq!(folds(&by_condition), ["c0", "c1"]);
    let split = select(&images, &AutoChoice::new(candidates, ValidateBy::Split), 1).unwrap();
    assert_eq!(folds(&split), ["split 0", "split 1", "split 2"]);
    // Two groups only: auto falls back to the conditions; without either, to splits.
    let two: Vec<LabeledImage<'_>> = images
        .iter()
        .filter(|i| matches!(i.group, Some("g0" | "g1")))
        .copied()
        .collect();
    let auto = select(&two, &AutoChoice::new(candidates, ValidateBy::Auto), 1).unwrap();
    assert_eq!(folds(&auto), ["c0", "c1"]);
    let plain: Vec<LabeledImage<'_>> = images
        .iter()
        .map(|i| LabeledImage::new(i.frame, i.label))
        .collect();
    let auto = select(&plain, &AutoChoice::new(candidates, ValidateBy::Auto), 1).unwrap();
    assert_eq!(folds(&auto), ["split 0", "split 1", "split 2"]);
    let err = select(&plain, &AutoChoice::new(candidates, ValidateBy::Group), 1).unwrap_err();
    assert!(
        matches!(&err, CoreError::NotEnoughData(reason) if reason.contains("validating by group")),
        "{err}"
    );
    assert_eq!("Group".parse::<ValidateBy>(), Ok(ValidateBy::Group));
    assert!(
        "person"
            .parse::<ValidateBy>()
            .unwrap_err()
            .contains("known: auto")
    );
}

/// When every candidate fails, the error names the first and gives its reason, once.
#[test]
fn every_candidate_failing_names_the_first_and_its_reason() {
    let frame = Frame::zeros(Grid::new(44, 44));
    let labels = ["a", "b"].repeat(6);
    let images: Vec<_> = labels
        .iter()
        .map(|label| LabeledImage::new(frame.view(), label))
        .collect();
    // Identical images: the Parzen window cannot scale σ to their distances.
    let pwe = TrainConfig::default().check().unwrap();
    let err = select(
        &images,
        &AutoChoice::new(std::slice::from_ref(&pwe), ValidateBy::Auto),
        1,
    )
    .unwrap_err();
    let text = err.to_string();
    assert!(
        text.starts_with("not enough data: fft1d + pwe could not be trained (not enough data: "),
        "{text}"
    );
    let err = select(
        &images,
        &AutoChoice::new(&[pwe.clone(), pwe], ValidateBy::Auto),
        1,
    )
    .unwrap_err();
    let text = err.to_string();
    assert!(
        text.starts_with(
            "not enough data: none of the 2 candidates could be trained (fft1d + pwe: "
        ),
        "{text}"
    );
}

/// Without validation images, a candidate that needs them (the Parzen window choosing σ) is refused
/// before any candidate is scored; with a fixed σ the same candidate trains.
#[test]
fn candidates_needing_validation_images_are_refused_up_front() {
    let frame = Frame::zeros(Grid::new(44, 44));
    let images = blank_images(&frame);
    let candidates = [TrainConfig::default().check().unwrap()];
    let err = train_auto(
        &images,
        &[],
        &AutoChoice::new(&candidates, ValidateBy::Auto),
        1,
    )
    .unwrap_err();
    assert!(
        matches!(&err, CoreError::NotEnoughData(reason) if reason.contains("fft1d + pwe")),
        "{err}"
    );
    let fixed = TrainConfig {
        classifier: crate::classifier::ClassifierConfig::of::<crate::classifier::PweFamily>(
            crate::classifier::ParzenConfig {
                sigma: crate::classifier::SigmaChoice::Fixed { sigma: 1.0 },
            },
        ),
        ..TrainConfig::default()
    };
    let trained = train_auto(
        &images,
        &[],
        &AutoChoice::new(&[fixed.check().unwrap()], ValidateBy::Auto),
        1,
    );
    assert!(trained.is_ok(), "{:?}", trained.err());
}

/// The slow, obvious oracle of `scoring`: each candidate trained on each fold with [`train`] and the
/// held-out images classified by a session, the first fold it cannot be trained on ending it.
fn score_by_training_each(
    images: &[LabeledImage<'_>],
    folds: &[folds::InnerFold],
    candidate: &CheckedTrainConfig,
) -> (Vec<(String, f64)>, Option<String>) {
    let mut per_fold = Vec::new();
    for fold in folds {
        let pick = |indices: &[usize]| indices.iter().map(|&i| images[i]).collect::<Vec<_>>();
        match train(&pick(&fold.train), &pick(&fold.validation), candidate) {
            Ok(model) => {
                let mut session = model.session();
                let correct = fold
                    .test
                    .iter()
                    .filter(|&&i| {
                        session.classify(&images[i].frame).unwrap().label == images[i].label
                    })
                    .count();
                per_fold.push((fold.name.clone(), correct as f64 / fold.test.len() as f64));
            }
            Err(err) => return (per_fold, Some(err.to_string())),
        }
    }
    (per_fold, None)
}

/// Features computed once per feature group and PCA once per fold and dims give, candidate for
/// candidate and fold for fold, what training each candidate on each fold gives: the same accuracies
/// (bit for bit) and the same failures. Candidates cover the fast 1-D path, 2-D and texture features,
/// an intensity transform, every classifier, and two numbers of components in one group.
#[test]
fn cached_scores_equal_training_each_candidate_on_each_fold() {
    use crate::classifier::ClassifierKind;
    use crate::features::FeatureKind;
    use crate::preprocess::{Intensity, Preprocess};
    let frames = four_class_frames(64, 11);
    let images = grouped(&frames);
    let config = |features: &[FeatureKind], classifier: ClassifierKind, dims, intensity| {
        TrainConfig {
            features: crate::features::FeatureConfig::combined(features),
            classifier: classifier.default_config(),
            dims,
            preprocess: Preprocess {
                intensity,
                ..Preprocess::NONE
            },
            ..TrainConfig::default()
        }
        .check()
        .unwrap()
    };
    let mut candidates = Vec::new();
    for classifier in ClassifierKind::all() {
        candidates.push(config(
            &[FeatureKind::FFT1D],
            classifier,
            12,
            Intensity::None,
        ));
    }
    candidates.push(config(
        &[FeatureKind::FFT1D],
        ClassifierKind::LDA,
        5,
        Intensity::None,
    ));
    candidates.push(config(
        &[FeatureKind::FFT2D],
        ClassifierKind::SVM,
        12,
        Intensity::None,
    ));
    candidates.push(config(
        &[FeatureKind::FFT1D],
        ClassifierKind::PWE,
        12,
        Intensity::Sqrt,
    ));
    candidates.push(config(
        &[FeatureKind::FFT2D_POLAR, FeatureKind::GLCM],
        ClassifierKind::KNN,
        8,
        Intensity::None,
    ));
    for by in [ValidateBy::Group, ValidateBy::Split] {
        let folds = folds::make_folds(&images, by, 5).unwrap().folds;
        let cached = scoring::score_candidates(
            &images,
            &folds,
            &candidates,
            None,
            &mut None,
            &mut Default::default(),
        )
        .unwrap();
        assert_eq!(cached.len(), candidates.len());
        for (candidate, score) in candidates.iter().zip(&cached) {
            let (per_fold, error) = score_by_training_each(&images, &folds, candidate);
            let name = format!("{} + {} ({by})", score.features, score.classifier);
            assert_eq!(score.error, error, "{name}");
            assert!(!score.skipped);
            if error.is_none() {
                let expected: BTreeMap<String, f64> = per_fold.into_iter().collect();
                assert_eq!(score.per_fold, expected, "{name}");
            }
        }
    }
}

/// A budget of nothing scores the first feature group only (the paper's method is never skipped) and
/// marks the rest skipped, saying why; the choice is among the scored.
#[test]
fn a_spent_budget_scores_the_first_feature_group_only() {
    use crate::classifier::ClassifierKind;
    let frames = four_class_frames(48, 3);
    let images = grouped(&frames);
    let with = |features: crate::features::FeatureConfig, classifier: ClassifierKind| {
        TrainConfig {
            features,
            classifier: classifier.default_config(),
            dims: 8,
            ..TrainConfig::default()
        }
        .check()
        .unwrap()
    };
    let fft2d = crate::features::FeatureKind::FFT2D.default_config();
    let candidates = [
        with(
            crate::features::FeatureConfig::default(),
            ClassifierKind::PWE,
        ),
        with(fft2d.clone(), ClassifierKind::LDA),
        with(
            crate::features::FeatureConfig::default(),
            ClassifierKind::LDA,
        ),
        with(fft2d, ClassifierKind::SVM),
    ];
    let choice = AutoChoice::new(&candidates, ValidateBy::Auto).with_budget(Some(Duration::ZERO));
    let selection = select(&images, &choice, 1).unwrap();
    let skipped: Vec<bool> = selection.scores.iter().map(|s| s.skipped).collect();
    assert_eq!(skipped, [false, true, false, true]);
    let reason = selection.scores[1].error.as_deref().unwrap();
    assert!(reason.contains("time budget"), "{reason}");
    assert!(matches!(selection.chosen, 0 | 2));
    let unlimited = select(&images, &AutoChoice::new(&candidates, ValidateBy::Auto), 1).unwrap();
    assert!(
        unlimited
            .scores
            .iter()
            .all(|s| !s.skipped && s.error.is_none())
    );
    assert_eq!(unlimited.scores[0], selection.scores[0]);
}

/// The one-standard-error rule picks the earliest candidate whose mean is within the best's standard
/// error (spread over the square root of the folds, at least the binomial one of the held-out
/// samples); failed candidates never; the best itself when nothing earlier is close; and the rules
/// parse by name.
#[test]
fn one_standard_error_picks_the_earliest_close_candidate() {
    let score = |mean: f64, std: f64, error: Option<&str>| CandidateScore {
        features: "fft1d".into(),
        classifier: "pwe".into(),
        config: TrainConfig::default(),
        accuracy: crate::metrics::MeanStd { mean, std },
        per_fold: (0..4).map(|k| (format!("g{k}"), mean)).collect(),
        error: error.map(str::to_owned),
        skipped: false,
        dropped_early: false,
    };
    // so many held-out samples that the binomial error (0.002 at 0.95) is below the folds' spread
    const MANY: usize = 10_000;
    // best: 0.95 with std 0.04 over 4 folds -> standard error 0.02, threshold 0.93
    let scores = [
        score(0.0, 0.0, Some("failed")),
        score(0.90, 0.10, None),
        score(0.93, 0.02, None),
        score(0.95, 0.04, None),
    ];
    assert_eq!(one_standard_error(&scores, 3, MANY), 2);
    // a candidate dropped early in a race is never picked, however close its first folds were
    let mut raced = scores.clone();
    raced[2].dropped_early = true;
    assert_eq!(one_standard_error(&raced, 3, MANY), 3);
    let far = [score(0.80, 0.0, None), score(0.95, 0.01, None)];
    assert_eq!(one_standard_error(&far, 1, MANY), 1);
    // folds that agree (no spread) on few samples: the binomial error, sqrt(0.95 x 0.05 / 100) =
    // 0.022, admits the earlier candidate 0.02 below; on 10,000 samples (0.002) it does not
    let agreeing = [score(0.93, 0.0, None), score(0.95, 0.0, None)];
    assert_eq!(one_standard_error(&agreeing, 1, 100), 0);
    assert_eq!(one_standard_error(&agreeing, 1, MANY), 1);
    // with two folds the spread is one difference: the best stands
    let two_folds: Vec<CandidateScore> = scores
        .iter()
        .map(|score| CandidateScore {
            per_fold: score.per_fold.clone().into_iter().take(2).collect(),
            ..score.clone()
        })
        .collect();
    assert_eq!(one_standard_error(&two_folds, 3, 100), 3);
    assert_eq!(
        "one-se".parse::<ChoiceRule>(),
        Ok(ChoiceRule::OneStandardError)
    );
    assert_eq!("BEST".parse::<ChoiceRule>(), Ok(ChoiceRule::Best));
    assert!(
        "median"
            .parse::<ChoiceRule>()
            .unwrap_err()
            .contains("known: best, one-se")
    );
}

/// With 4 or more folds the candidates race: one clearly behind on the first two folds is scored on
/// those only (the same accuracies as scoring it on every fold) and marked `dropped_early`; the others
/// get every fold's score, as without the race; the choice is the same.
#[test]
fn a_race_drops_clear_losers_after_the_first_folds_only() {
    use crate::classifier::ClassifierKind;
    let frames = four_class_frames(96, 5);
    let images = grouped(&frames);
    let config = |classifier: ClassifierKind, dims| {
        TrainConfig {
            classifier: classifier.default_config(),
            dims,
            ..TrainConfig::default()
        }
        .check()
        .unwrap()
    };
    // One component cannot tell four classes apart.
    let candidates = [
        config(ClassifierKind::PWE, 12),
        config(ClassifierKind::LDA, 1),
        config(ClassifierKind::KNN, 12),
    ];
    let folds = folds::make_folds(&images, ValidateBy::Group, 1)
        .unwrap()
        .folds;
    assert_eq!(folds.len(), 4);
    let full = scoring::score_candidates(
        &images,
        &folds,
        &candidates,
        None,
        &mut None,
        &mut Default::default(),
    )
    .unwrap();
    let raced = scoring::score_candidates(
        &images,
        &folds,
        &candidates,
        None,
        &mut scoring::Race::of(&folds),
        &mut Default::default(),
    )
    .unwrap();
    assert!(full.iter().all(|score| score.is_contender()));
    assert!(raced[1].dropped_early, "{:?}", raced[1].accuracy);
    let first: BTreeMap<String, f64> = folds[..RACE_FOLDS]
        .iter()
        .map(|fold| (fold.name.clone(), full[1].per_fold[&fold.name]))
        .collect();
    assert_eq!(raced[1].per_fold, first);
    for m in [0, 2] {
        assert_eq!(raced[m], full[m]);
    }
    let choice = AutoChoice::new(&candidates, ValidateBy::Group);
    let selection = select(&images, &choice, 1).unwrap();
    assert_eq!(selection.scores[1], raced[1]);
    let best_full = (0..3)
        .max_by(|&a, &b| {
            full[a]
                .accuracy
                .mean
                .total_cmp(&full[b].accuracy.mean)
                .then(b.cmp(&a))
        })
        .unwrap();
    assert_eq!(selection.chosen, best_full);
}

/// More groups than [`MAX_INNER_FOLDS`] are merged, whole, into that many folds of about equal size:
/// every group held out exactly once, never split across folds, and the method says so.
#[test]
fn many_groups_are_merged_whole_into_five_folds() {
    let frames = four_class_frames(84, 2);
    const GROUPS: [&str; 7] = ["p0", "p1", "p2", "p3", "p4", "p5", "p6"];
    let images: Vec<LabeledImage<'_>> = frames
        .iter()
        .enumerate()
        .map(|(i, frame)| LabeledImage {
            frame: frame.view(),
            label: crate::testing::SYNTHETIC_CLASSES[i % 4],
            condition: None,
            group: Some(GROUPS[(i / 4) % 7]),
        })
        .collect();
    let folds::Folds { folds, method, .. } =
        folds::make_folds(&images, ValidateBy::Auto, 1).unwrap();
    assert_eq!(folds.len(), MAX_INNER_FOLDS);
    assert!(method.starts_with("5 folds of whole groups"), "{method}");
    assert!(method.contains("7 groups"), "{method}");
    let mut held_out = Vec::new();
    for fold in &folds {
        let groups: std::collections::BTreeSet<&str> = fold
            .test
            .iter()
            .map(|&i| images[i].group.unwrap())
            .collect();
        assert_eq!(
            fold.name,
            groups.iter().copied().collect::<Vec<_>>().join("+")
        );
        for &i in fold.train.iter().chain(&fold.validation) {
            assert!(
                !groups.contains(images[i].group.unwrap()),
                "a group split across a fold"
            );
        }
        held_out.extend(groups);
        // 12 images per group: two merged groups at most
        assert!((12..=24).contains(&fold.test.len()), "{}", fold.test.len());
    }
    held_out.sort_unstable();
    assert_eq!(held_out, GROUPS);
    // Five groups or fewer: one fold each, as before.
    let five: Vec<LabeledImage<'_>> = images
        .iter()
        .filter(|i| !matches!(i.group, Some("p5" | "p6")))
        .copied()
        .collect();
    let folds::Folds { folds, method, .. } = folds::make_folds(&five, ValidateBy::Auto, 1).unwrap();
    assert_eq!(folds.len(), 5);
    assert!(method.starts_with("leave one group out"), "{method}");
}

/// A held-out fold that holds a class its training part lacks scores every candidate 0 on it: such a
/// scheme is passed over, and the selection says which and why (issue #35: every class in one group,
/// as in one gait of the simulator's trials).
#[test]
fn a_fold_holding_a_class_training_lacks_falls_back_and_says_so() {
    let frames = four_class_frames(48, 4);
    // One group per class (the class's trial), and two conditions that each hold every class.
    let images: Vec<LabeledImage<'_>> = frames
        .iter()
        .enumerate()
        .map(|(i, frame)| LabeledImage {
            frame: frame.view(),
            label: crate::testing::SYNTHETIC_CLASSES[i % 4],
            condition: Some(["c0", "c1"][(i / 4) % 2]),
            group: Some(["t0", "t1", "t2", "t3"][i % 4]),
        })
        .collect();
    let lda = TrainConfig {
        classifier: crate::classifier::ClassifierKind::LDA.default_config(),
        dims: 8,
        ..TrainConfig::default()
    }
    .check()
    .unwrap();
    let candidates = std::slice::from_ref(&lda);
    let folds = |selection: &Selection| -> Vec<String> {
        selection.scores[0].per_fold.keys().cloned().collect()
    };
    // auto: by group would hold every image of a class out; the conditions are used instead.
    let auto = select(&images, &AutoChoice::new(candidates, ValidateBy::Auto), 1).unwrap();
    assert_eq!(folds(&auto), ["c0", "c1"]);
    let fallback = auto.fallback.clone().unwrap();
    assert_eq!(
        (fallback.wanted, fallback.used),
        (ValidateBy::Group, ValidateBy::Condition)
    );
    assert_eq!(fallback.unseen.len(), 4, "{:?}", fallback.unseen);
    assert_eq!(
        fallback.unseen[0],
        (
            crate::testing::SYNTHETIC_CLASSES[0].to_owned(),
            "t0".to_owned()
        )
    );
    assert!(auto.scores[0].accuracy.mean > 0.5, "{:?}", auto.scores[0]);
    // Without conditions, and when group is asked for: stratified splits.
    let one_condition: Vec<LabeledImage<'_>> = images
        .iter()
        .map(|i| LabeledImage {
            condition: Some("G2"),
            ..*i
        })
        .collect();
    for by in [ValidateBy::Auto, ValidateBy::Group] {
        let selection = select(&one_condition, &AutoChoice::new(candidates, by), 1).unwrap();
        assert_eq!(folds(&selection), ["split 0", "split 1", "split 2"]);
        let fallback = selection.fallback.unwrap();
        assert_eq!(
            (fallback.wanted, fallback.used),
            (ValidateBy::Group, ValidateBy::Split)
        );
        assert!(selection.scores[0].accuracy.mean > 0.5);
    }
    // Groups that each hold every class are used as they are, with no fallback.
    let shared = grouped(&frames);
    let selection = select(&shared, &AutoChoice::new(candidates, ValidateBy::Auto), 1).unwrap();
    assert_eq!(folds(&selection), ["g0", "g1", "g2", "g3"]);
    assert_eq!(selection.fallback, None);
}

/// Candidates cut by the budget name the budget in force, rounded, whichever call of the scoring
/// (the candidates, or the refinement of the dims after them) cut them (issue #35: the refinement
/// said "the time budget of 10.643012081 s", what was left of 60 s).
#[test]
fn a_cut_candidate_names_the_whole_budget_rounded() {
    use crate::classifier::ClassifierKind;
    let frames = four_class_frames(32, 3);
    let images = grouped(&frames);
    let with = |features: crate::features::FeatureConfig| {
        TrainConfig {
            features,
            classifier: ClassifierKind::LDA.default_config(),
            dims: 8,
            ..TrainConfig::default()
        }
        .check()
        .unwrap()
    };
    let candidates = [
        with(crate::features::FeatureConfig::default()),
        with(crate::features::FeatureKind::FFT2D.default_config()),
    ];
    let folds = folds::make_folds(&images, ValidateBy::Group, 1)
        .unwrap()
        .folds;
    let Some(started) = std::time::Instant::now().checked_sub(Duration::from_secs(61)) else {
        return;
    };
    // 61 s into a budget of 60.4 s: the first group is scored, the second is cut.
    let budget = scoring::Budget {
        started,
        total: Duration::from_secs_f64(60.4),
    };
    let scores = scoring::score_candidates(
        &images,
        &folds,
        &candidates,
        Some(budget),
        &mut None,
        &mut Default::default(),
    )
    .unwrap();
    assert!(!scores[0].skipped);
    assert!(scores[1].skipped);
    assert_eq!(
        scores[1].error.as_deref(),
        Some("not tried: the time budget of 60 s was spent")
    );
    assert_eq!(
        scoring::seconds_text(Duration::from_secs_f64(2.46)),
        "2.5 s"
    );
}

/// In a race every feature group is scored on the first folds before any finishes, so a candidate is
/// dropped when clearly behind the best of all there, even one scored before the best's group (issue
/// #35: the default search races the transforms with every FFT family; what the first folds say
/// decides what finishes).
#[test]
fn a_race_drops_against_the_best_of_every_group_on_the_first_folds() {
    use crate::classifier::ClassifierKind;
    let frames = four_class_frames(64, 5);
    let images = grouped(&frames);
    let config = |features: crate::features::FeatureConfig, dims| {
        TrainConfig {
            features,
            classifier: ClassifierKind::LDA.default_config(),
            dims,
            ..TrainConfig::default()
        }
        .check()
        .unwrap()
    };
    // The weak candidate's group comes first; the strong one's after it.
    let candidates = [
        config(crate::features::FeatureConfig::default(), 1),
        config(crate::features::FeatureKind::FFT2D.default_config(), 12),
    ];
    let folds = folds::make_folds(&images, ValidateBy::Group, 1)
        .unwrap()
        .folds;
    let full = scoring::score_candidates(
        &images,
        &folds,
        &candidates,
        None,
        &mut None,
        &mut Default::default(),
    )
    .unwrap();
    assert!(
        full[1].accuracy.mean > full[0].accuracy.mean + 0.3,
        "{:?}",
        full
    );
    let raced = scoring::score_candidates(
        &images,
        &folds,
        &candidates,
        None,
        &mut scoring::Race::of(&folds),
        &mut Default::default(),
    )
    .unwrap();
    assert!(raced[0].dropped_early, "{:?}", raced[0]);
    assert_eq!(raced[0].per_fold.len(), RACE_FOLDS);
    assert_eq!(raced[1], full[1]);
}

/// A candidate whose classifier takes every feature (ridge) has no PCA, so no dims to refine: the
/// refinement tries other dims with the best candidates that have one, and a ridge winner is trained
/// without a PCA.
#[test]
fn ridge_is_not_refined_and_its_model_has_no_pca() {
    use crate::classifier::ClassifierKind;
    let frames = four_class_frames(48, 7);
    let images = grouped(&frames);
    let with = |classifier: ClassifierKind| {
        TrainConfig {
            classifier: classifier.default_config(),
            dims: 8,
            ..TrainConfig::default()
        }
        .check()
        .unwrap()
    };
    let candidates = [with(ClassifierKind::RIDGE), with(ClassifierKind::LDA)];
    let choice = AutoChoice::new(&candidates, ValidateBy::Group).with_refined_dims(&[4, 8]);
    let selection = select(&images, &choice, 1).unwrap();
    let names: Vec<(String, usize)> = selection
        .scores
        .iter()
        .map(|score| (score.classifier.clone(), score.config.dims))
        .collect();
    // The two candidates, then LDA with 4 dims: ridge, even if it scored best, gets no variant.
    assert_eq!(
        names,
        [("ridge".into(), 8), ("lda".into(), 8), ("lda".into(), 4)]
    );
    assert!(selection.scores.iter().all(|score| score.error.is_none()));
    let model = train_auto(
        &images[..32],
        &images[32..],
        &AutoChoice::new(&candidates[..1], ValidateBy::Split),
        1,
    )
    .unwrap();
    assert!(model.pca().is_none());
    assert_eq!(model.classifier_dims(), model.n_features());
}

/// Large training data are scored on a stratified, seeded subsample of the size asked for (the
/// selection says so), every stage is told to the observer, and the winner is trained on every image.
#[test]
fn large_data_are_scored_on_a_stratified_subsample_and_the_winner_on_everything() {
    let frames = four_class_frames(96, 5);
    let images = grouped(&frames);
    let lda = TrainConfig {
        classifier: crate::classifier::ClassifierKind::LDA.default_config(),
        dims: 8,
        ..TrainConfig::default()
    }
    .check()
    .unwrap();
    let candidates = std::slice::from_ref(&lda);
    let stages = std::sync::Mutex::new(Vec::<String>::new());
    let tell = |stage: &str| stages.lock().unwrap().push(stage.to_owned());
    let choice = AutoChoice::new(candidates, ValidateBy::Group)
        .with_scoring_samples(Some(48))
        .with_stages(StageObserver(&tell));
    let model = train_auto(&images[..64], &images[64..], &choice, 3).unwrap();
    let cost = model.selection().unwrap().cost.clone().unwrap();
    assert_eq!((cost.samples, cost.scored_on), (96, 48));
    assert!(cost.subsampled());
    assert!(cost.scoring_seconds >= cost.features_seconds && cost.features_seconds > 0.0);
    assert!(cost.final_fit_seconds > 0.0);
    // the winner learns from every image
    let trained: usize = model.summary().train_per_class.iter().sum::<usize>()
        + model.summary().validation_per_class.iter().sum::<usize>();
    assert_eq!(trained, 96);
    let stages = stages.lock().unwrap().clone();
    assert_eq!(stages.len(), 3, "{stages:?}");
    assert!(
        stages[0].contains("on 48 samples (a stratified subsample of 96)"),
        "{stages:?}"
    );
    assert!(stages[1].starts_with("features: fft1d"), "{stages:?}");
    assert!(stages[2].contains("training the winner") && stages[2].contains("on 96 samples"));
    // the same seed scores the same subsample; without a cap, every image
    let again = select(&images, &choice, 3).unwrap();
    let first = select(&images, &choice, 3).unwrap();
    assert_eq!(again.scores, first.scores);
    let whole = select(&images, &choice.with_scoring_samples(None), 3).unwrap();
    assert_eq!(whole.cost.unwrap().scored_on, 96);
}

/// On large data an SVM winner's kernel and C are searched (and its posteriors calibrated) on the
/// scoring subsample, and only that choice is fitted on every image (the fit on every image searches
/// nothing: its model lists no candidates); the selection says on how many samples it was searched.
/// On data no larger than the subsample, nothing changes: the model is `train`'s, searched on every
/// image. (That a pinned fit on the same data is the searched model: `svm::fit`'s tests.)
#[test]
fn an_svm_winner_is_searched_on_the_subsample_and_small_data_train_as_before() {
    use crate::classifier::svm::SvmFamily;
    let frames = four_class_frames(96, 5);
    let images = grouped(&frames);
    let svm = TrainConfig {
        classifier: crate::classifier::ClassifierKind::SVM.default_config(),
        dims: 8,
        ..TrainConfig::default()
    }
    .check()
    .unwrap();
    let candidates = std::slice::from_ref(&svm);
    let (train_images, validation_images) = (&images[..64], &images[64..]);
    let large = AutoChoice::new(candidates, ValidateBy::Group).with_scoring_samples(Some(48));
    let model = train_auto(train_images, validation_images, &large, 3).unwrap();
    let cost = model.selection().unwrap().cost.clone().unwrap();
    assert_eq!(cost.searched_on, Some(48));
    let pinned = model.classifier().get::<SvmFamily>().unwrap();
    assert!(pinned.candidates().is_empty());
    let trained: usize = model.summary().train_per_class.iter().sum::<usize>()
        + model.summary().validation_per_class.iter().sum::<usize>();
    assert_eq!(trained, 96);
    // Small data: no subsample, no pinning, the model `train` gives.
    let small = AutoChoice::new(candidates, ValidateBy::Group);
    let model = train_auto(train_images, validation_images, &small, 3).unwrap();
    assert_eq!(
        model.selection().unwrap().cost.clone().unwrap().searched_on,
        None
    );
    let plain = train(train_images, validation_images, &svm).unwrap();
    assert_eq!(model.classifier(), plain.classifier());
    assert_eq!(model.pca(), plain.pca());
    let searched = model.classifier().get::<SvmFamily>().unwrap();
    assert!(!searched.candidates().is_empty());
}

/// On large data a ridge winner's alpha and temperature are chosen by leave-one-out on the scoring
/// subsample and the fit on every image solves at that alpha (features in single precision); it is
/// the model a ridge with that alpha pinned gives. Small data train as before.
#[test]
fn a_ridge_winner_is_pinned_on_the_subsample_and_small_data_train_as_before() {
    use crate::classifier::RidgeFamily;
    let frames = four_class_frames(96, 5);
    let images = grouped(&frames);
    let ridge = ridge_of_8_dims();
    let candidates = std::slice::from_ref(&ridge);
    let (train_images, validation_images) = (&images[..64], &images[64..]);
    let large = AutoChoice::new(candidates, ValidateBy::Group).with_scoring_samples(Some(48));
    let model = train_auto(train_images, validation_images, &large, 3).unwrap();
    assert_eq!(
        model.selection().unwrap().cost.clone().unwrap().searched_on,
        Some(48)
    );
    let fitted = model.classifier().get::<RidgeFamily>().unwrap();
    let plain = train(train_images, validation_images, &ridge).unwrap();
    let searched_on_all = plain.classifier().get::<RidgeFamily>().unwrap();
    // Fitted on every image (the same standardisation), its leave-one-out curve the subsample's.
    assert_eq!(fitted.means(), searched_on_all.means());
    assert_ne!(fitted.loo_errors(), searched_on_all.loo_errors());
    assert_eq!(fitted.loo_samples(), Some(48));
    assert_eq!(searched_on_all.loo_samples(), Some(96));
    assert!(
        model.classifier().describe().contains("over 48 vectors"),
        "{}",
        model.classifier().describe()
    );
    // Small data: the model `train` gives.
    let small = AutoChoice::new(candidates, ValidateBy::Group);
    let model = train_auto(train_images, validation_images, &small, 3).unwrap();
    assert_eq!(model.classifier(), plain.classifier());
}

/// One feature group's table is kept at a time: a group scored again (the race's second phase) has its
/// features computed again, said so in the stage, with the scores of a choice that kept them (the
/// features are deterministic: `cached_scores_equal_training_each_candidate_on_each_fold`).
#[test]
fn a_group_scored_again_computes_its_features_again_and_says_so() {
    use crate::classifier::ClassifierKind;
    use crate::features::{FeatureConfig, FeatureKind};
    let frames = four_class_frames(64, 13);
    let images = grouped(&frames);
    let with = |features: FeatureKind| {
        TrainConfig {
            features: FeatureConfig::combined(&[features]),
            classifier: ClassifierKind::LDA.default_config(),
            dims: 8,
            ..TrainConfig::default()
        }
        .check()
        .unwrap()
    };
    let candidates = [with(FeatureKind::FFT1D), with(FeatureKind::FFT2D)];
    let stages = std::sync::Mutex::new(Vec::<String>::new());
    let tell = |stage: &str| stages.lock().unwrap().push(stage.to_owned());
    let choice = AutoChoice::new(&candidates, ValidateBy::Group).with_stages(StageObserver(&tell));
    let selection = select(&images, &choice, 1).unwrap();
    let features: Vec<String> = stages
        .lock()
        .unwrap()
        .iter()
        .filter(|stage| stage.starts_with("features: "))
        .cloned()
        .collect();
    assert!(
        features[0].starts_with("features: fft1d") && !features[0].contains("again"),
        "{features:?}"
    );
    assert!(
        features.iter().any(|stage| stage.ends_with("(again)")),
        "{features:?}"
    );
    let first = features.iter().filter(|stage| !stage.ends_with("(again)"));
    assert_eq!(first.count(), 2, "{features:?}");
    let quiet = select(&images, &AutoChoice::new(&candidates, ValidateBy::Group), 1).unwrap();
    assert_eq!(selection.scores, quiet.scores);
}

/// A fixed ridge on large data gets the automatic choice's winner's treatment: its alpha searched on a
/// stratified subsample (the same draw as the choice's with the same seed), recorded in the model's
/// summary, the fit on every image; a family that pins nothing, and small data, train as `train`.
#[test]
fn a_fixed_method_on_large_data_is_searched_on_the_subsample_as_the_winner_is() {
    use crate::classifier::RidgeFamily;
    let frames = four_class_frames(96, 5);
    let images = grouped(&frames);
    let ridge = ridge_of_8_dims();
    let (train_images, validation_images) = (&images[..64], &images[64..]);
    let (fixed, searched_on) =
        train_fixed(train_images, validation_images, &ridge, Some(48), 3).unwrap();
    assert_eq!(searched_on, Some(48));
    assert_eq!(fixed.summary().searched_on, Some(48));
    // The automatic choice with this one candidate and the same subsample trains the same model.
    let candidates = std::slice::from_ref(&ridge);
    let large = AutoChoice::new(candidates, ValidateBy::Group).with_scoring_samples(Some(48));
    let chosen = train_auto(train_images, validation_images, &large, 3).unwrap();
    assert_eq!(fixed.classifier(), chosen.classifier());
    assert_eq!(chosen.summary().searched_on, Some(48));
    let pinned = fixed.classifier().get::<RidgeFamily>().unwrap();
    assert_eq!(pinned.loo_samples(), Some(48));
    // Small data, or no subsample asked for: `train`'s model, searched on every image.
    let plain = train(train_images, validation_images, &ridge).unwrap();
    for at_most in [Some(96), None] {
        let (model, searched_on) =
            train_fixed(train_images, validation_images, &ridge, at_most, 3).unwrap();
        assert_eq!(searched_on, None);
        assert_eq!(model.classifier(), plain.classifier());
    }
    // A Parzen window pins nothing: trained on every image as `train` trains it.
    let parzen = TrainConfig {
        dims: 8,
        ..TrainConfig::default()
    }
    .check()
    .unwrap();
    let (model, searched_on) =
        train_fixed(train_images, validation_images, &parzen, Some(48), 3).unwrap();
    assert_eq!(searched_on, None);
    let plain = train(train_images, validation_images, &parzen).unwrap();
    assert_eq!(model.classifier(), plain.classifier());
}

/// Ridge with 8 principal components asked for (ridge takes every feature, so they are unused).
fn ridge_of_8_dims() -> CheckedTrainConfig {
    TrainConfig {
        classifier: crate::classifier::ClassifierKind::RIDGE.default_config(),
        dims: 8,
        ..TrainConfig::default()
    }
    .check()
    .unwrap()
}

/// A candidate of `features` + `classifier` scored `mean` on every fold.
fn scored(features: &str, classifier: &str, dims: usize, mean: f64) -> CandidateScore {
    CandidateScore {
        features: features.into(),
        classifier: classifier.into(),
        config: TrainConfig {
            dims,
            ..TrainConfig::default()
        },
        accuracy: crate::metrics::MeanStd { mean, std: 0.0 },
        per_fold: (0..3).map(|k| (format!("g{k}"), mean)).collect(),
        error: None,
        skipped: false,
        dropped_early: false,
    }
}

/// The methods that scored what the chosen one did are named once each; another number of components
/// of the chosen method, a lower score, a failed or dropped candidate are not ties.
#[test]
fn the_methods_tied_with_the_chosen_one_are_named_once() {
    let mut failed = scored("fft1d", "lda", 51, 1.0);
    failed.error = Some("singular".into());
    let mut dropped = scored("glcm", "knn", 51, 1.0);
    dropped.dropped_early = true;
    let mut selection = Selection {
        method: "three folds".into(),
        chosen: 0,
        scores: vec![
            scored("rocket", "ridge_raw", 51, 1.0),
            scored("rocket", "ridge_raw", 102, 1.0),
            scored("rocket", "svm", 51, 1.0),
            scored("rocket", "svm", 102, 1.0),
            scored("fft1d", "pwe", 51, 1.0 - 1e-6),
            failed,
            dropped,
            scored("multirocket", "ridge", 51, 1.0),
        ],
        fallback: None,
        cost: None,
    };
    let names = |s: &Selection| -> Vec<String> { s.tied().iter().map(|c| c.name()).collect() };
    assert_eq!(
        names(&selection),
        ["rocket + svm, 51 dims", "multirocket + ridge, 51 dims"]
    );
    assert!(
        selection.best_above_chosen().is_none(),
        "the chosen one ties the best"
    );
    // a choice below the best (the one-standard-error rule's) is the rule's, not a tie, and names
    // the best above it (the first of the best: failed and dropped candidates are not)
    selection.chosen = 4;
    assert!(selection.tied().is_empty());
    let best = selection.best_above_chosen().map(CandidateScore::name);
    assert_eq!(best.as_deref(), Some("rocket + ridge_raw, 51 dims"));
    selection.chosen = 5;
    assert!(selection.best_above_chosen().is_none(), "a failed choice");
    selection.chosen = 0;
    // a candidate alone at the top ties with nothing
    selection.scores[0].accuracy.mean = 1.0;
    selection.scores.truncate(2);
    assert!(selection.tied().is_empty());
    selection.scores[1] = scored("rocket", "svm", 51, 0.9);
    assert!(selection.tied().is_empty());
}

/// The preferred candidate wins a tie for the best score, and only a tie: not against a better
/// candidate, not when it failed or was dropped, and a missing preference leaves the earlier.
#[test]
fn the_preferred_candidate_wins_a_tie_and_only_a_tie() {
    let scores = [
        scored("rocket_unscaled", "ridge_raw", 51, 1.0),
        scored("rocket", "svm", 51, 1.0 - 1e-12),
        scored("fft1d", "pwe", 51, 0.9),
    ];
    assert_eq!(preferred_if_tied(&scores, 0, Some(1)), 1);
    assert_eq!(preferred_if_tied(&scores, 0, None), 0);
    assert_eq!(preferred_if_tied(&scores, 0, Some(2)), 0);
    let mut failed = scores.clone();
    failed[1].error = Some("singular".into());
    assert_eq!(preferred_if_tied(&failed, 0, Some(1)), 0);
    let mut dropped = scores.clone();
    dropped[1].dropped_early = true;
    assert_eq!(preferred_if_tied(&dropped, 0, Some(1)), 0);
    // a preference past the scores is none
    assert_eq!(preferred_if_tied(&scores, 0, Some(7)), 0);
}

/// Under either rule a tie for the best goes to the preferred candidate; without a tie, `best` keeps
/// the best and `one-se` takes the earliest close candidate (not the preferred one, however close).
#[test]
fn both_rules_give_a_tie_to_the_preferred_candidate_and_one_se_the_rest_to_the_order() {
    let with_spread = |mut score: CandidateScore, std: f64| {
        score.accuracy.std = std;
        score
    };
    let tied = [
        scored("rocket_unscaled", "ridge_raw", 51, 0.97),
        scored("rocket_unscaled", "svm", 51, 0.98),
        scored("rocket", "svm", 51, 0.98),
    ];
    for rule in [ChoiceRule::Best, ChoiceRule::OneStandardError] {
        assert_eq!(choose(&tied, 1, rule, Some(2), 10_000), 2, "{rule:?}");
    }
    // no tie: the best's standard error (0.02 over 3 folds: 0.0115) reaches the first candidate
    let close = [
        scored("rocket_unscaled", "ridge_raw", 51, 0.97),
        with_spread(scored("rocket_unscaled", "svm", 51, 0.98), 0.02),
        scored("rocket", "svm", 51, 0.975),
    ];
    assert_eq!(choose(&close, 1, ChoiceRule::Best, Some(2), 10_000), 1);
    assert_eq!(
        choose(&close, 1, ChoiceRule::OneStandardError, Some(2), 10_000),
        0
    );
    assert_eq!(
        choose(&close, 1, ChoiceRule::OneStandardError, None, 10_000),
        0
    );
}

/// End to end: two candidates the validation cannot tell apart (the same method twice) go to the
/// earlier, or to the preferred one when there is one, under either rule; a preference past the
/// candidates is none.
#[test]
fn select_gives_a_tie_to_the_preferred_candidate() {
    let frames = four_class_frames(48, 21);
    let images = grouped(&frames);
    let candidates = vec![TrainConfig::default().check().unwrap(); 2];
    let choose = |choice: AutoChoice<'_>| {
        let selection = select(&images, &choice, 1).unwrap();
        assert_eq!(selection.tied().len(), 0, "the same method is not a tie");
        selection.chosen
    };
    let choice = AutoChoice::new(&candidates, ValidateBy::Auto);
    assert_eq!(choose(choice), 0);
    assert_eq!(choose(choice.with_preferred_on_tie(Some(1))), 1);
    assert_eq!(choose(choice.with_preferred_on_tie(Some(2))), 0);
    let one_se = choice.with_rule(ChoiceRule::OneStandardError);
    assert_eq!(choose(one_se), 0);
    assert_eq!(choose(one_se.with_preferred_on_tie(Some(1))), 1);
}

/// A candidate on several MiniRocket draws says so in its name; one draw (and every other family)
/// reads as before.
#[test]
fn a_candidate_s_name_counts_its_minirocket_draws() {
    use crate::classifier::ClassifierKind;
    use crate::features::{FeatureConfig, RocketFamily, RocketParams};
    let rocket = |draws: usize| {
        let mut score = scored("rocket_unscaled", "ridge_raw", 51, 0.9);
        score.config.features = FeatureConfig::of::<RocketFamily>(RocketParams {
            channel_scaling: false,
            draws,
            ..RocketParams::default()
        });
        score.config.classifier = ClassifierKind::RIDGE_RAW.default_config();
        score
    };
    assert_eq!(
        rocket(4).name(),
        "rocket_unscaled + ridge_raw, all features, 4 draws"
    );
    assert_eq!(
        rocket(1).name(),
        "rocket_unscaled + ridge_raw, all features"
    );
    assert_eq!(
        scored("fft1d", "pwe", 51, 0.9).name(),
        "fft1d + pwe, 51 dims"
    );
}
