//! Ridge without the PCA step: `train --features rocket --classifier ridge` keeps every feature (no PCA in
//! its model) and classifies as the ridge arithmetic on those features gives, done here by hand; and
//! model files written before (a ridge model with a PCA, `fixtures/old_ridge_model/`, made by its
//! `make_fixture.sh` with the build of main at 8c3daaf) still load and classify identically.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};

use presrs::core::classifier::{ClassifierKind, RidgeFamily};
use presrs::core::features::FeatureKind;
use presrs::core::sample::SampleKind;
use presrs::method::{ClassifierChoice, FeatureChoice};
use presrs::train::{TrainOptions, train};
use presrs::{Dataset, Method, Quiet, SampleOptions};

fn shared(set: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join(format!("../../../shared/data/real/{set}/manifest.csv"))
}

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("tests/fixtures/old_ridge_model/{name}"))
}

#[test]
fn rocket_with_ridge_keeps_every_feature_and_classifies_as_the_ridge_arithmetic() {
    let options = SampleOptions {
        kind: SampleKind::Series {
            time_in_rows: false,
        },
        ..SampleOptions::default()
    };
    let dataset = Dataset::load(&shared("icub20"), &options, &Quiet).unwrap();
    let training = train(
        &dataset,
        &TrainOptions {
            per_class: Some(6),
            method: Method {
                features: FeatureChoice::Kinds(vec![FeatureKind::ROCKET]),
                classifier: ClassifierChoice::Kind(ClassifierKind::RIDGE),
                ..Method::default()
            },
            ..TrainOptions::default()
        },
    )
    .unwrap();
    let model = &training.model;
    assert!(model.pca().is_none(), "rocket + ridge has no PCA step");
    let n_features = model.n_features();
    assert!(n_features > 9000, "{n_features} features");
    assert_eq!(model.classifier_dims(), n_features);
    assert_eq!(
        model.describe_projection(),
        format!("no PCA: {n_features} standardised features")
    );
    let ridge = model.classifier().get::<RidgeFamily>().unwrap();
    let n_classes = model.class_names().len();
    let mut session = model.session();
    let mut right = 0;
    let tested: Vec<_> = dataset.samples.iter().step_by(37).collect();
    for sample in &tested {
        let features = session
            .fast_features(&sample.frame.view())
            .unwrap()
            .to_vec();
        // By hand: each feature standardised, every class's linear decision, the largest wins.
        let scores: Vec<f64> = (0..n_classes)
            .map(|class| {
                let w = ridge.coefficients(class).unwrap();
                let z = features
                    .iter()
                    .zip(ridge.means().iter().zip(ridge.scales()))
                    .map(|(x, (m, s))| (x - m) / s);
                w.iter().zip(z).map(|(w, z)| w * z).sum::<f64>() + ridge.intercepts()[class]
            })
            .collect();
        let best = (0..n_classes)
            .max_by(|&a, &b| scores[a].total_cmp(&scores[b]))
            .unwrap();
        let prediction = session.classify(&sample.frame.view()).unwrap();
        assert_eq!(prediction.class, best, "{scores:?}");
        // The posteriors are the softmax of the decisions over the model's temperature.
        let t = ridge.temperature();
        let total: f64 = scores.iter().map(|s| ((s - scores[best]) / t).exp()).sum();
        for (class, posterior) in prediction.posteriors.iter().enumerate() {
            let expected = ((scores[class] - scores[best]) / t).exp() / total;
            assert!(
                (posterior - expected).abs() < 1e-9,
                "{posterior} vs {expected}"
            );
        }
        right += usize::from(Some(prediction.label) == sample.label.as_deref());
    }
    // Most of these were training samples; well above chance (1 in 20) all the same.
    assert!(right * 2 > tested.len(), "{right} of {}", tested.len());
}

#[test]
fn a_ridge_model_with_a_pca_written_before_loads_and_classifies_identically() {
    let file = presrs::io::model_file::load_model(&fixture("model.json")).unwrap();
    let model = &file.model;
    assert_eq!(model.pca().map(|pca| pca.n_components()), Some(4));
    assert_eq!(model.classifier().kind(), ClassifierKind::RIDGE);
    assert_eq!(model.describe_projection(), "PCA 4 components");
    let expected: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(fixture("expected.json")).unwrap()).unwrap();
    let results = expected["results"].as_array().unwrap();
    assert_eq!(results.len(), 9);
    let mut session = model.session();
    for result in results {
        let path = fixture(result["file"].as_str().unwrap());
        let image = presrs::io::npy::read_npy(&path).unwrap();
        let prediction = session.classify(&image.frame(0).unwrap()).unwrap();
        assert_eq!(prediction.label, result["label"].as_str().unwrap());
        for (class, name) in model.class_names().iter().enumerate() {
            let old = result["posteriors"][name].as_f64().unwrap();
            let new = prediction.posteriors[class];
            assert!((new - old).abs() <= 1e-12, "{name}: {new} vs {old}");
        }
    }
}
