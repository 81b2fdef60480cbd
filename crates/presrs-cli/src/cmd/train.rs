//! `presrs train`: train the pipeline on a manifest and write a model file.

use std::collections::BTreeMap;
use std::io::Write;
use std::path::PathBuf;

use anyhow::Context;
use presrs_core::pipeline::{LabeledImage, train};
use presrs_core::split::{ValidationSize, stratified_split};
use presrs_io::dataset::Sample;
use presrs_io::model_file::{DeadSenselProvenance, ModelFile, Provenance, save_model};

use super::common::{PipelineArgs, SampleArgs, load_manifest};

/// Train a classifier from a dataset manifest (CSV: path,label and optionally condition,group,frame,load).
#[derive(Debug, clap::Args)]
#[command(
    after_help = "By default the feature family and classifier are chosen automatically by validation \
inside the training data (--features auto --classifier auto; --full-search for every family).\n\n\
Example (the paper's method and protocol: 1-D |FFT| + Parzen window, 20 images per terrain from gait G2, \
7 of them for choosing sigma):\n  presrs train --manifest sim/manifest.csv --out g2.model.json \
--features fft1d --classifier pwe --train-condition G2 --per-class 20 --validation 7 --seed 1"
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
    /// Random samples drawn per class, at least 1 (default: every sample).
    #[arg(long, value_parser = super::common::parse_positive)]
    pub per_class: Option<usize>,
    /// Of those, how many per class validate the hyper-parameters: a count (7) or a fraction (0.35).
    #[arg(long, default_value = "0.35", value_parser = |t: &str| t.parse::<ValidationSize>().map_err(|e| e.to_string()))]
    pub validation: ValidationSize,
    /// Seed of the random draw.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Also write an online profile into the model file (calibration and sample frame learned from the
    /// manifest's recordings by offline segmentation), for `presrs stream` and `presrs simulate --adaptive`.
    /// Off by default: it reads every recording of the manifest once more.
    #[arg(long)]
    pub online_profile: bool,
    /// Terrain-to-gait table for the online profile (implies --online-profile): `sim` measures, with the
    /// simulator, the fastest gait that never fell on each terrain of the model, in steady runs or
    /// stepping onto another terrain, with a margin in `beta_des` (`presrs_sim::track::gait_table`, over
    /// the configured gaits and their --gait-sweep variants; ~30 s on 2 cores), or give it:
    /// TERRAIN=GAIT,... (configured gaits or variants such as G3@0.62).
    #[arg(long, value_name = "sim|TERRAIN=GAIT,...")]
    pub gait_table: Option<String>,
    /// Simulator configuration JSON for `--gait-table sim` (its gaits are the candidates) [default: the
    /// built-in configuration].
    #[arg(long, requires = "gait_table")]
    pub sim_config: Option<PathBuf>,
    /// For `--gait-table sim`: the `beta_des` grid searched around each configured gait, FROM:TO:STEP in
    /// radians, or none (the configured gaits only). Variants are named BASE@BETA, e.g. G3@0.62.
    #[arg(long, value_name = "none|FROM:TO:STEP", default_value = super::track::GaitSweep::DEFAULT_TEXT,
          value_parser = super::track::parse_gait_sweep)]
    pub gait_sweep: super::track::GaitSweep,
    #[command(flatten)]
    pub pipeline: PipelineArgs,
    #[command(flatten)]
    pub samples: SampleArgs,
}

pub fn run(args: &TrainArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    let (manifest, loaded) = load_manifest(&args.manifest, &args.samples)?;
    manifest.require_column("label", "training needs a label for every sample")?;
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
    super::common::check_validation_set(&args.pipeline, args.validation, split.validation.len())
        .with_context(|| format!("{}: cannot train", args.manifest.display()))?;
    let grid = pool[0].frame.grid();
    let config = args.pipeline.train_config(grid)?;
    let images = |indices: &[usize]| -> Vec<LabeledImage<'_>> {
        indices
            .iter()
            .map(|&i| LabeledImage::new(pool[i].frame.view(), labels[i]))
            .collect()
    };
    let (train_images, validation_images) = (images(&split.train), images(&split.validation));
    let model = if args.pipeline.is_auto() {
        // validate the candidates inside the training data; across its conditions when it spans several
        let conditions: Option<Vec<&str>> = split
            .train
            .iter()
            .chain(&split.validation)
            .map(|&i| pool[i].condition.as_deref())
            .collect();
        presrs_core::selection::train_auto(
            &train_images,
            &validation_images,
            conditions.as_deref(),
            &args.pipeline.candidates(grid, false)?,
            args.seed,
        )
    } else {
        train(&train_images, &validation_images, &config)
    }
    .map_err(|err| anyhow::anyhow!("{}: training failed: {err}", args.manifest.display()))?;
    let kept = model.pca().n_components();
    if let Some(dims) = args.pipeline.dims
        && kept < dims
    {
        stderr_line!(
            "warning: --dims {dims}: kept {kept} principal components, the most that {} training images \
             of {} features allow (at most one fewer than the training images, and no more than the \
             features)",
            split.train.len(),
            model.pca().n_features()
        );
    }
    if let Some(selection) = model.selection() {
        writeln!(out, "automatic choice ({}):", selection.method)?;
        for (i, score) in selection.scores.iter().enumerate() {
            let mark = if i == selection.chosen { "*" } else { " " };
            match &score.error {
                None => writeln!(
                    out,
                    "{mark} {:<18} {:<5} {:6.2} % +- {:.2}",
                    score.features,
                    score.classifier,
                    100.0 * score.accuracy.mean,
                    100.0 * score.accuracy.std
                )?,
                Some(err) => writeln!(
                    out,
                    "{mark} {:<18} {:<5} failed: {err}",
                    score.features, score.classifier
                )?,
            }
        }
        if let Some(chosen) = selection.chosen() {
            writeln!(
                out,
                "chosen: {} + {} (the paper's method: --features fft1d --classifier pwe)",
                chosen.features, chosen.classifier
            )?;
        }
    }
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
        dead_sensels: Some(DeadSenselProvenance {
            corrected: !args.samples.keep_dead_sensels,
            sensels: loaded.dead_sensels.sensels(),
            recordings: loaded.dead_sensels.recordings.len(),
        }),
    };
    let mut file = ModelFile::new(model.clone(), provenance);
    if args.online_profile || args.gait_table.is_some() {
        let mut profile = super::stream::learn_profile(&args.manifest).with_context(|| {
            format!(
                "{}: cannot learn the online profile",
                args.manifest.display()
            )
        })?;
        if let Some(source) = &args.gait_table {
            profile.gait_table = terrain_gait_table(source, model.class_names(), args, out)?;
        }
        file.online = Some(profile);
    }
    save_model(&args.out, &file)?;
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
        "crop {} -> {} image, preprocessing {}, {} features ({}), PCA {} components{}",
        model.crop(),
        model.image_grid(),
        model.preprocess(),
        model.pca().n_features(),
        model.features().name(),
        model.pca().n_components(),
        model
            .sigma()
            .map_or_else(String::new, |s| format!(", sigma {s:.4}"))
    )?;
    if let Some(profile) = &file.online {
        let table: Vec<String> = profile
            .gait_table
            .iter()
            .map(|(t, g)| format!("{t}={g}"))
            .collect();
        writeln!(
            out,
            "online profile: sample frame k = {}, {}, gait table {}",
            profile.params.sample_offset,
            if profile.calibration.is_some() {
                "calibrated"
            } else {
                "warm-up calibration"
            },
            if table.is_empty() {
                "empty".to_owned()
            } else {
                table.join(",")
            }
        )?;
    }
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

/// The terrain-to-gait table of `--gait-table`: measured with the simulator (`sim`) or given.
fn terrain_gait_table(
    source: &str,
    class_names: &[String],
    args: &TrainArgs,
    out: &mut dyn Write,
) -> anyhow::Result<BTreeMap<String, String>> {
    if source.trim() != "sim" {
        let mut table = BTreeMap::new();
        for entry in source.split(',').filter(|e| !e.trim().is_empty()) {
            let (terrain, gait) = entry
                .split_once('=')
                .filter(|(t, g)| !t.trim().is_empty() && !g.trim().is_empty())
                .with_context(|| {
                    format!("--gait-table expects sim or TERRAIN=GAIT,..., got {entry:?}")
                })?;
            table.insert(terrain.trim().to_owned(), gait.trim().to_owned());
        }
        return Ok(table);
    }
    let config = super::simulate::load_config(args.sim_config.as_deref())?;
    let table =
        super::track::measure_gait_table(&config, args.seed, class_names, args.gait_sweep, out)?;
    Ok(table.best)
}
