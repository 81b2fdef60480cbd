//! What a report is made from: the samples and, optionally, a model, evaluations, fault results and
//! the simulator's outputs.

use std::collections::BTreeMap;

use presrs_core::evaluation::{EvalReport, MeanStd};
use presrs_core::perturb::Perturbation;
use presrs_core::pipeline::TrainedModel;
use presrs_core::stance::{SampleFrame, ValidSegmentParams};
use presrs_core::{Recording, Sample, SensorMeta};
use presrs_sim::VelocityTable;
use presrs_sim::trace::HopTrace;

/// A recording whose load curve is shown.
#[derive(Clone, Debug)]
pub struct ReportRecording<'a> {
    pub name: String,
    pub recording: &'a Recording,
}

/// An evaluation to show (confusion matrix, accuracy per condition).
#[derive(Clone, Debug)]
pub struct Evaluation<'a> {
    /// E.g. `trained on G2`.
    pub name: String,
    pub report: &'a EvalReport,
    /// Reference accuracies per tested condition (and `overall`) to compare with, e.g. the paper's
    /// Table II; empty for none.
    pub reference: BTreeMap<String, f64>,
}

/// Accuracy of one method with every test image perturbed ([`presrs_core::perturb`]): one point of the
/// accuracy-against-fault chart. `perturbation: None` is the clean run, drawn at the clean level of
/// every kind.
#[derive(Clone, Debug, PartialEq)]
pub struct FaultResult {
    pub perturbation: Option<Perturbation>,
    /// E.g. `paper: fft1d + pwe`, `automatic choice`.
    pub method: String,
    pub accuracy: MeanStd,
}

/// What only simulated data sets have.
#[derive(Clone, Debug)]
pub struct SimulationInputs<'a> {
    /// Table I: forward velocity per gait and terrain (with the paper's values).
    pub velocity: &'a VelocityTable,
    /// A few hops of the hopper (see `presrs_sim::trace::trace_hops`).
    pub traces: &'a [HopTrace],
}

/// Early decisions (`eval --decide-at`): accuracy against the decision point after touchdown.
#[derive(Clone, Debug, PartialEq)]
pub struct EarlyCurve {
    /// The decision points, in increasing frames.
    pub points: Vec<EarlyCurvePoint>,
    /// The whole-stance classifier at lift-off, on the same held-out stances.
    pub whole_accuracy: f64,
    /// `auto` (the first point whose confidence passes the learned threshold, else the deadline point),
    /// when evaluated.
    pub auto: Option<EarlyAutoResult>,
    /// Median length of the held-out stances, frames.
    pub median_stance_frames: usize,
    /// The recordings' frame period, when they state one (times are then given in ms too).
    pub frame_period_ms: Option<f64>,
    /// Held-out stances.
    pub tested: usize,
    /// How the stances were held out (e.g. `leave one group out, 2 folds`).
    pub note: String,
}

/// One decision point of [`EarlyCurve`].
#[derive(Clone, Debug, PartialEq)]
pub struct EarlyCurvePoint {
    /// `K`: frames after touchdown.
    pub frames: usize,
    /// The stance model's classifier for `K`.
    pub accuracy: f64,
    /// The one-frame model on frame `K` of the same stances, when measured.
    pub frame_accuracy: Option<f64>,
}

/// `auto`'s result in [`EarlyCurve`].
#[derive(Clone, Debug, PartialEq)]
pub struct EarlyAutoResult {
    pub accuracy: f64,
    /// Mean decision time after touchdown, frames (a lift-off decision counts the stance's length).
    pub mean_frames: f64,
    /// Share of the stances decided before their lift-off.
    pub decided_early: f64,
    /// Share of the stances decided by their mid-stance (at most half their own length).
    pub decided_by_mid_stance: f64,
}

/// Everything a report can show; all optional except the samples.
#[derive(Clone, Debug)]
pub struct ReportInputs<'a> {
    pub title: String,
    /// Lines of context under the title (command, data set, seed).
    pub notes: Vec<String>,
    /// The sensor (units and pitch) of the samples; raw counts and square sensels when `None`.
    pub sensor: Option<&'a SensorMeta>,
    pub samples: &'a [Sample],
    /// A trained model: its crop, features, PCA and validation curve are shown.
    pub model: Option<&'a TrainedModel>,
    /// How the model was obtained (e.g. `trained on G2, 13 + 7 images per class, seed 1`).
    pub model_note: Option<String>,
    pub evaluations: Vec<Evaluation<'a>>,
    /// Recordings whose load curves are shown (a handful).
    pub recordings: Vec<ReportRecording<'a>>,
    /// How the stances of those recordings are found and sampled.
    pub segment: ValidSegmentParams,
    pub sample_frame: SampleFrame,
    /// Whether stances cut by a recording's ends are sampled too (`--include-partial`, and every
    /// recording with one sample per file).
    pub include_partial: bool,
    pub simulation: Option<SimulationInputs<'a>>,
    /// Accuracy under sensor faults (a sweep of levels per kind, a line per method); empty for none.
    pub faults: Vec<FaultResult>,
    /// How the fault results were obtained (protocol, repeats), shown under the chart.
    pub fault_note: Option<String>,
    /// Early decisions against decision time (`eval --decide-at`); `None` for none.
    pub early: Option<EarlyCurve>,
    /// `eval --leave-class-out`'s figures, per held-out class.
    pub novelty: Option<NoveltyResult>,
}

impl<'a> ReportInputs<'a> {
    /// Inputs with only samples (add the rest field by field).
    pub fn new(title: impl Into<String>, samples: &'a [Sample]) -> Self {
        Self {
            title: title.into(),
            notes: Vec::new(),
            sensor: None,
            samples,
            model: None,
            model_note: None,
            evaluations: Vec::new(),
            recordings: Vec::new(),
            segment: ValidSegmentParams::default(),
            sample_frame: SampleFrame::default(),
            include_partial: false,
            simulation: None,
            faults: Vec::new(),
            fault_note: None,
            early: None,
            novelty: None,
        }
    }
}

/// One held-out class's figures (`presrs::eval::novelty::HeldOutClass`, as the report needs them).
#[derive(Clone, Debug, PartialEq)]
pub struct NoveltyRow {
    pub class: String,
    pub novel_samples: usize,
    pub known_samples: usize,
    pub auroc: Option<f64>,
    pub auroc_posterior: Option<f64>,
    /// Shares of held-out samples decided as a known class with confidence >= 0.9, with and without the
    /// novelty score.
    pub confident_known: f64,
    pub confident_known_without: f64,
    /// Share of known test samples decided `unknown`.
    pub known_rejected: f64,
}

/// The leave-class-out results a report shows.
#[derive(Clone, Debug, PartialEq)]
pub struct NoveltyResult {
    /// How they were obtained (protocol, threshold), shown above the table.
    pub note: String,
    pub rows: Vec<NoveltyRow>,
}
