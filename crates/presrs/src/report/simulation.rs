//! The report of a simulated data set, as `presrs reproduce` writes it, with the paper's Table II beside
//! the evaluation trained on G2.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use presrs_core::evaluation::EvalReport;
use presrs_core::pipeline::{CheckedTrainConfig, LabeledImage, TrainedModel, train};
use presrs_core::split::{ValidationSize, stratified_split};
use presrs_core::stance::{ValidSegmentParams, segment_recording};
use presrs_core::{Frame, Recording, SensorMeta};
use presrs_report::{Evaluation, ReportInputs, ReportRecording, SimulationInputs};
use presrs_sim::{SimConfig, SimulatedDataset, VelocityTable};

use super::draws::shrink_draw;
use super::model_check::labelled;
use super::page::write_report;
use super::provenance::provenance;
use super::sources::{first_seconds, preferred_condition, simulation_traces};
use crate::dataset::Sample;
use crate::error::Result;
use crate::train::split_images;

/// The paper's Table II (trained on G2).
pub const PAPER_TABLE2: [(&str, f64); 4] = [
    ("G1", 0.993),
    ("G2", 0.991),
    ("G3", 0.986),
    ("overall", 0.990),
];

/// The names of `evaluations`' reports: `trained on KEY`.
// Called by `reproduce` and `eval` once they write reports.
pub(super) fn named_evaluations(evaluations: &BTreeMap<String, EvalReport>) -> Vec<Evaluation<'_>> {
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
        let train_gait = preferred_condition(&samples).map(str::to_owned);
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

/// The paper's Table II values for the conditions `report` tested (and overall).
pub(super) fn paper_reference(report: &EvalReport) -> BTreeMap<String, f64> {
    PAPER_TABLE2
        .iter()
        .filter(|(c, _)| *c == "overall" || report.per_condition.contains_key(*c))
        .map(|(c, v)| ((*c).to_owned(), *v))
        .collect()
}
