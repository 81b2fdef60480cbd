//! `presrs report`: every figure of a data set (and a model, an evaluation, the simulation) in a folder
//! with an `index.html` that opens offline; the assembly is [`presrs::report`]'s.

use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

use presrs::eval::race::RaceReadings;
use presrs::report::{ReportOptions, report_dataset, report_racing_samples};
use presrs_core::split::ValidationSize;

use super::common::{
    PipelineArgs, SampleArgs, TerminalProgress, load_manifest, print_load_warnings,
};

/// Write an HTML report of a data set: pressure images per label and condition (Fig. 5), feature
/// spectra (Fig. 6), load curves, principal components, validation curve, confusion matrix, accuracy
/// per condition; Table I and the hopper's motion for `presrs simulate` output.
#[derive(Debug, clap::Args)]
#[command(after_help = "Examples:
  presrs report --manifest sim/manifest.csv --out report
  presrs report --manifest walks.csv --model model.json --out report
  presrs report --manifest walks.csv --leave-one-out group --out report")]
pub struct ReportArgs {
    /// The dataset manifest.
    #[arg(long)]
    pub manifest: PathBuf,
    /// A trained model to show (crop, PCA, validation curve) and to test on every image. Without it,
    /// the method (--features/--classifier, auto by default) is evaluated as `presrs eval` would with
    /// the same options, and the report shows the evaluation's first model.
    #[arg(long)]
    pub model: Option<PathBuf>,
    /// Output folder (index.html and the figures).
    #[arg(long)]
    pub out: PathBuf,
    /// Train on this condition, test on every other sample. Default: G2 when present (the paper's
    /// protocol); else leave one group out when the manifest has two or more groups; else a random
    /// draw from every condition.
    #[arg(long, conflicts_with = "leave_one_out")]
    pub train_condition: Option<String>,
    /// Hold out each value of this manifest column in turn (e.g. group, condition; not label).
    #[arg(long, value_parser = super::eval::parse_leave_one_out)]
    pub leave_one_out: Option<String>,
    /// Images drawn per class for training + validation, at least 1 (fewer if a class has fewer; when
    /// every condition trains and a class has no more than this, the evaluations draw two thirds of it
    /// and test on the rest).
    #[arg(long, default_value_t = 20, value_parser = super::usage::positive_count)]
    pub per_class: usize,
    /// Of those, how many per class validate sigma: a count (7) or a fraction (0.35). When a class has
    /// fewer images than --per-class, a count becomes the same fraction of what is drawn (7 of 20: 0.35).
    #[arg(long, default_value = "7", value_parser = |t: &str| t.parse::<ValidationSize>().map_err(|e| e.to_string()))]
    pub validation: ValidationSize,
    /// Repeats of the evaluation (0: no evaluation).
    #[arg(long, default_value_t = 5)]
    pub repeats: usize,
    /// Repeats of the sensor-fault sweep (accuracy with the test images perturbed at three levels of
    /// each of dead, stuck, gain, noise, shift, rotate and load, for the paper's method and the
    /// automatic choice; each model trained once per repeat); 0 skips it.
    #[arg(long, default_value_t = 3)]
    pub fault_repeats: usize,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    #[command(flatten)]
    pub pipeline: PipelineArgs,
    #[command(flatten)]
    pub samples: SampleArgs,
}

pub fn run(args: &ReportArgs, out: &mut dyn Write) -> anyhow::Result<()> {
    let started = Instant::now();
    presrs_io::output_path::check_output_dir(&args.out)?;
    args.samples.check_settings("report")?;
    let options = ReportOptions {
        model: args.model.clone(),
        train_condition: args.train_condition.clone(),
        leave_one_out: args.leave_one_out.clone(),
        per_class: args.per_class,
        validation: args.validation,
        repeats: args.repeats,
        fault_repeats: args.fault_repeats,
        seed: args.seed,
        method: args.pipeline.method(),
        samples: args.samples.options_or_frames()?,
        command_line: Some(std::env::args().collect::<Vec<_>>().join(" ")),
    };
    let progress = TerminalProgress::default();
    let summary = if args.samples.choice()?.is_auto() {
        let whole = args.samples.whole_sample();
        let readings = RaceReadings::load(&args.manifest, &options.samples, whole, &progress)?;
        print_load_warnings(&readings.frames);
        report_racing_samples(&readings, &options, &args.out, &progress)?
    } else {
        let dataset = load_manifest(&args.manifest, &args.samples)?;
        report_dataset(&dataset, &options, &args.out, &progress)?
    };
    for warning in &summary.warnings {
        stderr_line!("warning: {warning}");
    }
    if let Some((name, report)) = &summary.evaluation {
        writeln!(
            out,
            "{name}, {} repeat(s): {:.2} % +- {:.2}",
            report.repeats.len(),
            100.0 * report.overall.mean,
            100.0 * report.overall.std
        )?;
    }
    writeln!(
        out,
        "wrote {} ({:.1} s)",
        summary.index.display(),
        started.elapsed().as_secs_f64()
    )?;
    Ok(())
}
