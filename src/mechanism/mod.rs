//! The model of a scene or a simulation, of any kind: planar or spatial bodies.
//!
//! Formulations and integrators see every kind through the system seam ([`MultibodySystem`]);
//! what differs between kinds is only what a user reads: the names of the elements, the output
//! columns ([`crate::output`]) and the reactions (a planar joint carries `fx, fy` and perhaps a
//! torque, a spatial one a force and a moment). [`ModelKind`] is that contract; `planar.rs` and
//! `spatial.rs` implement it for the two kinds there are.

use dalembert_integrators::Sample;
use dalembert_system::MultibodySystem;
use std::any::Any;
use std::sync::Arc;

mod planar;
mod spatial;

pub use planar::PLANAR_BODY_COLUMNS;
pub use spatial::{SPATIAL_BODY_COLUMNS, SPATIAL_JOINT_COLUMNS, SPATIAL_JOINT_VALUE_COLUMNS};

/// What a kind of model (planar bodies, spatial bodies, later flexible ones) provides beyond the
/// system seam, so that scenes' analyses, output, the command line and Python serve it without
/// knowing which kind it is: the names of its elements and the columns of its output.
///
/// A new body kind implements this trait (one file, as `planar.rs` and `spatial.rs` in this module
/// do) and [`MultibodySystem`]; nothing that reads a [`Mechanism`] matches on its kind.
pub trait ModelKind: std::fmt::Debug + Send + Sync + Any {
    /// The model as formulations and integrators see it.
    fn system(&self) -> &dyn MultibodySystem;

    /// The model through the seam, shared.
    fn shared_system(self: Arc<Self>) -> Arc<dyn MultibodySystem>;

    /// 2 for a planar model, 3 for a spatial one: the components of a force, a velocity or a
    /// body's position a user gives or reads.
    fn dimension(&self) -> usize;

    /// The names of the joints, drivers and couplings, in the order of their reaction and effort
    /// columns.
    fn constraint_names(&self) -> Vec<String>;

    /// The names of the drivers, in the order of their `<driver>.effort` columns.
    fn driver_names(&self) -> Vec<String>;

    /// The names of the force elements that are not conservative (they do work beyond the
    /// potential energy), in order.
    fn nonconservative_force_names(&self) -> Vec<String>;

    /// The position columns of a body that say where it is (`x, y, angle` or `x, y, z`): the
    /// default outputs of a sweep.
    fn position_columns(&self) -> &'static [&'static str];

    /// The writer of the body and reaction columns of this model's output.
    fn columns(self: Arc<Self>) -> Box<dyn ColumnWriter>;

    /// The model as [`Any`], to reach the concrete kind ([`Mechanism::planar`]).
    fn as_any(&self) -> &dyn Any;

    /// The shared model as [`Any`] ([`Mechanism::downcast`]).
    fn into_any(self: Arc<Self>) -> Arc<dyn Any + Send + Sync>;
}

/// The body and reaction columns of one kind of model's output, and the scratch space to fill a
/// row of them (allocation-free after construction). [`crate::output::Rows`] adds `t` before and
/// the energy and violations after.
pub trait ColumnWriter: std::fmt::Debug + Send + Sync {
    /// The body columns (`<body>.x`, …), in order.
    fn body_columns(&self) -> Vec<String>;

    /// The reaction and effort columns (`<joint>.fx`, …, `<driver>.effort`), in order.
    fn reaction_columns(&self) -> Vec<String>;

    /// Appends the values of the body columns, then of the reaction columns, of sample `s`.
    fn push(&mut self, s: &Sample<'_>, row: &mut Vec<f64>);

    /// A copy with its own scratch space.
    fn boxed_clone(&self) -> Box<dyn ColumnWriter>;
}

/// A multibody model of any kind ([`ModelKind`]): planar or spatial.
#[derive(Debug, Clone)]
pub struct Mechanism(Arc<dyn ModelKind>);

impl Mechanism {
    /// A mechanism of the given kind.
    pub fn new(kind: Arc<dyn ModelKind>) -> Self {
        Mechanism(kind)
    }

    /// The model's kind, through its contract.
    pub fn kind(&self) -> &dyn ModelKind {
        self.0.as_ref()
    }

    /// The model as the formulations and integrators see it.
    pub fn system(&self) -> Arc<dyn MultibodySystem> {
        self.0.clone().shared_system()
    }

    /// The model through the seam, borrowed.
    pub fn as_system(&self) -> &dyn MultibodySystem {
        self.0.system()
    }

    /// The model if it is of kind `T`, shared.
    pub fn downcast<T: ModelKind>(&self) -> Option<Arc<T>> {
        self.0.clone().into_any().downcast::<T>().ok()
    }

    /// The planar model, if this is one.
    pub fn planar(&self) -> Option<&dalembert_constraints::Model> {
        self.0.as_any().downcast_ref()
    }

    /// The spatial model, if this is one.
    pub fn spatial(&self) -> Option<&dalembert_spatial::Model> {
        self.0.as_any().downcast_ref()
    }

    /// True for a model in space ([`ModelKind::dimension`] 3).
    pub fn is_spatial(&self) -> bool {
        self.0.dimension() == 3
    }

    /// The writer of this model's body and reaction columns.
    pub fn columns(&self) -> Box<dyn ColumnWriter> {
        self.0.clone().columns()
    }

    /// The bodies' names, in coordinate order.
    pub fn body_names(&self) -> Vec<String> {
        self.as_system()
            .layout()
            .bodies()
            .iter()
            .map(|b| b.name.clone())
            .collect()
    }

    /// Number of bodies.
    pub fn num_bodies(&self) -> usize {
        self.as_system().layout().bodies().len()
    }

    /// The names of the joints, drivers and couplings, in the order of their reaction and effort
    /// columns.
    pub fn constraint_names(&self) -> Vec<String> {
        self.0.constraint_names()
    }

    /// Number of position coordinates `n_q`.
    pub fn num_positions(&self) -> usize {
        self.as_system().layout().n_q()
    }

    /// Number of velocity coordinates `n_v` (the length of accelerations and of `C_q`'s rows).
    pub fn num_velocities(&self) -> usize {
        self.as_system().layout().n_v()
    }

    /// Number of constraint equations (joints and drivers).
    pub fn num_equations(&self) -> usize {
        self.as_system().num_equations()
    }

    /// `<body>.<label>` of every velocity coordinate (`crank.x`, `crank.angle` for a planar body;
    /// `top.vx`, …, `top.wz'` for a spatial one, `'` marking body-frame components): the names
    /// of the entries of an acceleration vector.
    pub fn velocity_names(&self) -> Vec<String> {
        self.as_system()
            .layout()
            .bodies()
            .iter()
            .flat_map(|b| b.v_labels.iter().map(move |l| format!("{}.{l}", b.name)))
            .collect()
    }

    /// One position coordinate per body for a short printed summary, as `(column name, index in
    /// q)`: the angle of a planar body, the height `z` of a spatial one; where the joints hold
    /// that coordinate fixed at `q` (a slider's angle), the first of the body's `x`, `y` (and `z`)
    /// that can move. A coordinate is fixed when its unit vector lies in the row space of `C_q`
    /// (every admissible velocity leaves it still); the test runs on models of up to
    /// [`SUMMARY_CHECK_LIMIT`] velocities (a dense SVD), larger ones keep the angle or `z`.
    pub fn summary_coordinates(&self, t: f64, q: &[f64]) -> Vec<(String, usize)> {
        let system = self.as_system();
        let preferred = 2; // the planar angle and the spatial z are both third
        let free = self.free_velocities(t, q);
        system
            .layout()
            .bodies()
            .iter()
            .map(|b| {
                let moves = |k: usize| free.as_ref().is_none_or(|f| f[b.v_offset + k]);
                let k = [preferred, 0, 1].into_iter().find(|&k| moves(k)).unwrap_or(preferred);
                (format!("{}.{}", b.name, b.q_labels[k]), b.q_offset + k)
            })
            .collect()
    }

    /// For each velocity coordinate, whether some admissible velocity at `(t, q)` moves it (see
    /// [`Mechanism::summary_coordinates`]); `None` for a model too large to check.
    fn free_velocities(&self, t: f64, q: &[f64]) -> Option<Vec<bool>> {
        let system = self.as_system();
        let n = self.num_velocities();
        if n > SUMMARY_CHECK_LIMIT || q.len() != system.layout().n_q() {
            return None;
        }
        let sys = system.constraints();
        let m = sys.num_equations();
        if m == 0 {
            return Some(vec![true; n]);
        }
        let mut values = sys.values();
        sys.evaluate(t, q, &vec![0.0; n], &mut values);
        let dense = sys.jacobian_dense(&values);
        let jac = nalgebra::DMatrix::from_fn(m, n, |i, j| dense[(i, j)]);
        let svd = jac.svd(false, true);
        let v_t = svd.v_t?;
        let largest = svd.singular_values.iter().cloned().fold(0.0f64, f64::max);
        let rank_rows: Vec<usize> = (0..svd.singular_values.len())
            .filter(|&k| svd.singular_values[k] > 1e-9 * largest.max(1.0))
            .collect();
        // |P_row e_j|² = Σ_k (V_t[k, j])² over the row space: 1 when coordinate j is fixed.
        Some(
            (0..n)
                .map(|j| rank_rows.iter().map(|&k| v_t[(k, j)].powi(2)).sum::<f64>() < 1.0 - 1e-9)
                .collect(),
        )
    }
}

/// Velocities past which [`Mechanism::summary_coordinates`] does not test which coordinates the
/// joints fix (a dense SVD of `C_q`: about 0.1 s at this size).
pub const SUMMARY_CHECK_LIMIT: usize = 600;

impl<T: ModelKind> From<Arc<T>> for Mechanism {
    fn from(m: Arc<T>) -> Self {
        Mechanism(m)
    }
}

impl From<dalembert_constraints::Model> for Mechanism {
    fn from(m: dalembert_constraints::Model) -> Self {
        Mechanism(Arc::new(m))
    }
}

impl From<dalembert_spatial::Model> for Mechanism {
    fn from(m: dalembert_spatial::Model) -> Self {
        Mechanism(Arc::new(m))
    }
}
