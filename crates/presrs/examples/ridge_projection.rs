//! Rocket + ridge with and without the PCA step, on presrs's own draws (`eval --export-draws DIR`):
//! for every draw, MiniRocket is fitted on the training samples (as `train` does), then ridge sees
//! (a) the 51 principal components of the features (the pipeline's path: PCA, each component
//! standardised) or (b) the full standardised features. Prints each variant's accuracy per repeat
//! (pooled over the repeat's folds), their mean and sample standard deviation, and the mean fit time.
//!
//! `cargo run --release -p presrs --example ridge_projection -- DIR` (bench/real/README.md).

use std::time::Instant;

use presrs::core::Grid;
use presrs::core::classifier::{ClassifierConfig, LabeledVectors, RidgeConfig, RidgeFamily};
use presrs::core::features::{FeatureConfig, FitImages, RocketFamily, RocketParams};
use presrs::core::projection::pca::Pca;

type Result<T> = std::result::Result<T, Box<dyn std::error::Error>>;

struct Draw {
    repeat: u64,
    train: Vec<usize>,
    validation: Vec<usize>,
    test: Vec<usize>,
}

fn indices(value: &serde_json::Value, key: &str) -> Result<Vec<usize>> {
    value[key]
        .as_array()
        .ok_or(format!("draw without {key}"))?
        .iter()
        .map(|i| i.as_u64().map(|i| i as usize).ok_or_else(|| "index".into()))
        .collect()
}

fn main() -> Result<()> {
    let dir = std::path::PathBuf::from(std::env::args().nth(1).ok_or("usage: DIR")?);
    let document: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("draws.json"))?)?;
    let images = presrs::io::npy::read_npy(&dir.join("images.npy"))?;
    let grid: Grid = images.grid();
    let labels: Vec<String> = document["labels"]
        .as_array()
        .ok_or("labels")?
        .iter()
        .map(|l| l.as_str().unwrap_or_default().to_owned())
        .collect();
    if labels.len() != images.frame_count() {
        return Err(format!(
            "{} labels for {} images",
            labels.len(),
            images.frame_count()
        )
        .into());
    }
    let mut names = labels.clone();
    names.sort();
    names.dedup();
    let classes: Vec<usize> = labels
        .iter()
        .map(|l| names.binary_search(l).unwrap_or(0))
        .collect();
    let draws: Vec<Draw> = document["draws"]
        .as_array()
        .ok_or("draws")?
        .iter()
        .map(|d| {
            Ok(Draw {
                repeat: d["repeat"].as_u64().ok_or("repeat")?,
                train: indices(d, "train")?,
                validation: indices(d, "validation")?,
                test: indices(d, "test")?,
            })
        })
        .collect::<Result<_>>()?;
    let data = images.data();
    let image = |i: usize| &data[i * grid.len()..(i + 1) * grid.len()];
    let ridge = ClassifierConfig::of::<RidgeFamily>(RidgeConfig::default());
    // (variant, repeat) -> (right, tested); fit seconds per variant
    let mut tally: std::collections::BTreeMap<(usize, u64), (usize, usize)> = Default::default();
    let mut fit_seconds = [0.0; 2];
    for draw in &draws {
        let train_values: Vec<f64> = draw.train.iter().flat_map(|&i| image(i).to_vec()).collect();
        let rocket = FeatureConfig::of::<RocketFamily>(RocketParams::default()).fit(FitImages {
            grid,
            values: &train_values,
        })?;
        let mut extractor = rocket.extractor(grid)?;
        let p = extractor.output_len();
        let features_of =
            |set: &[usize], extractor: &mut presrs::core::features::FeatureExtractor| {
                let mut rows = vec![0.0; set.len() * p];
                for (&i, row) in set.iter().zip(rows.chunks_exact_mut(p)) {
                    extractor.extract_into(image(i), row)?;
                }
                Ok::<_, presrs::core::CoreError>(rows)
            };
        let train = features_of(&draw.train, &mut extractor)?;
        let validation = features_of(&draw.validation, &mut extractor)?;
        let test = features_of(&draw.test, &mut extractor)?;
        let class_of = |set: &[usize]| set.iter().map(|&i| classes[i]).collect::<Vec<_>>();
        let (train_classes, validation_classes) =
            (class_of(&draw.train), class_of(&draw.validation));
        for variant in 0..2 {
            let start = Instant::now();
            let (dims, tr, va, te) = if variant == 0 {
                let pca = Pca::fit(&train, p, 51)?;
                let d = pca.n_components();
                let project = |rows: &[f64]| -> Result<Vec<f64>> {
                    let mut out = vec![0.0; rows.len() / p * d];
                    let mut scratch = pca.scratch();
                    for (x, o) in rows.chunks_exact(p).zip(out.chunks_exact_mut(d)) {
                        pca.project_fast_into(x, &mut scratch, o)?;
                    }
                    Ok(out)
                };
                (d, project(&train)?, project(&validation)?, project(&test)?)
            } else {
                (p, train.clone(), validation.clone(), test.clone())
            };
            let model = ridge.fit(
                LabeledVectors {
                    vectors: &tr,
                    classes: &train_classes,
                },
                LabeledVectors {
                    vectors: &va,
                    classes: &validation_classes,
                },
                names.len(),
                dims,
            )?;
            fit_seconds[variant] += start.elapsed().as_secs_f64();
            let mut scratch = model.scratch();
            let mut posteriors = vec![0.0; names.len()];
            let entry = tally.entry((variant, draw.repeat)).or_default();
            for (x, &i) in te.chunks_exact(dims).zip(&draw.test) {
                let class = model.classify_into(x, &mut scratch, &mut posteriors)?;
                entry.0 += usize::from(class == classes[i]);
                entry.1 += 1;
            }
        }
    }
    for (variant, name) in [
        "PCA(51), components standardised",
        "full features standardised",
    ]
    .iter()
    .enumerate()
    {
        let accuracies: Vec<f64> = tally
            .iter()
            .filter(|((v, _), _)| *v == variant)
            .map(|(_, &(right, tested))| right as f64 / tested as f64)
            .collect();
        let n = accuracies.len() as f64;
        let mean = accuracies.iter().sum::<f64>() / n;
        let std = (accuracies.iter().map(|a| (a - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0))
            .sqrt();
        println!(
            "rocket + ridge, {name}: {:.1} +- {:.1} % ({:?}), PCA + ridge fit {:.2} s per model",
            100.0 * mean,
            100.0 * std,
            accuracies
                .iter()
                .map(|a| (1000.0 * a).round() / 10.0)
                .collect::<Vec<_>>(),
            fit_seconds[variant] / draws.len() as f64
        );
    }
    Ok(())
}
