//! Trained models read from JSON are checked on load (`TrainedModel`'s promise that loading re-checks
//! that the parts fit together): a corrupted but well-formed model is an error naming the field, never a
//! model that panics, allocates gigabytes or gives NaN posteriors when it classifies.

#![allow(clippy::unwrap_used, clippy::expect_used)] // helpers of integration tests are test code too

use presrs_core::classifier::ClassifierKind;
use presrs_core::features::{FeatureConfig, Fft1dConfig};
use presrs_core::pipeline::{LabeledImage, MAX_TRANSFORM_LEN, TrainConfig, TrainedModel, train};
use presrs_core::testing::{SYNTHETIC_CLASSES, synthetic_frame};
use presrs_core::{Crop, Frame};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde_json::{Value, json};

/// A small trained model of `kind` (4 classes, 2 components) as JSON, and a frame it takes.
fn model_json(kind: ClassifierKind) -> (Value, Frame) {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let set: Vec<(Frame, &str)> = (0..4 * 8)
        .map(|i| (synthetic_frame(i % 4, &mut rng), SYNTHETIC_CLASSES[i % 4]))
        .collect();
    let images: Vec<LabeledImage<'_>> = set
        .iter()
        .map(|(frame, label)| LabeledImage::new(frame.view(), label))
        .collect();
    let config = TrainConfig {
        crop: Crop::PAPER,
        dims: 2,
        classifier: kind.default_config(),
        ..TrainConfig::default()
    }
    .check()
    .unwrap();
    let model = train(&images[..20], &images[20..], &config).unwrap();
    (serde_json::to_value(&model).unwrap(), set[0].0.clone())
}

/// An edit of a model's JSON and the words the error of loading it must hold.
type Case<'a> = (&'a dyn Fn(&mut Value), &'a str);

/// Checks every `(edit, words)` case on the model of `kind`: the edited model must fail to load with an
/// error holding `words` (the field). The unedited model loads and classifies with finite posteriors.
fn rejects(kind: ClassifierKind, cases: &[Case<'_>]) {
    let (value, frame) = model_json(kind);
    let model: TrainedModel = serde_json::from_value(value.clone()).unwrap();
    let mut session = model.session();
    let prediction = session.classify(&frame.view()).unwrap();
    assert!(prediction.posteriors.iter().all(|p| p.is_finite()));
    for (i, (edit, words)) in cases.iter().enumerate() {
        let mut edited = value.clone();
        edit(&mut edited);
        let err = serde_json::from_value::<TrainedModel>(edited)
            .map(|_| ())
            .expect_err(&format!("{kind} case {i} ({words}) loaded"))
            .to_string();
        assert!(err.contains(words), "{kind} case {i}: {err}");
    }
}

fn classifier(v: &mut Value) -> &mut Value {
    &mut v["classifier"]
}

#[test]
fn knn_models_are_checked_on_load() {
    rejects(
        ClassifierKind::KNN,
        &[
            (&|v| classifier(v)["k"] = json!(0), "`k`"),
            (&|v| classifier(v)["k"] = json!(1000), "`k`"),
            (&|v| classifier(v)["k"] = json!(u64::MAX), "`k`"),
            (&|v| classifier(v)["classes"][0] = json!(4), "`classes`"),
            (
                &|v| classifier(v)["classes"] = json!([0, 1, 2, 3]),
                "`vectors`",
            ),
            (&|v| classifier(v)["dims"] = json!(0), "`dims`"),
            (
                &|v| classifier(v)["temperature"] = json!(0.0),
                "`temperature`",
            ),
            (
                &|v| classifier(v)["temperature"] = json!(-2.0),
                "`temperature`",
            ),
            // every stored vector relabelled to class 0: classes 1..3 have none
            (
                &|v| {
                    let n = classifier(v)["classes"].as_array().unwrap().len();
                    classifier(v)["classes"] = json!(vec![0; n]);
                },
                "no stored vector",
            ),
            (
                &|v| classifier(v)["n_classes"] = json!(u64::MAX),
                "no stored vector",
            ),
        ],
    );
}

#[test]
fn gaussian_models_are_checked_on_load() {
    for kind in [ClassifierKind::MLE, ClassifierKind::LDA] {
        rejects(
            kind,
            &[
                (&|v| classifier(v)["factors"] = json!([]), "`factors`"),
                (&|v| classifier(v)["means"] = json!([0.0, 0.0]), "`means`"),
                (&|v| classifier(v)["log_dets"] = json!([]), "`log_dets`"),
                (&|v| classifier(v)["shrinkage"] = json!([]), "`shrinkage`"),
                (
                    &|v| classifier(v)["shrinkage"][0] = json!(1.5),
                    "`shrinkage`",
                ),
                (
                    &|v| classifier(v)["temperature"] = json!(0.0),
                    "`temperature`",
                ),
                (
                    &|v| classifier(v)["temperature"] = json!(-2.0),
                    "`temperature`",
                ),
                (&|v| classifier(v)["factors"][0] = json!(0.0), "`factors`"),
                (&|v| classifier(v)["dims"] = json!(0), "`dims`"),
                (
                    &|v| classifier(v)["shared"] = json!(kind == ClassifierKind::MLE),
                    "`factors`",
                ),
                (&|v| classifier(v)["n_classes"] = json!(u64::MAX), "`means`"),
            ],
        );
    }
}

#[test]
fn svm_models_are_checked_on_load() {
    rejects(
        ClassifierKind::SVM,
        &[
            (&|v| classifier(v)["machines"] = json!([]), "`machines`"),
            (
                &|v| classifier(v)["machines"][0]["support"][0] = json!(999),
                "`machines[0].support`",
            ),
            (
                &|v| classifier(v)["machines"][2]["coefs"] = json!([]),
                "`machines[2]`",
            ),
            (&|v| classifier(v)["dims"] = json!(0), "`dims`"),
            (&|v| classifier(v)["vectors"] = json!([1.0]), "`vectors`"),
            (
                &|v| classifier(v)["temperature"] = json!(0.0),
                "`temperature`",
            ),
            (&|v| classifier(v)["c"] = json!(-1.0), "`c`"),
            (
                &|v| classifier(v)["kernel"] = json!({"kind": "rbf", "gamma": -1.0}),
                "`gamma`",
            ),
            (
                &|v| classifier(v)["n_classes"] = json!(u64::MAX),
                "`machines`",
            ),
        ],
    );
}

#[test]
fn parzen_models_need_a_usable_sigma() {
    rejects(
        ClassifierKind::PWE,
        &[
            // σ² underflows to 0: 1/(2σ²) would be infinite and every posterior NaN
            (&|v| classifier(v)["sigma"] = json!(1e-160), "`sigma`"),
            (&|v| classifier(v)["sigma"] = json!(1e160), "`sigma`"),
            (&|v| classifier(v)["dims"] = json!(0), "`dims`"),
            // finite, but its square overflows: every distance to it would be NaN
            (&|v| classifier(v)["vectors"][0] = json!(1e200), "too long"),
        ],
    );
}

#[test]
fn sizes_are_capped_before_anything_is_planned() {
    rejects(
        ClassifierKind::PWE,
        &[
            // would plan a 2^32-point FFT (tens of GB) before noticing the PCA does not fit
            (
                &|v| v["image_grid"] = json!({"rows": 65536, "cols": 65536}),
                "image_grid",
            ),
            (
                &|v| v["image_grid"] = json!({"rows": u64::MAX, "cols": 3}),
                "image_grid",
            ),
            (
                &|v| v["image_grid"] = json!({"rows": 0, "cols": 41}),
                "image_grid",
            ),
            (
                &|v| v["features"] = json!({"kind": "fft1d", "fft_len": 1u64 << 40}),
                "fft_len",
            ),
            (
                &|v| {
                    v["features"] = json!({"kind": "fft2d", "pad_rows": 1u64 << 20,
                        "pad_cols": 1u64 << 20, "form": "polar"})
                },
                "pad_rows",
            ),
            (
                &|v| {
                    v["features"] = json!({"kind": "fft2d", "form": "polar",
                        "radial_bins": u64::MAX, "angular_bins": 2})
                },
                "radial_bins",
            ),
            (
                &|v| {
                    let part = json!({"kind": "fft2d", "pad_rows": 2048, "pad_cols": 2048,
                        "form": "polar", "radial_bins": 1, "angular_bins": 1});
                    v["features"] = json!({"kind": "combined", "parts": [part, part]});
                },
                "at most",
            ),
        ],
    );
}

/// Training applies the same limits, so every model it makes can be loaded again.
#[test]
fn training_cannot_make_a_model_too_large_to_load() {
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    let frames: Vec<Frame> = (0..8).map(|i| synthetic_frame(i % 4, &mut rng)).collect();
    let images: Vec<LabeledImage<'_>> = frames
        .iter()
        .enumerate()
        .map(|(i, frame)| LabeledImage::new(frame.view(), SYNTHETIC_CLASSES[i % 4]))
        .collect();
    let config = TrainConfig {
        features: FeatureConfig::of::<presrs_core::features::Fft1dFamily>(Fft1dConfig {
            fft_len: Some(MAX_TRANSFORM_LEN + 2),
        }),
        ..TrainConfig::default()
    }
    .check()
    .unwrap();
    let err = train(&images, &[], &config).unwrap_err().to_string();
    assert!(err.contains("fft_len") && err.contains("limit"), "{err}");
}

/// A ridge model has no PCA step (it takes every feature); a file must not drop the PCA of a classifier
/// that takes principal components, nor give ridge vectors of another length than the features.
#[test]
fn a_model_without_a_pca_is_only_one_whose_classifier_takes_every_feature() {
    let (ridge, _) = model_json(ClassifierKind::RIDGE);
    assert!(ridge.get("pca").is_none(), "a ridge model stores no PCA");
    rejects(
        ClassifierKind::RIDGE,
        &[
            (
                &|v| v["features"]["fft_len"] = json!(4096),
                "2049 features per image but the classifier takes 1025",
            ),
            (
                &|v| {
                    let (with_pca, _) = model_json(ClassifierKind::LDA);
                    v["pca"] = with_pca["pca"].clone();
                },
                "the PCA gives 2 components",
            ),
        ],
    );
    rejects(
        ClassifierKind::LDA,
        &[(
            &|v| {
                v.as_object_mut().unwrap().remove("pca");
            },
            "no PCA, but the lda classifier takes principal components",
        )],
    );
}
