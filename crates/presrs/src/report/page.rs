//! The page of a manifest's data set (`index.html` and its figures), as `eval --report` and `presrs
//! report` write it: the samples in words, the model shown and how it was trained, the evaluations, the
//! load curves of a few movies, and what the evaluation adds (faults, early decisions, novelty).

use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use presrs_core::evaluation::FirstModel;
use presrs_core::pipeline::TrainedModel;
use presrs_report::{
    EarlyCurve, Evaluation, FaultResult, ReportInputs, ReportRecording, SimulationInputs,
};

use super::provenance::provenance;
use super::sources::{
    manifest_recordings, preferred_condition, simulate_outputs, simulation_traces,
};
use crate::dataset::{Dataset, Sample, SampleOptions};
use crate::error::{Context, Result};
use crate::eval::{EvalOptions, EvalOutcome};

/// Writes `out_dir/index.html` and its figures from `inputs`; returns the page's path.
pub fn write_report(inputs: &ReportInputs<'_>, out_dir: &Path) -> Result<PathBuf> {
    presrs_report::write_report(inputs, out_dir)
        .with_context(|| format!("cannot write the report in {}", out_dir.display()))
}

/// The report of `presrs eval`: the manifest's samples, the evaluation `outcome` of `options`, the model
/// it trained first (for the PCA and validation-curve figures) and the load curves of up to four
/// movies; with `faults` (from `--perturb`), accuracy against fault level.
pub fn write_eval_report(
    dataset: &Dataset,
    options: &EvalOptions,
    outcome: &EvalOutcome,
    faults: &[FaultResult],
    sample_options: &SampleOptions,
    command_line: Option<&str>,
    out_dir: &Path,
) -> Result<PathBuf> {
    let evaluation_name = options.holdout.describe();
    let report = &outcome.report;
    let model = outcome
        .first_model
        .as_ref()
        .map(|first| (&first.model, first_model_note(first, options)));
    let evaluations = vec![Evaluation {
        name: evaluation_name.clone(),
        report,
        reference: BTreeMap::new(),
    }];
    let fault_note = format!(
        "{evaluation_name}, {} repeat(s) with the evaluation's draws.",
        report.repeats.len()
    );
    write_manifest_report(
        dataset,
        model,
        evaluations,
        sample_options,
        (faults, fault_note, None),
        &race_notes(outcome, command_line),
        out_dir,
    )
}

/// `presrs eval --decide-at --report DIR`: the report of the data set read as whole stances, with the
/// early decisions' curve (`early`, from [`crate::eval::early::EarlyEvaluation::curve`]).
pub fn write_early_report(
    dataset: &Dataset,
    early: EarlyCurve,
    sample_options: &SampleOptions,
    command_line: Option<&str>,
    out_dir: &Path,
) -> Result<PathBuf> {
    write_manifest_report(
        dataset,
        None,
        Vec::new(),
        sample_options,
        (&[], String::new(), Some(early)),
        &[provenance(command_line)],
        out_dir,
    )
}

/// `eval --leave-class-out --report DIR`: the data set and the leave-class-out table.
pub fn write_leave_class_out_report(
    dataset: &Dataset,
    result: &crate::eval::novelty::LeaveClassOut,
    command_line: Option<&str>,
    out_dir: &Path,
) -> Result<PathBuf> {
    let samples = &dataset.samples;
    let mut inputs = ReportInputs::new(
        format!(
            "presrs report: {} (leave one class out)",
            dataset.path().display()
        ),
        samples,
    );
    inputs.notes = vec![format!(
        "{} images from {}.",
        samples.len(),
        dataset.path().display()
    )];
    inputs
        .notes
        .extend(command_line.map(|line| format!("Command: {line}")));
    inputs.novelty = Some(result.report_rows());
    write_report(&inputs, out_dir)
}

/// The notes after the samples' line: with `--sample auto`, the sample race of every fold; then the
/// provenance.
pub(super) fn race_notes(outcome: &EvalOutcome, command_line: Option<&str>) -> Vec<String> {
    let mut notes = crate::eval::race::race_lines(&outcome.sample_races);
    if let Some(first) = notes.first_mut() {
        // The folds' lines under the first, as one note each.
        first.insert_str(0, "The sample kinds raced: ");
        first.push('.');
    }
    notes.push(provenance(command_line));
    notes
}

/// What the samples are, in words: single images, frames the manifest names, and stance frames of
/// movies, each with its count (only the kinds there are).
fn describe_samples(samples: &[Sample], options: &SampleOptions) -> String {
    let mut per_source: BTreeMap<&Path, usize> = BTreeMap::new();
    for s in samples {
        *per_source.entry(s.source.as_path()).or_default() += 1;
    }
    let (mut single, mut named, mut stance) = (0, 0, 0);
    let mut movies = BTreeSet::new();
    for s in samples {
        if s.columns.contains_key("frame") {
            named += 1;
        } else if s.frame_index == 0 && per_source.get(s.source.as_path()) == Some(&1) {
            // One sample at frame 0 of its file: a single image (a movie's stance rarely starts at
            // its first frame, and partial stances are left out unless asked for).
            single += 1;
        } else {
            stance += 1;
            movies.insert(s.source.as_path());
        }
    }
    let of_each = if options.one_sample_per_file {
        // The whole recording is the one contact, complete or not.
        "the whole recording (one contact per file)"
    } else if options.include_partial {
        "each stance"
    } else {
        "each complete stance"
    };
    let mut parts = Vec::new();
    if single > 0 {
        parts.push(format!("{single} single image(s)"));
    }
    if named > 0 {
        parts.push(format!("{named} frame(s) named by the manifest"));
    }
    if stance > 0 {
        parts.push(format!(
            "{stance} {} frame(s) of {of_each} of {} movie(s)",
            options.sample,
            movies.len()
        ));
    }
    parts.join(", ")
}

pub(super) fn write_manifest_report(
    loaded: &Dataset,
    model: Option<(&TrainedModel, String)>,
    evaluations: Vec<Evaluation<'_>>,
    sample_options: &SampleOptions,
    (faults, fault_note, early): (&[FaultResult], String, Option<EarlyCurve>),
    notes: &[String],
    out_dir: &Path,
) -> Result<PathBuf> {
    let manifest_path = loaded.path();
    let samples = &loaded.samples;
    let preferred = preferred_condition(samples);
    let (meta, movies) = manifest_recordings(loaded, sample_options, preferred);
    let simulated = manifest_path.parent().and_then(|dir| {
        simulate_outputs(if dir.as_os_str().is_empty() {
            Path::new(".")
        } else {
            dir
        })
    });
    let traces = simulated
        .as_ref()
        .map(|(table, config)| simulation_traces(config, table, preferred.unwrap_or("G2")))
        .unwrap_or_default();
    let title = format!("presrs report: {}", manifest_path.display());
    let mut inputs = ReportInputs::new(title, samples);
    inputs.notes = vec![format!(
        "{} images from {}: {}.",
        samples.len(),
        manifest_path.display(),
        describe_samples(samples, sample_options)
    )];
    inputs.notes.extend(notes.iter().cloned());
    inputs.sensor = meta.as_ref();
    inputs.model = model.as_ref().map(|m| m.0);
    inputs.model_note = model.map(|m| m.1);
    inputs.evaluations = evaluations;
    inputs.recordings = movies
        .iter()
        .map(|(name, recording)| ReportRecording {
            name: name.clone(),
            recording,
        })
        .collect();
    inputs.sample_frame = sample_options.sample;
    // The curves segmented and sampled as the data set was (one contact per file, partial stances).
    inputs.segment = sample_options.segment_params();
    inputs.include_partial = sample_options.include_partial();
    inputs.simulation = simulated.as_ref().map(|(table, _)| SimulationInputs {
        velocity: table,
        traces: &traces,
    });
    inputs.faults = faults.to_vec();
    inputs.fault_note = Some(fault_note);
    inputs.early = early;
    write_report(&inputs, out_dir)
}

/// How the model the report shows was trained, in a sentence or two.
pub(super) fn first_model_note(first: &FirstModel, eval_options: &EvalOptions) -> String {
    let fold = first
        .held_out
        .as_ref()
        .map_or_else(String::new, |value| format!(", holding out {value}"));
    let mut note = format!(
        "The evaluation's first model ({}, seed {}{fold}): {} training + {} validation images, tested \
         on {}. {}.",
        eval_options.holdout.describe(),
        first.seed,
        first.n_train,
        first.n_validation,
        first.n_test,
        crate::describe::pipeline_summary(&first.model)
    );
    if let Some(selection) = first.model.selection()
        && let Some(chosen) = selection.chosen()
    {
        let _ = write!(
            note,
            " Chosen automatically ({}) among {} candidates: {} + {}, validation accuracy {:.1} %.",
            selection.method,
            selection.scores.len(),
            chosen.features,
            chosen.classifier,
            100.0 * chosen.accuracy.mean
        );
    }
    note
}
