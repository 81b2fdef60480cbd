//! What `results.json` holds: the reproduction's numbers beside the paper's, and where its data came from.

use std::collections::BTreeMap;
use std::path::PathBuf;

use presrs_core::evaluation::{ComparisonRow, EvalReport, MeanStd};
use serde::Serialize;

use crate::eval::CalibrationJson;

/// Where a data set came from.
#[derive(Debug, Clone, Serialize)]
pub struct DatasetOrigin {
    pub path: PathBuf,
    /// `reusing DIR (seed S, presrs V)` or `simulating DIR (seed S, M kg): REASON`.
    #[serde(skip)]
    pub note: String,
    /// Read back from `path` (its stamp matched) rather than simulated.
    pub reused: bool,
    /// Why it was simulated (no data set there, a mismatch, a changed file, `--resimulate`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub simulated_because: Option<String>,
}

/// Load independence: a model trained at the nominal load tested on images recorded at a higher load,
/// as they are and scaled by nominal / actual load (the paper's "scaling factor").
#[derive(Debug, Serialize)]
pub struct LoadCheck {
    pub nominal_load_kg: f64,
    pub test_load_kg: f64,
    pub test_images: usize,
    /// Accuracy on the heavier robot's images as recorded.
    pub accuracy_unscaled: MeanStd,
    /// Accuracy after multiplying every test image by nominal / test load.
    pub accuracy_scaled: MeanStd,
    /// Accuracy of a model trained with `--normalise-load` (each image divided by its total load) on the
    /// heavier robot's images as recorded: no knowledge of the load.
    pub accuracy_normalised: MeanStd,
}

/// One feature x classifier combination of the comparison (trained on G2, 20 per terrain, 7 validating).
#[derive(Debug, Serialize)]
pub struct ComparisonSummary {
    pub features: String,
    pub classifier: String,
    /// Over every tested image (mean and spread over repeats); `None` when it could not be trained.
    pub overall: Option<MeanStd>,
    pub per_gait: BTreeMap<String, MeanStd>,
    /// Training time of one model, ms.
    pub train_ms: MeanStd,
    pub median_classify_ns: u64,
    pub error: Option<String>,
}

impl ComparisonSummary {
    pub fn of(row: &ComparisonRow) -> Self {
        let (overall, per_gait, median_classify_ns, error) = match &row.report {
            Ok(report) => (
                Some(report.overall),
                report.per_condition.clone(),
                report.median_classify_ns,
                None,
            ),
            Err(err) => (None, BTreeMap::new(), 0, Some(err.clone())),
        };
        Self {
            features: row.features.clone(),
            classifier: row.classifier.clone(),
            overall,
            per_gait,
            train_ms: MeanStd {
                mean: 1e3 * row.train_seconds.mean,
                std: 1e3 * row.train_seconds.std,
            },
            median_classify_ns,
            error,
        }
    }
}

#[derive(Debug, Serialize)]
pub struct SegmentationCheck {
    /// Hops the simulator recorded (with a stance frame) and stances the segmentation found.
    pub true_hops: usize,
    pub found_stances: usize,
    /// True hops whose stance was found with its first and last frame within one frame.
    pub matched_within_one_frame: usize,
    /// Found mid-stance frames equal to the simulator's.
    pub same_mid_frame: usize,
}

/// The training draw: images per terrain, and how many of them validate.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Draw {
    pub per_class: usize,
    pub validation: usize,
}

#[derive(Debug, Serialize)]
pub struct Results {
    pub seed: u64,
    pub repeats: usize,
    /// Training images per terrain and how many of them validate (the paper's 20 and 7).
    pub draw: Draw,
    pub presrs_version: &'static str,
    /// Forward velocity per gait and terrain, m/s.
    pub table1: BTreeMap<String, BTreeMap<String, f64>>,
    pub table1_paper: BTreeMap<String, BTreeMap<String, f64>>,
    /// Accuracy per tested gait and overall, trained on G2 (means over repeats).
    pub table2: BTreeMap<String, f64>,
    pub table2_std: BTreeMap<String, f64>,
    pub table2_paper: BTreeMap<String, f64>,
    pub median_classify_ns: u64,
    pub paper_classify_ns: u64,
    /// Table II's confidences against whether they were right, as `eval --json` gives them.
    pub table2_calibration: CalibrationJson,
    /// Train gait -> tested gait -> accuracy (means over repeats).
    pub train_test_matrix: BTreeMap<String, BTreeMap<String, f64>>,
    pub images_per_gait: BTreeMap<String, usize>,
    pub segmentation: SegmentationCheck,
    /// Where the data sets came from: `main` and (when measured) `load`.
    pub datasets: BTreeMap<String, DatasetOrigin>,
    /// `None` when the heavier hopper could not be simulated (the reason is printed).
    pub load_independence: Option<LoadCheck>,
    /// Every feature family x classifier with Table II's protocol and draws (empty with --no-comparison).
    pub comparison: Vec<ComparisonSummary>,
    /// Full reports of every training gait.
    pub evaluations: BTreeMap<String, EvalReport>,
    pub timings_s: BTreeMap<String, f64>,
}
