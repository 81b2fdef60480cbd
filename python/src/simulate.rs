//! `presrs.simulate`: the hopper simulator's recordings (one TekScan-like movie per trial), in memory.

use std::path::PathBuf;

use presrs::Warnings;
use presrs::simulator::dataset::{DatasetSpec, simulate_dataset};
use pyo3::prelude::*;

use crate::errors::IntoPyResult;
use crate::recording::Recording;
use crate::threads::detached;

/// One simulated trial: a movie of a hopper on one terrain with one gait.
#[pyclass(module = "presrs", name = "Trial", frozen, get_all)]
#[derive(Debug)]
pub struct Trial {
    /// `wood_G1_000`: terrain, gait and trial index.
    name: String,
    /// The terrain (the label a classifier should give).
    terrain: String,
    /// The gait (the condition).
    gait: String,
    /// Body mass with payload, kg.
    load_kg: f64,
    /// The pressure movie under the foot.
    recording: Py<Recording>,
}

#[pymethods]
impl Trial {
    fn __repr__(&self) -> String {
        format!(
            "<presrs.Trial {}: {} frames>",
            self.name,
            self.recording.get().recording.frame_count()
        )
    }
}

/// Simulates trials of the hopper on `terrains` (built-in: wood, carpet, clay, grass) with `gaits`
/// (G1-G3), `hops` recorded hops each (default: the configuration's), as `presrs simulate` does: same
/// seed, same frames. `config`: a simulator configuration file (JSON) instead of the paper's.
#[pyfunction]
#[pyo3(signature = (*, terrains = None, gaits = None, hops = None, seed = 1, load_kg = None,
    config = None))]
pub fn simulate(
    py: Python<'_>,
    terrains: Option<Vec<String>>,
    gaits: Option<Vec<String>>,
    hops: Option<usize>,
    seed: u64,
    load_kg: Option<f64>,
    config: Option<PathBuf>,
) -> PyResult<Vec<Trial>> {
    let config = presrs::sim::load_config(config.as_deref()).py_err()?;
    let mut spec = DatasetSpec::paper(seed);
    if let Some(terrains) = terrains {
        spec.terrains = terrains;
    }
    if let Some(gaits) = gaits {
        spec.gaits = gaits;
    }
    spec.hops_per_gait = hops;
    spec.load_kg = load_kg;
    let dataset = detached(py, || simulate_dataset(&config, &spec))?
        .map_err(presrs::Error::from)
        .py_err()?;
    dataset
        .trials
        .into_iter()
        .map(|trial| {
            Ok(Trial {
                name: trial.plan.name(),
                terrain: trial.plan.terrain.clone(),
                gait: trial.plan.gait.name.clone(),
                load_kg: trial.plan.load_kg,
                recording: Py::new(py, Recording::of(trial.recording, None, Warnings::new()))?,
            })
        })
        .collect()
}
