//! The amalgamated formulation (`FORMULATIONS.md` §6): accelerations `q̈`, generalized constraint
//! forces `Q_c` and independent accelerations `q̈_i` are all unknowns of one symmetric system,
//!
//! ```text
//! [ M    −I    0   ] [ q̈   ]   [  Q_e ]
//! [ −I    0    B_i ] [ Q_c ] = [ −γ_i ]
//! [ 0    B_iᵀ  0   ] [ q̈_i ]   [  0   ]
//! ```
//!
//! from `M q̈ = Q_e + Q_c`, `q̈ = B_i q̈_i + γ_i` and `B_iᵀ Q_c = 0` (constraint forces do no work on
//! admissible motions). The multipliers consistent with the other formulations follow from
//! `Q_c = −C_qᵀ λ` on the dependent columns: `C_qdᵀ λ_R = −Q_c,d`.
//!
//! The velocity transformation and its partition are shared with the embedding formulation
//! (`dalembert_system::partition`). The system (size `3n − r`) is solved with dense LU for
//! small models and with faer's sparse LU above 150 unknowns (measured: chain of 16, 112 unknowns,
//! dense 70 µs vs sparse 86 µs; chain of 64, dense 2.56 ms vs sparse 0.76 ms); the sparse pattern
//! (with `B_i` full in its dependent rows) depends only on the partition, so its symbolic analysis
//! is redone only at a re-partition. (A symmetric indefinite sparse factorization would halve the work; faer's needs
//! regularisation on this matrix, see `shared/LINALG-NOTES.md`.)

use dalembert_system::{
    BlockDiagonal, ConstraintValues, DynamicsError, Formulation, FormulationStats, MultibodySystem, PartitionTracker,
    RedundancyTreatment, Stabilization,
};
use faer::linalg::solvers::Solve;
use faer::Mat;
use std::sync::Arc;

mod sparse;
use sparse::SparseSystem;

/// Above this many unknowns the sparse factorization is used.
const DENSE_LIMIT: usize = 150;

/// The amalgamated formulation of a model.
pub struct Amalgamated {
    model: Arc<dyn MultibodySystem>,
    redundancy: RedundancyTreatment,
    tracker: PartitionTracker,
    mass: BlockDiagonal,
    values: ConstraintValues,
    q_e: Vec<f64>,
    cdot: Vec<f64>,
    rhs: Vec<f64>,
    stats: FormulationStats,
    sparse: Option<SparseSystem>,
}

impl std::fmt::Debug for Amalgamated {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Amalgamated")
            .field("partition", &self.tracker.current())
            .finish()
    }
}

impl Amalgamated {
    /// Sets up the formulation; `redundancy` as in the augmented formulation.
    pub fn new(model: Arc<dyn MultibodySystem>, redundancy: RedundancyTreatment) -> Self {
        let n = model.layout().n_v();
        let m = model.num_equations();
        Amalgamated {
            mass: model.mass_storage(),
            values: model.constraints().values(),
            q_e: vec![0.0; n],
            cdot: vec![0.0; m],
            rhs: vec![0.0; m],
            tracker: PartitionTracker::new(1e3),
            redundancy,
            model,
            stats: FormulationStats::default(),
            sparse: None,
        }
    }

    /// With redundant constraints treated as errors.
    pub fn with_defaults(model: Arc<dyn MultibodySystem>) -> Self {
        Self::new(model, RedundancyTreatment::Error)
    }

    fn singular(&self, t: f64) -> DynamicsError {
        self.model.constraints().redundancy_error(t, &self.values)
    }
}

impl Amalgamated {
    /// The dense amalgamated matrix `[M −I 0; −I 0 B_i; 0 B_iᵀ 0]`.
    fn dense_matrix(&self, n: usize, ni: usize, b: &Mat<f64>) -> Mat<f64> {
        let dim = 2 * n + ni;
        let mut k = Mat::<f64>::zeros(dim, dim);
        for (r, c, v) in self.mass.entries() {
            k[(r, c)] = v;
        }
        for i in 0..n {
            k[(i, n + i)] = -1.0;
            k[(n + i, i)] = -1.0;
            for j in 0..ni {
                k[(n + i, 2 * n + j)] = b[(i, j)];
                k[(2 * n + j, n + i)] = b[(i, j)];
            }
        }
        k
    }
}

impl Formulation for Amalgamated {
    fn name(&self) -> &'static str {
        "amalgamated"
    }

    fn system(&self) -> &dyn MultibodySystem {
        &*self.model
    }

    fn accelerations(
        &mut self,
        t: f64,
        q: &[f64],
        qd: &[f64],
        stabilization: Stabilization,
        qdd: &mut [f64],
        lambda: &mut [f64],
    ) -> Result<(), DynamicsError> {
        self.stats.evaluations += 1;
        self.model.check_lengths(&[("q̈", qdd.len())], &[("λ", lambda.len())])?;
        self.model.check_state(t, q, qd)?;
        let n = qd.len();
        self.model.mass(q, &mut self.mass);
        self.model.applied_forces(t, q, qd, &mut self.q_e);
        self.model.check_forces(t, q, qd, &self.q_e)?;
        let sys = self.model.constraints();
        sys.evaluate(t, q, qd, &mut self.values);
        sys.check_values(t, &self.values)?;
        if stabilization != Stabilization::None {
            sys.velocity_residual(&self.values, qd, &mut self.cdot);
        }
        stabilization.apply(&self.values.gamma, &self.values.c, &self.cdot, &mut self.rhs);
        let before = self.tracker.log.len();
        let (partition, vt) = match self.tracker.transform(t, sys, &self.values, &self.rhs) {
            Some((p, vt)) => (p.clone(), vt),
            None => return Err(self.singular(t)),
        };
        self.stats.repartitions += (self.tracker.log.len() - before) as u64;
        let redundant = partition.rows.len() < sys.num_equations();
        if redundant && self.redundancy == RedundancyTreatment::Error {
            return Err(self.singular(t));
        }
        let ni = partition.independent.len();
        let dim = 2 * n + ni;
        let rhs: Vec<f64> = (0..dim)
            .map(|i| {
                if i < n {
                    self.q_e[i]
                } else if i < 2 * n {
                    -vt.gamma[i - n]
                } else {
                    0.0
                }
            })
            .collect();
        self.stats.factorizations += 1;
        let mut sol = rhs.clone();
        let accurate = if dim > DENSE_LIMIT {
            if self
                .sparse
                .as_ref()
                .is_none_or(|s| s.independent != partition.independent)
            {
                self.sparse = SparseSystem::new(&self.mass, &partition);
            }
            match self.sparse.as_mut() {
                Some(sp) => {
                    let solved = sp.solve(&self.mass, &vt.b, &mut sol).is_some();
                    let mut r = vec![0.0; dim];
                    sp.mul(&sol, &mut r);
                    let res = r.iter().zip(&rhs).fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
                    let size = rhs.iter().chain(&sol).fold(0.0f64, |a, v| a.max(v.abs()));
                    solved && res <= 1e-9 * size.max(1.0)
                }
                None => false,
            }
        } else {
            let k = self.dense_matrix(n, ni, &vt.b);
            let b = Mat::from_fn(dim, 1, |i, _| rhs[i]);
            let x = k.partial_piv_lu().solve(&b);
            let res = (&k * &x - &b).norm_max();
            for i in 0..dim {
                sol[i] = x[(i, 0)];
            }
            res <= 1e-9 * (b.norm_max() + k.norm_max() * x.norm_max())
        };
        if !accurate || sol.iter().any(|v| !v.is_finite()) {
            return Err(self.model.singular_mass_error(t, "amalgamated system singular"));
        }
        qdd.copy_from_slice(&sol[..n]);
        // λ on the independent rows from the dependent columns of Q_c = −C_qᵀ λ.
        let mut y: Vec<f64> = partition.dependent.iter().map(|&d| -sol[n + d]).collect();
        vt.solve_dependent_transpose(&mut y);
        sys.scatter_multipliers(t, &self.values, &partition.rows, &y, lambda)?;
        Ok(())
    }

    fn residuals(&mut self, t: f64, q: &[f64], qd: &[f64], c: &mut [f64], cdot: &mut [f64]) {
        self.model.constraints().residuals(t, q, qd, &mut self.values, c, cdot);
    }

    /// Coordinate partitioning (`PartitionTracker::project`): independent coordinates held,
    /// dependent positions by Newton–Raphson, dependent velocities from the velocity equation.
    fn project(&mut self, t: f64, q: &mut [f64], qd: &mut [f64], tolerance: f64) -> Result<usize, DynamicsError> {
        let sys = self.model.constraints();
        self.tracker
            .project_counted(t, sys, &mut self.values, (q, qd), tolerance, &mut self.stats)
    }

    fn stats(&self) -> FormulationStats {
        self.stats
    }
}
