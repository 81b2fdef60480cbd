//! `presrs train`: train the pipeline on a manifest and write a model file.

use std::collections::BTreeMap;
use std::io::Write;
use std::path::PathBuf;

use anyhow::Context;
use presrs_core::pipeline::{LabeledImage, train};
use presrs_core::split::{ValidationSize, stratified_split};
use presrs_io::dataset::Sample;
use presrs_io::model_file::{ModelFile, Provenance, save_model};

use super::common::{PipelineArgs, SampleArgs, load_manifest};

/// Train a classifier from a dataset manifest (CSV: path,label[,condition,group,frame,load]).
#[derive(Debug, clap::Args)]
#[command(
    after_help = "Example (the paper's protocol: 20 images per terrain from gait G2, 7 of them \
for choosing sigma):\n  presrs train --manifest sim/manifest.csv --out g2.model.json --train-condition G2 \
--per-class 20 --validation 7 --seed 1"
)]
pub struct TrainArgs {
    /// The dataset manifest.
    #[arg(long)]
    pub manifest: PathBuf,
    /// Where to write the model (JSON).
    #[arg(long)]
    pub out: PathBuf,
    /// Train only on samples of this condition (the manifest's `condition` column, e.g. a gait).
    #[arg(long)]
    pub train_condition: Option<String>,
    /// Random samples drawn per class (default: every sample).
    #[arg(long)]
    pub per_class: Option<usize>,
    /// Of those, how many per class validate the hyper-parameters: a count (7) or a fraction (0.35).
    #[arg(long, default_value = "0.35", value_parser = |t: &str| t.parse::<ValidationSize>().map_err(|e| e.to_string()))]
    pub validation: ValidationSize,
    /// Seed of the random draw.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    #[command(flatten)]
    pub pipeline: PipelineArgs,
    #[command(flatten)]
    pub samples: SampleArgs,
}

pub fn run(args: &TrainArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    let (manifest, loaded) = load_manifest(&args.manifest, &args.samples)?;
    let pool: Vec<&Sample> = match &args.train_condition {
        Some(condition) => {
            let pool: Vec<&Sample> = loaded
                .samples
                .iter()
                .filter(|sample| sample.condition.as_deref() == Some(condition.as_str()))
                .collect();
            if pool.is_empty() {
                let mut known: Vec<&str> = loaded
                    .samples
                    .iter()
                    .filter_map(|s| s.condition.as_deref())
                    .collect();
                known.sort_unstable();
                known.dedup();
                anyhow::bail!(
                    "{}: no sample has condition {condition:?} (conditions present: {})",
                    args.manifest.display(),
                    if known.is_empty() {
                        "none".to_owned()
                    } else {
                        known.join(", ")
                    }
                );
            }
            pool
        }
        None => loaded.samples.iter().collect(),
    };
    let labels = sample_labels(&manifest.source, &pool)?;
    let split = stratified_split(&labels, args.per_class, args.validation, args.seed)
        .with_context(|| format!("{}: cannot draw the training set", args.manifest.display()))?;
    let grid = pool[0].frame.grid();
    let config = args.pipeline.train_config(grid)?;
    let images = |indices: &[usize]| -> Vec<LabeledImage<'_>> {
        indices
            .iter()
            .map(|&i| LabeledImage::new(pool[i].frame.view(), labels[i]))
            .collect()
    };
    let (train_images, validation_images) = (images(&split.train), images(&split.validation));
    let model = train(&train_images, &validation_images, &config)
        .map_err(|err| anyhow::anyhow!("{}: training failed: {err}", args.manifest.display()))?;
    let count = |indices: &[usize]| {
        let mut counts = BTreeMap::new();
        for &i in indices {
            *counts.entry(labels[i].to_owned()).or_insert(0) += 1;
        }
        counts
    };
    let provenance = Provenance {
        manifest: Some(args.manifest.display().to_string()),
        manifest_sha256: Some(manifest.sha256.clone()),
        seed: Some(args.seed),
        train_condition: args.train_condition.clone(),
        train_counts: count(&split.train),
        validation_counts: count(&split.validation),
        command: Some(std::env::args().collect::<Vec<_>>().join(" ")),
        created_unix_s: std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .ok()
            .map(|d| d.as_secs()),
    };
    save_model(&args.out, &ModelFile::new(model.clone(), provenance))?;
    writeln!(
        out,
        "trained {} on {} images ({} training + {} validation) of {} classes: {}",
        model.classifier().kind(),
        split.train.len() + split.validation.len(),
        split.train.len(),
        split.validation.len(),
        model.class_names().len(),
        model.class_names().join(", ")
    )?;
    writeln!(
        out,
        "crop {} -> {} image, {} features, PCA {} components{}",
        model.crop(),
        model.image_grid(),
        model.pca().n_features(),
        model.pca().n_components(),
        model
            .sigma()
            .map_or_else(String::new, |s| format!(", sigma {s:.4}"))
    )?;
    writeln!(out, "model written to {}", args.out.display())?;
    Ok(())
}

/// The label of every sample; a sample without one is an error naming its manifest line.
pub fn sample_labels<'s>(
    manifest: &std::path::Path,
    samples: &[&'s Sample],
) -> anyhow::Result<Vec<&'s str>> {
    samples
        .iter()
        .map(|sample| {
            sample.label.as_deref().ok_or_else(|| {
                anyhow::anyhow!(
                    "{} line {}: field `label` is empty; training needs a label for every sample",
                    manifest.display(),
                    sample.manifest_line
                )
            })
        })
        .collect()
}
