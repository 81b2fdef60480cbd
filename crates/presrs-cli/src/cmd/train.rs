//! `presrs train`: train the pipeline on a manifest and write a model file.

use std::io::Write;
use std::path::PathBuf;

use presrs::train::TrainOptions;
use presrs::train::early::DecisionPoints;
use presrs::train::profile::{
    GaitTableSim, ProfileChoice, ProfileRequest, TrainRequest, train_model_file,
};
use presrs_core::split::ValidationSize;
use presrs_io::model_file::save_model;

use super::common::{PipelineArgs, SampleArgs, TerminalProgress, print_load_warnings};
use crate::printer::profile_summary::profile_summary;

/// Train a classifier from a dataset manifest (CSV: path,label and optionally condition,group,frame,load).
#[derive(Debug, clap::Args)]
#[command(
    after_help = "By default the feature family and classifier are chosen automatically by validation \
inside the training data (--features auto --classifier auto; --full-search: no time budget and, on whole samples, every family).\n\n\
Examples (sim/ made by `presrs simulate --out sim`; the second is the paper's method and protocol: \
1-D |FFT| + Parzen window, 20 images per terrain from gait G2, 7 of them for choosing sigma):
  presrs train --manifest sim/manifest.csv --out g2.model.json
  presrs train --manifest sim/manifest.csv --out g2.model.json \\
    --features fft1d --classifier pwe --train-condition G2 \\
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
    /// Random samples drawn per class, at least 1 (default: every sample); a class with fewer gives
    /// all it has, with one warning.
    #[arg(long, value_parser = super::usage::positive_count)]
    pub per_class: Option<usize>,
    /// Of those, how many per class validate the hyper-parameters: a count (7) or a fraction (0.35).
    #[arg(long, default_value = "0.35", value_parser = |t: &str| t.parse::<ValidationSize>().map_err(|e| e.to_string()))]
    pub validation: ValidationSize,
    /// Seed of the random draw.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Write an online profile into the model file (calibration and sample frame learned from the
    /// manifest's recordings by offline segmentation), for `presrs stream` and `presrs simulate --adaptive`:
    /// a stream then classifies from its first stance, with no warm-up. The default when the training
    /// samples come from movies (learned from them as read for training); this flag asks for it on other data too, and
    /// fails if it cannot be learned.
    #[arg(long)]
    pub online_profile: bool,
    /// Write no online profile, even when the training samples come from movies.
    #[arg(long, conflicts_with_all = ["online_profile", "gait_table"])]
    pub no_online_profile: bool,
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
    #[arg(long, value_name = "none|FROM:TO:STEP", default_value = presrs::sim::gait::GaitSweep::DEFAULT_TEXT,
          value_parser = presrs::sim::gait::parse_gait_sweep)]
    pub gait_sweep: presrs::sim::gait::GaitSweep,
    /// With --sample stance: also train classifiers for decisions before lift-off, at these frames after
    /// touchdown (each on the training stances cut there, with the whole stance's method, or its own
    /// automatic choice when the method is automatic), and the confidence threshold and deadline
    /// point of `stream --decide-at auto`: `8,16,32,whole`, or `auto` (points at 10-80 % of the
    /// median training stance). `whole`: the lift-off only.
    #[arg(long, value_name = "K,...,whole|auto", default_value = "whole",
          value_parser = |t: &str| t.parse::<DecisionPoints>())]
    pub decide_at: DecisionPoints,
    #[command(flatten)]
    pub pipeline: PipelineArgs,
    #[command(flatten)]
    pub samples: SampleArgs,
    #[command(flatten)]
    pub novelty: super::common::NoveltyArgs,
}

pub fn run(args: &TrainArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    presrs_io::output_path::check_output_file(&args.out)?;
    args.samples.check_settings("train")?;
    let options = TrainOptions {
        condition: args.train_condition.clone(),
        per_class: args.per_class,
        validation: args.validation,
        seed: args.seed,
        method: args.pipeline.method(),
        novelty: args.novelty.novelty,
    };
    let choice = if args.online_profile || args.gait_table.is_some() {
        ProfileChoice::Required
    } else if args.no_online_profile {
        ProfileChoice::Never
    } else {
        ProfileChoice::WhenMovies
    };
    let sim = GaitTableSim {
        config: args.sim_config.as_deref(),
        seed: args.seed,
        sweep: args.gait_sweep,
    };
    let request = TrainRequest {
        manifest: &args.manifest,
        sample: args.samples.choice()?,
        samples: args.samples.options_or_frames()?,
        whole: args.samples.whole_sample(),
        train: options,
        decide_at: args.decide_at.clone(),
        profile: ProfileRequest {
            choice,
            gait_table: args.gait_table.as_deref(),
            sim,
        },
        command: Some(std::env::args().collect::<Vec<_>>().join(" ")),
    };
    // The automatic choice can take a while: a spinner on a terminal, a line every few seconds otherwise.
    let progress = TerminalProgress::default();
    let trained = train_model_file(&request, &progress, &mut |dataset, race| {
        for line in race.iter().flat_map(|race| race.lines()) {
            stderr_line!("note: {line}");
        }
        print_load_warnings(dataset);
    })?;
    let (training, file) = (&trained.training, &trained.file);
    for warning in &training.warnings {
        stderr_line!("warning: {warning}");
    }
    let model = &training.model;
    if let Some(selection) = model.selection() {
        for line in
            crate::printer::selection_table::selection_lines(selection, model, training.n_train())
        {
            writeln!(out, "{line}")?;
        }
    }
    if let Some(warning) = &trained.profile.warning {
        stderr_line!("warning: {warning}");
    }
    if let Some(measured) = &trained.profile.measured {
        write!(out, "{}", measured.format())?;
    }
    save_model(&args.out, file)?;
    writeln!(
        out,
        "trained {} on {} {} ({} training + {} validation) of {} classes: {}",
        model.classifier().kind(),
        training.n_train() + training.n_validation(),
        model.sample().nouns(),
        training.n_train(),
        training.n_validation(),
        model.class_names().len(),
        model.class_names().join(", ")
    )?;
    writeln!(out, "{}", presrs::describe::pipeline_summary(model))?;
    // (the automatic choice's cost line says the same for its winner)
    if model.selection().is_none()
        && let Some(searched_on) = model.summary().searched_on
    {
        writeln!(
            out,
            "{}'s hyper-parameters searched on a stratified subsample of {searched_on} of the {} samples \
             (large data), then fitted on all of them",
            model.classifier().kind(),
            training.n_train() + training.n_validation()
        )?;
    }
    if let Some(early) = presrs::describe::early_summary(model) {
        // (each point's own automatic choice has its budget; the rest is after the model's)
        let budget =
            if model.selection().is_some() && model.early().is_some_and(|e| e.cost.is_some()) {
                ", not covered by the budget"
            } else {
                ""
            };
        writeln!(out, "{early}{budget}")?;
    }
    if let Some(seconds) = training.novelty_seconds {
        let what = model.novelty().map_or_else(
            || "none (every decision is one of the classes)".to_owned(),
            |novelty| novelty.describe(),
        );
        let budget = if model.selection().is_some() {
            ", not covered by the budget"
        } else {
            ""
        };
        writeln!(out, "novelty: {what}; fitted in {seconds:.1} s{budget}")?;
    }
    if let Some(profile) = &file.online {
        writeln!(out, "{}", profile_summary(profile))?;
    }
    writeln!(out, "model written to {}", args.out.display())?;
    if let Some(memory) = presrs::resources::MemoryUse::now(trained.dataset.samples.len()) {
        writeln!(out, "{}", memory.line())?;
    }
    Ok(())
}
