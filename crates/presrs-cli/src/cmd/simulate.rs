//! `presrs simulate`: write the built-in simulated dataset (TekScan movies + manifest + ground truth).
//!
//! The folder layout is [`presrs::sim`]'s.
//!
//! With `--track SPEC` it writes no data set but runs the terrain-to-gait comparison ([`presrs::sim::gait`], [`run_track_comparison`]).

use presrs_core::online::DecideAt;
use std::io::Write;
use std::path::PathBuf;

use presrs::sim::gait::{TrackOptions, compare_on_track};
use presrs::sim::{dataset_names, load_config, read_terrain_image, write_dataset};
use presrs_sim::{DatasetSpec, SimConfig};

use super::common::TerminalProgress;
use crate::args::values::TerrainImage;

/// Simulate the one-legged hopper with PreSRS on the paper's terrains and gaits.
#[derive(Debug, clap::Args)]
pub struct SimulateArgs {
    #[command(flatten)]
    pub novelty: super::common::NoveltyArgs,
    /// Output folder; receives manifest.csv, one TekScan ASCII movie per trial (recordings/), the ground
    /// truth (truth/), table1.csv, config.json and, last, stamp.json (what it was made from and a
    /// fingerprint of every file: `presrs reproduce --out R` reuses R/dataset when it matches).
    #[arg(long, required_unless_present_any = ["print_config", "track"])]
    pub out: Option<PathBuf>,
    /// Replace the data set already in --out (its manifest.csv and recordings); without it an --out
    /// that holds a manifest.csv is refused.
    #[arg(long)]
    pub force: bool,
    /// Seed of every random choice; the same seed gives the same bytes.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Recorded hops (stance images) per terrain for each gait, at least 1 [default: 80, i.e. 320 per
    /// gait].
    #[arg(long, value_parser = super::usage::positive_count)]
    pub hops_per_gait: Option<usize>,
    /// Terrains, comma separated, each once: wood, carpet, clay, grass, or names given with
    /// --terrain-image [default: the four built-ins plus every --terrain-image].
    #[arg(long, value_delimiter = ',')]
    pub terrains: Vec<String>,
    /// Gaits, comma separated, each once (names from the configuration) [default: G1,G2,G3].
    #[arg(long, value_delimiter = ',')]
    pub gaits: Vec<String>,
    /// Body mass including payload, kg, above 0 [default: the configuration's robot.body_mass_kg, 2.5].
    #[arg(long, value_parser = super::usage::positive_number)]
    pub load: Option<f64>,
    /// JSON file of parameter overrides (any subset of what --print-config shows).
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Print the complete configuration (defaults plus --config overrides) as JSON and exit.
    #[arg(long)]
    pub print_config: bool,
    /// A terrain given as a greyscale height-map image, NAME=PNG (repeatable), e.g.
    /// --terrain-image photo_grass=grass.png. NAME must differ from the
    /// built-in terrains' names and from the other images'.
    #[arg(long, value_name = "NAME=PNG", value_parser = crate::args::values::terrain_image)]
    pub terrain_image: Vec<TerrainImage>,
    /// Run a track instead of writing a data set: terrain:metres segments in sequence (built-in
    /// terrains), e.g. wood:3,grass:3,clay:3,carpet:3. Each fixed gait runs it (and the adaptive policy
    /// with --adaptive). Not with --terrains or --terrain-image, which choose a data set's terrains.
    #[arg(long, value_name = "SPEC", value_parser = crate::args::values::track,
          conflicts_with_all = ["terrains", "terrain_image"])]
    pub track: Option<String>,
    /// Model file for the adaptive run: every stance is classified online (the model's online profile)
    /// and the robot switches to the gait its terrain-to-gait table recommends. Without a table in the
    /// model, the table is measured with the simulator first.
    #[arg(long, value_name = "MODEL", requires = "track")]
    pub adaptive: Option<PathBuf>,
    /// With --adaptive and a model without a terrain-to-gait table: the `beta_des` grid searched around
    /// each configured gait when measuring it, FROM:TO:STEP in radians, or none (the configured gaits
    /// only). Variants are named BASE@BETA, e.g. G3@0.62.
    #[arg(long, value_name = "none|FROM:TO:STEP", default_value = presrs::sim::gait::GaitSweep::DEFAULT_TEXT,
          value_parser = presrs::sim::gait::parse_gait_sweep)]
    pub gait_sweep: presrs::sim::gait::GaitSweep,
    /// The adaptive run switches gait only after this many consecutive stances classified as the same
    /// terrain (1: on every decision, the default: on 3 m segments a delay costs more than the wrong
    /// switches it saves).
    #[arg(long, default_value_t = 1, requires = "adaptive", value_parser = super::usage::positive_count)]
    pub confirm: usize,
    /// Fixed gaits to compare with, comma separated (configured gaits or variants such as G3@0.62)
    /// [default: every gait of the configuration and every gait the terrain-to-gait table recommends].
    #[arg(long, value_delimiter = ',', requires = "track")]
    pub fixed_gait: Vec<String>,
    /// Gait of the adaptive run at the start line (it knows no terrain yet): a configured gait or a
    /// variant such as G3@0.62 [default: the second gait of the configuration, G2].
    #[arg(long, requires = "adaptive")]
    pub start_gait: Option<String>,
    /// With a whole-stance --adaptive model: decide K frames after touchdown, or at its first
    /// confident decision point (`auto`, else at its deadline point), instead of at lift-off (a moment the model was trained for).
    #[arg(long, value_name = "K|auto", requires = "adaptive")]
    pub decide_at: Option<DecideAt>,
    /// Runs per policy, at least 1 (seeds --seed, --seed + 1, ...); every policy runs on the same seeds.
    #[arg(long, default_value_t = 3, requires = "track", value_parser = super::usage::positive_count)]
    pub repeats: usize,
    /// Also write the comparison, every run and every hop as JSON to this file.
    #[arg(long, requires = "track")]
    pub json: Option<PathBuf>,
}

pub fn run(args: &SimulateArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    let config = load_config(args.config.as_deref())?;
    if args.print_config {
        writeln!(out, "{}", config.to_json_pretty())?;
        return Ok(());
    }
    if let Some(track) = &args.track {
        return run_track_comparison(args, &config, track, out);
    }
    let Some(out_dir) = args.out.as_deref() else {
        anyhow::bail!("--out DIR is required");
    };
    presrs::sim::check_dataset_out(out_dir, args.force)?;
    let image_names: Vec<&str> = args.terrain_image.iter().map(|i| i.name.as_str()).collect();
    let (terrains, gaits) = dataset_names(&args.terrains, &image_names, &args.gaits, &config)
        .map_err(|message| {
            super::usage::UsageError::error("simulate", message.render(presrs::Face::Cli))
        })?;
    let images = args
        .terrain_image
        .iter()
        .map(|image| read_terrain_image(&image.name, &image.path))
        .collect::<presrs::Result<Vec<_>>>()?;
    let mut spec = DatasetSpec::paper(args.seed);
    spec.terrains = terrains;
    spec.gaits = gaits;
    spec.hops_per_gait = args.hops_per_gait;
    spec.load_kg = args.load;
    spec.image_terrains = images;

    let start = std::time::Instant::now();
    let summary = write_dataset(&config, &spec, out_dir, &TerminalProgress::default())?;
    let secs = start.elapsed().as_secs_f64();
    write!(out, "{}", summary.velocity.format_with_paper())?;
    writeln!(
        out,
        "{} trials, {} hops (mean stance {:.0} ms), {} frames in {:.1} s; {} trial(s) rerun after a fall",
        summary.trials,
        summary.hops,
        summary.mean_stance_s * 1e3,
        summary.frames,
        secs,
        summary.reruns
    )?;
    writeln!(out, "manifest: {}", summary.manifest.display())?;
    Ok(())
}

/// `--track`: fixed gaits and (with `--adaptive`) the adaptive policy on the same seeds.
pub fn run_track_comparison(
    args: &SimulateArgs,
    config: &SimConfig,
    spec: &str,
    out: &mut dyn Write,
) -> anyhow::Result<()> {
    args.json
        .as_deref()
        .map(presrs_io::output_path::check_output_file)
        .transpose()?;
    // Gait names are judged with the configuration, before anything runs.
    if let Err(message) = presrs::sim::check_gaits(presrs::Opt::StartGait, &args.start_gait, config)
        .and_then(|()| presrs::sim::check_gaits(presrs::Opt::FixedGait, &args.fixed_gait, config))
    {
        return Err(super::usage::UsageError::error(
            "simulate",
            message.render(presrs::Face::Cli),
        ));
    }
    let options = TrackOptions {
        seed: args.seed,
        repeats: args.repeats,
        adaptive: args.adaptive.clone(),
        gait_sweep: args.gait_sweep,
        confirm: args.confirm,
        fixed_gaits: args.fixed_gait.clone(),
        start_gait: args.start_gait.clone(),
        decide_at: args.decide_at,
        novelty: args.novelty.novelty,
    };
    let outcome = compare_on_track(config, spec, &options, &TerminalProgress::default())?;
    for note in &outcome.notes {
        writeln!(out, "{note}")?;
    }
    if let Some(measured) = &outcome.measured {
        write!(out, "{}", measured.format())?;
    }
    write!(out, "{}", outcome.comparison.format())?;
    if let Some(path) = &args.json {
        outcome.comparison.write_json(path)?;
        writeln!(out, "JSON: {}", path.display())?;
    }
    Ok(())
}
