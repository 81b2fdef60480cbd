//! `presrs eval`: the evaluation protocols on any manifest.

use std::io::Write;
use std::path::PathBuf;

use anyhow::Context;
use presrs::eval::document::{CompareJson, EvalJson, PerturbedJson, perturbation_fault_results};
use presrs::eval::novelty::{HeldOutClasses, LeaveClassOut};
use presrs::eval::{EvalOptions, EvalOutcome, EvalSetup, Holdout, PerturbationRow};
use presrs::resources::MemoryUse;
use presrs_core::evaluation::{ComparisonRow, EvalReport};
use presrs_core::split::ValidationSize;

use super::common::{
    PipelineArgs, SampleArgs, TerminalProgress, load_manifest, print_load_warnings, write_json,
};
use crate::printer::eval_tables;

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
    /// With --sample stance: evaluate early decisions at these frames after touchdown
    /// (`8,16,32,whole`, or `auto`: 10-80 % of the median stance), each fold training a classifier
    /// per point and `auto`'s threshold, beside the one-frame model at the same offsets: accuracy
    /// against decision time, and `auto`'s accuracy and mean decision time.
    #[arg(long, value_name = "K,...,whole|auto",
          value_parser = |t: &str| t.parse::<presrs::train::early::DecisionPoints>())]
    pub decide_at: Option<presrs::train::early::DecisionPoints>,
    /// Hold classes out of training in turn, on the evaluation's draws, and measure the novelty score
    /// (`unknown`): a count (6: spread over the sorted labels) or names (a,b). Prints, per held-out
    /// class, the AUROC of the score (held-out against known test samples), the share of held-out
    /// samples decided as a known class with confidence >= 0.9, and the share of known test samples
    /// decided unknown (`leave_class_out` with --json; a section of --report).
    #[arg(long, value_name = "N|CLASSES", conflicts_with_all = ["compare", "perturb", "export_draws", "decide_at"], value_parser = |t: &str| t.parse::<HeldOutClasses>())]
    pub leave_class_out: Option<HeldOutClasses>,
    #[command(flatten)]
    pub pipeline: PipelineArgs,
    #[command(flatten)]
    pub samples: SampleArgs,
}

pub fn run(args: &EvalArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    for dir in [&args.report, &args.export_draws].into_iter().flatten() {
        presrs_io::output_path::check_output_dir(dir)?;
    }
    args.samples.check_settings("eval")?;
    if let Some(held_out) = &args.leave_class_out {
        return run_leave_class_out(args, held_out, out);
    }
    if let Some(points) = &args.decide_at {
        return run_early(args, points, out);
    }
    if args.samples.choice()?.is_auto() {
        return run_racing(args, out);
    }
    let dataset = load_manifest(&args.manifest, &args.samples)?;
    let options = eval_options(args, &dataset);
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
    let faults = perturbation_fault_results(&perturbed, options.method.is_auto());
    write_report(args, (&dataset, &options), &outcome, &faults)?;
    let mut eval = EvalJson::of(&outcome, &setup.never_trained);
    eval.memory = MemoryUse::now(dataset.samples.len());
    eval.warnings = (setup.warnings.iter().map(ToString::to_string))
        .chain(outcome.warnings.iter().map(ToString::to_string))
        .collect();
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
    print_report(&outcome.report, Some(dataset.sample), out)?;
    print_perturbations(&perturbed, out)?;
    print_choices(&outcome, &eval, out)?;
    print_memory(&eval, out)
}

/// The run's peak memory, last (measured once the run is over).
fn print_memory(eval: &EvalJson<'_>, out: &mut dyn Write) -> anyhow::Result<()> {
    if let Some(memory) = &eval.memory {
        writeln!(out, "{}", memory.line())?;
    }
    Ok(())
}

/// `--decide-at`: early decisions on the protocol's draws (`presrs::eval::early`).
fn run_early(
    args: &EvalArgs,
    points: &presrs::train::early::DecisionPoints,
    out: &mut dyn Write,
) -> anyhow::Result<()> {
    let progress = TerminalProgress::default();
    let options = args.samples.options()?;
    let dataset = presrs::train::profile::load_with_points(
        &args.manifest,
        options.clone(),
        points,
        &progress,
    )?;
    print_load_warnings(&dataset);
    let eval_options = eval_options(args, &dataset);
    let setup = EvalSetup::new(&dataset, &eval_options)?;
    for warning in &setup.warnings {
        stderr_line!("warning: {warning}");
    }
    let frames =
        presrs::eval::early::FrameReadings::load(&args.manifest, &options, &dataset, &progress)?;
    let early = presrs::eval::early::evaluate_early(&setup, Some(&frames), &progress)?;
    if let Some(dir) = &args.report {
        let note = format!(
            "{}, {} fold(s)",
            eval_options.holdout.describe(),
            early.folds
        );
        let line = std::env::args().collect::<Vec<_>>().join(" ");
        let path = presrs::report::write_early_report(
            &dataset,
            early.curve(note),
            &options,
            Some(&line),
            dir,
        )?;
        stderr_line!("report written to {}", path.display());
    }
    if args.json {
        return write_json(out, &early);
    }
    Ok(write!(
        out,
        "{}",
        crate::printer::early_table::early_table(&early)
    )?)
}

/// `--leave-class-out` (the samples as named, frames with `--sample auto`): the table, or
/// `{"leave_class_out": ...}` with --json; the report with --report.
fn run_leave_class_out(
    args: &EvalArgs,
    held_out: &HeldOutClasses,
    out: &mut dyn Write,
) -> anyhow::Result<()> {
    let progress = TerminalProgress::default();
    let dataset = presrs::Dataset::load(
        &args.manifest,
        &args.samples.options_or_frames()?,
        &progress,
    )?;
    print_load_warnings(&dataset);
    let options = eval_options(args, &dataset);
    let setup = EvalSetup::new(&dataset, &options)?;
    for warning in &setup.warnings {
        stderr_line!("warning: {warning}");
    }
    let result = presrs::eval::novelty::leave_class_out(&setup, held_out, &progress)?;
    print_leave_class_out(args, &dataset, &result, out)
}

fn print_leave_class_out(
    args: &EvalArgs,
    dataset: &presrs::Dataset,
    result: &LeaveClassOut,
    out: &mut dyn Write,
) -> anyhow::Result<()> {
    if let Some(dir) = &args.report {
        let line = std::env::args().collect::<Vec<_>>().join(" ");
        let path = presrs::report::write_leave_class_out_report(dataset, result, Some(&line), dir)?;
        stderr_line!("report written to {}", path.display());
    }
    if args.json {
        return write_json(out, &serde_json::json!({ "leave_class_out": result }));
    }
    Ok(write!(
        out,
        "{}",
        crate::printer::novelty_table::leave_class_out_table(result)
    )?)
}

/// `--sample auto`: the sample kinds raced inside every fold (`presrs::eval::race`).
fn run_racing(args: &EvalArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    anyhow::ensure!(
        !args.compare && args.perturb.is_empty() && args.export_draws.is_none(),
        "--sample auto tests each fold's winner in its own sample; --compare, --perturb and \
         --export-draws take one sample kind: name it with --sample frame, stance or series"
    );
    let progress = TerminalProgress::default();
    let frames = args.samples.options_or_frames()?;
    let whole = args.samples.whole_sample();
    let readings =
        presrs::eval::race::RaceReadings::load(&args.manifest, &frames, whole, &progress)?;
    print_load_warnings(&readings.frames);
    let options = eval_options(args, &readings.frames);
    let raced = presrs::eval::race::evaluate_racing_samples(&readings, &options, &progress)?;
    for warning in &raced.outcome.warnings {
        stderr_line!("warning: {warning}");
    }
    write_report(args, (&readings.frames, &options), &raced.outcome, &[])?;
    let mut eval = EvalJson::of(&raced.outcome, &raced.never_trained);
    eval.memory = MemoryUse::now(readings.frames.samples.len());
    eval.warnings = raced
        .outcome
        .warnings
        .iter()
        .map(ToString::to_string)
        .collect();
    if args.json {
        return write_json(out, &eval);
    }
    print_report(&raced.outcome.report, None, out)?;
    print_choices(&raced.outcome, &eval, out)?;
    print_memory(&eval, out)
}

fn eval_options(args: &EvalArgs, dataset: &presrs::Dataset) -> EvalOptions {
    let (loo, condition) = (args.leave_one_out.clone(), args.train_condition.clone());
    EvalOptions {
        holdout: Holdout::resolve(dataset, loo, condition, args.per_class),
        per_class: args.per_class,
        validation: args.validation,
        repeats: args.repeats,
        seed: args.seed,
        method: args.pipeline.method(),
    }
}

/// `--report DIR`: the evaluation's HTML report.
fn write_report(
    args: &EvalArgs,
    (dataset, options): (&presrs::Dataset, &EvalOptions),
    outcome: &EvalOutcome,
    faults: &[presrs_report::FaultResult],
) -> anyhow::Result<()> {
    if let Some(dir) = &args.report {
        let line = std::env::args().collect::<Vec<_>>().join(" ");
        let samples = args.samples.options_or_frames()?;
        let path = presrs::report::write_eval_report(
            dataset,
            options,
            outcome,
            faults,
            &samples,
            Some(&line),
            dir,
        )?;
        stderr_line!("report written to {}", path.display());
    }
    Ok(())
}

/// The sample races, the automatic choices' counts and their own estimate next to the test's.
fn print_choices(
    outcome: &EvalOutcome,
    eval: &EvalJson<'_>,
    out: &mut dyn Write,
) -> anyhow::Result<()> {
    let internal = eval.internal_estimate.as_ref();
    Ok(write!(
        out,
        "{}",
        eval_tables::choices_text(outcome, internal)
    )?)
}

/// The human-readable tables of an evaluation (`crate::printer::eval_tables::report_table`) of
/// `sample`s (`None`: raced).
pub fn print_report(
    report: &EvalReport,
    sample: Option<presrs_core::sample::SampleKind>,
    out: &mut dyn Write,
) -> anyhow::Result<()> {
    Ok(write!(
        out,
        "{}",
        eval_tables::report_table(report, sample)
    )?)
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
    Ok(write!(out, "{}", eval_tables::comparison_table(rows))?)
}

/// The accuracy-against-fault table (one column per method).
fn print_perturbations(rows: &[PerturbationRow], out: &mut dyn Write) -> anyhow::Result<()> {
    Ok(write!(out, "{}", eval_tables::perturbation_table(rows))?)
}
