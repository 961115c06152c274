//! `dalembert.Scene`: load, change, check, simulate, inverse dynamics, trade; and the native
//! sweep chunk runner.

use crate::convert::scene_value;
use crate::errors::{IntegrationError, SceneError};
use crate::interrupt;
use crate::run::PyRun;
use crate::simulator::PySimulator;
use dalembert::output::Rows;
use dalembert::scene::{method_parameter, parameter_keys, RunOverrides, Spelling};
use dalembert::sweep::{run_one, sweep, Assignment, Output};
use dalembert::trade::{trade_cancellable, TradeGrid};
use dalembert::Scene;
use pyo3::exceptions::{PyKeyboardInterrupt, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyTuple};
use std::sync::Arc;

/// A mechanism and its run settings, loaded from a scene file (TOML, `docs/scenes.md`) and
/// assembled. Scenes are immutable: `with_values` returns a changed copy. They pickle as their
/// TOML text, so they can be sent to other processes (sweeps on executors).
#[pyclass(name = "Scene", module = "dalembert", frozen)]
pub struct PyScene {
    pub inner: Arc<Scene>,
}

fn scene_error(e: impl std::fmt::Display) -> PyErr {
    SceneError::new_err(dalembert::scene::one_line(&e.to_string()).into_owned())
}

fn warn(py: Python<'_>, message: &str) -> PyResult<()> {
    let warnings = py.import("warnings")?;
    let kw = PyDict::new(py);
    kw.set_item("stacklevel", 2)?;
    warnings.call_method("warn", (message,), Some(&kw))?;
    Ok(())
}

/// The exception for a run that stopped at `time` after computing `run`'s rows.
fn integration_error(py: Python<'_>, message: String, time: Option<f64>, run: PyRun) -> PyResult<PyErr> {
    let err = IntegrationError::new_err(dalembert::scene::one_line(&message).into_owned());
    let value = err.value(py);
    value.setattr("time", time)?;
    value.setattr("run", Py::new(py, run)?)?;
    Ok(err)
}

/// The keywords of `Scene.simulate`: the run settings, then the methods' parameters.
const SIMULATE_KEYWORDS: &[&str] = &[
    "end",
    "formulation",
    "integrator",
    "step",
    "every",
    "stabilization",
    "redundant",
    "coordinates",
    "strict",
];

/// A `TypeError` for an unknown keyword of `method`, listing every keyword and the nearest one.
fn unexpected_keyword(method: &str, key: &str) -> PyErr {
    let mut keys = SIMULATE_KEYWORDS.to_vec();
    keys.extend(parameter_keys());
    let hint = dalembert::scene::nearest(key, &keys).map_or(String::new(), |k| format!("; did you mean '{k}'?"));
    pyo3::exceptions::PyTypeError::new_err(format!(
        "{method}() got an unexpected keyword '{key}' (keywords: {}){hint}",
        keys.join(", ")
    ))
}

/// An interrupt raised while a run went on, with the rows so far attached as `run`.
fn interrupted(py: Python<'_>, e: PyErr, run: PyRun) -> PyResult<PyErr> {
    if e.is_instance_of::<PyKeyboardInterrupt>(py) {
        e.value(py).setattr("run", Py::new(py, run)?)?;
    }
    Ok(e)
}

/// The methods' parameters among the keywords of `method` (`rtol=1e-8`), checked against the
/// registry (a `TypeError` for an unknown keyword).
fn method_parameters(method: &str, parameters: Option<&Bound<'_, PyDict>>) -> PyResult<Vec<(String, f64)>> {
    let mut given = Vec::new();
    for (k, v) in parameters.into_iter().flatten() {
        let key: String = k.extract()?;
        if method_parameter(&key).is_none() {
            return Err(unexpected_keyword(method, &key));
        }
        let value: f64 = v
            .extract()
            .map_err(|_| PyValueError::new_err(format!("{key} must be a number, got {v}")))?;
        given.push((key, value));
    }
    Ok(given)
}

impl PyScene {
    /// This scene with the run settings `o` changes (warnings issued as Python warnings), checked
    /// before anything runs.
    fn overridden(&self, py: Python<'_>, o: RunOverrides) -> PyResult<Scene> {
        let (settings, warnings) = o
            .apply(&self.inner.settings, Spelling::Keywords)
            .map_err(PyValueError::new_err)?;
        for w in &warnings {
            warn(py, w)?;
        }
        let mut scene = (*self.inner).clone();
        scene.settings = settings;
        scene
            .check_settings(Spelling::Keywords)
            .map_err(PyValueError::new_err)?;
        Ok(scene)
    }
}

#[pymethods]
impl PyScene {
    /// Reads, builds and assembles a scene file. Raises SceneError naming the line at fault.
    #[staticmethod]
    fn load(path: std::path::PathBuf) -> PyResult<Self> {
        let s = Scene::from_path(&path).map_err(scene_error)?;
        Ok(PyScene { inner: Arc::new(s) })
    }

    /// Builds and assembles a scene from TOML text; `origin` names it in errors.
    #[staticmethod]
    #[pyo3(signature = (text, origin="<string>"))]
    fn from_toml(text: &str, origin: &str) -> PyResult<Self> {
        let s = Scene::from_toml(text, origin).map_err(scene_error)?;
        Ok(PyScene { inner: Arc::new(s) })
    }

    /// The scene's name.
    #[getter]
    fn name(&self) -> String {
        self.inner.name.clone()
    }

    /// The TOML text the scene was built from.
    #[getter]
    fn source(&self) -> String {
        self.inner.source.clone()
    }

    /// Where the scene came from (its path), as errors name it.
    #[getter]
    fn origin(&self) -> String {
        self.inner.origin.clone()
    }

    /// The columns a run of this scene has (`t`, positions, velocities, reactions, efforts, …).
    #[getter]
    fn columns(&self) -> Vec<String> {
        Rows::new(&self.inner.model).names().to_vec()
    }

    /// Names of the moving bodies.
    #[getter]
    fn bodies(&self) -> Vec<String> {
        self.inner.model.body_names()
    }

    /// Names of the joints, drivers and couplings, in the order of their reaction and effort
    /// columns.
    #[getter]
    fn constraints(&self) -> Vec<String> {
        self.inner.model.constraint_names()
    }

    /// The run settings of the scene's `[simulation]` table, defaults filled in.
    #[getter]
    fn settings<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let s = &self.inner.settings;
        let d = PyDict::new(py);
        d.set_item("end", s.end)?;
        d.set_item("formulation", s.formulation.name())?;
        d.set_item("integrator", s.method.name())?;
        d.set_item("step", s.step)?;
        d.set_item("every", s.output_every)?;
        d.set_item("stabilization", s.stabilization.name())?;
        // Every method parameter of the registry: the method's value, or the one the scene gives,
        // or the default.
        for key in parameter_keys() {
            let given = s.parameters.iter().find(|(k, _)| *k == key).map(|(_, v)| *v);
            let v = s
                .method
                .get(key)
                .or(given)
                .or_else(|| method_parameter(key).map(|p| p.default));
            d.set_item(key, v)?;
        }
        d.set_item(
            "redundant",
            match s.redundancy {
                dalembert::system::RedundancyTreatment::MinimumNorm => "minimum-norm",
                _ => "error",
            },
        )?;
        // The embedding's independent coordinates by name (`body.label`), or None.
        let names = self.inner.model.velocity_names();
        let independent: Option<Vec<&str>> = s
            .independent
            .as_ref()
            .map(|ix| ix.iter().filter_map(|&i| names.get(i).map(String::as_str)).collect());
        d.set_item("independent", independent)?;
        Ok(d)
    }

    /// A copy with values changed by path, e.g. `{"bodies.slider.mass": 2.0,
    /// "forces.return-spring.stiffness": 80.0, "simulation.end": 2.0}`; rebuilt and re-assembled.
    fn with_values(&self, values: &Bound<'_, PyDict>) -> PyResult<Self> {
        let pairs = assignment(values)?;
        let refs: Vec<(&str, dalembert::SceneValue)> = pairs.iter().map(|(p, v)| (p.as_str(), v.clone())).collect();
        let s = self.inner.with_values(&refs).map_err(scene_error)?;
        Ok(PyScene { inner: Arc::new(s) })
    }

    /// Degrees of freedom, rank, redundant equations, assembly residual, and the accelerations
    /// and reactions at t = 0, as `dalembert check` prints them. `problems` lists what keeps the
    /// scene from running as written (empty when it can).
    fn check<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let scene = self.inner.clone();
        let r = py.detach(move || scene.check()).map_err(scene_error)?;
        let d = PyDict::new(py);
        d.set_item("scene", &r.scene)?;
        d.set_item("bodies", r.bodies)?;
        d.set_item("coordinates", r.coordinates)?;
        d.set_item("equations", r.equations)?;
        d.set_item("rank", r.rank)?;
        d.set_item("dof", r.degrees_of_freedom)?;
        d.set_item("redundant", &r.redundant)?;
        d.set_item("minimum_norm", r.minimum_norm)?;
        d.set_item("max_violation", r.max_violation)?;
        let acc = PyDict::new(py);
        if let Ok(qdd) = &r.accelerations {
            for (n, v) in r.coordinate_names.iter().zip(qdd) {
                acc.set_item(n, v)?;
            }
        }
        d.set_item("accelerations", acc)?;
        let reactions = PyDict::new(py);
        for (n, v) in &r.reactions {
            reactions.set_item(n, v)?;
        }
        d.set_item("reactions", reactions)?;
        d.set_item("problems", r.problems())?;
        Ok(d)
    }

    /// The static equilibrium nearest the scene's position (drivers held at t = 0, inputs at 0):
    /// a dict from the position columns (`rod.x`, …, as in the CSV) to their values, with
    /// `reactions` (a dict of the reaction and effort columns), `stable`, `free_directions`,
    /// `unstable_directions`, `stiffness` (the eigenvalues of the reduced stiffness relative to
    /// the reduced mass, 1/s²), `held` (the joints whose limits it rests against, held at a bound
    /// by their stops' forces: the `<joint>.limit` reactions) and `iterations`. Raises ValueError
    /// naming the cause when there is none (a net force along a direction nothing resists) or
    /// Newton's method does not converge.
    fn equilibrium<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let scene = self.inner.clone();
        let eq = py
            .detach(move || scene.equilibrium())
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        equilibrium_dict(py, &eq)
    }

    /// The scene started at rest at its static equilibrium: a new Scene whose text holds an
    /// `[initial]` table of the equilibrium's positions and zero velocities (what `dalembert
    /// equilibrium --output` writes). Raises ValueError as `equilibrium()` does.
    fn at_equilibrium(&self, py: Python<'_>) -> PyResult<PyScene> {
        let scene = self.inner.clone();
        let resting = py
            .detach(move || -> Result<dalembert::Scene, String> {
                let eq = scene.equilibrium().map_err(|e| e.to_string())?;
                scene.resting_at(&eq).map_err(|e| e.to_string())
            })
            .map_err(PyValueError::new_err)?;
        Ok(PyScene {
            inner: Arc::new(resting),
        })
    }

    /// Natural frequencies (Hz, ascending), damping ratios and mode shapes about the static
    /// equilibrium: a dict with `frequencies` and `damping_ratios` (numpy arrays), `shapes` (a
    /// numpy array, one row per mode over `columns`, the position columns), and `equilibrium`
    /// (as `equilibrium()` returns it). Raises ValueError at an unstable equilibrium.
    fn modes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let scene = self.inner.clone();
        let modes = py
            .detach(move || scene.modes())
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        let d = PyDict::new(py);
        d.set_item("frequencies", numpy::PyArray1::from_vec(py, modes.frequencies.clone()))?;
        d.set_item(
            "damping_ratios",
            numpy::PyArray1::from_vec(py, modes.damping_ratios.clone()),
        )?;
        let (rows, cols) = (modes.shapes.len(), modes.columns.len());
        let flat: Vec<f64> = modes.shapes.iter().flatten().copied().collect();
        let array = numpy::ndarray::Array2::from_shape_vec((rows, cols), flat)
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        d.set_item("shapes", numpy::PyArray2::from_owned_array(py, array))?;
        d.set_item("columns", &modes.columns)?;
        d.set_item("equilibrium", equilibrium_dict(py, &modes.equilibrium)?)?;
        Ok(d)
    }

    /// The motion linearized in minimal coordinates, `dx/dt = A x + B u`, `y = C x + D u`
    /// (`docs/statics.md`, "Linearization"): a dict with `A`, `B`, `C`, `D` (2-D numpy arrays),
    /// `states` (position states such as `rod.angle`, then velocity states such as `rod.omega`),
    /// `inputs`, `outputs` (names), `drift` (the state's rate at the operating point: 0 at an
    /// equilibrium), `outputs_at`, and the operating point `t`, `q`, `qd`. `inputs` are the
    /// scene's named inputs, `outputs` any CSV columns, `states` the independent coordinates (by
    /// default the scene's `independent`, or coordinate partitioning's choice); `at` is
    /// `"equilibrium"`, `"initial"`, or a dict with `q`, `qd` (the model's coordinates) and
    /// optionally `t` and `inputs` (a dict of input values). Raises ValueError naming what is
    /// wrong (an unknown name, a singular position).
    #[pyo3(signature = (inputs=None, outputs=None, at=None, states=None))]
    fn linearize<'py>(
        &self,
        py: Python<'py>,
        inputs: Option<Vec<String>>,
        outputs: Option<Vec<String>>,
        at: Option<Bound<'py, PyAny>>,
        states: Option<Vec<String>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let about = match at {
            None => dalembert::About::Equilibrium,
            Some(a) => match a.extract::<String>() {
                Ok(s) if s == "equilibrium" => dalembert::About::Equilibrium,
                Ok(s) if s == "initial" => dalembert::About::Initial,
                Ok(s) => {
                    return Err(PyValueError::new_err(format!(
                        "linearize: at = '{s}': expected 'equilibrium', 'initial' or a dict with q and qd"
                    )))
                }
                Err(_) => {
                    let d = a.cast::<PyDict>().map_err(|_| {
                        PyValueError::new_err("linearize: at must be 'equilibrium', 'initial' or a dict with q and qd")
                    })?;
                    let item = |k: &str| d.get_item(k);
                    let need = |k: &str| -> PyResult<Vec<f64>> {
                        item(k)?
                            .ok_or_else(|| PyValueError::new_err(format!("linearize: at has no '{k}'")))?
                            .extract()
                    };
                    let t = match item("t")? {
                        Some(t) => t.extract()?,
                        None => 0.0,
                    };
                    let values: Vec<(String, f64)> = match item("inputs")? {
                        Some(i) => i
                            .extract::<std::collections::HashMap<String, f64>>()?
                            .into_iter()
                            .collect(),
                        None => Vec::new(),
                    };
                    dalembert::About::State {
                        t,
                        q: need("q")?,
                        qd: need("qd")?,
                        inputs: values,
                    }
                }
            },
        };
        linearized(py, self.inner.clone(), (inputs, outputs, states), about)
    }

    /// Simulates the scene; keyword arguments override its `[simulation]` settings (as the command
    /// line's flags do); the methods' parameters (`rtol`, `atol`, `rho_inf`, `penalty`) are keywords too. Returns a Run. Raises IntegrationError (with `.time` and `.run`, the rows
    /// so far) when the run stops early; with `strict=True` also when a conservative model's
    /// energy drifts by more than 1 % (otherwise a warning). `coordinates="joint"` runs a spatial
    /// tree in joint coordinates (same outputs). The GIL is released during the run, and Ctrl-C
    /// stops it within one step (within one output interval in joint coordinates;
    /// KeyboardInterrupt, rows so far in `.run`).
    ///
    /// `sensitivities=["forces.spring.stiffness", "bodies.upper.mass"]` carries the derivatives of
    /// the outputs to these scene values along with the run (the same method and steps;
    /// `docs/sensitivities.md`): `run.sensitivity("lower.x", "bodies.upper.mass")` is then a numpy
    /// array over the output times. `sensitivity_of` restricts the columns differentiated (default
    /// every column), `relative_change` sets the change of each parameter (default 1e-4 of it).
    #[pyo3(signature = (*, end=None, formulation=None, integrator=None, step=None, every=None, stabilization=None, redundant=None, coordinates=None, strict=false, sensitivities=None, sensitivity_of=None, relative_change=None, **parameters))]
    fn simulate(
        &self,
        py: Python<'_>,
        end: Option<f64>,
        formulation: Option<String>,
        integrator: Option<String>,
        step: Option<f64>,
        every: Option<f64>,
        stabilization: Option<String>,
        redundant: Option<String>,
        coordinates: Option<String>,
        strict: bool,
        sensitivities: Option<Vec<String>>,
        sensitivity_of: Option<Vec<String>>,
        relative_change: Option<f64>,
        parameters: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<PyRun> {
        let o = RunOverrides {
            formulation,
            integrator,
            parameters: method_parameters("simulate", parameters)?,
            step,
            end,
            every,
            stabilization,
            redundant,
            coordinates,
        };
        let scene = self.overridden(py, o)?;
        let scene = Arc::new(scene);
        let request = match sensitivities {
            None if sensitivity_of.is_some() || relative_change.is_some() => return Err(PyValueError::new_err(
                "sensitivity_of and relative_change need sensitivities=[...] (the scene values to differentiate by)",
            )),
            None => None,
            Some(parameters) => {
                let mut request = dalembert::SensitivityRequest::new(&[], &[]);
                request.parameters = parameters;
                request.of = sensitivity_of.unwrap_or_default();
                if let Some(r) = relative_change {
                    request.relative_change = r;
                }
                Some(request)
            }
        };
        let (rec, raised) = {
            let scene = scene.clone();
            interrupt::run(py, move |cancel| match request {
                None => Ok((scene.record(cancel), None)),
                Some(request) => scene.sensitivities(&request, cancel).map(|r| {
                    let rec = dalembert::Recording {
                        table: r.table,
                        outcome: r.outcome,
                        warning: r.warning,
                    };
                    (rec, Some(r.sensitivities))
                }),
            })
        };
        let (rec, sensitivities) = rec.map_err(|e| match e {
            dalembert::SensitivityError::Scene(e) => scene_error(e),
            e => PyValueError::new_err(dalembert::scene::one_line(&e.to_string()).into_owned()),
        })?;
        let time = rec.table.column("t").and_then(|t| t.last().copied());
        match rec.outcome {
            Ok(stats) => {
                let run = PyRun {
                    table: rec.table,
                    statistics: Some(stats),
                    warning: rec.warning.clone(),
                    scene,
                    sensitivities,
                };
                if let Some(e) = raised {
                    return Err(interrupted(py, e, run)?);
                }
                if let Some(w) = &rec.warning {
                    if strict {
                        return Err(integration_error(py, w.clone(), time, run)?);
                    }
                    warn(py, w)?;
                }
                Ok(run)
            }
            Err(e) => {
                let advice = scene.advice(&e).map_or(String::new(), |a| format!("; {a}"));
                let run = PyRun {
                    table: rec.table,
                    statistics: None,
                    warning: None,
                    scene,
                    sensitivities,
                };
                // The time the run stopped at (the failure's own; the last row's when it has none).
                let time = e.time().or(time);
                match raised {
                    Some(r) => Err(interrupted(py, r, run)?),
                    None => Err(integration_error(py, format!("{e}{advice}"), time, run)?),
                }
            }
        }
    }

    /// A Simulator of this scene: the same keywords as `simulate` (but `strict`), stepped from
    /// Python with `step()`, `advance_to(t)` and `set_input(name, value)`.
    #[pyo3(signature = (*, end=None, formulation=None, integrator=None, step=None, every=None, stabilization=None, redundant=None, coordinates=None, **parameters))]
    fn simulator(
        &self,
        py: Python<'_>,
        end: Option<f64>,
        formulation: Option<String>,
        integrator: Option<String>,
        step: Option<f64>,
        every: Option<f64>,
        stabilization: Option<String>,
        redundant: Option<String>,
        coordinates: Option<String>,
        parameters: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<PySimulator> {
        let o = RunOverrides {
            formulation,
            integrator,
            parameters: method_parameters("simulator", parameters)?,
            step,
            end,
            every,
            stabilization,
            redundant,
            coordinates,
        };
        let scene = self.overridden(py, o)?;
        PySimulator::new(Arc::new(scene))
    }

    /// The scene's named inputs (`{ input = "NAME" }`), in the order first met in the file.
    #[getter]
    fn inputs(&self) -> Vec<String> {
        self.inner.inputs.clone()
    }

    /// The scene's code forces (`type = "code"` elements), whose wrench a Simulator's function
    /// gives (`Simulator.set_force`).
    #[getter]
    fn code_forces(&self) -> Vec<String> {
        self.inner.code_forces.clone()
    }

    /// Inverse dynamics of a fully driven scene on the grid 0, every, …, end (the scene's end and
    /// output interval by default): a Run whose `<driver>.effort` columns are the driving forces
    /// and whose reaction columns are the joint reactions. Raises IntegrationError (with `.run`)
    /// when the kinematics fail part way.
    #[pyo3(signature = (end=None, every=None))]
    fn inverse(&self, py: Python<'_>, end: Option<f64>, every: Option<f64>) -> PyResult<PyRun> {
        let end = end.unwrap_or(self.inner.settings.end);
        let every = every.unwrap_or(self.inner.settings.output_every);
        let scene = self.inner.clone();
        let (table, res) = py.detach(move || scene.inverse_table(end, every));
        let time = table.column("t").and_then(|t| t.last().copied());
        let run = PyRun {
            table,
            statistics: None,
            warning: None,
            scene: self.inner.clone(),
            sensitivities: None,
        };
        match res {
            Ok(()) => Ok(run),
            Err(e) => Err(integration_error(py, e.to_string(), time, run)?),
        }
    }

    /// The speed–accuracy trade of `dalembert trade`: one dict per run of the grid (method,
    /// parameter, time_s, evaluations, error, max_constraint_violation, max_energy_change,
    /// status, pareto). Arguments default to the command line's grid.
    #[pyo3(signature = (*, formulations=None, integrators=None, stabilizations=None, steps=None, tolerances=None, end=None, every=None))]
    fn trade<'py>(
        &self,
        py: Python<'py>,
        formulations: Option<Vec<String>>,
        integrators: Option<Vec<String>>,
        stabilizations: Option<Vec<String>>,
        steps: Option<Vec<f64>>,
        tolerances: Option<Vec<f64>>,
        end: Option<f64>,
        every: Option<f64>,
    ) -> PyResult<Bound<'py, PyList>> {
        let d = TradeGrid::default();
        let grid = TradeGrid {
            formulations: formulations.unwrap_or(d.formulations),
            integrators: integrators.unwrap_or(d.integrators),
            stabilizations: stabilizations.unwrap_or(d.stabilizations),
            steps: steps.unwrap_or(d.steps),
            tolerances: tolerances.unwrap_or(d.tolerances),
            end,
            every,
        };
        let scene = self.inner.clone();
        // Ctrl-C stops the run in progress at its next step: KeyboardInterrupt, the rows so far in
        // its `rows`.
        let (t, raised) = interrupt::run(py, move |cancel| {
            trade_cancellable(&scene, &grid, &mut |_, _| {}, cancel)
        });
        let t = match (t, raised) {
            (Err(_), Some(e)) => return Err(e),
            (t, None) => t.map_err(PyValueError::new_err)?,
            (Ok(t), Some(e)) => {
                e.value(py).setattr("rows", trade_rows(py, &t)?)?;
                return Err(e);
            }
        };
        trade_rows(py, &t)
    }

    /// Writes a self-contained HTML animation of a simulation with the scene's settings (meshes as
    /// `Run.animate` reads them).
    #[pyo3(signature = (path, max_frames=2400, packages=None, any_mesh_path=false))]
    fn animate(
        &self,
        py: Python<'_>,
        path: std::path::PathBuf,
        max_frames: usize,
        packages: Option<std::collections::BTreeMap<String, std::path::PathBuf>>,
        any_mesh_path: bool,
    ) -> PyResult<()> {
        let sources = crate::run::mesh_sources(&self.inner, packages, any_mesh_path);
        if let Some(spatial) = &self.inner.drawing.spatial {
            // A bad mesh stops here, before the simulation.
            sources
                .load(spatial)
                .map_err(|e| PyValueError::new_err(e.to_string()))?;
        }
        let run = self.simulate(
            py, None, None, None, None, None, None, None, None, false, None, None, None, None,
        )?;
        run.animate_to(&path, max_frames, &sources)
    }

    /// Writes a self-contained HTML page animating vibration mode `mode` (1 = the lowest) about
    /// the static equilibrium, over `cycles` periods (`docs/statics.md`, "Modes"). Raises
    /// ValueError for a mode the scene does not have.
    #[pyo3(signature = (path, mode=1, cycles=3))]
    fn animate_mode(&self, py: Python<'_>, path: std::path::PathBuf, mode: usize, cycles: usize) -> PyResult<()> {
        let scene = self.inner.clone();
        let page = py
            .detach(move || -> Result<String, String> {
                let modes = scene.modes().map_err(|e| e.to_string())?;
                let k = mode.checked_sub(1).ok_or("mode: modes are numbered from 1")?;
                let frames = scene.mode_frames(&modes, k, cycles).map_err(|e| e.to_string())?;
                let title = format!("{}: mode {mode} at {:.6} Hz", scene.name, modes.frequencies[k]);
                Ok(dalembert::animation::Viewer::new(&title, &scene.drawing).html(&frames))
            })
            .map_err(PyValueError::new_err)?;
        std::fs::write(&path, page).map_err(|e| PyValueError::new_err(format!("{}: {e}", path.display())))
    }

    fn __repr__(&self) -> String {
        format!(
            "<dalembert.Scene '{}' from {}: {} bodies>",
            self.inner.name,
            self.inner.origin,
            self.inner.model.num_bodies()
        )
    }

    /// Pickled as its TOML text and origin.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        let ctor = py.get_type::<PyScene>().getattr("from_toml")?;
        let args = PyTuple::new(py, [self.inner.source.clone(), self.inner.origin.clone()])?;
        PyTuple::new(py, [ctor, args.into_any()])
    }
}

/// `(path, value)` pairs from a dict of path → value.
fn assignment(values: &Bound<'_, PyDict>) -> PyResult<Assignment> {
    values
        .iter()
        .map(|(k, v)| {
            let path: String = k.extract()?;
            let value = scene_value(&v, &path)?;
            Ok((path, value))
        })
        .collect()
}

/// The rows of a trade as dicts (`pareto`: on the front).
fn trade_rows<'py>(py: Python<'py>, t: &dalembert::trade::Trade) -> PyResult<Bound<'py, PyList>> {
    let out = PyList::empty(py);
    for (i, r) in t.runs.iter().enumerate() {
        let d = PyDict::new(py);
        d.set_item("method", &r.method)?;
        d.set_item("parameter", r.parameter)?;
        d.set_item("time_s", r.time_s)?;
        d.set_item("evaluations", r.evaluations)?;
        d.set_item("error", r.error)?;
        d.set_item("max_constraint_violation", r.constraint)?;
        d.set_item("max_energy_change", r.energy)?;
        d.set_item("status", &r.status)?;
        d.set_item("pareto", t.front.contains(&i))?;
        out.append(d)?;
    }
    Ok(out)
}

/// Runs `runs` (a list of dicts path → value) of `scene` on `threads` threads (all cores when
/// None), the GIL released. Returns one `(outputs, wall_time_s, error)` tuple per run, in order.
/// Raises SceneError when a path or an output name does not exist (before any run).
#[pyfunction]
#[pyo3(signature = (scene, runs, outputs, end=None, threads=None))]
pub fn sweep_runs<'py>(
    py: Python<'py>,
    scene: &PyScene,
    runs: Vec<Bound<'py, PyDict>>,
    outputs: Vec<String>,
    end: Option<f64>,
    threads: Option<usize>,
) -> PyResult<Bound<'py, PyList>> {
    let s = scene.inner.clone();
    if let Some(e) = end {
        if !(e.is_finite() && e > 0.0) {
            return Err(PyValueError::new_err(format!("end must be positive, got {e}")));
        }
    }
    if threads == Some(0) {
        return Err(PyValueError::new_err("threads must be at least 1"));
    }
    let parsed = outputs
        .iter()
        .map(|n| Output::parse(&s, n))
        .collect::<Result<Vec<_>, _>>()
        .map_err(SceneError::new_err)?;
    let assignments = runs.iter().map(assignment).collect::<PyResult<Vec<_>>>()?;
    let mut paths: Vec<&str> = assignments.iter().flatten().map(|(p, _)| p.as_str()).collect();
    paths.sort_unstable();
    paths.dedup();
    for p in paths {
        s.check_path(p).map_err(scene_error)?;
    }
    let (rows, raised) = if assignments.len() == 1 && threads == Some(1) {
        // One run on this thread: no pool to start.
        let a = &assignments[0];
        let (row, raised) = interrupt::run(py, |cancel| run_one(&s, a, end, &parsed, cancel));
        (vec![row], raised)
    } else {
        let (rows, raised) = interrupt::run(py, |cancel| sweep(&s, &assignments, end, &parsed, threads, cancel));
        (rows.map_err(PyValueError::new_err)?, raised)
    };
    if let Some(e) = raised {
        // Ctrl-C stopped the runs in progress at their next step: the rows so far go with the
        // KeyboardInterrupt (`rows`), the stopped ones marked "interrupted at t = …".
        let list = PyList::empty(py);
        for r in rows {
            list.append((r.outputs, r.wall_time, r.error))?;
        }
        e.value(py).setattr("rows", list)?;
        return Err(e);
    }
    let out = PyList::empty(py);
    for r in rows {
        let item = (r.outputs, r.wall_time, r.error);
        out.append(item)?;
    }
    Ok(out)
}

/// An equilibrium as the dict `Scene.equilibrium` returns.
fn equilibrium_dict<'py>(py: Python<'py>, eq: &dalembert::Equilibrium) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    for (n, v) in &eq.positions {
        d.set_item(n, v)?;
    }
    let reactions = PyDict::new(py);
    for (n, v) in &eq.reactions {
        reactions.set_item(n, v)?;
    }
    d.set_item("reactions", reactions)?;
    d.set_item("stable", eq.stable)?;
    d.set_item("free_directions", &eq.free_directions)?;
    d.set_item("unstable_directions", &eq.unstable_directions)?;
    d.set_item("held", &eq.held)?;
    d.set_item("stiffness", &eq.stiffness)?;
    d.set_item("iterations", eq.iterations)?;
    Ok(d)
}

/// The names of a linearization's inputs, outputs and states (each `None`: none, or the default).
pub(crate) type Names = (Option<Vec<String>>, Option<Vec<String>>, Option<Vec<String>>);

/// `scene` linearized about `about` (the GIL released), as the dict `scene.linearize()` returns.
pub(crate) fn linearized<'py>(
    py: Python<'py>,
    scene: Arc<dalembert::Scene>,
    (inputs, outputs, states): Names,
    about: dalembert::About,
) -> PyResult<Bound<'py, PyDict>> {
    let options = dalembert::LinearizeOptions {
        inputs: inputs.unwrap_or_default(),
        outputs: outputs.unwrap_or_default(),
        states: states.unwrap_or_default(),
        about,
    };
    let lin = py
        .detach(move || scene.linearize(&options))
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    linearization_dict(py, &lin)
}

/// A linear model as the dict `scene.linearize()` returns (`A`, `B`, `C`, `D`, names, drift,
/// outputs at the operating point, and the operating point).
pub(crate) fn linearization_dict<'py>(py: Python<'py>, lin: &dalembert::Linearization) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    for (name, m) in [("A", &lin.a), ("B", &lin.b), ("C", &lin.c), ("D", &lin.d)] {
        let array = numpy::ndarray::Array2::from_shape_fn(m.shape(), |(i, j)| m[(i, j)]);
        d.set_item(name, numpy::PyArray2::from_owned_array(py, array))?;
    }
    d.set_item("states", &lin.states)?;
    d.set_item("inputs", &lin.inputs)?;
    d.set_item("outputs", &lin.outputs)?;
    d.set_item("drift", numpy::PyArray1::from_vec(py, lin.drift.clone()))?;
    d.set_item("outputs_at", numpy::PyArray1::from_vec(py, lin.outputs_at.clone()))?;
    d.set_item("t", lin.t)?;
    d.set_item("q", numpy::PyArray1::from_vec(py, lin.q.clone()))?;
    d.set_item("qd", numpy::PyArray1::from_vec(py, lin.qd.clone()))?;
    Ok(d)
}
