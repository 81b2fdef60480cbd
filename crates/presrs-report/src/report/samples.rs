//! The sections about the samples themselves: the data set, example images, feature spectra, load
//! curves and the principal components.

use std::collections::BTreeSet;
use std::fmt::Write as _;

use presrs_core::Crop;
use presrs_core::features::{FeatureConfig, Fft1dFamily};
use presrs_core::pipeline::{TrainedModel, extract_features};
use presrs_core::projection::pca::Pca;
use presrs_core::{FrameView, Grid, Recording};
use rayon::prelude::*;

use presrs_core::Sample;

use super::inputs::ReportInputs;
use super::page::{Job, Section, esc};
use crate::charts::{LoadCurveData, LoadCurvesFigure, ScatterFigure, SpectraFigure, SpectrumPanel};
use crate::error::{ReportError, Result};
use crate::pressure::{Outline, PressureGrid, PressureScale};

/// The samples grouped by label (rows) and condition (columns), with what the sections about them share.
pub(super) struct Groups<'a> {
    pub(super) samples: &'a [Sample],
    pub(super) scale: PressureScale,
    /// The grid of the first sample.
    pub(super) grid: Grid,
    /// The crop of the features (the model's, or the CLI's `auto`).
    pub(super) crop: Crop,
    pub(super) features_config: FeatureConfig,
    /// Labels, sorted (`(no label)` when no sample has one).
    pub(super) row_names: Vec<String>,
    /// Conditions, sorted (one unnamed column when no sample has one).
    pub(super) col_names: Vec<String>,
    /// Whether any sample names its condition.
    pub(super) has_conditions: bool,
    /// Whether the data are the paper's experiment (simulated): only then do the headings name the
    /// paper's figures. A report on a user's data speaks of that data.
    pub(super) paper: bool,
}

impl<'a> Groups<'a> {
    /// Fails when there is no sample (the report has nothing to show).
    pub(super) fn new(inputs: &ReportInputs<'a>) -> Result<Self> {
        let scale = PressureScale::from_meta(inputs.sensor);
        let samples = inputs.samples;
        let labels = distinct(samples.iter().filter_map(|s| s.label.as_deref()));
        let conditions = distinct(samples.iter().filter_map(|s| s.condition.as_deref()));
        let has_conditions = !conditions.is_empty();
        let row_names = if labels.is_empty() {
            vec!["(no label)".to_owned()]
        } else {
            labels
        };
        let col_names = if conditions.is_empty() {
            vec![String::new()]
        } else {
            conditions
        };
        let grid = samples
            .first()
            .map(|s| s.frame.grid())
            .ok_or_else(|| ReportError::Input("the report needs at least one sample".into()))?;
        Ok(Self {
            samples,
            scale,
            grid,
            crop: feature_crop(inputs.model, grid),
            features_config: inputs
                .model
                .map_or_else(FeatureConfig::default, |m| m.features().clone()),
            row_names,
            col_names,
            has_conditions,
            paper: inputs.simulation.is_some(),
        })
    }

    pub(super) fn label_index(&self, s: &Sample) -> usize {
        self.row_names
            .iter()
            .position(|n| n == label_of(s))
            .unwrap_or(0)
    }

    pub(super) fn cond_index(&self, s: &Sample) -> usize {
        s.condition
            .as_deref()
            .and_then(|c| self.col_names.iter().position(|n| n == c))
            .unwrap_or(0)
    }

    /// The features of every sample (`None` where they cannot be computed), in parallel.
    pub(super) fn features(&self) -> Features {
        let vectors: Vec<Option<Vec<f64>>> = self
            .samples
            .par_iter()
            .map(|s| extract_features(&s.frame.view(), &self.crop, &self.features_config).ok())
            .collect();
        let len = vectors.iter().flatten().map(Vec::len).next().unwrap_or(0);
        Features { vectors, len }
    }
}

/// The features of every sample; those of another length than the first are left out of the figures.
pub(super) struct Features {
    pub(super) vectors: Vec<Option<Vec<f64>>>,
    pub(super) len: usize,
}

fn label_of(sample: &Sample) -> &str {
    sample.label.as_deref().unwrap_or("(no label)")
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

/// The data set: images per label and condition, the sensor, and the model's summary.
pub(super) fn data_section<'a>(inputs: &ReportInputs<'_>, g: &Groups<'a>) -> Section<'a> {
    let Groups {
        samples,
        scale,
        row_names,
        col_names,
        ..
    } = g;
    let label_index = |s: &Sample| g.label_index(s);
    let cond_index = |s: &Sample| g.cond_index(s);
    let grid = g.grid;
    let mut counts = vec![vec![0usize; col_names.len()]; row_names.len()];
    for s in *samples {
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
    for c in col_names {
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
            "<p>Model: classes {}; crop {} → {} image; {}; classifier {} ({}).{}</p>",
            esc(&model.class_names().join(", ")),
            model.crop(),
            model.image_grid(),
            model.describe_projection(),
            esc(model.classifier().kind().as_str()),
            esc(&model.classifier().describe()),
            inputs
                .model_note
                .as_ref()
                .map_or(String::new(), |n| format!(" {}", esc(n)))
        );
    }
    Section {
        id: "data",
        heading: "Data set".into(),
        intro: summary,
        figure: None,
        after: String::new(),
    }
}

/// A heading, naming the paper's figure `figure` only for the paper's experiment.
fn paper_figure(heading: &str, figure: &str, paper: bool) -> String {
    if paper {
        format!("{heading} (the paper's {figure})")
    } else {
        heading.to_owned()
    }
}

/// Example images per label x condition (the paper's Fig. 5): the sample with the median load of each
/// cell, with the crop outlined.
pub(super) fn images_section<'a>(g: &Groups<'a>) -> Section<'a> {
    let Groups {
        samples,
        scale,
        row_names,
        col_names,
        ..
    } = g;
    let label_index = |s: &Sample| g.label_index(s);
    let cond_index = |s: &Sample| g.cond_index(s);
    let (grid, crop) = (g.grid, g.crop);
    let mut cells: Vec<Vec<Option<FrameView<'_>>>> =
        vec![vec![None; col_names.len()]; row_names.len()];
    let mut chosen: Vec<Vec<Option<&Sample>>> = vec![vec![None; col_names.len()]; row_names.len()];
    for (r, row) in cells.iter_mut().enumerate() {
        for (c, cell) in row.iter_mut().enumerate() {
            let mut members: Vec<(&Sample, f64)> = samples
                .iter()
                .filter(|s| label_index(s) == r && cond_index(s) == c)
                .map(|s| (s, s.frame.view().total()))
                .collect();
            members.sort_by(|a, b| a.1.total_cmp(&b.1));
            if let Some(&(s, _)) = members.get(members.len() / 2) {
                *cell = Some(s.frame.view());
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
                    esc(&s.source.display().to_string()),
                    s.frame_index
                );
            }
        }
    }
    chosen_list.push_str("</ul></details>");
    Section {
        id: "images",
        heading: paper_figure("Pressure images per label and condition", "Fig. 5", g.paper),
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
    }
}

/// Mean feature spectra per label, conditions overlaid (the paper's Fig. 6); `None` without features.
pub(super) fn spectra_section<'a>(g: &Groups<'a>, features: &Features) -> Option<Section<'a>> {
    let Groups {
        samples,
        scale,
        row_names,
        col_names,
        ..
    } = g;
    let label_index = |s: &Sample| g.label_index(s);
    let cond_index = |s: &Sample| g.cond_index(s);
    let (grid, crop, features_config) = (g.grid, g.crop, &g.features_config);
    let n_features = features.len;
    let features = &features.vectors;
    if n_features == 0 {
        return None;
    }
    let image_grid = crop.output_grid(grid).unwrap_or(grid);
    let fft1d = features_config.params::<Fft1dFamily>();
    let (x, x_label) = match fft1d {
        Some(config) => {
            let n = config.resolved_len(image_grid).unwrap_or(2 * n_features) as f64;
            let (_, pitch) = scale.pitches();
            let per = if scale.physical() { "mm" } else { "sensel" };
            (
                (0..n_features).map(|k| k as f64 / (n * pitch)).collect(),
                format!("spatial frequency along the row-major image vector (cycles/{per})"),
            )
        }
        None => (
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
            for (s, f) in samples.iter().zip(features) {
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
    Some(Section {
        id: "spectra",
        heading: paper_figure(
            "Feature spectra per label, conditions overlaid",
            "Fig. 6",
            g.paper,
        ),
        intro: String::new(),
        figure: Some((
            "fig6_spectra.png".into(),
            Job::Spectra(SpectraFigure {
                title: "Feature vectors |FFT(vec(I))| per label, conditions overlaid".into(),
                x,
                x_label,
                y_label: format!("|F| ({} x sensels, log scale)", scale_unit_short(scale)),
                panels,
            }),
            format!(
                "The classifier's features (the magnitude of the 1-D DFT of the cropped, row-major \
                 image), averaged over the images of each label and condition. Overlaid lines that \
                 coincide mean the terrain signature does not depend on the condition{}; the spikes \
                 repeat at multiples of one over the row length.",
                if g.paper { " (the paper's claim)" } else { "" }
            ),
        )),
        after: String::new(),
    })
}

/// Load curves of a few recordings with their stances and sampled frames; `None` without recordings.
pub(super) fn load_section<'a>(inputs: &ReportInputs<'_>) -> Option<Section<'a>> {
    if inputs.recordings.is_empty() {
        return None;
    }
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
                (inputs.sample_frame, inputs.include_partial),
            )
            .ok()
        })
        .collect();
    if curves.is_empty() {
        return None;
    }
    let caption = load_caption(&curves, inputs);
    Some(Section {
        id: "load",
        heading: "Load curves, detected stances and sampled frames".into(),
        intro: String::new(),
        figure: Some((
            "load_curves.png".into(),
            Job::Curves(LoadCurvesFigure {
                title: "Total load per frame of sample recordings".into(),
                curves,
            }),
            caption,
        )),
        after: String::new(),
    })
}

/// What the load curves show: the red dots only when some curve has a sampled frame.
fn load_caption(curves: &[LoadCurveData], inputs: &ReportInputs<'_>) -> String {
    let shown = "Total load of every frame (sum over sensels), the stance phases the segmentation \
                 found (shaded), its baseline (grey)";
    if curves.iter().any(|c| !c.sampled.is_empty()) {
        format!(
            "{shown} and the frames taken as samples ({}, red dots).",
            esc(&inputs.sample_frame.to_string())
        )
    } else {
        format!("{shown}; none of these recordings gives a sample.")
    }
}

/// The samples in the first two principal components (the model's, else fitted to them); `None` with
/// too few samples or components.
pub(super) fn pca_section<'a>(
    inputs: &ReportInputs<'_>,
    g: &Groups<'a>,
    features: &Features,
) -> Option<Section<'a>> {
    let Groups {
        samples,
        row_names,
        col_names,
        ..
    } = g;
    let label_index = |s: &Sample| g.label_index(s);
    let cond_index = |s: &Sample| g.cond_index(s);
    let n_features = features.len;
    let features = &features.vectors;
    let usable: Vec<(usize, &Vec<f64>)> = features
        .iter()
        .enumerate()
        .filter_map(|(i, f)| f.as_ref().filter(|f| f.len() == n_features).map(|f| (i, f)))
        .collect();
    let fitted;
    let (pca, pca_note): (Option<&Pca>, &str) = match inputs.model {
        Some(model)
            if model
                .pca()
                .is_some_and(|pca| pca.n_features() == n_features) =>
        {
            (
                model.pca(),
                "the model's principal components (fitted on its training images)",
            )
        }
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
    let pca = pca.filter(|p| p.n_components() >= 2)?;
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
    Some(Section {
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
                conditions: if !g.has_conditions {
                    Vec::new()
                } else {
                    col_names.clone()
                },
                points,
            }),
            format!(
                "Every image's feature vector projected on {pca_note}; {}. Separate clusters per \
                 label that mix the conditions are what a condition-independent classifier needs.",
                if row_names.len() > crate::render::PALETTE.len() {
                    "colour and marker: label (more labels than colours)"
                } else if g.has_conditions {
                    "colour: label, marker: condition"
                } else {
                    "colour: label"
                }
            ),
        )),
        after: String::new(),
    })
}

/// The value unit in an axis label (`counts` for raw counts).
fn scale_unit_short(scale: &PressureScale) -> String {
    if scale.unit == "raw counts" {
        "counts".to_owned()
    } else {
        scale.unit.clone()
    }
}
