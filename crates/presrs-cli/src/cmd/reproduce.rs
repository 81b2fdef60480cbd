//! `presrs reproduce`: the paper's experiment end to end on the built-in simulator (Tables I and II);
//! the workflow is [`presrs::reproduce`]'s, this prints what it found.

use std::io::Write;
use std::path::PathBuf;

use presrs::evaluate::calibration_line;
use presrs::report::PAPER_TABLE2;
use presrs::reproduce::{
    PAPER_CLASSIFY_NS, ReproduceOptions, Reproduction, check_options, reproduce,
};
use presrs_sim::SimConfig;

use super::common::TerminalProgress;

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

/// Where the data set came from, Table I, the stance images, Table II and the train x test matrix.
fn print_tables(reproduction: &Reproduction, out: &mut dyn Write) -> anyhow::Result<()> {
    let results = &reproduction.results;
    if let Some(main) = results.datasets.get("main") {
        writeln!(out, "{}", main.note)?;
    }
    writeln!(out, "Table I (simulated vs paper)")?;
    writeln!(out, "{}", reproduction.table1_text)?;
    let segmentation = &results.segmentation;
    writeln!(
        out,
        "{} stance images ({}); segmentation found {} of {} simulated stances within one frame, {} with the \
         same mid-stance frame",
        results.images_per_gait.values().sum::<usize>(),
        results
            .images_per_gait
            .iter()
            .map(|(g, n)| format!("{g}: {n}"))
            .collect::<Vec<_>>()
            .join(", "),
        segmentation.matched_within_one_frame,
        segmentation.true_hops,
        segmentation.same_mid_frame
    )?;
    writeln!(
        out,
        "\nTable II (trained on G2, {} images per terrain; mean +- std over {} repeats)",
        results.draw.per_class, results.repeats
    )?;
    writeln!(out, "{:<10} {:>18} {:>8}", "tested", "simulated", "paper")?;
    for (name, paper) in PAPER_TABLE2 {
        if let (Some(mean), Some(std)) = (results.table2.get(name), results.table2_std.get(name)) {
            writeln!(
                out,
                "{:<10} {:>9.1} % +- {:<4.1} {:>6.1} %",
                name,
                100.0 * mean,
                100.0 * std,
                100.0 * paper
            )?;
        }
    }
    writeln!(
        out,
        "median classification time {:.2} us per image (paper: {:.0} us on a 2.67 GHz Core 2 Duo)",
        results.median_classify_ns as f64 / 1e3,
        PAPER_CLASSIFY_NS as f64 / 1e3
    )?;
    if let Some(line) = results
        .evaluations
        .get("G2")
        .and_then(|main| calibration_line(&main.reliability))
    {
        writeln!(out, "{line}")?;
    }
    let gaits: Vec<&String> = results.images_per_gait.keys().collect();
    writeln!(out, "\nTrain gait x test gait accuracy (%)")?;
    write!(out, "{:<8}", "train")?;
    for gait in &gaits {
        write!(out, " {gait:>7}")?;
    }
    writeln!(out, " {:>8}", "overall")?;
    for (train_gait, row) in &results.train_test_matrix {
        write!(out, "{train_gait:<8}")?;
        for gait in &gaits {
            let value = row.get(*gait).copied().unwrap_or(f64::NAN);
            write!(out, " {:>7.1}", 100.0 * value)?;
        }
        let overall = row.get("overall").copied().unwrap_or(f64::NAN);
        writeln!(out, " {:>8.1}", 100.0 * overall)?;
    }
    Ok(())
}

/// The load-independence test and the comparison of the other methods.
fn print_load_and_methods(reproduction: &Reproduction, out: &mut dyn Write) -> anyhow::Result<()> {
    let results = &reproduction.results;
    if let Some(note) = &reproduction.load_dataset_note {
        writeln!(out, "{note}")?;
    }
    if let Some(err) = &reproduction.load_error {
        writeln!(out, "\nLoad independence: not measured: {err}")?;
    }
    if let Some(load_check) = &results.load_independence {
        writeln!(
            out,
            "\nLoad independence (trained on G2 at {:.2} kg, tested on all gaits at {:.2} kg, {} images)",
            load_check.nominal_load_kg, load_check.test_load_kg, load_check.test_images
        )?;
        writeln!(
            out,
            "  as recorded        {:5.1} % +- {:.1}\n  scaled by load     {:5.1} % +- {:.1}  (the paper: \
             the load is known)\n  normalised         {:5.1} % +- {:.1}  (--normalise-load: trained and \
             tested on images divided by their total, the load unknown)",
            100.0 * load_check.accuracy_unscaled.mean,
            100.0 * load_check.accuracy_unscaled.std,
            100.0 * load_check.accuracy_scaled.mean,
            100.0 * load_check.accuracy_scaled.std,
            100.0 * load_check.accuracy_normalised.mean,
            100.0 * load_check.accuracy_normalised.std
        )?;
    }
    if !reproduction.comparison.is_empty() {
        writeln!(
            out,
            "\nOther methods (trained on G2, {} images per terrain, the same draws as Table II; the paper's \
             is fft1d + pwe)",
            results.draw.per_class
        )?;
        super::eval::print_comparison(&reproduction.comparison, out)?;
    }
    Ok(())
}
