//! Scaffolding shared by the whole-stance tests: a small MiniRocket model trained on a data set.

use presrs::Dataset;
use presrs::core::classifier::ClassifierKind;
use presrs::core::crop::Crop;
use presrs::core::features::{FeatureConfig, RocketFamily, RocketParams};
use presrs::core::pipeline::{
    DecisionPoint, EarlyDecisions, LabeledImage, TrainConfig, TrainedModel, train, train_like,
};
use presrs::core::preprocess::Preprocess;
use presrs::core::sample::SampleKind;

/// Every sample of `dataset` with its label, as `train` takes them.
pub fn labeled_images(dataset: &Dataset) -> Vec<LabeledImage<'_>> {
    dataset
        .samples
        .iter()
        .map(|s| LabeledImage::new(s.frame.view(), s.label.as_deref().unwrap()))
        .collect()
}

/// A model of 168 MiniRocket features, `dims` components and `classifier`, trained on every sample of
/// `dataset` (no validation images) and stored with `sample`, the kind it classifies.
pub fn small_rocket_model(
    dataset: &Dataset,
    classifier: ClassifierKind,
    dims: usize,
    sample: SampleKind,
) -> TrainedModel {
    let images = labeled_images(dataset);
    let config = TrainConfig {
        crop: Crop::NONE,
        features: FeatureConfig::of::<RocketFamily>(RocketParams {
            num_features: 168,
            ..RocketParams::default()
        }),
        dims,
        classifier: classifier.default_config(),
        preprocess: Preprocess::NONE,
    }
    .check()
    .unwrap();
    train(&images, &[], &config)
        .unwrap()
        .with_sample(sample)
        .unwrap()
}

/// `model` (trained on `dataset`'s samples) with a classifier for each decision point the data set was
/// read with ([`presrs::SampleOptions::decision_points`]), each trained by `model`'s method on the
/// stances cut there; no `auto` threshold.
#[allow(dead_code)]
pub fn with_points(model: TrainedModel, dataset: &Dataset) -> TrainedModel {
    let points = dataset
        .stances
        .points
        .iter()
        .map(|(frames, cuts)| {
            let images: Vec<LabeledImage<'_>> = cuts
                .iter()
                .zip(&dataset.samples)
                .map(|(cut, s)| LabeledImage::new(cut.view(), s.label.as_deref().unwrap()))
                .collect();
            DecisionPoint {
                frames: *frames,
                model: train_like(&model, &images, &[]).unwrap(),
            }
        })
        .collect();
    model
        .with_early(EarlyDecisions {
            points,
            auto: None,
            cost: None,
        })
        .unwrap()
}
