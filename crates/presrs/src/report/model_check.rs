//! A given model tested on a data set's labelled samples (the report's evaluation when a model is given).

use std::collections::BTreeMap;
use std::time::Instant;

use presrs_core::Frame;
use presrs_core::evaluation::{Confusion, EvalReport, MeanStd, Protocol, RepeatResult};
use presrs_core::pipeline::{LabeledImage, TrainedModel};
use presrs_core::reliability::Reliability;
use presrs_core::split::ValidationSize;

use crate::dataset::Sample;
use crate::error::{Error, Result};

/// `(frame, label, condition)` of every sample, when all have a label.
pub(super) fn labelled(samples: &[Sample]) -> Option<Vec<(&Frame, &str, Option<&str>)>> {
    samples
        .iter()
        .map(|s| Some((&s.frame, s.label.as_deref()?, s.condition.as_deref())))
        .collect()
}

/// Evaluation samples (no group) of labelled frames.
pub(super) fn eval_samples<'a>(
    triples: &[(&'a Frame, &'a str, Option<&'a str>)],
) -> Vec<LabeledImage<'a>> {
    triples
        .iter()
        .map(|&(frame, label, condition)| LabeledImage {
            frame: frame.view(),
            label,
            condition,
            group: None,
        })
        .collect()
}

/// Tests `model` on every sample (one "repeat"): its confusion matrix and accuracy per condition.
pub(super) fn model_on_samples(model: &TrainedModel, samples: &[Sample]) -> Result<EvalReport> {
    let frames: Vec<_> = samples.iter().map(|s| s.frame.view()).collect();
    let started = Instant::now();
    let results = model.classify_batch(&frames);
    let elapsed = started.elapsed();
    let labels: Vec<String> = model.class_names().to_vec();
    let mut counts = vec![vec![0u64; labels.len()]; labels.len()];
    let mut by_condition: BTreeMap<String, (u64, u64)> = BTreeMap::new();
    let (mut correct, mut total) = (0u64, 0u64);
    let mut reliability = Reliability::default();
    for (sample, result) in samples.iter().zip(results) {
        let prediction = result?;
        let predicted = prediction.class;
        let Some(truth) = sample
            .label
            .as_deref()
            .and_then(|l| labels.iter().position(|x| x == l))
        else {
            continue;
        };
        counts[truth][predicted] += 1;
        reliability.add(prediction.confidence, truth == predicted);
        let hit = u64::from(truth == predicted);
        let entry = by_condition
            .entry(sample.condition.clone().unwrap_or_else(|| "all".to_owned()))
            .or_default();
        entry.0 += hit;
        entry.1 += 1;
        correct += hit;
        total += 1;
    }
    if total == 0 {
        return Err(Error::data(format!(
            "no sample has a label the model knows ({})",
            labels.join(", ")
        )));
    }
    let ratio = |c: u64, t: u64| c as f64 / t.max(1) as f64;
    let per_condition: BTreeMap<String, f64> = by_condition
        .iter()
        .map(|(k, &(c, t))| (k.clone(), ratio(c, t)))
        .collect();
    Ok(EvalReport {
        protocol: Protocol::TrainCondition {
            condition: None,
            per_class: None,
            validation: ValidationSize::default(),
        },
        repeats: vec![RepeatResult {
            seed: 0,
            overall_accuracy: ratio(correct, total),
            per_condition: per_condition.clone(),
            sigmas: model.sigma().into_iter().collect(),
            n_train: 0,
            n_validation: 0,
            n_test: total as usize,
            train_seconds: 0.0,
            folds: 1,
        }],
        overall: MeanStd::of(&[ratio(correct, total)]),
        per_condition: per_condition
            .iter()
            .map(|(k, &v)| (k.clone(), MeanStd::of(&[v])))
            .collect(),
        confusion: Confusion { labels, counts },
        median_classify_ns: (elapsed.as_nanos() / samples.len().max(1) as u128) as u64,
        unclassified: 0,
        reliability,
    })
}
