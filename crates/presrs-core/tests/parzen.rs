//! The Parzen-window classifier: fast scores against the definition, the sigma search, stored vectors.

#![allow(clippy::unwrap_used)] // helpers of integration tests are test code too

use presrs_core::classifier::{
    ClassifierConfig, ClassifierModel, LabeledVectors, ParzenConfig, ParzenModel, PweFamily,
    SigmaChoice, SigmaSearch,
};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// `per_class` points per class around class centres `spacing` apart along the first axis.
fn blobs(
    n_classes: usize,
    per_class: usize,
    dims: usize,
    spacing: f64,
    seed: u64,
) -> (Vec<f64>, Vec<usize>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut vectors = Vec::new();
    let mut classes = Vec::new();
    for i in 0..n_classes * per_class {
        let class = i % n_classes;
        for d in 0..dims {
            let centre = if d == 0 { spacing * class as f64 } else { 0.0 };
            vectors.push(centre + rng.random_range(-1.0..1.0));
        }
        classes.push(class);
    }
    (vectors, classes)
}

fn labeled<'a>(data: &'a (Vec<f64>, Vec<usize>)) -> LabeledVectors<'a> {
    LabeledVectors {
        vectors: &data.0,
        classes: &data.1,
    }
}

/// log(mean_p exp(-|x - p|² / 2σ²)) per class, computed directly (with a shift so it cannot underflow).
fn naive_log_scores(model: &ParzenModel, x: &[f64]) -> Vec<f64> {
    let dims = model.dims();
    (0..model.n_classes())
        .map(|class| {
            let exponents: Vec<f64> = model
                .class_vectors(class)
                .chunks(dims)
                .map(|p| {
                    let d2: f64 = x.iter().zip(p).map(|(a, b)| (a - b) * (a - b)).sum();
                    -d2 / (2.0 * model.sigma() * model.sigma())
                })
                .collect();
            let top = exponents.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
            top + (exponents.iter().map(|e| (e - top).exp()).sum::<f64>() / exponents.len() as f64)
                .ln()
        })
        .collect()
}

#[test]
fn fast_scores_match_the_definition() {
    let train = blobs(4, 13, 51, 3.0, 1);
    let validation = blobs(4, 7, 51, 3.0, 2);
    let model = ParzenModel::fit(
        labeled(&train),
        labeled(&validation),
        4,
        51,
        &ParzenConfig::default(),
    )
    .unwrap();
    let queries = blobs(4, 10, 51, 3.0, 3);
    let mut scratch = model.scratch();
    let mut scores = vec![0.0; 4];
    let mut posteriors = vec![0.0; 4];
    for x in queries.0.chunks(51) {
        model.log_scores_into(x, &mut scratch, &mut scores).unwrap();
        let naive = naive_log_scores(&model, x);
        for (fast, slow) in scores.iter().zip(&naive) {
            assert!(
                (fast - slow).abs() <= 1e-9 * slow.abs().max(1.0),
                "{fast} vs {slow}"
            );
        }
        let class = model
            .classify_into(x, &mut scratch, &mut posteriors)
            .unwrap();
        let best = (0..4)
            .max_by(|&a, &b| naive[a].total_cmp(&naive[b]))
            .unwrap();
        assert_eq!(class, best);
        // Equal priors, calibrated: softmax(scores / T).
        let t = model.temperature();
        let total: f64 = naive.iter().map(|s| ((s - naive[best]) / t).exp()).sum();
        for (p, s) in posteriors.iter().zip(&naive) {
            assert!(
                (p - ((s - naive[best]) / t).exp() / total).abs() < 1e-9,
                "equal-prior posterior at temperature {t}"
            );
        }
    }
}

#[test]
fn stores_training_and_validation_vectors() {
    let train = blobs(4, 13, 5, 4.0, 4);
    let validation = blobs(4, 7, 5, 4.0, 5);
    let model = ParzenModel::fit(
        labeled(&train),
        labeled(&validation),
        4,
        5,
        &ParzenConfig::default(),
    )
    .unwrap();
    assert_eq!(
        model.n_stored(),
        80,
        "the paper's P has p + q = 52 + 28 columns"
    );
    for class in 0..4 {
        assert_eq!(model.class_vectors(class).len(), 20 * 5);
        // the first stored vector of each class is its first training vector
        let first_train = train.1.iter().position(|&c| c == class).unwrap();
        assert_eq!(
            &model.class_vectors(class)[..5],
            &train.0[first_train * 5..first_train * 5 + 5]
        );
    }
}

/// Mean over `validation` of the log posterior (equal priors) of the true class under `model`, from
/// the naive scores.
fn naive_mean_log_posterior(model: &ParzenModel, validation: &(Vec<f64>, Vec<usize>)) -> f64 {
    let dims = model.dims();
    let total: f64 = validation
        .0
        .chunks(dims)
        .zip(&validation.1)
        .map(|(x, &class)| {
            let scores = naive_log_scores(model, x);
            let top = scores.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
            let log_total = top + scores.iter().map(|s| (s - top).exp()).sum::<f64>().ln();
            scores[class] - log_total
        })
        .sum();
    total / validation.1.len() as f64
}

#[test]
fn search_records_the_curve_and_breaks_ties_toward_larger_sigma() {
    // Classes 50 apart with points within 1 of their centre: every sigma of the grid classifies the
    // validation set perfectly and with posteriors that round to exactly 1, so accuracy and log-loss
    // tie everywhere and the chosen sigma is the largest.
    let train = blobs(3, 10, 4, 50.0, 6);
    let validation = blobs(3, 5, 4, 50.0, 7);
    let search = SigmaSearch {
        min_factor: 0.25,
        max_factor: 4.0,
        steps: 5,
    };
    let config = ParzenConfig {
        sigma: SigmaChoice::Search(search),
    };
    let model = ParzenModel::fit(labeled(&train), labeled(&validation), 3, 4, &config).unwrap();
    let curve = model.validation_curve();
    assert_eq!(curve.len(), 5);
    assert!(curve.windows(2).all(|w| w[0].sigma < w[1].sigma));
    let scale = model.scale().unwrap();
    for (point, factor) in curve.iter().zip([0.25, 0.5, 1.0, 2.0, 4.0]) {
        assert!((point.factor - factor).abs() < 1e-12);
        assert!((point.sigma - factor * scale).abs() < 1e-9 * scale);
        assert!(point.mean_log_likelihood.is_finite());
        assert_eq!(point.accuracy, 1.0);
        assert_eq!(point.mean_log_posterior, Some(0.0), "{point:?}");
    }
    assert_eq!(model.sigma(), curve.last().unwrap().sigma);
}

#[test]
fn search_breaks_accuracy_ties_by_the_validation_log_loss() {
    // Classes 6 apart: the whole grid classifies validation perfectly, but the widest kernels spread
    // each class's density over its neighbours and flatten the posteriors. Accuracy alone chose the
    // widest, where an obvious image got a confidence near 1/3.
    let train = blobs(3, 10, 2, 6.0, 16);
    let validation = blobs(3, 10, 2, 6.0, 17);
    let config = ParzenConfig {
        sigma: SigmaChoice::Search(SigmaSearch {
            min_factor: 0.25,
            max_factor: 32.0,
            steps: 8,
        }),
    };
    let model = ParzenModel::fit(labeled(&train), labeled(&validation), 3, 2, &config).unwrap();
    let curve = model.validation_curve();
    assert!(curve.iter().all(|p| p.accuracy == 1.0), "{curve:?}");
    // The recorded log posteriors are the definition's, from a model on the training set alone.
    for point in curve {
        let fixed = ParzenConfig {
            sigma: SigmaChoice::Fixed { sigma: point.sigma },
        };
        let train_only =
            ParzenModel::fit(labeled(&train), labeled(&(vec![], vec![])), 3, 2, &fixed).unwrap();
        let expected = naive_mean_log_posterior(&train_only, &validation);
        let recorded = point.mean_log_posterior.unwrap();
        assert!(
            (recorded - expected).abs() <= 1e-9 * (1.0 + expected.abs()),
            "sigma {}: {recorded} vs {expected}",
            point.sigma
        );
        assert!(recorded <= 0.0);
    }
    let best = curve
        .iter()
        .max_by(|a, b| {
            a.mean_log_posterior
                .partial_cmp(&b.mean_log_posterior)
                .unwrap()
        })
        .unwrap();
    assert_eq!(model.sigma(), best.sigma);
    assert!(model.sigma() < curve.last().unwrap().sigma);
    // The widest kernel's confidence in a class centre is near 1/3; the chosen one's is near 1.
    let confidence = |model: &ParzenModel| {
        let mut scratch = model.scratch();
        let mut posteriors = vec![0.0; 3];
        let class = model
            .classify_into(&[12.0, 0.0], &mut scratch, &mut posteriors)
            .unwrap();
        assert_eq!(class, 2);
        posteriors[class]
    };
    assert!(confidence(&model) > 0.95, "{}", confidence(&model));
    // Uncalibrated, the widest kernel's posteriors are nearly flat.
    let widest = ParzenModel::fit(
        labeled(&train),
        labeled(&(vec![], vec![])),
        3,
        2,
        &ParzenConfig {
            sigma: SigmaChoice::Fixed {
                sigma: curve.last().unwrap().sigma,
            },
        },
    )
    .unwrap();
    assert_eq!(widest.temperature(), 1.0);
    assert!(confidence(&widest) < 0.5, "{}", confidence(&widest));
}

#[test]
fn search_prefers_the_accurate_sigma_over_the_larger_one() {
    // Two classes whose points interleave along the first axis at different offsets: a wide kernel
    // blurs them together, a narrow one (about the nearest-neighbour distance) separates them.
    let mut train = (Vec::new(), Vec::new());
    let mut validation = (Vec::new(), Vec::new());
    for i in 0..20 {
        let class = i % 2;
        let x = i as f64 + 0.5 * class as f64;
        train.0.extend([x, 0.0]);
        train.1.push(class);
        validation.0.extend([x + 0.02, 0.01]);
        validation.1.push(class);
    }
    let config = ParzenConfig {
        sigma: SigmaChoice::Search(SigmaSearch {
            min_factor: 1.0 / 16.0,
            max_factor: 64.0,
            steps: 11,
        }),
    };
    let model = ParzenModel::fit(labeled(&train), labeled(&validation), 2, 2, &config).unwrap();
    let curve = model.validation_curve();
    let chosen = curve.iter().find(|p| p.sigma == model.sigma()).unwrap();
    assert_eq!(chosen.accuracy, 1.0);
    assert!(
        curve.last().unwrap().accuracy < 1.0,
        "the widest kernel should fail here: {curve:?}"
    );
    assert!(model.sigma() < curve.last().unwrap().sigma);
}

#[test]
fn fixed_sigma_needs_no_validation_set_but_search_does() {
    let train = blobs(2, 5, 3, 5.0, 8);
    let empty = (Vec::new(), Vec::new());
    let fixed = ParzenConfig {
        sigma: SigmaChoice::Fixed { sigma: 1.5 },
    };
    let model = ParzenModel::fit(labeled(&train), labeled(&empty), 2, 3, &fixed).unwrap();
    assert_eq!(model.sigma(), 1.5);
    assert!(model.validation_curve().is_empty());
    assert!(
        ParzenModel::fit(
            labeled(&train),
            labeled(&empty),
            2,
            3,
            &ParzenConfig::default()
        )
        .is_err()
    );
}

#[test]
fn rejects_bad_training_data() {
    let train = blobs(2, 5, 3, 5.0, 9);
    let validation = blobs(2, 2, 3, 5.0, 10);
    let config = ParzenConfig::default();
    // a class with no training vector
    assert!(ParzenModel::fit(labeled(&train), labeled(&validation), 3, 3, &config).is_err());
    // a class index out of range
    let bad_labels = (validation.0.clone(), vec![0, 1, 5, 0]);
    assert!(ParzenModel::fit(labeled(&train), labeled(&bad_labels), 2, 3, &config).is_err());
    // vectors of the wrong length
    let ragged = (train.0[..train.0.len() - 1].to_vec(), train.1.clone());
    assert!(ParzenModel::fit(labeled(&ragged), labeled(&validation), 2, 3, &config).is_err());
    // NaN
    let mut nan = train.clone();
    nan.0[4] = f64::NAN;
    assert!(ParzenModel::fit(labeled(&nan), labeled(&validation), 2, 3, &config).is_err());
}

#[test]
fn classifier_model_serde_round_trip_classifies_identically() {
    let train = blobs(3, 8, 6, 2.0, 11);
    let validation = blobs(3, 4, 6, 2.0, 12);
    let model = ClassifierConfig::default()
        .fit(labeled(&train), labeled(&validation), 3, 6)
        .unwrap();
    let json = serde_json::to_string(&model).unwrap();
    assert!(json.starts_with(r#"{"kind":"pwe""#), "{}", &json[..40]);
    let back: ClassifierModel = serde_json::from_str(&json).unwrap();
    assert_eq!(back, model);
    let queries = blobs(3, 5, 6, 2.0, 13);
    let (mut s1, mut s2) = (model.scratch(), back.scratch());
    let (mut p1, mut p2) = (vec![0.0; 3], vec![0.0; 3]);
    for x in queries.0.chunks(6) {
        let c1 = model.classify_into(x, &mut s1, &mut p1).unwrap();
        let c2 = back.classify_into(x, &mut s2, &mut p2).unwrap();
        assert_eq!((c1, &p1), (c2, &p2));
    }
    // A model file written before calibration (no `temperature`): the same labels, uncalibrated
    // posteriors.
    let mut value: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert!(value["temperature"].as_f64().unwrap() != 1.0);
    value.as_object_mut().unwrap().remove("temperature");
    let old: ClassifierModel = serde_json::from_value(value).unwrap();
    let old_pwe = old.get::<PweFamily>().unwrap();
    assert_eq!(old_pwe.temperature(), 1.0);
    let mut s3 = old.scratch();
    let mut p3 = vec![0.0; 3];
    for x in queries.0.chunks(6) {
        let c1 = model.classify_into(x, &mut s1, &mut p1).unwrap();
        assert_eq!(old.classify_into(x, &mut s3, &mut p3).unwrap(), c1);
    }
    for bad in [0.0, -1.0] {
        let mut value: serde_json::Value = serde_json::from_str(&json).unwrap();
        value["temperature"] = serde_json::json!(bad);
        let err = serde_json::from_value::<ClassifierModel>(value).unwrap_err();
        assert!(err.to_string().contains("temperature"), "{err}");
    }
    // tampered: class_starts that do not cover the stored vectors
    let mut value: serde_json::Value = serde_json::from_str(&json).unwrap();
    value["class_starts"] = serde_json::json!([0, 5, 3]);
    assert!(serde_json::from_value::<ClassifierModel>(value).is_err());
}

/// A vector whose squared length overflows is refused with a reason, in training and when classified,
/// instead of giving NaN posteriors.
#[test]
fn vectors_too_long_to_square_are_refused() {
    let train = blobs(2, 5, 3, 3.0, 11);
    let validation = blobs(2, 3, 3, 3.0, 12);
    let model = ParzenModel::fit(
        labeled(&train),
        labeled(&validation),
        2,
        3,
        &ParzenConfig::default(),
    )
    .unwrap();
    let mut scratch = model.scratch();
    let mut posteriors = vec![0.0; 2];
    let err = model
        .classify_into(&[1e200, 0.0, 0.0], &mut scratch, &mut posteriors)
        .unwrap_err();
    assert!(err.to_string().contains("too long"), "{err}");
    assert!(
        model
            .log_scores_into(&[0.0, -1e160, 0.0], &mut scratch, &mut posteriors)
            .is_err()
    );
    // 1e150 squares to 1e300: still usable.
    assert!(
        model
            .classify_into(&[1e150, 0.0, 0.0], &mut scratch, &mut posteriors)
            .is_ok()
    );
    let mut huge = train.clone();
    huge.0[4] = 1e155;
    let err = ParzenModel::fit(
        labeled(&huge),
        labeled(&validation),
        2,
        3,
        &ParzenConfig::default(),
    )
    .unwrap_err();
    assert!(err.to_string().contains("too long"), "{err}");
}

#[test]
fn the_temperature_is_fitted_to_leave_one_out_scores() {
    // Overlapping classes (centres 1.5 apart, points within 1): some stored vectors are nearer another
    // class, so the fit lands inside the range, not at an end.
    let train = blobs(3, 12, 3, 1.5, 21);
    let validation = blobs(3, 6, 3, 1.5, 22);
    let model = ParzenModel::fit(
        labeled(&train),
        labeled(&validation),
        3,
        3,
        &ParzenConfig::default(),
    )
    .unwrap();
    // The oracle: every stored vector scored by a fixed-σ model of all the other stored vectors.
    let stored: Vec<(Vec<f64>, usize)> = (0..3)
        .flat_map(|class| {
            model
                .class_vectors(class)
                .chunks(3)
                .map(move |p| (p.to_vec(), class))
                .collect::<Vec<_>>()
        })
        .collect();
    let mut scores = Vec::new();
    let mut truths = Vec::new();
    for (i, (x, class)) in stored.iter().enumerate() {
        let others: (Vec<f64>, Vec<usize>) = (
            stored
                .iter()
                .enumerate()
                .filter(|(j, _)| *j != i)
                .flat_map(|(_, (p, _))| p.clone())
                .collect(),
            stored
                .iter()
                .enumerate()
                .filter(|(j, _)| *j != i)
                .map(|(_, (_, c))| *c)
                .collect(),
        );
        let fixed = ParzenConfig {
            sigma: SigmaChoice::Fixed {
                sigma: model.sigma(),
            },
        };
        let leave_one_out =
            ParzenModel::fit(labeled(&others), labeled(&(vec![], vec![])), 3, 3, &fixed).unwrap();
        scores.extend(naive_log_scores(&leave_one_out, x));
        truths.push(*class);
    }
    let expected =
        presrs_core::classifier::calibration::fit_temperature(&scores, &truths, 3).unwrap();
    let t = model.temperature();
    assert!((t - expected).abs() <= 1e-6 * expected, "{t} vs {expected}");
    let (lo, hi) = presrs_core::classifier::calibration::TEMPERATURE_RANGE;
    assert!(t > lo && t < hi, "{t}");
}

#[test]
fn tempered_posteriors_keep_classes_whose_density_underflows() {
    // Classes 60 apart with σ = 1: another class's score is about -1800 below the best, where its
    // density underflows f64 (exp(-745) is the least), but at T = 1000 its posterior is e^-1.8 relative.
    let train = blobs(2, 6, 2, 60.0, 31);
    let fixed = ParzenConfig {
        sigma: SigmaChoice::Fixed { sigma: 1.0 },
    };
    let model =
        ParzenModel::fit(labeled(&train), labeled(&(vec![], vec![])), 2, 2, &fixed).unwrap();
    let mut value = serde_json::to_value(&model).unwrap();
    value["temperature"] = serde_json::json!(1000.0);
    let model: ParzenModel = serde_json::from_value(value).unwrap();
    let mut scratch = model.scratch();
    let mut posteriors = vec![0.0; 2];
    for x in [[0.5, 0.0], [59.0, 0.3], [30.5, 0.0]] {
        let naive = naive_log_scores(&model, &x);
        let best = if naive[1] > naive[0] { 1 } else { 0 };
        let class = model
            .classify_into(&x, &mut scratch, &mut posteriors)
            .unwrap();
        assert_eq!(class, best);
        let gap = naive[best] - naive[1 - best];
        let expected_other = 1.0 / (1.0 + (gap / 1000.0).exp());
        assert!(
            (posteriors[1 - best] - expected_other).abs() < 1e-9,
            "{x:?}: gap {gap}, {posteriors:?} vs {expected_other}"
        );
        if x[0] < 1.0 {
            assert!(
                gap > 745.0 && posteriors[1 - best] > 0.1,
                "{gap} {posteriors:?}"
            );
        }
    }
}
