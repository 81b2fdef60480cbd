//! `presrs reproduce`: the paper's experiment end to end on the built-in simulator (Tables I and II);
//! the workflow is [`presrs::reproduce`]'s, this prints what it found.

use std::io::Write;
use std::path::PathBuf;

use presrs::reproduce::{ReproduceOptions, check_options, reproduce};
use presrs_sim::SimConfig;

use super::common::TerminalProgress;
use crate::printer::reproduce_tables::{print_load_and_methods, print_tables};

/// Reproduce the paper: simulate the hopper on wood, carpet, clay and grass at gaits G1-G3, print
/// Table I (forward velocities), train on G2 (20 images per terrain: 13 + 7) and test on all other images
/// (Table II), repeated with new draws; also train on G1 and G3.
///
/// The simulated data set is written to DIR/dataset (TekScan movies, manifest.csv, truth, config.json and
/// stamp.json, as `presrs simulate --out` writes them), the heavier hopper's to DIR/dataset-load1.30. A
/// later run with the same seed, hops per gait and presrs version reads them back instead of simulating
/// (the results are the same), and says so; on any mismatch or missing or changed file it says why and
/// simulates afresh. `presrs simulate --out DIR/dataset --seed S` makes a data set this reuses.
#[derive(Debug, clap::Args)]
#[command(
    after_help = "Data sets: the simulated data set is kept in DIR/dataset (the layout of \
`presrs simulate --out`: recordings/*.asf TekScan movies, manifest.csv, truth/, config.json, and \
stamp.json, written last), the heavier hopper's of the load test in DIR/dataset-load1.30. A later run \
with the same seed, hops per gait and presrs version reads them back instead of simulating (the results \
are the same) and says so; on any mismatch, a missing or changed file, or a simulator that no longer \
makes its first trial, it says why and simulates afresh.

Examples:
  presrs reproduce --out results --seed 1
  presrs reproduce --out results --seed 1 --resimulate
  presrs simulate --out results/dataset --seed 1   # reproduce reuses it
  presrs reproduce --out small --hops-per-gait 10 --per-class 8 \\
    --validation 3 --repeats 3"
)]
pub struct ReproduceArgs {
    /// Folder for results.json, results.md, the report and the simulated data sets (dataset/,
    /// dataset-load1.30/).
    #[arg(long, default_value = "results")]
    pub out: PathBuf,
    /// Seed of the simulation and of the training draws.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Repeats of each training draw, at least 1.
    #[arg(long, default_value_t = 10, value_parser = super::usage::positive_count)]
    pub repeats: usize,
    /// Training images drawn per terrain (the paper's 20), of which --validation choose the Parzen
    /// window's sigma; smaller values allow a small --hops-per-gait (at least this many per gait).
    #[arg(long, default_value_t = 20)]
    pub per_class: usize,
    /// Of the --per-class images, how many validate (the paper's 7).
    #[arg(long, default_value_t = 7)]
    pub validation: usize,
    /// Recorded hops per terrain and gait, at least --per-class (default: the simulator's paper-sized
    /// experiment, 80).
    #[arg(long, value_parser = super::usage::positive_count)]
    pub hops_per_gait: Option<usize>,
    /// Skip the HTML report (DIR/report/index.html).
    #[arg(long)]
    pub no_report: bool,
    /// Extra load of the load-independence test, as a fraction of the nominal body mass: the heavier
    /// hopper weighs nominal x (1 + EXTRA_LOAD), so it must be above -1 (a negative value tests a
    /// lighter hopper).
    #[arg(long, default_value_t = 0.3, allow_negative_numbers = true, value_parser = crate::args::values::extra_load)]
    pub extra_load: f64,
    /// Skip the comparison of every feature family x classifier (same draws as Table II).
    #[arg(long)]
    pub no_comparison: bool,
    /// Simulate the data sets afresh (and rewrite them) even when DIR holds matching ones.
    #[arg(long)]
    pub resimulate: bool,
}

impl ReproduceArgs {
    fn options(&self) -> ReproduceOptions {
        ReproduceOptions {
            out: self.out.clone(),
            seed: self.seed,
            repeats: self.repeats,
            per_class: self.per_class,
            validation: self.validation,
            hops_per_gait: self.hops_per_gait,
            report: !self.no_report,
            extra_load: self.extra_load,
            comparison: !self.no_comparison,
            resimulate: self.resimulate,
        }
    }
}

pub fn run(args: &ReproduceArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    let started = std::time::Instant::now();
    presrs_io::output_path::check_output_dir(&args.out)?;
    let options = args.options();
    if let Err(message) = check_options(&options, &SimConfig::default()) {
        return Err(super::usage::UsageError::error(
            "reproduce",
            message.render(presrs::Face::Cli),
        ));
    }
    let reproduction = reproduce(&options, &TerminalProgress::default())?;
    print_tables(&reproduction, out)?;
    print_load_and_methods(&reproduction, out)?;
    writeln!(
        out,
        "\nwrote {} and {}{} ({:.1} s in all)",
        reproduction.json_path.display(),
        reproduction.markdown_path.display(),
        reproduction
            .report_path
            .as_ref()
            .map_or_else(String::new, |p| format!(" and the report {}", p.display())),
        started.elapsed().as_secs_f64()
    )?;
    Ok(())
}
