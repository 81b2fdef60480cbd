//! Report assembly: every figure of a data set (and a model, an evaluation, the simulation) in a
//! folder with an `index.html` that opens offline. [`report_dataset`] is `presrs report`;
//! [`write_simulation_report`] (a simulated data set and its evaluations) is what `reproduce` writes,
//! [`write_eval_report`] what `eval --report` writes. The figures themselves are `presrs-report`'s,
//! re-exported here.

mod draws;
mod model_check;
mod provenance;
mod sources;

use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use presrs_core::evaluation::{EvalReport, FirstModel, Models, Protocol};
use presrs_core::pipeline::{CheckedTrainConfig, LabeledImage, TrainedModel, train};
use presrs_core::split::{ValidationSize, stratified_split};
use presrs_core::stance::{ValidSegmentParams, segment_recording};
use presrs_core::{Frame, Recording, SensorMeta};
use presrs_io::model_file::load_model;
use presrs_sim::trace::{HopTrace, trace_hops};
use presrs_sim::{SimConfig, SimulatedDataset, VelocityTable};

pub use presrs_report::{
    EarlyCurve, Evaluation, FaultResult, Figure, Format, MovieOptions, PressureFigure,
    PressureGrid, PressureScale, ReportError, ReportInputs, ReportRecording, SimulationInputs,
    render_rgb, render_svg, save_figure, write_movie,
};

use crate::dataset::{Dataset, Sample, SampleOptions};
use crate::error::{Context, Error, Result};
use crate::eval::{EvalOptions, EvalOutcome, EvalSetup, Holdout, run_counted};
use crate::method::Method;
use crate::progress::Progress;
use crate::train::split_images;
use presrs_io::message::Warnings;

pub use draws::shrink_draw;
use draws::{evaluation_draw, smallest_class};
use model_check::{eval_samples, labelled, model_on_samples};
pub use provenance::provenance;
use sources::{first_seconds, is_simulate_output, manifest_recordings, simulate_outputs};

/// The paper's Table II (trained on G2).
pub const PAPER_TABLE2: [(&str, f64); 4] = [
    ("G1", 0.993),
    ("G2", 0.991),
    ("G3", 0.986),
    ("overall", 0.990),
];

/// The paper's method, as fault results name it.
pub const PAPER_METHOD: &str = "paper: fft1d + pwe";
/// The automatic choice of features and classifier, as fault results name it.
pub const AUTO_METHOD: &str = "automatic choice";

/// What `presrs report` shows and how its model and evaluations are made.
#[derive(Clone, Debug)]
pub struct ReportOptions {
    /// A trained model to show (crop, PCA, validation curve) and to test on every image. Without it,
    /// a model is trained on the data set (the paper's protocol) and evaluated with repeats.
    pub model: Option<PathBuf>,
    /// Train on this condition, test on the others (see [`report_holdout`] for the default).
    pub train_condition: Option<String>,
    /// Hold out each value of this manifest column in turn (see [`report_holdout`] for the default).
    pub leave_one_out: Option<String>,
    /// Images drawn per class for training + validation (fewer if a class has fewer).
    pub per_class: usize,
    pub validation: ValidationSize,
    /// Repeats of the evaluation (0: none).
    pub repeats: usize,
    /// Repeats of the sensor-fault sweep (0: none).
    pub fault_repeats: usize,
    pub seed: u64,
    pub method: Method,
    /// How the data set's samples were taken (the report says which stance frame, and reads movies
    /// for load curves the same way).
    pub samples: SampleOptions,
    /// The command line the report was made with, stated in it.
    pub command_line: Option<String>,
}

impl Default for ReportOptions {
    fn default() -> Self {
        Self {
            model: None,
            train_condition: None,
            leave_one_out: None,
            per_class: 20,
            validation: ValidationSize::Count(7),
            repeats: 5,
            fault_repeats: 3,
            seed: 1,
            method: Method::default(),
            samples: SampleOptions::default(),
            command_line: None,
        }
    }
}

/// Writes `out_dir/index.html` and its figures from `inputs`; returns the page's path.
pub fn write_report(inputs: &ReportInputs<'_>, out_dir: &Path) -> Result<PathBuf> {
    presrs_report::write_report(inputs, out_dir)
        .with_context(|| format!("cannot write the report in {}", out_dir.display()))
}

/// The names of `evaluations`' reports: `trained on KEY`.
// Called by `reproduce` and `eval` once they write reports.
fn named_evaluations(evaluations: &BTreeMap<String, EvalReport>) -> Vec<Evaluation<'_>> {
    evaluations
        .iter()
        .map(|(key, report)| Evaluation {
            name: format!("trained on {key}"),
            report,
            reference: if key == "G2" {
                paper_reference(report)
            } else {
                BTreeMap::new()
            },
        })
        .collect()
}

/// Trains the model the report shows: `per_class` images per class of `condition` (all conditions when
/// `None`), `validation` of them for sigma. Returns the model and a description.
pub fn train_report_model(
    samples: &[(&Frame, &str, Option<&str>)],
    condition: Option<&str>,
    per_class: usize,
    validation: ValidationSize,
    seed: u64,
    config: &CheckedTrainConfig,
) -> Result<(TrainedModel, String)> {
    let pool: Vec<usize> = (0..samples.len())
        .filter(|&i| condition.is_none_or(|c| samples[i].2 == Some(c)))
        .collect();
    let labels: Vec<&str> = pool.iter().map(|&i| samples[i].1).collect();
    let smallest = labels
        .iter()
        .collect::<BTreeSet<_>>()
        .iter()
        .map(|l| labels.iter().filter(|x| x == l).count())
        .min()
        .unwrap_or(0);
    let (per_class, validation) = shrink_draw(smallest, per_class, validation);
    let split = stratified_split(&labels, Some(per_class), validation, seed)?;
    let (train_images, validation_images) = split_images(&split, |k| {
        let (frame, label, _) = samples[pool[k]];
        LabeledImage::new(frame.view(), label)
    });
    let model = train(&train_images, &validation_images, config)?;
    let note = format!(
        "Trained for this report on {}: {} training + {} validation images (seed {seed}).",
        condition.map_or_else(|| "all conditions".to_owned(), |c| format!("condition {c}")),
        train_images.len(),
        validation_images.len()
    );
    Ok((model, note))
}

/// What the report of a simulated data set takes from it: the mid-stance frame of every complete stance
/// (with its terrain, gait, trial and frame index), the first 3 s of one recording per terrain at the
/// training gait, the velocity table and the sensor. A few MB where the data set's movies are hundreds:
/// `reproduce` keeps this and drops the movies before it simulates the heavier hopper.
#[derive(Debug)]
pub struct SimulationReportData {
    /// The mid-stance image of every complete stance (terrain label, gait condition, trial source).
    samples: Vec<Sample>,
    train_gait: Option<String>,
    recordings: Vec<(String, Recording)>,
    table: VelocityTable,
    sensor: Option<SensorMeta>,
    segment: ValidSegmentParams,
}

impl SimulationReportData {
    pub fn from_dataset(dataset: &SimulatedDataset) -> Result<Self> {
        let segment = ValidSegmentParams::default();
        let mut samples = Vec::new();
        for trial in &dataset.trials {
            let segmentation = segment_recording(&trial.recording, &segment)?;
            for stance in segmentation.complete() {
                if let Some(frame) = trial.recording.frame(stance.mid_frame()) {
                    let mut sample = Sample::new(
                        frame.to_frame(),
                        trial.plan.terrain.clone(),
                        PathBuf::from(trial.plan.name()),
                        stance.mid_frame(),
                    );
                    sample.condition = Some(trial.plan.gait.name.clone());
                    samples.push(sample);
                }
            }
        }
        let gaits: BTreeSet<&str> = samples
            .iter()
            .filter_map(|s| s.condition.as_deref())
            .collect();
        let train_gait = if gaits.contains("G2") {
            Some("G2")
        } else {
            gaits.first().copied()
        }
        .map(str::to_owned);
        // One recording per terrain, at the training gait.
        let mut seen = BTreeSet::new();
        let recordings = dataset
            .trials
            .iter()
            .filter(|t| train_gait.as_ref().is_none_or(|g| &t.plan.gait.name == g))
            .filter(|t| seen.insert(t.plan.terrain.clone()))
            .map(|t| {
                let name = format!("{} (first 3 s)", t.plan.name());
                first_seconds(&t.recording, 3.0).map(|clipped| (name, clipped))
            })
            .collect::<Result<_>>()?;
        Ok(Self {
            samples,
            train_gait,
            recordings,
            table: dataset.velocity_table(),
            sensor: dataset.trials.first().map(|t| t.recording.meta.clone()),
            segment,
        })
    }
}

/// The report of a simulated data set (from [`SimulationReportData::from_dataset`]), as `presrs
/// reproduce` writes it: `evaluations` are keyed by training gait (the paper's Table II is shown next to
/// `G2`). Trains one model on G2 (13 + 7 images per terrain, `seed`) for the PCA and validation-curve
/// figures and traces four hops on wood and grass.
pub fn write_simulation_report(
    data: &SimulationReportData,
    config: &SimConfig,
    evaluations: &BTreeMap<String, EvalReport>,
    seed: u64,
    out_dir: &Path,
) -> Result<PathBuf> {
    let samples = &data.samples;
    let train_gait = data.train_gait.as_deref();
    let train_config = presrs_core::pipeline::TrainConfig::default().check()?;
    let triples = labelled(samples).unwrap_or_default();
    let model = train_report_model(
        &triples,
        train_gait,
        20,
        ValidationSize::Count(7),
        seed,
        &train_config,
    )
    .ok();
    let recordings: Vec<ReportRecording<'_>> = data
        .recordings
        .iter()
        .map(|(name, recording)| ReportRecording {
            name: name.clone(),
            recording,
        })
        .collect();
    let table = &data.table;
    let traces = simulation_traces(config, table, train_gait.unwrap_or("G2"));
    let mut inputs = ReportInputs::new(
        "presrs reproduce: the paper's experiment on the simulator",
        samples,
    );
    inputs.notes = vec![
        format!(
            "Simulated hopper on {} terrains x {} gaits, seed {seed}: the mid-stance frame of every \
             complete stance the segmentation found.",
            table.terrains.len(),
            table.gaits.len()
        ),
        provenance(None),
    ];
    inputs.sensor = data.sensor.as_ref();
    inputs.model_note = model.as_ref().map(|m| m.1.clone());
    inputs.model = model.as_ref().map(|m| &m.0);
    inputs.evaluations = named_evaluations(evaluations);
    inputs.recordings = recordings;
    inputs.segment = data.segment.clone();
    inputs.simulation = Some(SimulationInputs {
        velocity: table,
        traces: &traces,
    });
    write_report(&inputs, out_dir)
}

/// Four hops on the slowest and the fastest terrain of `table` at `gait` (nothing if tracing fails).
fn simulation_traces(config: &SimConfig, table: &VelocityTable, gait: &str) -> Vec<HopTrace> {
    let mut terrains: Vec<&str> = Vec::new();
    for preferred in ["wood", "grass"] {
        if table.terrains.iter().any(|t| t == preferred) {
            terrains.push(preferred);
        }
    }
    if terrains.is_empty() {
        terrains.extend(table.terrains.first().map(String::as_str));
    }
    terrains
        .into_iter()
        .filter_map(|t| trace_hops(config, t, gait, 4, 1e-3).ok())
        .collect()
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
fn race_notes(outcome: &EvalOutcome, command_line: Option<&str>) -> Vec<String> {
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

fn write_manifest_report(
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
    let conditions: BTreeSet<&str> = loaded
        .samples
        .iter()
        .filter_map(|s| s.condition.as_deref())
        .collect();
    let preferred = if conditions.contains("G2") {
        Some("G2")
    } else {
        conditions.first().copied()
    };
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

/// How the model the report shows was trained, in a sentence or two.
fn first_model_note(first: &FirstModel, eval_options: &EvalOptions) -> String {
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

/// The paper's Table II values for the conditions `report` tested (and overall).
fn paper_reference(report: &EvalReport) -> BTreeMap<String, f64> {
    PAPER_TABLE2
        .iter()
        .filter(|(c, _)| *c == "overall" || report.per_condition.contains_key(*c))
        .map(|(c, v)| ((*c).to_owned(), *v))
        .collect()
}

/// The words for `protocol`: `trained on G2`, `leave one group out`, `random draw`.
fn protocol_words(protocol: &Protocol) -> String {
    match protocol {
        Protocol::TrainCondition { condition, .. } => {
            Holdout::TrainCondition(condition.clone()).describe()
        }
        Protocol::LeaveOneOut { column, .. } => Holdout::LeaveOneOut(column.clone()).describe(),
    }
}

/// `presrs report`'s sensor-fault sweep: the evaluation's protocol and draws with every test image
/// perturbed at each level of
/// [`Perturbation::default_sweep`](presrs_core::perturb::Perturbation::default_sweep), for the configured
/// pipeline `config`, or with auto options for the paper's method (whatever the fixed part says) and the
/// automatic choice; each model is trained once per repeat and tested under every perturbation. Also
/// returns a note on how it was run.
pub fn fault_sweep(
    options: &ReportOptions,
    samples: &[LabeledImage<'_>],
    protocol: &Protocol,
    config: &CheckedTrainConfig,
    progress: &dyn Progress,
) -> Result<(Vec<FaultResult>, String)> {
    use presrs_core::evaluation::TestTransform;
    use presrs_core::perturb::Perturbation;
    let started = Instant::now();
    let sweep = Perturbation::default_sweep();
    let transforms: Vec<_> = sweep.iter().map(Perturbation::transform).collect();
    let mut each: Vec<Option<&TestTransform<'_>>> = vec![None];
    each.extend(transforms.iter().map(|t| Some(t as &TestTransform<'_>)));
    let auto = options.method.is_auto();
    let methods = 1 + usize::from(auto);
    let grid = samples[0].frame.grid();
    // Next to an automatic choice the paper's method; else the configured pipeline alone.
    let paper_config;
    let paper = if auto {
        paper_config = options.method.paper_config(grid)?;
        &paper_config
    } else {
        config
    };
    let candidates = if auto {
        options
            .method
            .candidates_for(grid, false, &options.samples.kind)?
    } else {
        Vec::new()
    };
    progress.note(&format!(
        "fault sweep: {} perturbations x {methods} method(s) x {} repeat(s) (--fault-repeats 0 skips it)",
        sweep.len(),
        options.fault_repeats
    ));
    let (paper_reports, auto_reports) = run_counted(
        samples,
        protocol,
        (options.fault_repeats, options.seed),
        (
            "fault sweep",
            (methods * protocol.models_per_repeat(samples) * options.fault_repeats) as u64,
        ),
        progress,
        |evaluation| {
            let paper = evaluation.run_each(Models::Config(paper), &each)?.reports;
            let auto = if auto {
                evaluation
                    .run_each(Models::Auto(options.method.auto_choice(&candidates)), &each)?
                    .reports
            } else {
                Vec::new()
            };
            Ok((paper, auto))
        },
    )?;
    let paper_name = if auto {
        PAPER_METHOD.to_owned()
    } else {
        let c = paper.config();
        format!("{} + {}", c.features.name(), c.classifier.kind().as_str())
    };
    let mut results = sweep_fault_results(&paper_name, paper_reports, &sweep);
    if auto {
        results.extend(sweep_fault_results(AUTO_METHOD, auto_reports, &sweep));
    }
    let seconds = started.elapsed().as_secs_f64();
    progress.note(&format!("fault sweep: {seconds:.1} s"));
    Ok((results, fault_sweep_note(options, protocol, seconds)))
}

/// The fault sweep's results of `method`, one per report: the first without a perturbation, then one
/// per level of `sweep`.
fn sweep_fault_results(
    method: &str,
    reports: Vec<EvalReport>,
    sweep: &[presrs_core::perturb::Perturbation],
) -> Vec<FaultResult> {
    reports
        .into_iter()
        .enumerate()
        .map(|(k, report)| FaultResult {
            perturbation: k.checked_sub(1).map(|k| sweep[k]),
            method: method.to_owned(),
            accuracy: report.overall,
        })
        .collect()
}

/// How the sweep was run: the protocol, the draw, the repeats, the seed and how long it took.
fn fault_sweep_note(options: &ReportOptions, protocol: &Protocol, seconds: f64) -> String {
    let per_class = match protocol {
        Protocol::TrainCondition { per_class, .. } | Protocol::LeaveOneOut { per_class, .. } => {
            per_class.map_or_else(
                || "every image".to_owned(),
                |n| format!("{n} images per class"),
            )
        }
    };
    let mut note = format!(
        "{} ({per_class}), {} repeat(s), seed {}; the sweep took {seconds:.1} s.",
        protocol_words(protocol),
        options.fault_repeats,
        options.seed
    );
    if options.repeats > 0 && options.repeats != options.fault_repeats {
        let _ = write!(
            note,
            " Its clean accuracy (as recorded) averages these {} repeat(s), where the evaluation \
             above averages {} with the same protocol and seeds from {}: the two figures differ by \
             the draws they cover, not by what was measured.",
            options.fault_repeats, options.repeats, options.seed
        );
    }
    note
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]

    use super::*;
    use crate::progress::Quiet;
    use presrs_core::Grid;
    use presrs_sim::{DatasetSpec, simulate_dataset};

    #[test]
    fn a_short_class_shrinks_the_whole_draw() {
        use ValidationSize::{Count, Fraction};
        assert_eq!(shrink_draw(30, 20, Count(7)), (20, Count(7)));
        assert_eq!(shrink_draw(6, 20, Count(7)), (6, Fraction(0.35)));
        assert_eq!(shrink_draw(6, 20, Count(5)), (6, Fraction(0.25)));
        assert_eq!(shrink_draw(6, 20, Fraction(0.3)), (6, Fraction(0.3)));
        // every image asked for: a count stays a count
        assert_eq!(shrink_draw(6, usize::MAX, Count(2)), (6, Count(2)));
        // the scaled draw splits: 6 picked give 2 for validation, 4 for training
        let labels = [["carpet"; 6], ["wood"; 6]].concat();
        let (per_class, validation) = shrink_draw(6, 20, Count(7));
        let split = stratified_split(&labels, Some(per_class), validation, 1).unwrap();
        assert_eq!((split.train.len(), split.validation.len()), (8, 4));
    }

    /// The entry point `reproduce` calls, on a small simulated data set.
    #[test]
    fn simulation_report_has_table1_and_the_hopper() {
        let config = SimConfig::default();
        let mut spec = DatasetSpec::paper(3);
        spec.hops_per_gait = Some(30);
        let dataset = simulate_dataset(&config, &spec).unwrap();
        let mut frames = Vec::new();
        for trial in &dataset.trials {
            let segmentation =
                segment_recording(&trial.recording, &ValidSegmentParams::default()).unwrap();
            for stance in segmentation.complete() {
                frames.push((
                    trial
                        .recording
                        .frame(stance.mid_frame())
                        .unwrap()
                        .to_frame(),
                    trial.plan.terrain.clone(),
                    trial.plan.gait.name.clone(),
                ));
            }
        }
        let samples: Vec<LabeledImage<'_>> = frames
            .iter()
            .map(|(f, t, g)| LabeledImage {
                frame: f.view(),
                label: t,
                condition: Some(g),
                group: None,
            })
            .collect();
        let protocol = Protocol::TrainCondition {
            condition: Some("G2".into()),
            per_class: Some(15),
            validation: ValidationSize::Count(5),
        };
        let config_train = presrs_core::pipeline::TrainConfig::default()
            .check()
            .unwrap();
        let report = presrs_core::evaluation::Evaluation {
            samples: &samples,
            protocol: &protocol,
            repeats: 2,
            seed: 1,
            progress: &|| {},
        }
        .run(Models::Config(&config_train))
        .unwrap();
        let evaluations = BTreeMap::from([("G2".to_owned(), report)]);
        let dir = tempfile::tempdir().unwrap();
        let index = write_simulation_report(
            &SimulationReportData::from_dataset(&dataset).unwrap(),
            &config,
            &evaluations,
            1,
            dir.path(),
        )
        .unwrap();
        let html = std::fs::read_to_string(index).unwrap();
        for needle in [
            "table1_velocity.png",
            "hopper.png",
            "confusion.png",
            "paper",
        ] {
            assert!(html.contains(needle), "{needle}");
        }
        for part in html.split("src=\"").skip(1) {
            let name = &part[..part.find('"').unwrap()];
            assert!(dir.path().join(name).is_file(), "{name}");
        }
    }

    /// The fault chart's numbers are those of `Evaluation::run_each`, and the report shows them.
    #[test]
    fn fault_sweep_numbers_come_from_the_evaluation_engine() {
        use presrs_core::classifier::ClassifierKind;
        use presrs_core::features::FeatureKind;
        use presrs_core::perturb::Perturbation;
        use presrs_core::synthetic::{SYNTHETIC_CLASSES, synthetic_frame};
        use rand::SeedableRng;

        use crate::method::{ClassifierChoice, FeatureChoice};

        // The report's options with `features`, `classifier` and the test's draw.
        let parse = |features: FeatureChoice, classifier: ClassifierKind| ReportOptions {
            per_class: 10,
            validation: ValidationSize::Count(3),
            fault_repeats: 2,
            method: Method {
                features,
                classifier: ClassifierChoice::Kind(classifier),
                dims: Some(20),
                ..Method::default()
            },
            ..ReportOptions::default()
        };
        let args = parse(
            FeatureChoice::Kinds(vec![FeatureKind::FFT1D]),
            ClassifierKind::PWE,
        );
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(4);
        let frames: Vec<(Frame, &str, &str)> = (0..96)
            .map(|i| {
                (
                    synthetic_frame(i % 4, &mut rng),
                    SYNTHETIC_CLASSES[i % 4],
                    ["G1", "G2", "G3"][(i / 4) % 3],
                )
            })
            .collect();
        let triples: Vec<(&Frame, &str, Option<&str>)> =
            frames.iter().map(|(f, l, c)| (f, *l, Some(*c))).collect();
        let config = args.method.train_config(Grid::new(44, 44)).unwrap();
        let samples = eval_samples(&triples);
        let protocol = Protocol::TrainCondition {
            condition: Some("G2".into()),
            per_class: Some(8), // 8 images per class of G2: fewer than --per-class 10
            validation: ValidationSize::Fraction(0.3), // --validation 3 of 10, scaled
        };
        let (faults, note) = fault_sweep(&args, &samples, &protocol, &config, &Quiet).unwrap();
        assert!(note.contains("2 repeat(s)"), "{note}");
        // The evaluation's 5 repeats against the sweep's 2: the page says why their figures differ.
        assert_eq!(args.repeats, 5);
        assert!(
            note.contains("averages these 2 repeat(s), where the evaluation above averages 5"),
            "{note}"
        );
        // Leaving one of 3 groups out: the progress announces the steps it takes (was 2 of 6).
        let grouped: Vec<LabeledImage<'_>> = samples
            .iter()
            .map(|s| LabeledImage {
                group: s.condition,
                ..*s
            })
            .collect();
        let by_group = Protocol::LeaveOneOut {
            column: "group".into(),
            per_class: Some(8),
            validation: ValidationSize::Fraction(0.3),
        };
        let recorder = crate::progress::Recorder::default();
        fault_sweep(&args, &grouped, &by_group, &config, &recorder).unwrap();
        let log = recorder.log();
        assert_eq!(log.tasks, [("fault sweep".to_owned(), Some(log.steps))]);
        assert_eq!(log.steps, 3 * 2, "3 groups x 2 repeats");
        assert!(
            note.starts_with("trained on G2 (8 images per class)"),
            "{note}"
        );
        let sweep = Perturbation::default_sweep();
        assert_eq!(
            faults.len(),
            1 + sweep.len(),
            "one method, the clean run and every level"
        );

        let dead = Perturbation::Dead(0.1);
        let transform = |i: usize, frame: presrs_core::FrameView<'_>, seed: u64| {
            Ok(dead.apply(frame, seed, i as u64))
        };
        let evaluation = presrs_core::evaluation::Evaluation {
            samples: &samples,
            protocol: &protocol,
            repeats: 2,
            seed: 1,
            progress: &|| {},
        };
        let direct = evaluation
            .run_each(Models::Config(&config), &[Some(&transform)])
            .unwrap()
            .reports
            .remove(0);
        let swept = faults
            .iter()
            .find(|f| f.perturbation == Some(dead))
            .unwrap();
        assert_eq!(swept.accuracy, direct.overall);
        let clean = evaluation.run(Models::Config(&config)).unwrap();
        assert_eq!(
            faults
                .iter()
                .find(|f| f.perturbation.is_none())
                .unwrap()
                .accuracy,
            clean.overall
        );

        // With the features automatic and the classifier fixed (mle), the line labelled the paper's
        // method is the paper's method: the numbers of the explicit fft1d + pwe run above (it was the
        // configured fft1d + mle).
        let mle_args = parse(FeatureChoice::Auto, ClassifierKind::MLE);
        let mle_config = mle_args.method.train_config(Grid::new(44, 44)).unwrap();
        let (auto_faults, _) =
            fault_sweep(&mle_args, &samples, &protocol, &mle_config, &Quiet).unwrap();
        let paper: Vec<_> = auto_faults
            .iter()
            .filter(|f| f.method == PAPER_METHOD)
            .map(|f| (f.perturbation, f.accuracy))
            .collect();
        let explicit: Vec<_> = faults
            .iter()
            .map(|f| (f.perturbation, f.accuracy))
            .collect();
        assert_eq!(paper, explicit);
        assert!(auto_faults.iter().any(|f| f.method == AUTO_METHOD));

        // The report draws them and tabulates the same numbers.
        let report_samples: Vec<Sample> = frames
            .iter()
            .map(|(f, l, c)| {
                let mut sample = Sample::new(f.clone(), *l, "synthetic".into(), 0);
                sample.condition = Some((*c).to_owned());
                sample
            })
            .collect();
        let mut inputs = ReportInputs::new("faults", &report_samples);
        inputs.faults = faults.clone();
        inputs.fault_note = Some(note);
        let dir = tempfile::tempdir().unwrap();
        let index = write_report(&inputs, dir.path()).unwrap();
        let html = std::fs::read_to_string(index).unwrap();
        assert!(html.contains("src=\"fault_sweep.png\""));
        assert!(dir.path().join("fault_sweep.png").is_file());
        let row = html.split("<tr><td>dead=0.1</td>").nth(1).unwrap();
        let expected = format!(
            "<td>{:.1} % ± {:.1}</td>",
            100.0 * direct.overall.mean,
            100.0 * direct.overall.std
        );
        assert!(row.starts_with(&expected), "{expected} vs {}", &row[..60]);
    }
}
