//! `eval --leave-class-out`: how the novelty score does with a class never seen. Each chosen class is
//! held out of training in turn, on the evaluation's own draws (every repeat and fold): a model is
//! trained on the other classes (the method asked for, the automatic choice included), its novelty
//! score fitted on those training images alone, and every test sample decided. Measured per held-out
//! class: the score's AUROC (held-out class against known test samples; the same for 1 - the highest
//! posterior beside it), the share of held-out samples decided as a known class with confidence 0.9 or
//! more (with and without the novelty score), and the share of known test samples decided `unknown`.
//! With the score, the confidence is the one decisions report (the posterior capped by the sample's
//! credibility); without it, the classifier's posterior. What the cap costs known samples is measured
//! beside: the share of known test samples decided as a known class at 0.9 or more.

use std::collections::BTreeSet;

use presrs_core::CheckedTrainConfig;
use presrs_core::novelty::{DEFAULT_REJECTION, auroc};
use presrs_core::pipeline::{LabeledImage, TrainedModel, train};
use serde::Serialize;

use crate::dataset::Sample;
use crate::error::{Context, Error, Result};
use crate::eval::EvalSetup;
use crate::progress::Progress;
use crate::train::with_novelty_by_recordings;

/// A decision counts as confident at this confidence or more.
pub const CONFIDENT: f64 = 0.9;

/// Which classes are held out.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum HeldOutClasses {
    /// This many, spread evenly over the sorted labels (the first and the last included).
    Spread(usize),
    /// These, by name.
    Named(Vec<String>),
}

impl std::str::FromStr for HeldOutClasses {
    type Err = String;

    /// `6` (a count, at least 1) or `cable_pipe,rock` (names).
    fn from_str(text: &str) -> std::result::Result<Self, String> {
        let text = text.trim();
        if let Ok(count) = text.parse::<usize>() {
            return if count == 0 {
                Err("hold out at least one class".to_owned())
            } else {
                Ok(Self::Spread(count))
            };
        }
        let names: Vec<String> = text
            .split(',')
            .map(|name| name.trim().to_owned())
            .filter(|name| !name.is_empty())
            .collect();
        if names.is_empty() {
            return Err("name the classes to hold out, or give a count".to_owned());
        }
        Ok(Self::Named(names))
    }
}

impl HeldOutClasses {
    /// The classes of `labels` (sorted, distinct) to hold out.
    pub fn resolve(&self, labels: &[&str]) -> std::result::Result<Vec<String>, String> {
        match self {
            Self::Spread(count) => {
                let count = (*count).min(labels.len());
                let last = labels.len().saturating_sub(1);
                let mut chosen: Vec<String> = (0..count)
                    .map(|k| {
                        let index = if count <= 1 {
                            0
                        } else {
                            (k * last + (count - 1) / 2) / (count - 1)
                        };
                        labels[index].to_owned()
                    })
                    .collect();
                chosen.dedup();
                Ok(chosen)
            }
            Self::Named(names) => {
                for name in names {
                    if !labels.contains(&name.as_str()) {
                        return Err(format!(
                            "no class {name:?} to hold out (classes: {})",
                            labels.join(", ")
                        ));
                    }
                }
                Ok(names.clone())
            }
        }
    }
}

/// What one held-out class gave, over every draw.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct HeldOutClass {
    pub class: String,
    /// Held-out (novel) and known test samples decided.
    pub novel_samples: usize,
    pub known_samples: usize,
    /// AUROC of the novelty score, novel against known (`null` when one side is empty).
    pub auroc: Option<f64>,
    /// AUROC of 1 - the highest posterior, for comparison.
    pub auroc_posterior: Option<f64>,
    /// Share of novel samples decided as a known class with confidence >= 0.9, with the novelty score.
    pub confident_known: f64,
    /// The same without the novelty score (every decision a known class).
    pub confident_known_without: f64,
    /// Share of known test samples decided `unknown`.
    pub known_rejected: f64,
    /// Share of novel samples decided `unknown`.
    pub novel_rejected: f64,
    /// Accuracy on the known test samples (their nearest class, whether `unknown` or not).
    pub known_accuracy: f64,
    /// Share of known test samples decided as a known class with confidence >= 0.9, with the novelty
    /// score (its confidence capped by the credibility) and without it.
    pub known_confident: f64,
    pub known_confident_without: f64,
}

/// The result of `eval --leave-class-out`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LeaveClassOut {
    /// The protocol of the draws (`leave one group out`, ...).
    pub protocol: String,
    /// The share of held-out known training samples each threshold was set to reject.
    pub rejection: f64,
    pub confident: f64,
    pub classes: Vec<HeldOutClass>,
    /// Means over the held-out classes.
    pub mean_auroc: Option<f64>,
    pub mean_auroc_posterior: Option<f64>,
    pub mean_confident_known: f64,
    pub mean_confident_known_without: f64,
    pub mean_known_rejected: f64,
    pub mean_known_confident: f64,
    pub mean_known_confident_without: f64,
    /// Models trained (held-out classes x draws).
    pub models: usize,
    /// Models without a novelty score: their decisions are never `unknown` (none since a wide
    /// classifier's vectors are reduced for the score; kept for the JSON's readers).
    pub models_without_novelty: usize,
}

impl LeaveClassOut {
    /// The figures as the HTML report shows them.
    pub fn report_rows(&self) -> presrs_report::NoveltyResult {
        presrs_report::NoveltyResult {
            note: format!(
                "Draws: {}; {} models; each threshold set to reject {:.0} % of the known training \
                 samples held out inside the training data.",
                self.protocol,
                self.models,
                100.0 * self.rejection
            ),
            rows: self
                .classes
                .iter()
                .map(|c| presrs_report::NoveltyRow {
                    class: c.class.clone(),
                    novel_samples: c.novel_samples,
                    known_samples: c.known_samples,
                    auroc: c.auroc,
                    auroc_posterior: c.auroc_posterior,
                    confident_known: c.confident_known,
                    confident_known_without: c.confident_known_without,
                    known_rejected: c.known_rejected,
                })
                .collect(),
        }
    }
}

/// One test sample's decision.
struct Decided {
    novel: bool,
    right: bool,
    /// The confidence reported (the posterior capped by the credibility, with a novelty score).
    confidence: f64,
    /// The classifier's posterior for its class.
    posterior: f64,
    score: Option<f64>,
    unknown: bool,
}

/// Holds each of `held_out` classes out in turn on `setup`'s draws (see the module documentation).
pub fn leave_class_out(
    setup: &EvalSetup<'_>,
    held_out: &HeldOutClasses,
    progress: &dyn Progress,
) -> Result<LeaveClassOut> {
    let name = setup.dataset().path().display().to_string();
    let samples = setup.samples();
    let labels: BTreeSet<&str> = samples.iter().map(|s| s.label).collect();
    let labels: Vec<&str> = labels.into_iter().collect();
    if labels.len() < 3 {
        return Err(Error::data(format!(
            "{name}: holding a class out needs three classes or more (two to train on), got {}",
            labels.len()
        )));
    }
    let classes = held_out
        .resolve(&labels)
        .map_err(|reason| Error::data(format!("{name}: {reason}")))?;
    let draws = setup.draws()?;
    let method = &setup.options.method;
    let grid = samples[0].frame.grid();
    let config = method.train_config(grid)?;
    let candidates = if method.is_auto() {
        method.candidates_for(
            grid,
            false,
            &setup.dataset().sample,
            crate::method::race_draws_for(samples.len()),
        )?
    } else {
        Vec::new()
    };
    progress.start(
        "leaving classes out",
        Some((classes.len() * draws.len()) as u64),
    );
    let mut results = Vec::with_capacity(classes.len());
    let (mut models, mut without) = (0, 0);
    for class in &classes {
        let mut decided = Vec::new();
        for draw in &draws {
            let kept = |set: &[usize]| -> Vec<usize> {
                set.iter()
                    .copied()
                    .filter(|&i| samples[i].label != class.as_str())
                    .collect()
            };
            let (train_kept, validation_kept) = (kept(&draw.train), kept(&draw.validation));
            let pick = |set: &[usize]| -> Vec<LabeledImage<'_>> {
                set.iter().map(|&i| samples[i]).collect()
            };
            let (train_images, validation_images) = (pick(&train_kept), pick(&validation_kept));
            let recordings: Vec<&Sample> = train_kept
                .iter()
                .chain(&validation_kept)
                .map(|&i| &setup.dataset().samples[i])
                .collect();
            let model = train_without(
                (&train_images, &validation_images),
                &recordings,
                (method, &config, &candidates),
                draw.seed,
            )
            .with_context(|| format!("{name}: with class {class} held out"))?;
            models += 1;
            without += usize::from(model.novelty().is_none());
            let test: Vec<LabeledImage<'_>> = draw.test.iter().map(|&i| samples[i]).collect();
            decide(&model, &test, class, &mut decided)?;
            progress.advance(1);
        }
        results.push(summarise(class, &decided));
    }
    progress.finish();
    Ok(summary(setup, results, models, without))
}

/// The method trained on the images of a draw without the held-out class, with its novelty score.
fn train_without(
    (train_images, validation_images): (&[LabeledImage<'_>], &[LabeledImage<'_>]),
    recordings: &[&Sample],
    (method, config, candidates): (
        &crate::method::Method,
        &CheckedTrainConfig,
        &[CheckedTrainConfig],
    ),
    seed: u64,
) -> Result<TrainedModel> {
    let model = if method.is_auto() {
        presrs_core::selection::train_auto(
            train_images,
            validation_images,
            &method.auto_choice(candidates),
            seed,
        )?
    } else {
        train(train_images, validation_images, config)?
    };
    let all: Vec<LabeledImage<'_>> = train_images
        .iter()
        .chain(validation_images)
        .copied()
        .collect();
    Ok(with_novelty_by_recordings(model, &all, recordings)?)
}

/// Decides every test image, noting whether it is of the held-out class.
fn decide(
    model: &TrainedModel,
    test: &[LabeledImage<'_>],
    held_out: &str,
    decided: &mut Vec<Decided>,
) -> Result<()> {
    let frames: Vec<_> = test.iter().map(|image| image.frame).collect();
    for (image, result) in test.iter().zip(model.classify_batch(&frames)) {
        let classification = result?;
        let novelty = classification.novelty;
        decided.push(Decided {
            novel: image.label == held_out,
            right: model.class_names()[classification.class] == image.label,
            confidence: classification.confidence,
            posterior: classification.posteriors[classification.class],
            score: novelty.map(|n| n.score),
            unknown: novelty.is_some_and(|n| n.unknown),
        });
    }
    Ok(())
}

fn share(count: usize, of: usize) -> f64 {
    if of == 0 {
        0.0
    } else {
        count as f64 / of as f64
    }
}

/// One held-out class's figures from its decisions over every draw.
fn summarise(class: &str, decided: &[Decided]) -> HeldOutClass {
    let (novel, known): (Vec<&Decided>, Vec<&Decided>) = decided.iter().partition(|d| d.novel);
    let scores = |set: &[&Decided]| -> Option<Vec<f64>> { set.iter().map(|d| d.score).collect() };
    let posterior =
        |set: &[&Decided]| -> Vec<f64> { set.iter().map(|d| 1.0 - d.posterior).collect() };
    let auroc_of_scores = match (scores(&novel), scores(&known)) {
        (Some(novel), Some(known)) => auroc(&novel, &known),
        _ => None,
    };
    let count =
        |set: &[&Decided], keep: &dyn Fn(&Decided) -> bool| set.iter().filter(|d| keep(d)).count();
    HeldOutClass {
        class: class.to_owned(),
        novel_samples: novel.len(),
        known_samples: known.len(),
        auroc: auroc_of_scores,
        auroc_posterior: auroc(&posterior(&novel), &posterior(&known)),
        confident_known: share(
            count(&novel, &|d| !d.unknown && d.confidence >= CONFIDENT),
            novel.len(),
        ),
        confident_known_without: share(count(&novel, &|d| d.posterior >= CONFIDENT), novel.len()),
        known_rejected: share(count(&known, &|d| d.unknown), known.len()),
        novel_rejected: share(count(&novel, &|d| d.unknown), novel.len()),
        known_accuracy: share(count(&known, &|d| d.right), known.len()),
        known_confident: share(
            count(&known, &|d| !d.unknown && d.confidence >= CONFIDENT),
            known.len(),
        ),
        known_confident_without: share(count(&known, &|d| d.posterior >= CONFIDENT), known.len()),
    }
}

fn summary(
    setup: &EvalSetup<'_>,
    classes: Vec<HeldOutClass>,
    models: usize,
    models_without_novelty: usize,
) -> LeaveClassOut {
    let mean = |value: &dyn Fn(&HeldOutClass) -> f64| {
        classes.iter().map(value).sum::<f64>() / classes.len().max(1) as f64
    };
    let mean_of = |value: &dyn Fn(&HeldOutClass) -> Option<f64>| -> Option<f64> {
        let values: Option<Vec<f64>> = classes.iter().map(value).collect();
        values
            .filter(|v| !v.is_empty())
            .map(|v| v.iter().sum::<f64>() / v.len() as f64)
    };
    LeaveClassOut {
        protocol: setup.options.holdout.describe(),
        rejection: DEFAULT_REJECTION,
        confident: CONFIDENT,
        mean_auroc: mean_of(&|c| c.auroc),
        mean_auroc_posterior: mean_of(&|c| c.auroc_posterior),
        mean_confident_known: mean(&|c| c.confident_known),
        mean_confident_known_without: mean(&|c| c.confident_known_without),
        mean_known_rejected: mean(&|c| c.known_rejected),
        mean_known_confident: mean(&|c| c.known_confident),
        mean_known_confident_without: mean(&|c| c.known_confident_without),
        models,
        models_without_novelty,
        classes,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn classes_are_spread_or_named() {
        let labels = ["a", "b", "c", "d", "e", "f", "g"];
        let spread = HeldOutClasses::Spread(3).resolve(&labels).unwrap();
        assert_eq!(spread, ["a", "d", "g"]);
        assert_eq!(
            HeldOutClasses::Spread(10).resolve(&labels).unwrap().len(),
            7
        );
        assert_eq!(
            "b, c".parse::<HeldOutClasses>().unwrap(),
            HeldOutClasses::Named(vec!["b".into(), "c".into()])
        );
        assert!("0".parse::<HeldOutClasses>().is_err());
        assert!(
            HeldOutClasses::Named(vec!["z".into()])
                .resolve(&labels)
                .is_err()
        );
    }
}
