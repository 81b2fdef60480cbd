//! `presrs eval`: the evaluation protocols on any manifest.

use std::io::Write;
use std::path::PathBuf;

use anyhow::Context;
use presrs::eval_document::{
    CompareJson, EvalJson, PerturbedJson, chosen_counts, fault_results, protocol_heading, sigmas,
};
use presrs::evaluate::{EvalOptions, EvalSetup, Holdout, PerturbationRow, calibration_line};
use presrs_core::evaluation::{ComparisonRow, EvalReport, MeanStd};
use presrs_core::split::ValidationSize;

use super::common::{
    PipelineArgs, SampleArgs, TerminalProgress, load_manifest, print_load_warnings, write_json,
};

/// Evaluate the pipeline on a manifest: accuracy per condition/group, overall, confusion, timing.
#[derive(Debug, clap::Args)]
#[command(
    after_help = "Besides accuracy and the confusion matrix it reports how far the confidences can be \
trusted: the mean confidence when right and when wrong, and the expected calibration error over ten \
confidence bins (0: calibrated; `calibration` in --json, the full tally under report.reliability).\n\n\
Examples:
  presrs eval --manifest sim/manifest.csv --train-condition G2 \\
    --per-class 20 --validation 7 --repeats 10
  presrs eval --manifest walks.csv --leave-one-out subject --json"
)]
pub struct EvalArgs {
    /// The dataset manifest.
    #[arg(long)]
    pub manifest: PathBuf,
    /// Train on samples of this condition only; test on every other sample (the paper's protocol).
    /// With neither this nor --leave-one-out: a random draw of --per-class tested on the rest, or
    /// without --per-class the protocol of `presrs report` (trained on G2 when there is such a
    /// condition, else leave one group out when every sample has a group).
    #[arg(long, conflicts_with = "leave_one_out")]
    pub train_condition: Option<String>,
    /// Hold out each value of this manifest column in turn (e.g. condition, group, or an extra column;
    /// not label: a held-out class could never be recognised).
    #[arg(long, value_parser = parse_leave_one_out)]
    pub leave_one_out: Option<String>,
    /// Random samples drawn per class for training + validation, at least 1 (default: all available);
    /// a class (or held-out fold) with fewer gives all it has, with one warning.
    #[arg(long, value_parser = super::usage::positive_count)]
    pub per_class: Option<usize>,
    /// Of those, how many per class validate the hyper-parameters: a count (7) or a fraction (0.35).
    #[arg(long, default_value = "0.35", value_parser = |t: &str| t.parse::<ValidationSize>().map_err(|e| e.to_string()))]
    pub validation: ValidationSize,
    /// Repeats with seeds seed, seed+1, ...; results are mean +- std (at least 1).
    #[arg(long, default_value_t = 10, value_parser = super::usage::positive_count)]
    pub repeats: usize,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Print one JSON document instead of tables.
    #[arg(long)]
    pub json: bool,
    /// Evaluate every feature x classifier combination with the same draws and print the comparison
    /// (accuracy per tested condition, training time, classification time). With --json the document
    /// holds every combination under `comparison`, and the usual fields (overall_accuracy,
    /// per_condition, confusion, median_classify_ns, ...) of one of them, named in `summary_of`: the
    /// combination given by --features and --classifier when both are given and compared, else the one
    /// with the highest overall accuracy.
    #[arg(long)]
    pub compare: bool,
    /// Also write an HTML report with figures in this folder (DIR/index.html).
    #[arg(long, value_name = "DIR")]
    pub report: Option<PathBuf>,
    /// Also evaluate with every test image perturbed (repeatable; same draws): dead=FRACTION,
    /// stuck=FRACTION, gain=SD, noise=SD (counts), shift=ROWS or ROWS,COLS, rotate=DEGREES, load=FACTOR or
    /// load=+-50%. Prints accuracy under each (for the paper's method too with --features/--classifier
    /// auto).
    #[arg(long, value_name = "KIND=LEVEL", value_parser = |t: &str| t.parse::<presrs_core::perturb::Perturbation>().map_err(|e| e.to_string()))]
    pub perturb: Vec<presrs_core::perturb::Perturbation>,
    /// Also write into this folder the samples as evaluated (`images.npy`: samples x rows x cols, absent
    /// sensels as 0) and the draws (`draws.json`: each sample's label, condition and group, and every
    /// repeat's folds as training, validation and test indices), so another implementation can be
    /// evaluated on the same images with the same draws (bench/real/ does).
    #[arg(long, value_name = "DIR")]
    pub export_draws: Option<PathBuf>,
    #[command(flatten)]
    pub pipeline: PipelineArgs,
    #[command(flatten)]
    pub samples: SampleArgs,
}

pub fn run(args: &EvalArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    for dir in [&args.report, &args.export_draws].into_iter().flatten() {
        presrs_io::output_path::check_output_dir(dir)?;
    }
    if args.samples.is_auto() {
        return run_racing(args, out);
    }
    let dataset = load_manifest(&args.manifest, &args.samples)?;
    let options = EvalOptions {
        holdout: Holdout::resolve(
            &dataset,
            args.leave_one_out.clone(),
            args.train_condition.clone(),
            args.per_class,
        ),
        per_class: args.per_class,
        validation: args.validation,
        repeats: args.repeats,
        seed: args.seed,
        method: args.pipeline.method(),
    };
    let setup = EvalSetup::new(&dataset, &options)?;
    for warning in &setup.warnings {
        stderr_line!("warning: {warning}");
    }
    if let Some(dir) = &args.export_draws {
        setup.export_draws(dir)?;
    }
    let progress = TerminalProgress::default();
    if args.compare {
        let rows = setup.compare(&progress)?;
        if args.json {
            let json = CompareJson::new(&rows, &options.method)
                .with_context(|| args.manifest.display().to_string())?;
            return write_json(out, &json);
        }
        return print_comparison(&rows, out);
    }
    let outcome = setup.evaluate(&progress)?;
    for warning in &outcome.warnings {
        stderr_line!("warning: {warning}");
    }
    let perturbed = setup.perturbed(&args.perturb, &outcome.report, &progress)?;
    if let Some(dir) = &args.report {
        let path = presrs::report::write_eval_report(
            &dataset,
            &options,
            &outcome,
            &fault_results(&perturbed, options.method.is_auto()),
            &args.samples.options()?,
            Some(&std::env::args().collect::<Vec<_>>().join(" ")),
            dir,
        )?;
        stderr_line!("report written to {}", path.display());
    }
    let eval = EvalJson::of(&outcome, &setup.never_trained);
    if args.json && perturbed.is_empty() {
        return write_json(out, &eval);
    }
    if args.json {
        let perturbations = &perturbed;
        return write_json(
            out,
            &PerturbedJson {
                eval,
                perturbations,
            },
        );
    }
    print_report(&outcome.report, out)?;
    print_perturbations(&perturbed, out)?;
    print_choices(&outcome, &eval, out)
}

/// `--sample auto`: the sample kinds raced inside every fold (`presrs::eval_race`).
fn run_racing(args: &EvalArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    if args.compare || !args.perturb.is_empty() || args.export_draws.is_some() {
        anyhow::bail!(
            "--sample auto races the sample kinds inside each fold and tests each fold's winner in its \
             own sample; --compare, --perturb and --export-draws take one sample kind: name it with \
             --sample frame, stance or series"
        );
    }
    let progress = TerminalProgress::default();
    let readings = presrs::eval_race::RaceReadings::load(
        &args.manifest,
        &args.samples.options_of("frame")?,
        args.samples.whole_sample(),
        &progress,
    )?;
    print_load_warnings(&readings.frames);
    let said: Vec<String> = readings
        .frames
        .warnings
        .iter()
        .map(|w| w.to_string())
        .collect();
    for warning in &readings.whole.warnings {
        if !said.contains(&warning.to_string()) {
            stderr_line!("warning: {warning}");
        }
    }
    let options = EvalOptions {
        holdout: Holdout::resolve(
            &readings.frames,
            args.leave_one_out.clone(),
            args.train_condition.clone(),
            args.per_class,
        ),
        per_class: args.per_class,
        validation: args.validation,
        repeats: args.repeats,
        seed: args.seed,
        method: args.pipeline.method(),
    };
    let raced = presrs::eval_race::evaluate_racing_samples(&readings, &options, &progress)?;
    let outcome = &raced.outcome;
    for warning in &outcome.warnings {
        stderr_line!("warning: {warning}");
    }
    if let Some(dir) = &args.report {
        let path = presrs::report::write_eval_report(
            &readings.frames,
            &options,
            outcome,
            &[],
            &args.samples.options_of("frame")?,
            Some(&std::env::args().collect::<Vec<_>>().join(" ")),
            dir,
        )?;
        stderr_line!("report written to {}", path.display());
    }
    let eval = EvalJson::of(outcome, &raced.never_trained);
    if args.json {
        return write_json(out, &eval);
    }
    print_report(&outcome.report, out)?;
    writeln!(out)?;
    for line in presrs::eval_race::race_lines(&outcome.sample_races) {
        writeln!(out, "{line}")?;
    }
    print_choices(outcome, &eval, out)
}

/// The automatic choices' counts and their own estimate next to the test's.
fn print_choices(
    outcome: &presrs::evaluate::EvalOutcome,
    eval: &EvalJson<'_>,
    out: &mut dyn Write,
) -> anyhow::Result<()> {
    if let Some(first) = outcome.selections.first() {
        let (method, models) = (&first.method, outcome.selections.len());
        writeln!(
            out,
            "\nautomatic choice ({method}), over {models} trained model(s):"
        )?;
        for (name, count) in chosen_counts(&outcome.selections) {
            writeln!(out, "  {name}: {count}")?;
        }
    }
    if let Some(internal) = &eval.internal_estimate {
        writeln!(
            out,
            "internal estimate (validation inside the training data): {:.2} % +- {:.2}; test: {:.2} %",
            100.0 * internal.accuracy.mean,
            100.0 * internal.accuracy.std,
            100.0 * outcome.report.overall.mean
        )?;
    }
    Ok(())
}

/// The human-readable tables of an evaluation.
pub fn print_report(report: &EvalReport, out: &mut dyn Write) -> anyhow::Result<()> {
    let percent = |m: &MeanStd| format!("{:6.2} % +- {:.2}", 100.0 * m.mean, 100.0 * m.std);
    let heading = protocol_heading(&report.protocol);
    writeln!(out, "{heading}; {} repeat(s)", report.repeats.len())?;
    writeln!(out, "{:<16} {:>20}", "tested", "accuracy")?;
    for (name, accuracy) in &report.per_condition {
        writeln!(out, "{:<16} {:>20}", name, percent(accuracy))?;
    }
    writeln!(out, "{:<16} {:>20}", "overall", percent(&report.overall))?;
    let confusion = &report.confusion;
    let width = confusion
        .labels
        .iter()
        .map(String::len)
        .max()
        .unwrap_or(4)
        .max(6);
    writeln!(
        out,
        "\nconfusion (rows: true, columns: predicted; all repeats)"
    )?;
    write!(out, "{:<width$}", "")?;
    for label in &confusion.labels {
        write!(out, " {label:>width$}")?;
    }
    writeln!(out, " {:>9} {:>9}", "recall", "precision")?;
    let (recall, precision) = (confusion.recall(), confusion.precision());
    for (i, row) in confusion.counts.iter().enumerate() {
        write!(out, "{:<width$}", confusion.labels[i])?;
        for count in row {
            write!(out, " {count:>width$}")?;
        }
        writeln!(
            out,
            " {:>8.1}% {:>8.1}%",
            100.0 * recall[i],
            100.0 * precision[i]
        )?;
    }
    if let Some(line) = calibration_line(&report.reliability) {
        writeln!(out, "{line}")?;
    }
    let sigmas = sigmas(report);
    if !sigmas.is_empty() {
        let sigma = MeanStd::of(&sigmas);
        writeln!(
            out,
            "\nParzen sigma chosen on validation: {:.4} +- {:.4}",
            sigma.mean, sigma.std
        )?;
    }
    let first = &report.repeats[0];
    writeln!(
        out,
        "per repeat: {}; training {:.3} s",
        first.counts_text(),
        first.train_seconds
    )?;
    writeln!(
        out,
        "median classification time: {:.2} us per image (paper: 245 us on a 2.67 GHz Core 2 Duo)",
        report.median_classify_ns as f64 / 1e3
    )?;
    Ok(())
}

/// `--leave-one-out`: any column but `label` (holding out a class leaves none of its samples to train on).
pub(crate) fn parse_leave_one_out(text: &str) -> Result<String, String> {
    if text.trim() == "label" {
        return Err(
            "cannot hold out `label`: the held-out class would have no training samples, so none of \
             its test samples could be recognised; hold out another column (condition, group, path \
             or an extra one)"
                .to_owned(),
        );
    }
    Ok(text.to_owned())
}

/// The comparison table: one row per feature x classifier combination.
pub fn print_comparison(rows: &[ComparisonRow], out: &mut dyn Write) -> anyhow::Result<()> {
    Ok(write!(
        out,
        "{}",
        presrs::eval_tables::comparison_table(rows)
    )?)
}

/// The accuracy-against-fault table (one column per method).
fn print_perturbations(rows: &[PerturbationRow], out: &mut dyn Write) -> anyhow::Result<()> {
    Ok(write!(
        out,
        "{}",
        presrs::eval_tables::perturbation_table(rows)
    )?)
}
