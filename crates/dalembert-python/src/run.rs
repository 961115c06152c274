//! `dalembert.Run`: the rows of a simulation or an inverse-dynamics run, as numpy arrays.

use dalembert::animation::{Frames, MeshSources, Viewer};
use dalembert::integrators::Statistics;
use dalembert::output::Table;
use dalembert::Scene;
use numpy::ndarray::Array2;
use numpy::{PyArray1, PyArray2};
use pyo3::exceptions::{PyKeyError, PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use std::sync::Arc;

/// The output of a run: one row per output sample, columns named as in the CSV of
/// `dalembert simulate` (`t`, `<body>.x`, `.y`, `.angle`, `.vx`, `.vy`, `.omega`, reactions
/// `<joint>.fx`, `.fy`, `.torque`, `<driver>.effort`, `energy`, `constraint_violation`,
/// `velocity_violation`). `run["slider.x"]` is a numpy array.
#[pyclass(name = "Run", module = "dalembert", frozen)]
pub struct PyRun {
    pub table: Table,
    pub statistics: Option<Statistics>,
    pub warning: Option<String>,
    pub scene: Arc<Scene>,
    /// `t` and the columns `d(column)/d(parameter)` of a run with sensitivities.
    pub sensitivities: Option<Table>,
}

pub fn statistics_dict<'py>(py: Python<'py>, s: &Statistics) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("steps", s.steps)?;
    d.set_item("rejected", s.rejected)?;
    d.set_item("evaluations", s.evaluations)?;
    d.set_item("factorizations", s.factorizations)?;
    d.set_item("newton_iterations", s.newton_iterations)?;
    d.set_item("repartitions", s.repartitions)?;
    d.set_item("handovers", s.handovers)?;
    d.set_item("bridges", s.bridges)?;
    d.set_item("kicks_undone", s.kicks_undone)?;
    d.set_item("events", s.events)?;
    d.set_item("wall_time_s", s.wall_time.as_secs_f64())?;
    d.set_item("max_constraint_violation", s.max_constraint_violation)?;
    d.set_item("max_velocity_violation", s.max_velocity_violation)?;
    d.set_item("max_energy_change", s.max_energy_change)?;
    d.set_item("max_projection_share", s.max_projection_share)?;
    d.set_item("min_step", s.min_step_taken)?;
    d.set_item("max_step", s.max_step_taken)?;
    Ok(d)
}

#[pymethods]
impl PyRun {
    /// Times of the rows (s).
    #[getter]
    fn t<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_vec(py, self.table.column("t").unwrap_or_default())
    }

    /// Column names, `t` first.
    #[getter]
    fn columns(&self) -> Vec<String> {
        self.table.columns.clone()
    }

    /// All rows as a 2-D array (rows × columns).
    #[getter]
    fn data<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let a = Array2::from_shape_vec((self.table.rows(), self.table.columns.len()), self.table.data.clone())
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        Ok(PyArray2::from_owned_array(py, a))
    }

    /// Counters and accuracy of the run (steps, evaluations, factorizations, wall time, largest
    /// constraint violation and energy change); empty for inverse dynamics.
    #[getter]
    fn statistics<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        match &self.statistics {
            Some(s) => statistics_dict(py, s),
            None => Ok(PyDict::new(py)),
        }
    }

    /// The energy warning of a conservative model whose energy, or of another model whose energy
    /// balance E − W, changed by more than 1 % of its energy scale (the same as
    /// `dalembert simulate`), or None.
    #[getter]
    fn warning(&self) -> Option<String> {
        self.warning.clone()
    }

    /// The column `name` as a numpy array.
    fn __getitem__<'py>(&self, py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyArray1<f64>>> {
        match self.table.column(name) {
            Some(v) => Ok(PyArray1::from_vec(py, v)),
            None => Err(PyKeyError::new_err(self.table.unknown_column(name))),
        }
    }

    /// `∂column/∂parameter` over the output times (numpy array), for a run simulated with
    /// `sensitivities=[parameter, ...]`. Raises KeyError naming what was computed otherwise.
    fn sensitivity<'py>(&self, py: Python<'py>, column: &str, parameter: &str) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let Some(table) = &self.sensitivities else {
            return Err(PyKeyError::new_err(
                "this run has no sensitivities: simulate with sensitivities=[\"bodies.NAME.mass\", ...]",
            ));
        };
        let name = dalembert::sensitivity::column_name(column, parameter);
        match table.column(&name) {
            Some(v) => Ok(PyArray1::from_vec(py, v)),
            None => Err(PyKeyError::new_err(table.unknown_column(&name))),
        }
    }

    /// The names `d(column)/d(parameter)` of the sensitivities computed (empty without).
    #[getter]
    fn sensitivity_columns(&self) -> Vec<String> {
        self.sensitivities
            .as_ref()
            .map_or(Vec::new(), |t| t.columns[1..].to_vec())
    }

    fn __contains__(&self, name: &str) -> bool {
        self.table.index(name).is_some()
    }

    /// Number of rows.
    fn __len__(&self) -> usize {
        self.table.rows()
    }

    fn __repr__(&self) -> String {
        let t = self.table.column("t").unwrap_or_default();
        format!(
            "<dalembert.Run of '{}': {} rows, t = {} … {} s, {} columns>",
            self.scene.name,
            self.table.rows(),
            t.first().copied().unwrap_or(f64::NAN),
            t.last().copied().unwrap_or(f64::NAN),
            self.table.columns.len()
        )
    }

    /// The rows as a pandas DataFrame indexed by `t` (needs pandas).
    fn to_pandas<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let pd = py.import("pandas")?;
        let kw = PyDict::new(py);
        kw.set_item("columns", self.columns())?;
        let df = pd.call_method("DataFrame", (self.data(py)?,), Some(&kw))?;
        df.call_method1("set_index", ("t",))
    }

    /// Plots `columns` against time on matplotlib axes `ax` (the current axes when None) and
    /// returns the axes (needs matplotlib).
    #[pyo3(signature = (*columns, ax=None))]
    fn plot<'py>(
        &self,
        py: Python<'py>,
        columns: &Bound<'py, PyTuple>,
        ax: Option<Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let ax = match ax {
            Some(ax) => ax,
            None => py.import("matplotlib.pyplot")?.call_method0("gca")?,
        };
        let t = self.t(py);
        for c in columns.iter() {
            let name: String = c.extract()?;
            let y = self.__getitem__(py, &name)?;
            let kw = PyDict::new(py);
            kw.set_item("label", &name)?;
            ax.call_method("plot", (&t, y), Some(&kw))?;
        }
        ax.call_method1("set_xlabel", ("t [s]",))?;
        ax.call_method0("legend")?;
        Ok(ax)
    }

    /// Writes a self-contained HTML animation of this run to `path` (as `dalembert animate`), at
    /// most `max_frames` frames. A spatial scene's visual meshes are read from its folder and from
    /// `packages` (`{"NAME": folder}` for `package://NAME/…` paths); `any_mesh_path` allows
    /// absolute paths and `..` (a model you trust).
    #[pyo3(signature = (path, max_frames=2400, packages=None, any_mesh_path=false))]
    fn animate(
        &self,
        path: std::path::PathBuf,
        max_frames: usize,
        packages: Option<std::collections::BTreeMap<String, std::path::PathBuf>>,
        any_mesh_path: bool,
    ) -> PyResult<()> {
        self.animate_to(&path, max_frames, &mesh_sources(&self.scene, packages, any_mesh_path))
    }
}

/// Where the viewer reads `scene`'s meshes from (see `animate`).
pub fn mesh_sources(
    scene: &Scene,
    packages: Option<std::collections::BTreeMap<String, std::path::PathBuf>>,
    any_mesh_path: bool,
) -> MeshSources {
    let mut sources = MeshSources::of_scene(&scene.origin).any_path(any_mesh_path);
    for (name, folder) in packages.unwrap_or_default() {
        sources = sources.package(name, folder);
    }
    sources
}

impl PyRun {
    /// See `animate`.
    pub fn animate_to(&self, path: &std::path::Path, max_frames: usize, meshes: &MeshSources) -> PyResult<()> {
        if max_frames < 2 {
            return Err(PyValueError::new_err(format!(
                "max_frames must be at least 2, got {max_frames}"
            )));
        }
        let table = &self.table;
        let frames = Frames::from_rows(
            &self.scene.drawing,
            &table.columns,
            (0..table.rows()).map(|i| table.row(i)),
        )
        .map_err(PyValueError::new_err)?;
        let mut viewer = Viewer::new(&self.scene.name, &self.scene.drawing).max_frames(max_frames);
        if let Some(spatial) = &self.scene.drawing.spatial {
            viewer = viewer.meshes(meshes.load(spatial).map_err(|e| PyValueError::new_err(e.to_string()))?);
        }
        let html = viewer.html(&frames);
        std::fs::write(path, html).map_err(|e| PyOSError::new_err(format!("{}: {e}", path.display())))
    }
}
