//! `dalembert.Simulator`: a scene driven step by step from Python ([`dalembert::Simulator`]).

use crate::errors::IntegrationError;
use crate::interrupt;
use crate::run::statistics_dict;
use dalembert::integrators::IntegrationError as RunError;
use dalembert::system::inputs::{BodyMotion, Wrench};
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
    /// The first exception a force function raised during the last call (the run then fails on
    /// the NaN wrench it was given, and the exception is raised in its place).
    raised: Arc<Mutex<Option<PyErr>>>,
    /// True once a force function is set: the simulator then steps on the calling thread with the
    /// GIL held (the functions need it at every stage; handing it to a helper thread and back
    /// cost 15 µs per call, measured), and Ctrl-C reaches it through the functions themselves.
    python_forces: bool,
}

/// The motion of the body a code force acts on, global components: `position` (centre of mass),
/// `rotation` (3 × 3, body to global, rows), `velocity`, `angular_velocity`; a planar body moves
/// in the x–y plane and its `angle` is given too.
#[pyclass(name = "BodyMotion", module = "dalembert", frozen)]
pub struct PyBodyMotion {
    #[pyo3(get)]
    position: (f64, f64, f64),
    #[pyo3(get)]
    rotation: (Triple, Triple, Triple),
    #[pyo3(get)]
    velocity: (f64, f64, f64),
    #[pyo3(get)]
    angular_velocity: (f64, f64, f64),
    /// The angle of a planar body (rad); `None` for a spatial one.
    #[pyo3(get)]
    angle: Option<f64>,
}

/// Three components, as Python sees them (a tuple).
type Triple = (f64, f64, f64);

fn triple(v: [f64; 3]) -> Triple {
    (v[0], v[1], v[2])
}

/// `function(t, motion)` as a wrench: `(fx, fy, torque)` for a planar body, `(fx, fy, fz, tx, ty,
/// tz)` for either.
fn call_force(
    py: Python<'_>,
    function: &Py<PyAny>,
    name: &str,
    planar: bool,
    t: f64,
    m: &BodyMotion,
) -> PyResult<Wrench> {
    let motion = PyBodyMotion {
        position: triple(m.position),
        rotation: (triple(m.rotation[0]), triple(m.rotation[1]), triple(m.rotation[2])),
        velocity: triple(m.velocity),
        angular_velocity: triple(m.angular_velocity),
        angle: planar.then(|| m.rotation[1][0].atan2(m.rotation[0][0])),
    };
    let out = function.call1(py, (t, motion))?;
    let values: Vec<f64> = out.extract(py).map_err(|_| {
        pyo3::exceptions::PyTypeError::new_err(format!(
            "code force '{name}': the function must return numbers (fx, fy, torque) or (fx, fy, fz, tx, ty, tz)"
        ))
    })?;
    match (values.len(), planar) {
        (3, true) => Ok(Wrench {
            force: [values[0], values[1], 0.0],
            torque: [0.0, 0.0, values[2]],
        }),
        (6, _) => Ok(Wrench {
            force: [values[0], values[1], values[2]],
            torque: [values[3], values[4], values[5]],
        }),
        (n, _) => Err(PyValueError::new_err(format!(
            "code force '{name}': the function returned {n} numbers; expected {}(fx, fy, fz, tx, ty, tz)",
            if planar { "(fx, fy, torque) or " } else { "" }
        ))),
    }
}

impl PySimulator {
    pub fn new(scene: Arc<Scene>) -> PyResult<Self> {
        let inner = scene.simulator().map_err(|e| PyValueError::new_err(one_line(&e)))?;
        Ok(PySimulator {
            inner: Mutex::new(inner),
            scene,
            raised: Arc::new(Mutex::new(None)),
            python_forces: false,
        })
    }
}

impl PySimulator {
    /// The exception a force function raised during the last call, if any.
    fn take_raised(&self) -> Option<PyErr> {
        self.raised.lock().unwrap_or_else(|p| p.into_inner()).take()
    }

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

    /// The scene's code forces (`type = "code"` elements).
    #[getter]
    fn code_forces(&self) -> Vec<String> {
        self.sim().code_forces().to_vec()
    }

    /// Computes code force `name` with `function(t, motion)` from now on, at every stage of every
    /// step: `motion` is a `BodyMotion` (global components), the result `(fx, fy, torque)` for a
    /// planar body or `(fx, fy, fz, tx, ty, tz)`, a force at the centre of mass and a torque,
    /// global. An exception it raises stops the run and is raised by `step` or `advance_to`.
    fn set_force(&mut self, py: Python<'_>, name: &str, function: Py<PyAny>) -> PyResult<()> {
        let planar = !self.scene.model.is_spatial();
        let raised = self.raised.clone();
        let owner = name.to_string();
        let closure = move |t: f64, m: &BodyMotion| -> Wrench {
            Python::attach(|py| match call_force(py, &function, &owner, planar, t, m) {
                Ok(w) => w,
                Err(e) => {
                    let mut first = raised.lock().unwrap_or_else(|p| p.into_inner());
                    first.get_or_insert(e);
                    Wrench {
                        force: [f64::NAN; 3],
                        torque: [f64::NAN; 3],
                    }
                }
            })
        };
        let result = self.sim().set_force(name, closure);
        match result {
            Ok(()) => {
                self.python_forces = true;
                Ok(())
            }
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
        let result = if self.python_forces {
            inner.step()
        } else {
            py.detach(|| inner.step())
        };
        match (result, self.take_raised()) {
            (Ok(()), _) => Ok(()),
            (Err(_), Some(raised)) => Err(raised),
            (Err(e), None) => Err(error(py, e, None)?),
        }
    }

    /// Advances to exactly `t` (s). The GIL is released; Ctrl-C stops it at the next step
    /// (KeyboardInterrupt; the simulator is then at that step and can go on).
    fn advance_to(&mut self, py: Python<'_>, t: f64) -> PyResult<()> {
        let mut guard = self.sim();
        let steps = (t - guard.time()) / self.scene.settings.step;
        let inner = &mut *guard;
        let (result, raised) = if self.python_forces {
            (inner.advance_to(t), None)
        } else if steps.is_finite() && steps <= INLINE_STEPS {
            (py.detach(|| inner.advance_to(t)), None)
        } else {
            interrupt::run(py, |cancel| inner.advance_to_cancellable(t, cancel))
        };
        drop(guard);
        match (result, raised, self.take_raised()) {
            (Ok(()), None, _) => Ok(()),
            (Ok(()), Some(r), _) => Err(r),
            (Err(_), None, Some(from_function)) => Err(from_function),
            (Err(e), raised, _) => Err(error(py, e, raised)?),
        }
    }

    /// The value of output column `column` at the current time (`KeyError` for an unknown one).
    fn __getitem__(&mut self, py: Python<'_>, column: &str) -> PyResult<f64> {
        let result = self.sim().value(column);
        match (result, self.take_raised()) {
            (Ok(v), _) => Ok(v),
            (Err(_), Some(raised)) => Err(raised),
            (Err(e), None) => Err(error(py, e, None)?),
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
            Err(e) => {
                drop(sim);
                return Err(self.take_raised().map_or_else(|| error(py, e, None), Ok)?);
            }
        };
        let d = PyDict::new(py);
        for (name, value) in names.iter().zip(row) {
            d.set_item(name, value)?;
        }
        Ok(d)
    }

    /// The motion linearized about the simulator's current time, state and input values, as
    /// `Scene.linearize` gives it (same arguments but `at`; `docs/statics.md`, "Linearization").
    /// Forces set from Python functions are not part of the model and are refused.
    #[pyo3(signature = (inputs=None, outputs=None, states=None))]
    fn linearize<'py>(
        &self,
        py: Python<'py>,
        inputs: Option<Vec<String>>,
        outputs: Option<Vec<String>>,
        states: Option<Vec<String>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        if self.python_forces {
            return Err(PyValueError::new_err(
                "linearize: the simulator's forces from Python functions are not part of the scene's model; linearize a simulator without them",
            ));
        }
        let about = {
            let sim = self.sim();
            let (q, qd) = sim.state();
            let values = (sim.inputs().iter())
                .map(|n| {
                    Ok((
                        n.clone(),
                        sim.input(n).map_err(|e| PyValueError::new_err(e.to_string()))?,
                    ))
                })
                .collect::<PyResult<Vec<_>>>()?;
            dalembert::About::State {
                t: sim.time(),
                q: q.to_vec(),
                qd: qd.to_vec(),
                inputs: values,
            }
        };
        crate::scene::linearized(py, self.scene.clone(), (inputs, outputs, states), about)
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
