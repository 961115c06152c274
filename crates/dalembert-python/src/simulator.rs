//! `dalembert.Simulator`: a scene driven step by step from Python ([`dalembert::Simulator`]).

use crate::errors::IntegrationError;
use crate::interrupt;
use crate::run::statistics_dict;
use dalembert::integrators::IntegrationError as RunError;
use dalembert::{Scene, SimulationError, Simulator, SimulatorError};
use numpy::PyArray1;
use pyo3::exceptions::{PyKeyError, PyKeyboardInterrupt, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use std::sync::{Arc, Mutex, MutexGuard};

/// Advances of at most this many steps run on the calling thread (with the GIL released); longer
/// ones on a helper thread while the calling thread watches for Ctrl-C, which costs a thread per
/// call (tens of microseconds, more than a short advance itself).
const INLINE_STEPS: f64 = 256.0;

/// A scene driven step by step: `step()`, `advance_to(t)`, named inputs held between sets
/// (`set_input`), any output column at the current time (`sim["slider.x"]`, the CSV's names),
/// `state` / `set_state`, `reset()`. Built by `Scene.simulator(...)` with the settings `simulate`
/// takes. Advanced in any chunks it is the same run, bitwise, as one advanced at once.
#[pyclass(name = "Simulator", module = "dalembert")]
pub struct PySimulator {
    /// Behind a mutex so that the class is `Sync` as Python objects must be (the formulations'
    /// work buffers are `Send` only); uncontended, as every method holds the object mutably.
    inner: Mutex<Simulator>,
    scene: Arc<Scene>,
}

impl PySimulator {
    pub fn new(scene: Arc<Scene>) -> PyResult<Self> {
        let inner = scene.simulator().map_err(|e| PyValueError::new_err(one_line(&e)))?;
        Ok(PySimulator {
            inner: Mutex::new(inner),
            scene,
        })
    }
}

impl PySimulator {
    fn sim(&self) -> MutexGuard<'_, Simulator> {
        // A panic while stepping poisons the lock; the simulator's state is then whatever the
        // step left, as after any failed step.
        self.inner.lock().unwrap_or_else(|p| p.into_inner())
    }
}

fn one_line(e: &impl std::fmt::Display) -> String {
    dalembert::scene::one_line(&e.to_string()).into_owned()
}

/// A refused request as `ValueError` (`KeyError` for an unknown column); a failed run as
/// `IntegrationError` with `.time`; an interrupted one as the `KeyboardInterrupt` raised.
fn error(py: Python<'_>, e: SimulatorError, raised: Option<PyErr>) -> PyResult<PyErr> {
    if let Some(r) = raised.filter(|r| r.is_instance_of::<PyKeyboardInterrupt>(py)) {
        return Ok(r);
    }
    Ok(match &e {
        SimulatorError::UnknownColumn { .. } => PyKeyError::new_err(one_line(&e)),
        SimulatorError::Simulation(SimulationError::Integration(f)) => {
            let err = IntegrationError::new_err(one_line(&e));
            let time = match f.error {
                RunError::Options(_) => None,
                _ => f.error.time(),
            };
            err.value(py).setattr("time", time)?;
            err.value(py).setattr("run", py.None())?;
            err
        }
        _ => PyValueError::new_err(one_line(&e)),
    })
}

#[pymethods]
impl PySimulator {
    /// The scene's input names (`{ input = "NAME" }` in its functions).
    #[getter]
    fn inputs(&self) -> Vec<String> {
        self.sim().inputs().to_vec()
    }

    /// Sets input `name` to `value` from now on (held until set again).
    fn set_input(&mut self, py: Python<'_>, name: &str, value: f64) -> PyResult<()> {
        match self.sim().set_input(name, value) {
            Ok(()) => Ok(()),
            Err(e) => Err(error(py, e, None)?),
        }
    }

    /// The value input `name` holds.
    fn input(&self, py: Python<'_>, name: &str) -> PyResult<f64> {
        match self.sim().input(name) {
            Ok(v) => Ok(v),
            Err(e) => Err(error(py, e, None)?),
        }
    }

    /// The current time (s).
    #[getter]
    fn t(&self) -> f64 {
        self.sim().time()
    }

    /// One step of the method (an adaptive method: one accepted step).
    fn step(&mut self, py: Python<'_>) -> PyResult<()> {
        let mut guard = self.sim();
        let inner = &mut *guard;
        match py.detach(|| inner.step()) {
            Ok(()) => Ok(()),
            Err(e) => Err(error(py, e, None)?),
        }
    }

    /// Advances to exactly `t` (s). The GIL is released; Ctrl-C stops it at the next step
    /// (KeyboardInterrupt; the simulator is then at that step and can go on).
    fn advance_to(&mut self, py: Python<'_>, t: f64) -> PyResult<()> {
        let mut guard = self.sim();
        let steps = (t - guard.time()) / self.scene.settings.step;
        let inner = &mut *guard;
        let (result, raised) = if steps.is_finite() && steps <= INLINE_STEPS {
            (py.detach(|| inner.advance_to(t)), None)
        } else {
            interrupt::run(py, |cancel| inner.advance_to_cancellable(t, cancel))
        };
        match (result, raised) {
            (Ok(()), None) => Ok(()),
            (Ok(()), Some(r)) => Err(r),
            (Err(e), raised) => Err(error(py, e, raised)?),
        }
    }

    /// The value of output column `column` at the current time (`KeyError` for an unknown one).
    fn __getitem__(&mut self, py: Python<'_>, column: &str) -> PyResult<f64> {
        match self.sim().value(column) {
            Ok(v) => Ok(v),
            Err(e) => Err(error(py, e, None)?),
        }
    }

    /// The output columns (`t` first), as in the CSV.
    #[getter]
    fn columns(&self) -> Vec<String> {
        self.sim().columns().to_vec()
    }

    /// Every output column at the current time, as a dict.
    fn row<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let mut sim = self.sim();
        let names = sim.columns().to_vec();
        let row = match sim.row() {
            Ok(r) => r.to_vec(),
            Err(e) => return Err(error(py, e, None)?),
        };
        let d = PyDict::new(py);
        for (name, value) in names.iter().zip(row) {
            d.set_item(name, value)?;
        }
        Ok(d)
    }

    /// The current state `(q, v)` as numpy arrays, in the model's coordinates (planar: x, y,
    /// angle per body; spatial: x, y, z and Euler parameters per body, then velocities).
    #[getter]
    fn state<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        let sim = self.sim();
        let (q, v) = sim.state();
        PyTuple::new(py, [PyArray1::from_slice(py, q), PyArray1::from_slice(py, v)])
    }

    /// Puts the simulator in state `(q, v)` at the current time, assembled to the constraints
    /// first; returns how far that moved it: `{"positions": ‖Δq‖∞, "velocities": ‖Δv‖∞}`.
    fn set_state<'py>(&mut self, py: Python<'py>, q: Vec<f64>, v: Vec<f64>) -> PyResult<Bound<'py, PyDict>> {
        let moved = match self.sim().set_state(&q, &v) {
            Ok(m) => m,
            Err(e) => return Err(error(py, e, None)?),
        };
        let d = PyDict::new(py);
        d.set_item("positions", moved.positions)?;
        d.set_item("velocities", moved.velocities)?;
        Ok(d)
    }

    /// Back to the initial state at t = 0, inputs at 0.
    fn reset(&mut self, py: Python<'_>) -> PyResult<()> {
        match self.sim().reset() {
            Ok(()) => Ok(()),
            Err(e) => Err(error(py, e, None)?),
        }
    }

    /// What the run has spent so far (the same keys as `Run.statistics`).
    #[getter]
    fn statistics<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        statistics_dict(py, &self.sim().statistics())
    }

    fn __repr__(&self) -> String {
        let sim = self.sim();
        format!(
            "Simulator({:?} at t = {}, inputs {:?})",
            self.scene.name,
            dalembert::system::Shortest(sim.time()),
            sim.inputs()
        )
    }
}
