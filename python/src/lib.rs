//! The native module of the `presrs` Python package (`presrs._native`): numpy arrays in and out over
//! the presrs library. The package's Python files (`presrs/__init__.py`, `presrs/sklearn.py`) re-export
//! it; see `python/README.md`.

mod arrays;
mod errors;
mod evaluate;
mod json;
mod model;
mod online;
mod progress;
mod recording;
mod sample_options;
mod simulate;
mod threads;

use pyo3::prelude::*;

#[pymodule]
fn _native(module: &Bound<'_, PyModule>) -> PyResult<()> {
    module.add("__version__", env!("CARGO_PKG_VERSION"))?;
    // The names `classifier=` and `features=` take (besides "auto"), from the core's registries.
    let classifiers = presrs::core::classifier::ClassifierKind::names();
    module.add(
        "CLASSIFIERS",
        pyo3::types::PyTuple::new(module.py(), classifiers)?,
    )?;
    let families = presrs::core::features::FeatureKind::names();
    module.add(
        "FEATURE_FAMILIES",
        pyo3::types::PyTuple::new(module.py(), families)?,
    )?;
    module.add_class::<model::Model>()?;
    module.add_class::<recording::Recording>()?;
    module.add_class::<recording::Stance>()?;
    module.add_class::<evaluate::Evaluation>()?;
    module.add_class::<simulate::Trial>()?;
    module.add_class::<online::OnlineClassifier>()?;
    module.add_function(wrap_pyfunction!(recording::read, module)?)?;
    module.add_function(wrap_pyfunction!(recording::segment, module)?)?;
    module.add_function(wrap_pyfunction!(recording::segment_params, module)?)?;
    module.add_function(wrap_pyfunction!(recording::features, module)?)?;
    module.add_function(wrap_pyfunction!(evaluate::evaluate, module)?)?;
    module.add_function(wrap_pyfunction!(arrays::check_labels, module)?)?;
    module.add_function(wrap_pyfunction!(simulate::simulate, module)?)?;
    Ok(())
}
