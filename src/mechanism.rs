//! The model of a scene or a simulation: planar or spatial.
//!
//! Formulations and integrators see either through the system seam
//! ([`MultibodySystem`]); what differs between the two is only
//! what a user reads: the output columns ([`crate::output`]), the reactions (a planar joint
//! carries `fx, fy` and perhaps a torque, a spatial one a force and a moment) and the drawing.

use dalembert_system::MultibodySystem;
use std::sync::Arc;

/// A planar or a spatial multibody model.
#[derive(Debug, Clone)]
#[non_exhaustive]
pub enum Mechanism {
    /// Planar bodies (`x, y, angle`), [`dalembert_constraints::Model`].
    Planar(Arc<dalembert_constraints::Model>),
    /// Spatial bodies (centre of mass and Euler parameters), [`dalembert_spatial::Model`].
    Spatial(Arc<dalembert_spatial::Model>),
}

impl Mechanism {
    /// The model as the formulations and integrators see it.
    pub fn system(&self) -> Arc<dyn MultibodySystem> {
        match self {
            Mechanism::Planar(m) => m.clone(),
            Mechanism::Spatial(m) => m.clone(),
        }
    }

    /// The model through the seam, borrowed.
    pub fn as_system(&self) -> &dyn MultibodySystem {
        match self {
            Mechanism::Planar(m) => m.as_ref(),
            Mechanism::Spatial(m) => m.as_ref(),
        }
    }

    /// The planar model, if this is one.
    pub fn planar(&self) -> Option<&Arc<dalembert_constraints::Model>> {
        match self {
            Mechanism::Planar(m) => Some(m),
            Mechanism::Spatial(_) => None,
        }
    }

    /// The spatial model, if this is one.
    pub fn spatial(&self) -> Option<&Arc<dalembert_spatial::Model>> {
        match self {
            Mechanism::Spatial(m) => Some(m),
            Mechanism::Planar(_) => None,
        }
    }

    /// True for a spatial model.
    pub fn is_spatial(&self) -> bool {
        matches!(self, Mechanism::Spatial(_))
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

    /// The names of the joints and drivers, in the order of their reaction and effort columns.
    pub fn constraint_names(&self) -> Vec<String> {
        match self {
            Mechanism::Planar(m) => m
                .constraints()
                .constraints()
                .iter()
                .map(|c| c.name().to_string())
                .collect(),
            Mechanism::Spatial(m) => m.joint_names().chain(m.driver_names()).map(String::from).collect(),
        }
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

impl From<Arc<dalembert_constraints::Model>> for Mechanism {
    fn from(m: Arc<dalembert_constraints::Model>) -> Self {
        Mechanism::Planar(m)
    }
}

impl From<Arc<dalembert_spatial::Model>> for Mechanism {
    fn from(m: Arc<dalembert_spatial::Model>) -> Self {
        Mechanism::Spatial(m)
    }
}

impl From<dalembert_constraints::Model> for Mechanism {
    fn from(m: dalembert_constraints::Model) -> Self {
        Mechanism::Planar(Arc::new(m))
    }
}

impl From<dalembert_spatial::Model> for Mechanism {
    fn from(m: dalembert_spatial::Model) -> Self {
        Mechanism::Spatial(Arc::new(m))
    }
}
