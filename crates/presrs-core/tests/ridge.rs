//! The ridge classifier against scikit-learn's `RidgeClassifierCV` (fixtures/ridge/, made by
//! `make_fixture.py` there): the same chosen alpha and leave-one-out curve, coefficients within 1e-8, the
//! same decisions and predictions. Also its registration, its model file checks, its calibration and its
//! errors.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use presrs_core::classifier::{
    ClassifierFamily, ClassifierKind, ClassifierModel, FitData, FitRows, LabeledVectors,
    RidgeConfig, RidgeFamily, RidgeModel, RidgeRawFamily,
};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde_json::Value;

fn fixture() -> Value {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/fixtures/ridge/ridge_sklearn.json"
    );
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn floats(value: &Value) -> Vec<f64> {
    value
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect()
}

fn indices(value: &Value) -> Vec<usize> {
    value
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap() as usize)
        .collect()
}

fn fit(
    config: &RidgeConfig,
    vectors: &[f64],
    classes: &[usize],
    n_classes: usize,
    calibrate: bool,
) -> presrs_core::error::Result<RidgeModel> {
    let dims = vectors.len() / classes.len().max(1);
    RidgeFamily::fit(
        config,
        FitData {
            calibrate,
            ..training_only(vectors, classes, n_classes, dims.max(1))
        },
    )
}

/// Training vectors (no validation ones) of `n_classes` classes, `dims` values each, calibrated.
fn training_only<'a, T>(
    vectors: &'a [T],
    classes: &'a [usize],
    n_classes: usize,
    dims: usize,
) -> FitData<'a, T> {
    FitData {
        train: LabeledVectors { vectors, classes },
        validation: LabeledVectors {
            vectors: &[],
            classes: &[],
        },
        n_classes,
        dims,
        calibrate: true,
    }
}

/// Largest `|a - b|` over two equally long lists.
fn max_difference(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

#[test]
fn the_default_alphas_are_numpys_logspace() {
    let expected = floats(&fixture()["alphas"]);
    let alphas = RidgeConfig::default().alphas;
    assert_eq!(alphas.len(), 10);
    for (a, e) in alphas.iter().zip(&expected) {
        assert!((a - e).abs() <= 1e-15 * e, "{a} vs {e}");
    }
}

#[test]
fn matches_scikit_learns_ridge_classifier_cv() {
    let fixture = fixture();
    let config = RidgeConfig {
        alphas: floats(&fixture["alphas"]),
        pinned: None,
    };
    let mut largest = Vec::new();
    for case in fixture["cases"].as_array().unwrap() {
        let name = case["name"].as_str().unwrap();
        let (dims, n_classes) = (
            case["dims"].as_u64().unwrap() as usize,
            case["n_classes"].as_u64().unwrap() as usize,
        );
        let classes = indices(&case["y_train"]);
        let model = fit(
            &config,
            &floats(&case["x_train"]),
            &classes,
            n_classes,
            true,
        )
        .unwrap();

        assert_eq!(model.alpha(), case["alpha"].as_f64().unwrap(), "{name}");
        assert!(max_difference(model.means(), &floats(&case["scaler_mean"])) < 1e-10);
        let scales = floats(&case["scaler_scale"]);
        for (s, e) in model.scales().iter().zip(&scales) {
            assert!((s - e).abs() <= 1e-12 * e, "{name}: scale {s} vs {e}");
        }
        let curve: Vec<f64> = model.loo_errors().iter().map(|&(_, e)| e).collect();
        let expected_curve = floats(&case["loo_errors"]);
        assert!(
            max_difference(&curve, &expected_curve) < 1e-10,
            "{name}: {curve:?} vs {expected_curve:?}"
        );

        // Coefficients on the standardised features: one row per class, or for two classes scikit-learn's
        // single row (the second class's) and its negation.
        let coef: Vec<Vec<f64>> = case["coef"]
            .as_array()
            .unwrap()
            .iter()
            .map(floats)
            .collect();
        let intercept = floats(&case["intercept"]);
        let mut difference = 0.0f64;
        for class in 0..n_classes {
            let (row, sign) = if n_classes == 2 {
                (0, if class == 0 { -1.0 } else { 1.0 })
            } else {
                (class, 1.0)
            };
            let expected: Vec<f64> = coef[row].iter().map(|c| sign * c).collect();
            difference = difference.max(max_difference(
                model.coefficients(class).unwrap(),
                &expected,
            ));
            difference = difference.max((model.intercepts()[class] - sign * intercept[row]).abs());
        }
        assert!(
            difference < 1e-8,
            "{name}: coefficients differ by {difference:e}"
        );
        largest.push((name, difference));

        // Decisions and predictions on the test vectors.
        let x_test = floats(&case["x_test"]);
        let decisions = floats(&case["decision_function"]);
        let predictions = indices(&case["predict"]);
        let mut scratch = model.scratch();
        let mut scores = vec![0.0; n_classes];
        let mut posteriors = vec![0.0; n_classes];
        let columns = if n_classes == 2 { 1 } else { n_classes };
        for (i, x) in x_test.chunks_exact(dims).enumerate() {
            model.decisions_into(x, &mut scratch, &mut scores).unwrap();
            let expected = &decisions[i * columns..(i + 1) * columns];
            let ours = if n_classes == 2 {
                &scores[1..]
            } else {
                &scores[..]
            };
            assert!(max_difference(ours, expected) < 1e-8, "{name} vector {i}");
            let class = model
                .classify_into(x, &mut scratch, &mut posteriors)
                .unwrap();
            assert_eq!(class, predictions[i], "{name} vector {i}");
            assert!((posteriors.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        }
    }
    // `cargo test -p presrs-core --test ridge -- --nocapture` shows the margins.
    println!("largest coefficient / intercept difference from scikit-learn: {largest:?}");
}

/// `per_class` draws of each of `n_classes` overlapping Gaussian classes in `dims` dimensions, with
/// uneven feature offsets and scales.
fn draw(per_class: usize, n_classes: usize, dims: usize, seed: u64) -> (Vec<f64>, Vec<usize>) {
    let mut centres = ChaCha8Rng::seed_from_u64(99);
    let centres: Vec<f64> = (0..n_classes * dims)
        .map(|_| centres.random_range(-0.6..0.6))
        .collect();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (mut x, mut y) = (Vec::new(), Vec::new());
    for i in 0..per_class * n_classes {
        let class = i % n_classes;
        for j in 0..dims {
            let noise: f64 = (0..4).map(|_| rng.random_range(-1.0..1.0)).sum::<f64>() * 0.6;
            x.push((centres[class * dims + j] + noise) * (1.0 + j as f64) + 10.0 * j as f64);
        }
        y.push(class);
    }
    (x, y)
}

#[test]
fn calibrated_confidences_follow_the_accuracy_and_calibrate_false_keeps_t_one() {
    let (n_classes, dims) = (3, 12);
    let (x, y) = draw(40, n_classes, dims, 1);
    let config = RidgeConfig::default();
    let plain = fit(&config, &x, &y, n_classes, false).unwrap();
    assert_eq!(plain.temperature(), 1.0);
    let model = fit(&config, &x, &y, n_classes, true).unwrap();
    assert_eq!(
        (model.alpha(), model.coefficients(0)),
        (plain.alpha(), plain.coefficients(0))
    );
    assert!(model.temperature() != 1.0);

    let (test_x, test_y) = draw(300, n_classes, dims, 2);
    let mut scratch = model.scratch();
    let mut posteriors = vec![0.0; n_classes];
    let (mut confidence, mut right) = (0.0, 0.0);
    for (x, &truth) in test_x.chunks_exact(dims).zip(&test_y) {
        let class = model
            .classify_into(x, &mut scratch, &mut posteriors)
            .unwrap();
        confidence += posteriors[class];
        right += f64::from(u8::from(class == truth));
    }
    let n = test_y.len() as f64;
    let (confidence, accuracy) = (confidence / n, right / n);
    assert!(
        accuracy > 0.6 && accuracy < 0.98,
        "the classes should overlap: accuracy {accuracy}"
    );
    assert!(
        (confidence - accuracy).abs() < 0.05,
        "mean confidence {confidence} against accuracy {accuracy} (T {})",
        model.temperature()
    );
    assert!((model.loo_accuracy() - accuracy).abs() < 0.1);
}

#[test]
fn two_classes_decide_by_the_sign_of_one_decision() {
    let (x, y) = draw(15, 2, 5, 3);
    let model = fit(&RidgeConfig::default(), &x, &y, 2, true).unwrap();
    assert_eq!(
        model.coefficients(0).unwrap(),
        model
            .coefficients(1)
            .unwrap()
            .iter()
            .map(|c| -c)
            .collect::<Vec<_>>()
    );
    let (test_x, _) = draw(20, 2, 5, 4);
    let mut scratch = model.scratch();
    let (mut scores, mut posteriors) = (vec![0.0; 2], vec![0.0; 2]);
    for x in test_x.chunks_exact(5) {
        model.decisions_into(x, &mut scratch, &mut scores).unwrap();
        assert_eq!(scores[0], -scores[1]);
        let class = model
            .classify_into(x, &mut scratch, &mut posteriors)
            .unwrap();
        assert_eq!(class, usize::from(scores[1] > 0.0));
        let expected = 1.0 / (1.0 + (-2.0 * scores[1] / model.temperature()).exp());
        assert!((posteriors[1] - expected).abs() < 1e-12);
    }
}

#[test]
fn registered_stored_loaded_and_not_yet_in_the_automatic_choice() {
    let kind = ClassifierKind::parse("Ridge").unwrap();
    assert_eq!(kind, ClassifierKind::RIDGE);
    assert!(ClassifierKind::all().contains(&kind));
    assert!(!kind.joins_auto());
    assert!(!ClassifierKind::auto_candidates().contains(&kind));

    let (x, y) = draw(10, 3, 4, 5);
    let model = fit(&RidgeConfig::default(), &x, &y, 3, true).unwrap();
    let none = LabeledVectors {
        vectors: &[],
        classes: &[],
    };
    let data = LabeledVectors {
        vectors: &x,
        classes: &y,
    };
    let stored = kind.default_config().fit(data, none, 3, 4).unwrap();
    assert_eq!(stored.get::<RidgeFamily>().unwrap(), &model);
    let json = serde_json::to_string(&stored).unwrap();
    assert!(
        json.starts_with(r#"{"kind":"ridge","dims":4,"n_classes":3,"alpha":"#),
        "{json}"
    );
    let back: ClassifierModel = serde_json::from_str(&json).unwrap();
    assert_eq!(back, stored);
    assert_eq!(back.get::<RidgeFamily>().unwrap(), &model);

    let config = r#"{"kind":"ridge","alphas":[0.5,2.0,0.1]}"#;
    let config: presrs_core::classifier::ClassifierConfig = serde_json::from_str(config).unwrap();
    assert_eq!(
        config.params::<RidgeFamily>().unwrap().alphas,
        [0.5, 2.0, 0.1]
    );
    for bad in [
        r#"{"kind":"ridge","alphas":[]}"#,
        r#"{"kind":"ridge","alphas":[1.0,0.0]}"#,
        r#"{"kind":"ridge","alphas":[-1.0]}"#,
        r#"{"kind":"ridge","alphas":[1e400]}"#,
    ] {
        let parsed = serde_json::from_str::<presrs_core::classifier::ClassifierConfig>(bad);
        assert!(parsed.is_err() || parsed.unwrap().check().is_err(), "{bad}");
    }
}

#[test]
fn crafted_model_files_are_errors_naming_the_field() {
    let (x, y) = draw(10, 3, 4, 6);
    let model = fit(&RidgeConfig::default(), &x, &y, 3, true).unwrap();
    let good = serde_json::to_value(&model).unwrap();
    let cases: [(&str, Value, &str); 9] = [
        ("dims", serde_json::json!(0), "`dims`"),
        ("n_classes", serde_json::json!(1), "`n_classes`"),
        ("n_classes", serde_json::json!(4), "`coefficients`"),
        ("means", serde_json::json!([0.0, 1.0]), "`means`"),
        (
            "scales",
            serde_json::json!([1.0, 1.0, 0.0, 1.0]),
            "`scales`",
        ),
        ("coefficients", serde_json::json!([1.0]), "`coefficients`"),
        ("intercepts", serde_json::json!([0.0, null, 1.0]), "null"),
        ("alpha", serde_json::json!(-2.0), "`alpha`"),
        ("temperature", serde_json::json!(0.0), "`temperature`"),
    ];
    for (field, value, message) in cases {
        let mut crafted = good.clone();
        crafted[field] = value;
        let err = serde_json::from_value::<RidgeModel>(crafted).unwrap_err();
        assert!(err.to_string().contains(message), "{field}: {err}");
    }
    let mut huge = good.clone();
    huge["dims"] = serde_json::json!(usize::MAX);
    assert!(serde_json::from_value::<RidgeModel>(huge).is_err());
    // A model file without a temperature reads with T = 1.
    let mut old = good;
    old.as_object_mut().unwrap().remove("temperature");
    assert_eq!(
        serde_json::from_value::<RidgeModel>(old)
            .unwrap()
            .temperature(),
        1.0
    );
}

#[test]
fn bad_training_data_is_an_error() {
    let config = RidgeConfig::default();
    let (x, y) = draw(5, 3, 4, 7);
    // A class without a vector.
    let only_two: Vec<usize> = y.iter().map(|&c| c.min(1)).collect();
    let err = fit(&config, &x, &only_two, 3, true).unwrap_err();
    assert!(err.to_string().contains("class 2"), "{err}");
    // One class.
    assert!(fit(&config, &x, &vec![0; y.len()], 1, true).is_err());
    // Not finite.
    let mut nan = x.clone();
    nan[7] = f64::NAN;
    assert!(fit(&config, &nan, &y, 3, true).is_err());
    // Bad hyper-parameters.
    assert!(
        fit(
            &RidgeConfig {
                alphas: vec![],
                pinned: None
            },
            &x,
            &y,
            3,
            true
        )
        .is_err()
    );
    // Constant features are kept with scale 1 and get no weight.
    let constant: Vec<f64> = x
        .chunks_exact(4)
        .flat_map(|row| [row[0], 3.5, row[2], row[3]])
        .collect();
    let model = fit(&config, &constant, &y, 3, true).unwrap();
    assert_eq!(model.scales()[1], 1.0);
    assert!((0..3).all(|c| model.coefficients(c).unwrap()[1].abs() < 1e-12));
}

#[test]
fn the_model_does_not_depend_on_the_thread_count() {
    // Large enough (a Gram matrix of 360) for faer to split the product, and its tridiagonalisation if
    // it were asked to, over threads.
    let (x, y) = draw(120, 3, 1000, 8);
    let fit_with = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| fit(&RidgeConfig::default(), &x, &y, 3, true).unwrap())
    };
    let one = fit_with(1);
    for threads in [2, 3] {
        assert_eq!(fit_with(threads), one, "{threads} threads");
    }
}

/// A pinned fit (one `α` and the temperature fixed, solved by Cholesky) against the leave-one-out fit
/// that chose them, on the same vectors: the same model to rounding, with more vectors than features
/// (the covariance system) and fewer (the Gram system), within one block and across several (rows or
/// columns past `direct.rs`'s 512), two and three classes, both scalings; and invariant to the thread
/// count.
#[test]
fn a_pinned_fit_is_the_leave_one_out_fit_at_its_alpha() {
    let cases = [
        (40, 3, 12, 11),
        (6, 3, 50, 12),
        (30, 2, 70, 13),
        (200, 3, 40, 14),
        (4, 3, 1100, 15),
    ];
    for (per_class, n_classes, dims, seed) in cases {
        let (x, y) = draw(per_class, n_classes, dims, seed);
        let data = training_only(&x, &y, n_classes, dims);
        let families: [fn(&RidgeConfig, FitData<'_>) -> presrs_core::error::Result<RidgeModel>; 2] =
            [RidgeFamily::fit, RidgeRawFamily::fit];
        let pins: [fn(&RidgeConfig, &RidgeModel) -> Option<RidgeConfig>; 2] =
            [RidgeFamily::pinned, RidgeRawFamily::pinned];
        for (fit_family, pin) in families.into_iter().zip(pins) {
            let searched = fit_family(&RidgeConfig::default(), data).unwrap();
            let pinned = pin(&RidgeConfig::default(), &searched).unwrap();
            pinned.check().unwrap();
            let direct = fit_family(&pinned, data).unwrap();
            assert_eq!(direct.alpha(), searched.alpha());
            assert_eq!(direct.temperature(), searched.temperature());
            assert_eq!(direct.loo_errors(), searched.loo_errors());
            assert_eq!(direct.means(), searched.means());
            let scale = (0..n_classes)
                .flat_map(|c| searched.coefficients(c).unwrap().to_vec())
                .fold(0.0f64, |m, v| m.max(v.abs()));
            for c in 0..n_classes {
                let gap = max_difference(
                    direct.coefficients(c).unwrap(),
                    searched.coefficients(c).unwrap(),
                );
                assert!(
                    gap <= 1e-8 * scale.max(1.0),
                    "{dims} dims, class {c}: {gap}"
                );
            }
            assert!(max_difference(direct.intercepts(), searched.intercepts()) < 1e-9);
            let threaded = rayon::ThreadPoolBuilder::new()
                .num_threads(3)
                .build()
                .unwrap()
                .install(|| fit_family(&pinned, data).unwrap());
            assert_eq!(threaded, direct);
        }
    }
}

/// The pipeline's path without the PCA step against numpy's |FFT| and scikit-learn's `StandardScaler`
/// and `RidgeClassifierCV` on the same images (fixtures/ridge/make_pipeline_fixture.py): training keeps
/// every feature (no PCA), chooses the same alpha, and gives the same coefficients, decisions and
/// predictions.
#[test]
fn the_pipeline_without_a_pca_equals_standard_scaler_and_ridge_classifier_cv() {
    use presrs_core::features::{FeatureConfig, Fft1dConfig, Fft1dFamily};
    use presrs_core::pipeline::{LabeledImage, TrainConfig, train};
    use presrs_core::{Crop, Frame, Grid};

    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/fixtures/ridge/ridge_pipeline_sklearn.json"
    );
    let fixture: Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    let grid = Grid::new(
        fixture["rows"].as_u64().unwrap() as usize,
        fixture["cols"].as_u64().unwrap() as usize,
    );
    let frames = |key: &str| -> Vec<Frame> {
        floats(&fixture[key])
            .chunks_exact(grid.len())
            .map(|values| Frame::new(grid, values.to_vec()).unwrap())
            .collect()
    };
    let (train_frames, test_frames) = (frames("train_images"), frames("test_images"));
    let labels: Vec<String> = fixture["train_labels"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| l.as_str().unwrap().to_owned())
        .collect();
    let images: Vec<LabeledImage<'_>> = train_frames
        .iter()
        .zip(&labels)
        .map(|(frame, label)| LabeledImage::new(frame.view(), label))
        .collect();
    let config = TrainConfig {
        crop: Crop::NONE,
        features: FeatureConfig::of::<Fft1dFamily>(Fft1dConfig {
            fft_len: fixture["fft_len"].as_u64().map(|n| n as usize),
        }),
        classifier: ClassifierKind::RIDGE.default_config(),
        ..TrainConfig::default()
    }
    .check()
    .unwrap();
    assert_eq!(config.config().pca_dims(), None);
    let model = train(&images, &[], &config).unwrap();
    assert!(model.pca().is_none());
    assert_eq!(model.classifier_dims(), FFT_FEATURES);
    let ridge = model.classifier().get::<RidgeFamily>().unwrap();
    assert_eq!(ridge.alpha(), fixture["alpha"].as_f64().unwrap());
    for (class, expected) in fixture["coef"].as_array().unwrap().iter().enumerate() {
        let difference = max_difference(ridge.coefficients(class).unwrap(), &floats(expected));
        assert!(
            difference < 1e-8,
            "class {class}: coefficients {difference}"
        );
    }
    let intercepts = max_difference(ridge.intercepts(), &floats(&fixture["intercept"]));
    assert!(intercepts < 1e-12, "intercepts {intercepts}");

    let expected_decisions = floats(&fixture["decision_function"]);
    let mut session = model.session();
    let mut scratch = ridge.scratch();
    let mut decisions = vec![0.0; model.class_names().len()];
    for (i, frame) in test_frames.iter().enumerate() {
        // On the exact features, the decisions; classification's own (single-precision |FFT|)
        // features give the same label.
        let features = session.features(&frame.view()).unwrap().to_vec();
        ridge
            .decisions_into(&features, &mut scratch, &mut decisions)
            .unwrap();
        let expected = &expected_decisions[i * decisions.len()..(i + 1) * decisions.len()];
        // Training read its features in single precision (each rounded to the nearest f32), so the
        // decisions are scikit-learn's on the f64 features to about 1e-8, not to the last digits.
        let difference = max_difference(&decisions, expected);
        assert!(difference < 1e-6, "image {i}: decisions {difference}");
        let prediction = session.classify(&frame.view()).unwrap();
        assert_eq!(prediction.label, fixture["predict"][i].as_str().unwrap());
    }
    // The batch path (no basis to share without a PCA) gives each frame's session result.
    let views: Vec<_> = test_frames.iter().map(Frame::view).collect();
    for (view, batched) in views.iter().zip(model.classify_batch(&views)) {
        let single = session.classify(view).unwrap().to_classification();
        assert_eq!(batched.unwrap(), single);
    }
}

/// `rfft` of 128 points keeps 65 bins.
const FFT_FEATURES: usize = 65;

/// `ridge_raw` is scikit-learn's `RidgeClassifierCV` on the features as they are (centred for the
/// intercept, not scaled): `fixtures/ridge/make_raw_fixture.py`, features of very different scales. The
/// same chosen alpha and leave-one-out curve, coefficients on the raw features within 1e-8, the same
/// decisions and predictions; `ridge` (standardising) on the same data is another model.
#[test]
fn ridge_raw_matches_scikit_learn_without_a_scaler() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/fixtures/ridge/ridge_raw_sklearn.json"
    );
    let fixture: Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    let config = RidgeConfig {
        alphas: floats(&fixture["alphas"]),
        pinned: None,
    };
    for case in fixture["cases"].as_array().unwrap() {
        let name = case["name"].as_str().unwrap();
        let (dims, n_classes) = (
            case["dims"].as_u64().unwrap() as usize,
            case["n_classes"].as_u64().unwrap() as usize,
        );
        let x = floats(&case["x_train"]);
        let classes = indices(&case["y_train"]);
        let data = training_only(&x, &classes, n_classes, dims);
        let model = RidgeRawFamily::fit(&config, data).unwrap();
        assert_eq!(model.alpha(), case["alpha"].as_f64().unwrap(), "{name}");
        assert!(model.scales().iter().all(|&s| s == 1.0), "{name}");
        let curve: Vec<f64> = model.loo_errors().iter().map(|&(_, e)| e).collect();
        assert!(
            max_difference(&curve, &floats(&case["loo_errors"])) < 1e-9,
            "{name}: {curve:?}"
        );
        let coef: Vec<Vec<f64>> = case["coef"]
            .as_array()
            .unwrap()
            .iter()
            .map(floats)
            .collect();
        let intercept = floats(&case["intercept"]);
        for class in 0..n_classes {
            let (row, sign) = if n_classes == 2 {
                (0, if class == 0 { -1.0 } else { 1.0 })
            } else {
                (class, 1.0)
            };
            let expected: Vec<f64> = coef[row].iter().map(|c| sign * c).collect();
            let ours = model.coefficients(class).unwrap();
            let scale = expected.iter().fold(1.0f64, |m, c| m.max(c.abs()));
            assert!(
                max_difference(ours, &expected) < 1e-8 * scale,
                "{name} class {class}"
            );
            // (the intercept of the centred model, `b - w . mean`)
            let offset: f64 = ours.iter().zip(model.means()).map(|(w, m)| w * m).sum();
            let b = model.intercepts()[class] - offset;
            assert!(
                (b - sign * intercept[row]).abs() < 1e-7 * (1.0 + intercept[row].abs()),
                "{name}: intercept {b} vs {}",
                sign * intercept[row]
            );
        }
        let x_test = floats(&case["x_test"]);
        let decisions = floats(&case["decision_function"]);
        let predictions = indices(&case["predict"]);
        let mut scratch = model.scratch();
        let mut scores = vec![0.0; n_classes];
        let columns = if n_classes == 2 { 1 } else { n_classes };
        for (i, row) in x_test.chunks_exact(dims).enumerate() {
            model
                .decisions_into(row, &mut scratch, &mut scores)
                .unwrap();
            let expected = &decisions[i * columns..(i + 1) * columns];
            let ours = if n_classes == 2 {
                &scores[1..]
            } else {
                &scores[..]
            };
            assert!(max_difference(ours, expected) < 1e-7, "{name} vector {i}");
            let predicted = (0..n_classes)
                .max_by(|&a, &b| scores[a].total_cmp(&scores[b]).then(b.cmp(&a)))
                .unwrap();
            assert_eq!(predicted, predictions[i], "{name} vector {i}");
        }
        let standardised = RidgeFamily::fit(&config, data).unwrap();
        assert_ne!(
            standardised.coefficients(0),
            model.coefficients(0),
            "{name}"
        );
    }
    assert_eq!(ClassifierKind::RIDGE_RAW.as_str(), "ridge_raw");
    assert!(ClassifierKind::RIDGE_RAW.takes_all_features());
    assert!(!ClassifierKind::RIDGE_RAW.joins_auto());
}

/// Single-precision vectors give exactly the model of the same values in double precision (every
/// `f32` is an `f64`, and ridge computes in `f64`), searched or pinned.
#[test]
fn single_precision_vectors_give_the_model_of_the_same_values() {
    for (per_class, dims, seed) in [(40, 12, 21), (5, 60, 22)] {
        let (x, y) = draw(per_class, 3, dims, seed);
        #[allow(clippy::cast_possible_truncation)]
        let single: Vec<f32> = x.iter().map(|&v| v as f32).collect();
        let double: Vec<f64> = single.iter().map(|&v| f64::from(v)).collect();
        let data = |vectors| training_only(vectors, &y, 3, dims);
        let single_data = training_only(&single, &y, 3, dims);
        const { assert!(RidgeFamily::READS_SINGLE) };
        let searched = RidgeFamily::fit(&RidgeConfig::default(), data(&double)).unwrap();
        let from_single = RidgeFamily::fit_single(&RidgeConfig::default(), single_data).unwrap();
        assert_eq!(from_single, searched);
        let pinned = RidgeFamily::pinned(&RidgeConfig::default(), &searched).unwrap();
        assert_eq!(
            RidgeFamily::fit_single(&pinned, single_data).unwrap(),
            RidgeFamily::fit(&pinned, data(&double)).unwrap()
        );
    }
}

/// Rows read in place (a feature table's, as the automatic choice scores ridge) give exactly the
/// model of the same rows laid end to end, for both families, searched and pinned, with training and
/// validation rows; rows of another length or a non-finite value are refused as `fit` refuses them.
#[test]
fn rows_in_place_give_the_model_of_the_same_rows_laid_end_to_end() {
    let dims = 9;
    let (x, y) = draw(20, 3, dims, 31);
    let rows: Vec<&[f64]> = x.chunks_exact(dims).collect();
    let (train, validation) = rows.split_at(40);
    let (train_classes, validation_classes) = y.split_at(40);
    let laid = |part: &[&[f64]]| part.concat();
    let (train_laid, validation_laid) = (laid(train), laid(validation));
    let data = FitData {
        train: LabeledVectors {
            vectors: &train_laid,
            classes: train_classes,
        },
        validation: LabeledVectors {
            vectors: &validation_laid,
            classes: validation_classes,
        },
        n_classes: 3,
        dims,
        calibrate: true,
    };
    let in_place = FitRows {
        train,
        train_classes,
        validation,
        validation_classes,
        n_classes: 3,
        dims,
        calibrate: true,
    };
    const { assert!(RidgeFamily::READS_ROWS && RidgeRawFamily::READS_ROWS) };
    let searched = RidgeFamily::fit(&RidgeConfig::default(), data).unwrap();
    assert_eq!(
        RidgeFamily::fit_rows(&RidgeConfig::default(), in_place).unwrap(),
        searched
    );
    assert_eq!(
        RidgeRawFamily::fit_rows(&RidgeConfig::default(), in_place).unwrap(),
        RidgeRawFamily::fit(&RidgeConfig::default(), data).unwrap()
    );
    let pinned = RidgeFamily::pinned(&RidgeConfig::default(), &searched).unwrap();
    assert_eq!(
        RidgeFamily::fit_rows(&pinned, in_place).unwrap(),
        RidgeFamily::fit(&pinned, data).unwrap()
    );
    let short = &x[..dims - 1];
    let mut bad_rows = train.to_vec();
    bad_rows[3] = short;
    let bad = FitRows {
        train: &bad_rows,
        ..in_place
    };
    assert!(RidgeFamily::fit_rows(&RidgeConfig::default(), bad).is_err());
    let nan = [f64::NAN; 9];
    bad_rows[3] = &nan;
    let bad = FitRows {
        train: &bad_rows,
        ..in_place
    };
    let err = RidgeFamily::fit_rows(&RidgeConfig::default(), bad).unwrap_err();
    assert!(err.to_string().contains("NaN"), "{err}");
}
