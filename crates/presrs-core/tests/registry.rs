//! A classifier family added through the registration alone: a toy nearest-class-mean classifier,
//! defined here, registered at run time, then trained, stored, loaded and chosen through the pipeline
//! like a built-in one. Also: the built-in families are stored exactly as the tagged enums stored them.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use presrs_core::classifier::{
    ClassifierConfig, ClassifierFamily, ClassifierKind, ClassifierModel, FitData, register,
};
use presrs_core::error::{CoreError, Result};
use presrs_core::pipeline::{LabeledImage, TrainConfig, TrainedModel, train};
use presrs_core::selection::{AutoChoice, ValidateBy, select};
use presrs_core::testing::{SYNTHETIC_CLASSES, labeled_set, synthetic_frame};
use presrs_core::{Crop, Frame};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// Nearest class mean; posteriors from the squared distances at temperature `scale`.
#[derive(Debug)]
struct NearestMean;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct MeanConfig {
    scale: f64,
}

impl Default for MeanConfig {
    fn default() -> Self {
        Self { scale: 1.0 }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct MeanModel {
    dims: usize,
    scale: f64,
    /// Row-major `n_classes x dims`.
    means: Vec<f64>,
}

impl ClassifierFamily for NearestMean {
    const NAME: &'static str = "nearest_mean";
    type Config = MeanConfig;
    type Model = MeanModel;
    type Scratch = ();

    fn check(config: &MeanConfig) -> Result<()> {
        if config.scale.is_finite() && config.scale > 0.0 {
            return Ok(());
        }
        Err(CoreError::Param {
            name: "scale",
            reason: "must be positive".into(),
        })
    }

    fn fit(config: &MeanConfig, data: FitData<'_>) -> Result<MeanModel> {
        let dims = data.dims;
        let mut means = vec![0.0; data.n_classes * dims];
        let mut counts = vec![0usize; data.n_classes];
        for set in [data.train, data.validation] {
            for (x, &class) in set.vectors.chunks_exact(dims).zip(set.classes) {
                counts[class] += 1;
                for (m, v) in means[class * dims..(class + 1) * dims].iter_mut().zip(x) {
                    *m += v;
                }
            }
        }
        for (mean, &count) in means.chunks_exact_mut(dims).zip(&counts) {
            if count == 0 {
                return Err(CoreError::NotEnoughData("a class without vectors".into()));
            }
            mean.iter_mut().for_each(|m| *m /= count as f64);
        }
        Ok(MeanModel {
            dims,
            scale: config.scale,
            means,
        })
    }

    fn dims(model: &MeanModel) -> usize {
        model.dims
    }

    fn n_classes(model: &MeanModel) -> usize {
        model.means.len() / model.dims
    }

    fn describe(model: &MeanModel) -> String {
        format!("scale {}", model.scale)
    }

    fn scratch(_model: &MeanModel) {}

    fn classify_into(
        model: &MeanModel,
        x: &[f64],
        _scratch: &mut (),
        posteriors: &mut [f64],
    ) -> Result<usize> {
        for (p, mean) in posteriors
            .iter_mut()
            .zip(model.means.chunks_exact(model.dims))
        {
            *p = -mean
                .iter()
                .zip(x)
                .map(|(m, v)| (m - v) * (m - v))
                .sum::<f64>();
        }
        // The nearest mean gets exp(0) = 1, the others less.
        let nearest = posteriors.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        posteriors
            .iter_mut()
            .for_each(|p| *p = ((*p - nearest) / model.scale).exp());
        let total: f64 = posteriors.iter().sum();
        posteriors.iter_mut().for_each(|p| *p /= total);
        Ok((0..posteriors.len())
            .max_by(|&a, &b| posteriors[a].total_cmp(&posteriors[b]))
            .unwrap_or(0))
    }
}

/// Another family that claims a built-in name.
#[derive(Debug)]
struct FakePwe;

impl ClassifierFamily for FakePwe {
    const NAME: &'static str = "pwe";
    type Config = MeanConfig;
    type Model = MeanModel;
    type Scratch = ();

    fn check(config: &MeanConfig) -> Result<()> {
        NearestMean::check(config)
    }

    fn fit(config: &MeanConfig, data: FitData<'_>) -> Result<MeanModel> {
        NearestMean::fit(config, data)
    }

    fn dims(model: &MeanModel) -> usize {
        model.dims
    }

    fn n_classes(model: &MeanModel) -> usize {
        NearestMean::n_classes(model)
    }

    fn describe(model: &MeanModel) -> String {
        NearestMean::describe(model)
    }

    fn scratch(_model: &MeanModel) {}

    fn classify_into(
        model: &MeanModel,
        x: &[f64],
        scratch: &mut (),
        posteriors: &mut [f64],
    ) -> Result<usize> {
        NearestMean::classify_into(model, x, scratch, posteriors)
    }
}

fn images<'a>(set: &'a [(Frame, &'static str)]) -> Vec<LabeledImage<'a>> {
    set.iter()
        .map(|(frame, label)| LabeledImage::new(frame.view(), label))
        .collect()
}

fn toy_config() -> TrainConfig {
    TrainConfig {
        crop: Crop::PAPER,
        dims: 8,
        classifier: ClassifierConfig::of::<NearestMean>(MeanConfig { scale: 0.5 }),
        ..TrainConfig::default()
    }
}

#[test]
fn a_registered_toy_classifier_trains_classifies_round_trips_and_is_chosen() {
    let kind = register::<NearestMean>().unwrap();
    assert_eq!(
        register::<NearestMean>().unwrap(),
        kind,
        "registering twice"
    );
    assert_eq!(ClassifierKind::parse(" Nearest_Mean ").unwrap(), kind);
    assert!(ClassifierKind::all().contains(&kind));
    assert!(ClassifierKind::auto_candidates().contains(&kind));
    assert!(register::<FakePwe>().is_err(), "a taken name");
    assert_eq!(kind.default_config().kind(), kind);
    assert!(
        ClassifierConfig::of::<NearestMean>(MeanConfig { scale: -1.0 })
            .check()
            .is_err()
    );

    // Trained through the pipeline.
    let (train_set, validation_set, test_set) =
        (labeled_set(10, 1), labeled_set(5, 2), labeled_set(10, 3));
    let config = toy_config().check().unwrap();
    let model = train(&images(&train_set), &images(&validation_set), &config).unwrap();
    assert_eq!(model.classifier().kind(), kind);
    assert_eq!(model.classifier().describe(), "scale 0.5");
    let stored = model.classifier().get::<NearestMean>().unwrap();
    assert_eq!((stored.dims, stored.means.len()), (8, 4 * 8));
    let mut session = model.session();
    let right = test_set
        .iter()
        .filter(|(frame, label)| session.classify(&frame.view()).unwrap().label == *label)
        .count();
    assert!(
        right * 10 >= test_set.len() * 9,
        "{right} of {}",
        test_set.len()
    );

    // Stored and loaded: the same JSON, the same answers.
    let json = serde_json::to_string(&model).unwrap();
    assert!(json.contains(r#""classifier":{"kind":"nearest_mean","dims":8,"scale":0.5,"#));
    let back: TrainedModel = serde_json::from_str(&json).unwrap();
    assert_eq!(serde_json::to_string(&back).unwrap(), json);
    let frames: Vec<_> = test_set.iter().map(|(frame, _)| frame.view()).collect();
    let (a, b) = (model.classify_batch(&frames), back.classify_batch(&frames));
    for (a, b) in a.into_iter().zip(b) {
        let (a, b) = (a.unwrap(), b.unwrap());
        assert!((a.posteriors.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        assert_eq!(a, b);
    }

    // Picked up by the automatic choice's list of candidates, and scored there beside LDA.
    let candidates: Vec<_> = ClassifierKind::auto_candidates()
        .into_iter()
        .filter(|k| *k == kind || *k == ClassifierKind::LDA)
        .map(|k| {
            TrainConfig {
                classifier: k.default_config(),
                ..toy_config()
            }
            .check()
            .unwrap()
        })
        .collect();
    assert_eq!(candidates.len(), 2);
    let mut all = images(&train_set);
    all.extend(images(&validation_set));
    let selection = select(&all, &AutoChoice::new(&candidates, ValidateBy::Split), 1).unwrap();
    let names: Vec<&str> = selection
        .scores
        .iter()
        .map(|s| s.classifier.as_str())
        .collect();
    assert!(names.contains(&"nearest_mean"), "{names:?}");
    assert!(selection.scores.iter().all(|s| s.error.is_none()));
}

#[test]
fn built_in_models_are_stored_as_the_tagged_enum_stored_them() {
    // `#[serde(tag = "kind")]` wrote the name first, then the model's own fields in order.
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    let set: Vec<(Frame, &str)> = (0..4 * 12)
        .map(|i| (synthetic_frame(i % 4, &mut rng), SYNTHETIC_CLASSES[i % 4]))
        .collect();
    let (train_set, validation_set) = set.split_at(4 * 8);
    for kind in [
        ClassifierKind::PWE,
        ClassifierKind::MLE,
        ClassifierKind::LDA,
        ClassifierKind::SVM,
        ClassifierKind::KNN,
        ClassifierKind::RIDGE,
    ] {
        let config = TrainConfig {
            dims: 6,
            classifier: kind.default_config(),
            ..TrainConfig::default()
        };
        let model = train(
            &images(train_set),
            &images(validation_set),
            &config.clone().check().unwrap(),
        )
        .unwrap();
        let classifier = model.classifier();
        let json = serde_json::to_string(classifier).unwrap();
        let own = match kind.as_str() {
            "pwe" => serde_json::to_string(
                classifier
                    .get::<presrs_core::classifier::PweFamily>()
                    .unwrap(),
            ),
            "mle" => serde_json::to_string(
                classifier
                    .get::<presrs_core::classifier::MleFamily>()
                    .unwrap(),
            ),
            "lda" => serde_json::to_string(
                classifier
                    .get::<presrs_core::classifier::LdaFamily>()
                    .unwrap(),
            ),
            "svm" => serde_json::to_string(
                classifier
                    .get::<presrs_core::classifier::SvmFamily>()
                    .unwrap(),
            ),
            "knn" => serde_json::to_string(
                classifier
                    .get::<presrs_core::classifier::KnnFamily>()
                    .unwrap(),
            ),
            _ => serde_json::to_string(
                classifier
                    .get::<presrs_core::classifier::RidgeFamily>()
                    .unwrap(),
            ),
        }
        .unwrap();
        assert_eq!(
            json,
            format!(r#"{{"kind":"{kind}",{}"#, &own[1..]),
            "{kind}"
        );
        let back: ClassifierModel = serde_json::from_str(&json).unwrap();
        assert_eq!(&back, classifier);
        let config_json = serde_json::to_string(&config.classifier).unwrap();
        assert!(
            config_json.starts_with(&format!(r#"{{"kind":"{kind}""#)),
            "{config_json}"
        );
        let config_back: ClassifierConfig = serde_json::from_str(&config_json).unwrap();
        assert_eq!(config_back, config.classifier);
    }
    let err = serde_json::from_str::<ClassifierConfig>(r#"{"kind":"lasso"}"#).unwrap_err();
    assert!(err.to_string().contains("unknown variant `lasso`"), "{err}");
    let err = serde_json::from_str::<ClassifierConfig>(r#"{"kind":"pwe","sigmaa":1}"#).unwrap_err();
    assert!(err.to_string().contains("sigmaa"), "{err}");
}
