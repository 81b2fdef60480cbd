//! The HTML report: every figure of a data set (and model, evaluations, simulation) in one folder that
//! opens offline: `index.html` with the PNG figures beside it.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use presrs_core::Crop;
use presrs_core::evaluation::{EvalReport, MeanStd};
use presrs_core::features::FeatureConfig;
use presrs_core::pca::Pca;
use presrs_core::perturb::Perturbation;
use presrs_core::pipeline::{TrainedModel, extract_features};
use presrs_core::stance::{SampleFrame, ValidSegmentParams};
use presrs_core::{FrameView, Grid, Recording, SensorMeta};
use presrs_sim::VelocityTable;
use presrs_sim::trace::HopTrace;
use rayon::prelude::*;

use crate::charts::{
    BarSeries, BarsFigure, ConfusionFigure, FaultFigure, FaultPanel, LoadCurveData,
    LoadCurvesFigure, ReliabilityFigure, ScatterFigure, SpectraFigure, SpectrumPanel, TraceFigure,
    ValidationFigure,
};
use crate::error::{ReportError, Result};
use crate::pressure::{Outline, PressureGrid, PressureScale};
use crate::render::{Figure, save_figure};

/// One image of the data set.
#[derive(Clone, Debug)]
pub struct ReportSample<'a> {
    pub frame: FrameView<'a>,
    pub label: Option<&'a str>,
    /// The operating condition (gait, load, ...), if any.
    pub condition: Option<&'a str>,
    /// Where it came from (a file or trial name) and its 0-based frame index there.
    pub source: String,
    pub frame_index: usize,
}

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

/// Everything a report can show; all optional except the samples.
#[derive(Clone, Debug)]
pub struct ReportInputs<'a> {
    pub title: String,
    /// Lines of context under the title (command, data set, seed).
    pub notes: Vec<String>,
    /// The sensor (units and pitch) of the samples; raw counts and square sensels when `None`.
    pub sensor: Option<&'a SensorMeta>,
    pub samples: &'a [ReportSample<'a>],
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
    pub simulation: Option<SimulationInputs<'a>>,
    /// Accuracy under sensor faults (a sweep of levels per kind, a line per method); empty for none.
    pub faults: Vec<FaultResult>,
    /// How the fault results were obtained (protocol, repeats), shown under the chart.
    pub fault_note: Option<String>,
}

impl<'a> ReportInputs<'a> {
    /// Inputs with only samples (add the rest field by field).
    pub fn new(title: impl Into<String>, samples: &'a [ReportSample<'a>]) -> Self {
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
            simulation: None,
            faults: Vec::new(),
            fault_note: None,
        }
    }
}

/// How far the evaluations' confidences can be trusted: a reliability diagram and a table (`None` when
/// no evaluation tallied a confidence, e.g. one read from a file written before they were).
fn reliability_section<'a>(evaluations: &[Evaluation<'_>]) -> Option<Section<'a>> {
    let tallied: Vec<&Evaluation<'_>> = evaluations
        .iter()
        .filter(|e| e.report.reliability.count() > 0)
        .collect();
    if tallied.is_empty() {
        return None;
    }
    let series = tallied
        .iter()
        .map(|e| {
            let bins = e
                .report
                .reliability
                .bins
                .iter()
                .filter_map(|bin| Some((bin.mean_confidence()?, bin.accuracy()?, bin.count)))
                .collect();
            (e.name.clone(), bins)
        })
        .collect();
    let mut table = String::from(
        "<table><tr><th>evaluation</th><th>images</th><th>right</th><th>mean confidence when \
         right</th><th>when wrong</th><th>calibration error</th></tr>",
    );
    let or_dash = |v: Option<f64>| v.map_or("—".to_owned(), |v| format!("{v:.3}"));
    for e in &tallied {
        let r = &e.report.reliability;
        let _ = write!(
            table,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            esc(&e.name),
            r.count(),
            r.accuracy()
                .map_or("—".to_owned(), |a| format!("{:.1} %", 100.0 * a)),
            or_dash(r.mean_confidence_right()),
            or_dash(r.mean_confidence_wrong()),
            or_dash(r.expected_calibration_error()),
        );
    }
    table.push_str("</table>");
    Some(Section {
        id: "reliability",
        heading: "How far the confidences can be trusted".into(),
        intro: String::new(),
        figure: Some((
            "reliability.png".into(),
            Job::Reliability(ReliabilityFigure {
                title: "Reliability of the reported confidence (all repeats)".into(),
                series,
            }),
            "Test images grouped by the confidence the model gave their label (ten bins of 0.1); \
             each point is a bin's mean confidence against the share of its images that were right. \
             A calibrated model follows the diagonal; points above it are under-confident, below \
             over-confident. The calibration error is the image-weighted mean distance to it."
                .to_owned(),
        )),
        after: table,
    })
}

/// A figure the report writes, with its file name.
enum Job<'a> {
    Grid(PressureGrid<'a>),
    Spectra(SpectraFigure),
    Curves(LoadCurvesFigure),
    Scatter(ScatterFigure),
    Validation(ValidationFigure),
    Confusion(ConfusionFigure),
    Bars(BarsFigure),
    Trace(TraceFigure),
    Faults(FaultFigure),
    Reliability(ReliabilityFigure),
}

impl Job<'_> {
    fn save(&self, path: &Path) -> Result<()> {
        match self {
            Self::Grid(f) => save_figure(f, path),
            Self::Spectra(f) => save_figure(f, path),
            Self::Curves(f) => save_figure(f, path),
            Self::Scatter(f) => save_figure(f, path),
            Self::Validation(f) => save_figure(f, path),
            Self::Confusion(f) => save_figure(f, path),
            Self::Bars(f) => save_figure(f, path),
            Self::Trace(f) => save_figure(f, path),
            Self::Faults(f) => save_figure(f, path),
            Self::Reliability(f) => save_figure(f, path),
        }
    }

    fn size(&self) -> (u32, u32) {
        match self {
            Self::Grid(f) => f.size(),
            Self::Spectra(f) => f.size(),
            Self::Curves(f) => f.size(),
            Self::Scatter(f) => f.size(),
            Self::Validation(f) => f.size(),
            Self::Confusion(f) => f.size(),
            Self::Bars(f) => f.size(),
            Self::Trace(f) => f.size(),
            Self::Faults(f) => f.size(),
            Self::Reliability(f) => f.size(),
        }
    }
}

/// A section of the page.
struct Section<'a> {
    id: &'static str,
    heading: String,
    /// HTML before the figure.
    intro: String,
    figure: Option<(String, Job<'a>, String)>,
    /// HTML after the figure (tables).
    after: String,
}

fn label_of<'s>(sample: &ReportSample<'s>) -> &'s str {
    sample.label.unwrap_or("(no label)")
}

fn esc(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

fn pct(m: &MeanStd) -> String {
    format!("{:.1} % ± {:.1}", 100.0 * m.mean, 100.0 * m.std)
}

/// Distinct values in first-seen order, sorted.
fn distinct<'s>(values: impl Iterator<Item = &'s str>) -> Vec<String> {
    values
        .collect::<BTreeSet<_>>()
        .into_iter()
        .map(str::to_owned)
        .collect()
}

/// The crop used for features: the model's, or the CLI's `auto` (the paper's crop for 44 x 44 images).
fn feature_crop(model: Option<&TrainedModel>, grid: Grid) -> Crop {
    match model {
        Some(m) => m.crop(),
        None if grid == Grid::new(44, 44) => Crop::PAPER,
        None => Crop::NONE,
    }
}

/// Writes `out_dir/index.html` and its figures; returns the page's path.
pub fn write_report(inputs: &ReportInputs<'_>, out_dir: &Path) -> Result<PathBuf> {
    std::fs::create_dir_all(out_dir)
        .map_err(|source| presrs_io::IoError::io("create", out_dir, source))?;
    let scale = PressureScale::from_meta(inputs.sensor);
    let samples = inputs.samples;
    let labels = distinct(samples.iter().filter_map(|s| s.label));
    let conditions = distinct(samples.iter().filter_map(|s| s.condition));
    let row_names: Vec<String> = if labels.is_empty() {
        vec!["(no label)".to_owned()]
    } else {
        labels.clone()
    };
    let col_names: Vec<String> = if conditions.is_empty() {
        vec![String::new()]
    } else {
        conditions.clone()
    };
    let cond_index = |s: &ReportSample<'_>| {
        s.condition
            .and_then(|c| col_names.iter().position(|n| n == c))
            .unwrap_or(0)
    };
    let label_index =
        |s: &ReportSample<'_>| row_names.iter().position(|n| n == label_of(s)).unwrap_or(0);
    let grid = samples
        .first()
        .map(|s| s.frame.grid())
        .ok_or_else(|| ReportError::Input("the report needs at least one sample".into()))?;
    let crop = feature_crop(inputs.model, grid);
    let features_config = inputs
        .model
        .map_or_else(FeatureConfig::default, |m| m.features().clone());

    let mut sections: Vec<Section<'_>> = Vec::new();

    // Data set summary.
    let mut counts = vec![vec![0usize; col_names.len()]; row_names.len()];
    for s in samples {
        counts[label_index(s)][cond_index(s)] += 1;
    }
    let mut summary = String::new();
    let _ = write!(
        summary,
        "<p>{} images of {} x {} sensels ({}; values in {}).</p><table><tr><th>label</th>",
        samples.len(),
        grid.rows,
        grid.cols,
        if scale.physical() {
            let (r, c) = scale.pitches();
            format!("pitch {r:.2} mm x {c:.2} mm")
        } else {
            "pitch unknown: sensels drawn square".to_owned()
        },
        esc(&scale.unit)
    );
    for c in &col_names {
        let _ = write!(
            summary,
            "<th>{}</th>",
            esc(if c.is_empty() { "images" } else { c })
        );
    }
    summary.push_str("</tr>");
    for (r, name) in row_names.iter().enumerate() {
        let _ = write!(summary, "<tr><td>{}</td>", esc(name));
        for n in &counts[r] {
            let _ = write!(summary, "<td>{n}</td>");
        }
        summary.push_str("</tr>");
    }
    summary.push_str("</table>");
    if let Some(model) = inputs.model {
        let _ = write!(
            summary,
            "<p>Model: classes {}; crop {:?} → {} image; {} principal components; Parzen σ = {}.{}</p>",
            esc(&model.class_names().join(", ")),
            model.crop(),
            model.image_grid(),
            model.pca().n_components(),
            model.sigma().map_or("—".to_owned(), |s| format!("{s:.4e}")),
            inputs
                .model_note
                .as_ref()
                .map_or(String::new(), |n| format!(" {}", esc(n)))
        );
    }
    sections.push(Section {
        id: "data",
        heading: "Data set".into(),
        intro: summary,
        figure: None,
        after: String::new(),
    });

    // 1. Example images per label x condition: the sample with the median load of each cell.
    let mut cells: Vec<Vec<Option<FrameView<'_>>>> =
        vec![vec![None; col_names.len()]; row_names.len()];
    let mut chosen: Vec<Vec<Option<&ReportSample<'_>>>> =
        vec![vec![None; col_names.len()]; row_names.len()];
    for (r, row) in cells.iter_mut().enumerate() {
        for (c, cell) in row.iter_mut().enumerate() {
            let mut members: Vec<(&ReportSample<'_>, f64)> = samples
                .iter()
                .filter(|s| label_index(s) == r && cond_index(s) == c)
                .map(|s| (s, s.frame.total()))
                .collect();
            members.sort_by(|a, b| a.1.total_cmp(&b.1));
            if let Some(&(s, _)) = members.get(members.len() / 2) {
                *cell = Some(s.frame);
                chosen[r][c] = Some(s);
            }
        }
    }
    let outline = crop
        .window(grid)
        .ok()
        .filter(|&(_, _, g)| g != grid)
        .map(|(row, col, grid)| Outline { row, col, grid });
    let mut chosen_list = String::from("<details><summary>which images</summary><ul>");
    for (r, row) in chosen.iter().enumerate() {
        for (c, s) in row.iter().enumerate() {
            if let Some(s) = s {
                let _ = write!(
                    chosen_list,
                    "<li>{} {}: {} frame {}</li>",
                    esc(&row_names[r]),
                    esc(&col_names[c]),
                    esc(&s.source),
                    s.frame_index
                );
            }
        }
    }
    chosen_list.push_str("</ul></details>");
    sections.push(Section {
        id: "images",
        heading: "Pressure images per label and condition (the paper's Fig. 5)".into(),
        intro: String::new(),
        figure: Some((
            "fig5_pressure_images.png".into(),
            Job::Grid(PressureGrid {
                title: "Example pressure images (median-load sample of each label and condition)"
                    .into(),
                row_names: row_names.clone(),
                col_names: col_names.clone(),
                cells,
                scale: scale.clone(),
                outline,
            }),
            format!(
                "One image per label (rows) and condition (columns): the sample whose total load is \
                 the median of its group, drawn at the sensor's true aspect ratio on one colour scale \
                 ({}).{} Grey crossed cells are sensels that do not exist.",
                esc(&scale.unit),
                if outline.is_some() {
                    " The white rectangle is the region the classifier uses (its crop)."
                } else {
                    ""
                }
            ),
        )),
        after: chosen_list,
    });

    // Features of every sample (crop + the model's features).
    let features: Vec<Option<Vec<f64>>> = samples
        .par_iter()
        .map(|s| extract_features(&s.frame, &crop, &features_config).ok())
        .collect();
    let n_features = features.iter().flatten().map(Vec::len).next().unwrap_or(0);

    // 2. Spectra per label, conditions overlaid.
    if n_features > 0 {
        let image_grid = crop.output_grid(grid).unwrap_or(grid);
        let (x, x_label) = match &features_config {
            FeatureConfig::Fft1d(config) => {
                let n = config.resolved_len(image_grid).unwrap_or(2 * n_features) as f64;
                let (_, pitch) = scale.pitches();
                let per = if scale.physical() { "mm" } else { "sensel" };
                (
                    (0..n_features).map(|k| k as f64 / (n * pitch)).collect(),
                    format!("spatial frequency along the row-major image vector (cycles/{per})"),
                )
            }
            #[allow(unreachable_patterns)]
            _ => (
                (0..n_features).map(|k| k as f64).collect(),
                "feature index".to_owned(),
            ),
        };
        let mut panels = Vec::new();
        for (r, label) in row_names.iter().enumerate() {
            let mut lines = Vec::new();
            for (c, cond) in col_names.iter().enumerate() {
                let mut sum = vec![0.0; n_features];
                let mut n = 0usize;
                for (s, f) in samples.iter().zip(&features) {
                    if let Some(f) = f.as_ref().filter(|f| f.len() == n_features)
                        && label_index(s) == r
                        && cond_index(s) == c
                    {
                        for (a, b) in sum.iter_mut().zip(f) {
                            *a += b;
                        }
                        n += 1;
                    }
                }
                if n > 0 {
                    let name = if cond.is_empty() {
                        format!("mean of {n}")
                    } else {
                        format!("{cond} (mean of {n})")
                    };
                    lines.push((name, sum.iter().map(|v| v / n as f64).collect()));
                }
            }
            panels.push(SpectrumPanel {
                title: label.clone(),
                lines,
            });
        }
        sections.push(Section {
            id: "spectra",
            heading: "Feature spectra per label, conditions overlaid (the paper's Fig. 6)".into(),
            intro: String::new(),
            figure: Some((
                "fig6_spectra.png".into(),
                Job::Spectra(SpectraFigure {
                    title: "Feature vectors |FFT(vec(I))| per label, conditions overlaid".into(),
                    x,
                    x_label,
                    y_label: format!("|F| ({} x sensels, log scale)", scale_unit_short(&scale)),
                    panels,
                }),
                "The classifier's features (the magnitude of the 1-D DFT of the cropped, row-major \
                 image), averaged over the images of each label and condition. Overlaid lines that \
                 coincide mean the terrain signature does not depend on the condition (the paper's \
                 claim); the spikes repeat at multiples of one over the row length."
                    .to_owned(),
            )),
            after: String::new(),
        });
    }

    // 3. Load curves.
    if !inputs.recordings.is_empty() {
        let scale_of = |r: &Recording| PressureScale::from_meta(Some(&r.meta));
        let curves: Vec<LoadCurveData> = inputs
            .recordings
            .iter()
            .filter_map(|r| {
                LoadCurveData::from_recording(
                    r.name.clone(),
                    r.recording,
                    &scale_of(r.recording),
                    &inputs.segment,
                    inputs.sample_frame,
                )
                .ok()
            })
            .collect();
        if !curves.is_empty() {
            sections.push(Section {
                id: "load",
                heading: "Load curves, detected stances and sampled frames".into(),
                intro: String::new(),
                figure: Some((
                    "load_curves.png".into(),
                    Job::Curves(LoadCurvesFigure {
                        title: "Total load per frame of sample recordings".into(),
                        curves,
                    }),
                    format!(
                        "Total load of every frame (sum over sensels), the stance phases the \
                         segmentation found (shaded), its baseline (grey) and the frames taken as \
                         samples ({}, red dots).",
                        esc(&inputs.sample_frame.to_string())
                    ),
                )),
                after: String::new(),
            });
        }
    }

    // 4. Principal components.
    let usable: Vec<(usize, &Vec<f64>)> = features
        .iter()
        .enumerate()
        .filter_map(|(i, f)| f.as_ref().filter(|f| f.len() == n_features).map(|f| (i, f)))
        .collect();
    let fitted;
    let (pca, pca_note): (Option<&Pca>, &str) = match inputs.model {
        Some(model) if model.pca().n_features() == n_features => (
            Some(model.pca()),
            "the model's principal components (fitted on its training images)",
        ),
        _ if usable.len() >= 3 => {
            let flat: Vec<f64> = usable.iter().flat_map(|(_, f)| f.iter().copied()).collect();
            fitted = Pca::fit(&flat, n_features, 2).ok();
            (
                fitted.as_ref(),
                "principal components fitted to all images shown",
            )
        }
        _ => (None, ""),
    };
    if let Some(pca) = pca.filter(|p| p.n_components() >= 2) {
        let ratio = pca.explained_variance_ratio();
        let points: Vec<(f64, f64, usize, usize)> = usable
            .par_iter()
            .filter_map(|&(i, f)| {
                let z = pca.project(f).ok()?;
                Some((
                    z[0],
                    z[1],
                    label_index(&samples[i]),
                    cond_index(&samples[i]),
                ))
            })
            .collect();
        sections.push(Section {
            id: "pca",
            heading: "The images in the first two principal components".into(),
            intro: String::new(),
            figure: Some((
                "pca.png".into(),
                Job::Scatter(ScatterFigure {
                    title: "Feature vectors in the first two principal components".into(),
                    x_label: format!("PC 1 score ({:.1} % of the variance)", 100.0 * ratio[0]),
                    y_label: format!("PC 2 score ({:.1} % of the variance)", 100.0 * ratio[1]),
                    labels: row_names.clone(),
                    conditions: if conditions.is_empty() {
                        Vec::new()
                    } else {
                        col_names.clone()
                    },
                    points,
                }),
                format!(
                    "Every image's feature vector projected on {pca_note}; colour: label, marker: \
                     condition. Separate clusters per label that mix the conditions are what a \
                     condition-independent classifier needs."
                ),
            )),
            after: String::new(),
        });
    }

    // 5. Validation curve.
    if let Some(model) = inputs.model {
        let curve: Vec<(f64, f64)> = model
            .validation_curve()
            .iter()
            .map(|p| (p.sigma, p.accuracy))
            .collect();
        let confidence: Vec<(f64, f64)> = model
            .validation_curve()
            .iter()
            .filter_map(|p| Some((p.sigma, p.mean_log_posterior?.exp())))
            .collect();
        if !curve.is_empty() {
            sections.push(Section {
                id: "validation",
                heading: "Choosing the hyper-parameters".into(),
                intro: String::new(),
                figure: Some((
                    "validation.png".into(),
                    Job::Validation(ValidationFigure {
                        title: "Validation curve and principal components".into(),
                        curve,
                        confidence,
                        chosen_sigma: model.sigma(),
                        explained: model.pca().explained_variance_ratio(),
                        kept: model.pca().n_components(),
                    }),
                    "Left: accuracy on the validation images of a model trained on the training \
                     images only, for each Parzen width σ tried, and the geometric mean of the \
                     posterior it gives their true class; the red line is the σ kept: the most \
                     accurate, and among those the most confident in the right answers (the lowest \
                     log-loss). Right: \
                     share of the training variance the kept principal components explain."
                        .to_owned(),
                )),
                after: String::new(),
            });
        }
    }

    // 6 and 7. Evaluations.
    if !inputs.evaluations.is_empty() {
        let matrices = inputs
            .evaluations
            .iter()
            .map(|e| {
                let total: u64 = e.report.confusion.counts.iter().flatten().sum();
                (
                    format!("{} ({} tests)", e.name, total),
                    e.report.confusion.clone(),
                )
            })
            .collect();
        sections.push(Section {
            id: "confusion",
            heading: "Confusion matrices".into(),
            intro: String::new(),
            figure: Some((
                "confusion.png".into(),
                Job::Confusion(ConfusionFigure {
                    title: "Confusion matrices (counts summed over repeats)".into(),
                    matrices,
                }),
                "Rows: true class; columns: predicted class. Each cell gives the count over all \
                 repeats and its share of the row; the colour is that share."
                    .to_owned(),
            )),
            after: String::new(),
        });
        let mut categories: Vec<String> = inputs
            .evaluations
            .iter()
            .flat_map(|e| e.report.per_condition.keys().cloned())
            .collect::<BTreeSet<_>>()
            .into_iter()
            .collect();
        categories.push("overall".into());
        let value = |e: &Evaluation<'_>, c: &str| {
            if c == "overall" {
                Some(e.report.overall)
            } else {
                e.report.per_condition.get(c).copied()
            }
        };
        let series: Vec<BarSeries> = inputs
            .evaluations
            .iter()
            .map(|e| BarSeries {
                name: e.name.clone(),
                values: categories
                    .iter()
                    .map(|c| value(e, c).map(|m| (100.0 * m.mean, 100.0 * m.std)))
                    .collect(),
                reference: categories
                    .iter()
                    .map(|c| e.reference.get(c).map(|v| 100.0 * v))
                    .collect(),
            })
            .collect();
        let low = series
            .iter()
            .flat_map(|s| {
                s.values
                    .iter()
                    .flatten()
                    .map(|(m, sd)| m - sd)
                    .chain(s.reference.iter().flatten().copied())
            })
            .fold(100.0_f64, f64::min);
        let y0 = ((low - 8.0) / 10.0).floor().clamp(0.0, 9.0) * 10.0;
        let repeats = inputs
            .evaluations
            .iter()
            .map(|e| e.report.repeats.len())
            .max()
            .unwrap_or(1);
        let has_reference = inputs.evaluations.iter().any(|e| !e.reference.is_empty());
        let mut table = String::from("<table><tr><th>evaluation</th>");
        for c in &categories {
            let _ = write!(table, "<th>{}</th>", esc(c));
        }
        table.push_str("</tr>");
        for e in &inputs.evaluations {
            let _ = write!(table, "<tr><td>{}</td>", esc(&e.name));
            for c in &categories {
                let _ = write!(
                    table,
                    "<td>{}</td>",
                    value(e, c).map_or("—".into(), |m| pct(&m))
                );
            }
            table.push_str("</tr>");
            if !e.reference.is_empty() {
                let _ = write!(table, "<tr class=\"ref\"><td>{} — paper</td>", esc(&e.name));
                for c in &categories {
                    let _ = write!(
                        table,
                        "<td>{}</td>",
                        e.reference
                            .get(c)
                            .map_or("—".into(), |v| format!("{:.1} %", 100.0 * v))
                    );
                }
                table.push_str("</tr>");
            }
        }
        table.push_str("</table>");
        let first = &inputs.evaluations[0].report;
        let _ = write!(
            table,
            "<p>Median classification time {:.1} µs per image.</p>",
            first.median_classify_ns as f64 / 1e3
        );
        sections.push(Section {
            id: "accuracy",
            heading: "Accuracy per condition".into(),
            intro: String::new(),
            figure: Some((
                "accuracy.png".into(),
                Job::Bars(BarsFigure {
                    title: "Accuracy per tested condition".into(),
                    x_label: "tested condition".into(),
                    y_label: "accuracy (%)".into(),
                    categories,
                    series,
                    reference_name: has_reference.then(|| "paper".to_owned()),
                    y_range: Some((y0, 100.5)),
                    spread_name: (repeats > 1).then(|| format!("±1 std over {repeats} repeats")),
                }),
                "Bars: mean accuracy over repeats with new random training draws; whiskers: one \
                 standard deviation; diamonds: the paper's values where known."
                    .to_owned(),
            )),
            after: table,
        });
        if let Some(section) = reliability_section(&inputs.evaluations) {
            sections.push(section);
        }
    }

    // 7b. Accuracy against fault level.
    if let Some(section) = fault_section(&inputs.faults, inputs.fault_note.as_deref()) {
        sections.push(section);
    }

    // 8. Simulation.
    if let Some(sim) = &inputs.simulation {
        let table = sim.velocity;
        let series: Vec<BarSeries> = table
            .gaits
            .iter()
            .enumerate()
            .map(|(g, gait)| BarSeries {
                name: format!("{gait} simulated"),
                values: table
                    .terrains
                    .iter()
                    .enumerate()
                    .map(|(t, _)| {
                        table
                            .velocity_m_per_s
                            .get(g)
                            .and_then(|row| row.get(t))
                            .copied()
                            .filter(|v| v.is_finite())
                            .map(|v| (v, 0.0))
                    })
                    .collect(),
                reference: table
                    .terrains
                    .iter()
                    .map(|t| VelocityTable::paper_value(gait, t))
                    .collect(),
            })
            .collect();
        let mut html = String::from("<table><tr><th>gait</th>");
        for t in &table.terrains {
            let _ = write!(html, "<th>{}</th>", esc(t));
        }
        html.push_str("</tr>");
        for (g, gait) in table.gaits.iter().enumerate() {
            let _ = write!(html, "<tr><td>{}</td>", esc(gait));
            for (t, terrain) in table.terrains.iter().enumerate() {
                let v = table
                    .velocity_m_per_s
                    .get(g)
                    .and_then(|row| row.get(t))
                    .copied()
                    .unwrap_or(f64::NAN);
                let paper = VelocityTable::paper_value(gait, terrain).map_or(String::new(), |p| {
                    format!(" <span class=\"ref\">(paper {p:.2})</span>")
                });
                let _ = write!(html, "<td>{v:.2}{paper}</td>");
            }
            html.push_str("</tr>");
        }
        html.push_str("</table>");
        sections.push(Section {
            id: "table1",
            heading: "Table I: forward velocity of the simulated hopper".into(),
            intro: String::new(),
            figure: Some((
                "table1_velocity.png".into(),
                Job::Bars(BarsFigure {
                    title: "Mean forward velocity per terrain and gait".into(),
                    x_label: "terrain".into(),
                    y_label: "forward velocity (m/s)".into(),
                    categories: table.terrains.clone(),
                    series,
                    reference_name: Some("paper (Table I)".into()),
                    y_range: None,
                    spread_name: None,
                }),
                "Mean forward velocity over the recorded hops (m/s); diamonds: the paper's Table I."
                    .to_owned(),
            )),
            after: html,
        });
        if !sim.traces.is_empty() {
            sections.push(Section {
                id: "hopper",
                heading: "The hopper over a few hops".into(),
                intro: String::new(),
                figure: Some((
                    "hopper.png".into(),
                    Job::Trace(TraceFigure {
                        title: "Simulated hopper: body path and ground force".into(),
                        traces: sim.traces.to_vec(),
                    }),
                    "Top: the body's path (thick where the foot is on the ground). Bottom: the \
                     ground's normal force (solid) and tangential force (dashed, negative = braking) \
                     on the foot."
                        .to_owned(),
                )),
                after: String::new(),
            });
        }
    }

    // Render the figures in parallel, then the page.
    let results: Vec<Result<()>> = sections
        .par_iter()
        .filter_map(|s| s.figure.as_ref())
        .map(|(name, job, _)| job.save(&out_dir.join(name)))
        .collect();
    for result in results {
        result?;
    }
    let page = html_page(inputs, &sections);
    let index = out_dir.join("index.html");
    presrs_io::write_atomic(&index, |w| w.write_all(page.as_bytes()))?;
    Ok(index)
}

/// The panels of the fault chart: a panel per kind present in `faults` (in [`Perturbation::KINDS`]
/// order), a line per method, the clean run at the kind's clean level.
pub fn fault_panels(faults: &[FaultResult]) -> Vec<FaultPanel> {
    let mut methods: Vec<&str> = Vec::new();
    for f in faults {
        if !methods.contains(&f.method.as_str()) {
            methods.push(&f.method);
        }
    }
    let mut panels = Vec::new();
    for kind in Perturbation::KINDS {
        let of_kind: Vec<&FaultResult> = faults
            .iter()
            .filter(|f| f.perturbation.is_some_and(|p| p.kind() == kind))
            .collect();
        let Some(example) = of_kind.first().and_then(|f| f.perturbation) else {
            continue;
        };
        let lines = methods
            .iter()
            .filter_map(|&method| {
                let clean = faults
                    .iter()
                    .filter(|f| f.perturbation.is_none() && f.method == method)
                    .map(|f| (example.clean_level(), f.accuracy));
                let perturbed = of_kind
                    .iter()
                    .filter(|f| f.method == method)
                    .filter_map(|f| Some((f.perturbation?.level(), f.accuracy)));
                let mut points: Vec<(f64, f64, f64)> = clean
                    .chain(perturbed)
                    .map(|(level, a)| (level, 100.0 * a.mean, 100.0 * a.std))
                    .collect();
                points.sort_by(|a, b| a.0.total_cmp(&b.0));
                (!points.is_empty()).then(|| (method.to_owned(), points))
            })
            .collect();
        panels.push(FaultPanel {
            title: kind.to_owned(),
            x_label: example.level_name().to_owned(),
            lines,
        });
    }
    panels
}

/// The section of the accuracy-against-fault chart and its table (`None` without perturbed results).
fn fault_section<'a>(faults: &[FaultResult], note: Option<&str>) -> Option<Section<'a>> {
    let panels = fault_panels(faults);
    if panels.is_empty() {
        return None;
    }
    let mut methods: Vec<&str> = Vec::new();
    for f in faults {
        if !methods.contains(&f.method.as_str()) {
            methods.push(&f.method);
        }
    }
    let mut table = String::from("<table><tr><th>test images</th>");
    for m in &methods {
        let _ = write!(table, "<th>{}</th>", esc(m));
    }
    table.push_str("</tr>");
    let mut rows: Vec<Option<Perturbation>> = Vec::new();
    for f in faults {
        if !rows.contains(&f.perturbation) {
            rows.push(f.perturbation);
        }
    }
    for row in rows {
        let name = row.map_or_else(|| "as recorded".to_owned(), |p| p.to_string());
        let _ = write!(table, "<tr><td>{}</td>", esc(&name));
        for m in &methods {
            let cell = faults
                .iter()
                .find(|f| f.perturbation == row && f.method == *m)
                .map_or("—".to_owned(), |f| pct(&f.accuracy));
            let _ = write!(table, "<td>{cell}</td>");
        }
        table.push_str("</tr>");
    }
    table.push_str("</table>");
    let repeats = note.map_or(String::new(), |n| format!(" {}", esc(n)));
    Some(Section {
        id: "faults",
        heading: "Accuracy against sensor faults".into(),
        intro: String::new(),
        figure: Some((
            "fault_sweep.png".into(),
            Job::Faults(FaultFigure {
                title: "Accuracy with faulty test images, per kind of fault".into(),
                panels,
                spread_name: Some("±1 std over repeats".into()),
            }),
            format!(
                "Every test image perturbed (training images as recorded; the same training draws \
                 and models at every level): dead = a fraction of the sensels read 0, stuck = read \
                 the image's maximum, gain = each sensel's gain drawn around 1, noise = Gaussian \
                 noise on every reading, shift = the foot print moved by whole sensels, rotate = \
                 turned about its centre of pressure, load = every value scaled. The leftmost point \
                 of each panel (the one at factor 1 for load) is the clean test set; where the \
                 lines coincide, the automatic choice picked the paper's method.{repeats}"
            ),
        )),
        after: table,
    })
}

fn scale_unit_short(scale: &PressureScale) -> String {
    if scale.unit == "raw counts" {
        "counts".to_owned()
    } else {
        scale.unit.clone()
    }
}

fn html_page(inputs: &ReportInputs<'_>, sections: &[Section<'_>]) -> String {
    let mut page = String::new();
    let _ = write!(
        page,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\
         <title>{title}</title><style>\
         body{{font-family:sans-serif;max-width:1200px;margin:2em auto;padding:0 1em;color:#222;line-height:1.45}}\
         h1{{font-size:1.6em}}h2{{font-size:1.25em;margin-top:2em;border-bottom:1px solid #ccc}}\
         figure{{margin:1em 0}}figure img{{max-width:100%;height:auto;border:1px solid #eee}}\
         figcaption{{color:#444;font-size:.95em}}table{{border-collapse:collapse;margin:1em 0}}\
         td,th{{border:1px solid #bbb;padding:.25em .6em;text-align:right}}th{{background:#f2f2f2}}\
         td:first-child{{text-align:left}}.ref{{color:#666}}nav a{{margin-right:1em}}\
         </style></head><body>\n<h1>{title}</h1>\n",
        title = esc(&inputs.title)
    );
    for note in &inputs.notes {
        let _ = writeln!(page, "<p>{}</p>", esc(note));
    }
    page.push_str("<nav>");
    for s in sections {
        let _ = write!(page, "<a href=\"#{}\">{}</a>", s.id, esc(&s.heading));
    }
    page.push_str("</nav>\n");
    for s in sections {
        let _ = write!(
            page,
            "<section id=\"{}\"><h2>{}</h2>{}",
            s.id,
            esc(&s.heading),
            s.intro
        );
        if let Some((name, job, caption)) = &s.figure {
            let (w, h) = job.size();
            let _ = write!(
                page,
                "<figure><img src=\"{name}\" width=\"{w}\" height=\"{h}\" alt=\"{}\">\
                 <figcaption>{caption}</figcaption></figure>",
                esc(&s.heading)
            );
        }
        let _ = writeln!(page, "{}</section>", s.after);
    }
    let _ = writeln!(
        page,
        "<footer><p class=\"ref\">Written by presrs {}.</p></footer></body></html>",
        env!("CARGO_PKG_VERSION")
    );
    page
}
