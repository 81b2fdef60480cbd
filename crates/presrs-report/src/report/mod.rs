//! The HTML report: every figure of a data set (and model, evaluations, simulation) in one folder that
//! opens offline: `index.html` with the PNG figures beside it.
//!
//! One file per group of sections; [`write_report`] lists them in page order.

mod early;
mod evaluation;
mod faults;
mod inputs;
mod novelty;
mod page;
mod samples;
mod simulation;

use std::path::{Path, PathBuf};

use rayon::prelude::*;

use self::early::early_section;
use self::evaluation::{
    accuracy_section, confusion_section, reliability_section, validation_section,
};
use self::faults::fault_section;
use self::novelty::novelty_section;
use self::page::{Section, html_page};
use self::samples::{
    Groups, data_section, images_section, load_section, pca_section, spectra_section,
};
use self::simulation::{hopper_section, table1_section};
use crate::error::Result;

pub use self::faults::fault_panels;
pub use self::inputs::{
    EarlyAutoResult, EarlyCurve, EarlyCurvePoint, Evaluation, FaultResult, NoveltyResult,
    NoveltyRow, ReportInputs, ReportRecording, SimulationInputs,
};

/// Writes `out_dir/index.html` and its figures; returns the page's path.
pub fn write_report(inputs: &ReportInputs<'_>, out_dir: &Path) -> Result<PathBuf> {
    std::fs::create_dir_all(out_dir)
        .map_err(|source| presrs_io::IoError::io("create", out_dir, source))?;
    let groups = Groups::new(inputs)?;
    let mut sections = vec![data_section(inputs, &groups), images_section(&groups)];
    let features = groups.features();
    sections.extend(spectra_section(&groups, &features));
    sections.extend(load_section(inputs));
    sections.extend(pca_section(inputs, &groups, &features));
    sections.extend(inputs.model.and_then(validation_section));
    if !inputs.evaluations.is_empty() {
        sections.push(confusion_section(&inputs.evaluations));
        sections.push(accuracy_section(&inputs.evaluations));
        sections.extend(reliability_section(&inputs.evaluations));
    }
    sections.extend(early_section(inputs.early.as_ref()));
    sections.extend(inputs.novelty.as_ref().and_then(novelty_section));
    sections.extend(fault_section(&inputs.faults, inputs.fault_note.as_deref()));
    if let Some(sim) = &inputs.simulation {
        sections.push(table1_section(sim));
        sections.extend(hopper_section(sim));
    }
    save_figures(&sections, out_dir)?;
    let index = out_dir.join("index.html");
    let page = html_page(inputs, &sections);
    presrs_io::write_atomic(&index, |w| w.write_all(page.as_bytes()))?;
    Ok(index)
}

/// Renders the sections' figures into `out_dir`, in parallel; the first error in page order wins.
fn save_figures(sections: &[Section<'_>], out_dir: &Path) -> Result<()> {
    let results: Vec<Result<()>> = sections
        .par_iter()
        .filter_map(|s| s.figure.as_ref())
        .map(|(name, job, _)| job.save(&out_dir.join(name)))
        .collect();
    results.into_iter().collect()
}
