//! The native part of the `dalembert` Python package (`dalembert._dalembert`). Everything here is
//! a thin conversion of the Rust facade: scenes, runs as numpy arrays, the check report, inverse
//! dynamics, the trade table and sweep chunks. The pure-Python part (`python/dalembert`) adds the
//! sweep driver for executors, pandas and matplotlib helpers.

use pyo3::prelude::*;

mod convert;
mod errors;
mod interrupt;
mod run;
mod scene;
mod simulator;

/// The native module.
#[pymodule]
fn _dalembert(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add_class::<scene::PyScene>()?;
    m.add_class::<run::PyRun>()?;
    m.add_class::<simulator::PySimulator>()?;
    m.add_class::<simulator::PyBodyMotion>()?;
    m.add("SceneError", py.get_type::<errors::SceneError>())?;
    m.add("IntegrationError", py.get_type::<errors::IntegrationError>())?;
    m.add_function(wrap_pyfunction!(scene::sweep_runs, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
