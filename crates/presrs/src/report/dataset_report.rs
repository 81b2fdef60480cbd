//! `presrs report` on a data set: its evaluation (as `presrs eval` runs it with the same options), the
//! model shown, the fault sweep, and the page.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use presrs_core::evaluation::EvalReport;
use presrs_core::pipeline::TrainedModel;
use presrs_core::split::ValidationSize;
use presrs_io::message::Warnings;
use presrs_io::model_file::load_model;
use presrs_report::Evaluation;

use super::draws::{evaluation_draw, smallest_class};
use super::faults::fault_sweep;
use super::model_check::{eval_samples, labelled, model_on_samples};
use super::options::ReportOptions;
use super::page::{first_model_note, race_notes, write_manifest_report};
use super::provenance::provenance;
use super::simulation::paper_reference;
use super::sources::is_simulate_output;
use crate::dataset::Dataset;
use crate::error::{Context, Error, Result};
use crate::eval::{EvalOptions, EvalSetup, Holdout};
use crate::progress::Progress;

/// What `presrs report` wrote and the figures it shows.
#[derive(Clone, Debug)]
pub struct ReportSummary {
    /// The page (`index.html`).
    pub index: PathBuf,
    /// The evaluation the report shows, with its name (`leave one group out`, `trained on G2`, the
    /// given model on every image); `None` with `--repeats 0` and no model.
    pub evaluation: Option<(String, EvalReport)>,
    /// What the user should know about the run (capped draws, labels no training set holds).
    pub warnings: Warnings,
}

/// The protocol of the report's evaluation: as asked (`--train-condition`, `--leave-one-out`); else
/// [`Holdout::default_for`] (the one `presrs eval` takes without a protocol or a per-class draw).
pub fn report_holdout(dataset: &Dataset, options: &ReportOptions) -> Holdout {
    if let Some(column) = &options.leave_one_out {
        return Holdout::LeaveOneOut(column.clone());
    }
    if let Some(condition) = &options.train_condition {
        return Holdout::TrainCondition(Some(condition.clone()));
    }
    Holdout::default_for(dataset)
}

/// `presrs report`: the report of a data set in `out_dir` (`index.html` and its figures), with a
/// model (given, or the first one its evaluation trained), its evaluation and the sensor-fault sweep as
/// `options` say. The evaluation is `presrs eval`'s with the same options (the method, auto by default,
/// and the protocol of [`report_holdout`]), so the two agree.
pub fn report_dataset(
    dataset: &Dataset,
    options: &ReportOptions,
    out_dir: &Path,
    progress: &dyn Progress,
) -> Result<ReportSummary> {
    let name = dataset.path().display();
    let mut evaluation: Option<(String, EvalReport)> = None;
    let mut warnings = Warnings::new();
    let mut faults = (Vec::new(), String::new());
    let model: Option<(TrainedModel, String)> = match &options.model {
        Some(path) => {
            let file = load_model(path)?;
            if labelled(&dataset.samples).is_some() {
                let report = model_on_samples(&file.model, &dataset.samples)?;
                evaluation = Some((format!("model {} on every image", path.display()), report));
            }
            Some((file.model, format!("Loaded from {}.", path.display())))
        }
        None if labelled(&dataset.samples).is_some() => {
            let (eval_options, notes) = report_eval_options(dataset, options);
            notes.iter().for_each(|note| progress.note(note));
            let setup = EvalSetup::new(dataset, &eval_options)?;
            warnings.extend(setup.warnings.iter().cloned());
            let outcome = setup.evaluate(progress).map_err(|err| {
                Error::data(format!(
                    "{name}: cannot evaluate the method for the report: {err}"
                ))
            })?;
            warnings.extend(outcome.warnings.iter().cloned());
            if options.repeats > 0 {
                evaluation = Some((eval_options.holdout.describe(), outcome.report));
            }
            if options.fault_repeats > 0 {
                let config = options.method.train_config(dataset.grid())?;
                faults = fault_sweep(
                    options,
                    setup.samples(),
                    setup.protocol(),
                    &config,
                    progress,
                )
                .with_context(|| format!("{name}: fault sweep"))?;
            }
            outcome.first_model.map(|first| {
                let note = first_model_note(&first, &eval_options);
                (first.model, note)
            })
        }
        None => None,
    };
    let evaluations: Vec<Evaluation<'_>> = evaluation
        .iter()
        .map(|(title, report)| Evaluation {
            name: title.clone(),
            report,
            // The paper's Table II only next to the paper's experiment (a `presrs simulate` folder).
            reference: if title == "trained on G2" && is_simulate_output(dataset.path()) {
                paper_reference(report)
            } else {
                BTreeMap::new()
            },
        })
        .collect();
    let index = write_manifest_report(
        dataset,
        model.as_ref().map(|(m, note)| (m, note.clone())),
        evaluations,
        &options.samples,
        (&faults.0, faults.1, None),
        &[provenance(options.command_line.as_deref())],
        out_dir,
    )?;
    Ok(ReportSummary {
        index,
        evaluation,
        warnings,
    })
}

/// `presrs report --sample auto`: the report of the data set read both ways (`readings`), its
/// evaluation racing the sample kinds in every fold as `presrs eval --sample auto` does (the races in
/// the notes, the first fold's winner as the model shown). A given model has one sample kind (name it
/// instead), and the fault sweep perturbs frames, so neither applies.
pub fn report_racing_samples(
    readings: &crate::eval::race::RaceReadings,
    options: &ReportOptions,
    out_dir: &Path,
    progress: &dyn Progress,
) -> Result<ReportSummary> {
    let dataset = &readings.frames;
    if options.model.is_some() {
        return Err(Error::invalid(
            presrs_io::message::Message::new()
                .opt_text(presrs_io::message::Opt::Sample, "auto")
                .text(
                    " races the sample kinds when training; a given model has its own: name its \
                     sample kind (frame, stance or series)",
                ),
        ));
    }
    let (eval_options, notes) = report_eval_options(dataset, options);
    notes.iter().for_each(|note| progress.note(note));
    let raced = crate::eval::race::evaluate_racing_samples(readings, &eval_options, progress)
        .map_err(|err| {
            Error::data(format!(
                "{}: cannot evaluate the method for the report: {err}",
                dataset.path().display()
            ))
        })?;
    let outcome = raced.outcome;
    let name = eval_options.holdout.describe();
    let evaluation = (options.repeats > 0).then(|| (name.clone(), outcome.report.clone()));
    let evaluations: Vec<Evaluation<'_>> = evaluation
        .iter()
        .map(|(title, report)| Evaluation {
            name: title.clone(),
            report,
            reference: BTreeMap::new(),
        })
        .collect();
    let model = outcome.first_model.as_ref().map(|first| {
        let note = first_model_note(first, &eval_options);
        (&first.model, note)
    });
    let index = write_manifest_report(
        dataset,
        model,
        evaluations,
        &options.samples,
        (&[], String::new(), None),
        &race_notes(&outcome, options.command_line.as_deref()),
        out_dir,
    )?;
    Ok(ReportSummary {
        index,
        evaluation,
        warnings: outcome.warnings,
    })
}

/// The evaluation options `presrs report` runs with (`presrs eval` with these gives the same figures),
/// and notes on how the draw was adapted. With the paper's protocol the draw shrinks when a class has
/// fewer images than asked, and when the training condition covers every sample, so that every class
/// keeps images to test on.
pub fn report_eval_options(
    dataset: &Dataset,
    options: &ReportOptions,
) -> (EvalOptions, Vec<String>) {
    let holdout = report_holdout(dataset, options);
    let mut notes = Vec::new();
    let (per_class, validation) = match &holdout {
        Holdout::TrainCondition(condition) => {
            let triples = labelled(&dataset.samples).unwrap_or_default();
            let samples = eval_samples(&triples);
            let condition = condition.as_deref();
            let smallest = smallest_class(&samples, condition);
            let (per_class, validation, held_out) =
                evaluation_draw(&samples, condition, options.per_class, options.validation);
            if held_out {
                notes.push(format!(
                    "the evaluations draw {per_class} image(s) per class for training + validation \
                     and test on the rest (every condition trains, and a class has too few images to \
                     draw --per-class {} and keep some)",
                    options.per_class
                ));
            } else if smallest < options.per_class {
                notes.push(format!(
                    "a class has only {smallest} image(s){}, fewer than --per-class {}: drawing \
                     {per_class} per class, {} of them for validation",
                    condition.map_or_else(String::new, |c| format!(" of condition {c}")),
                    options.per_class,
                    match validation {
                        ValidationSize::Count(count) => count.to_string(),
                        ValidationSize::Fraction(f) => format!("a fraction {f}"),
                    }
                ));
            }
            (per_class, validation)
        }
        Holdout::LeaveOneOut(_) => (options.per_class, options.validation),
    };
    let eval_options = EvalOptions {
        holdout,
        per_class: Some(per_class),
        validation,
        // The model shown is the evaluation's first: one repeat when no evaluation is shown.
        repeats: options.repeats.max(1),
        seed: options.seed,
        method: options.method.clone(),
    };
    (eval_options, notes)
}
