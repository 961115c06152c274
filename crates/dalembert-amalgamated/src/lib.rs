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

use dalembert_system::linalg::DenseLu;
use dalembert_system::partition::VelocityTransform;
use dalembert_system::{
    BlockDiagonal, ConstraintValues, DynamicsError, Formulation, FormulationStats, MultibodySystem, PartitionTracker,
    RedundancyTreatment, Stabilization,
};
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
    work: Work,
}

/// Storage of one evaluation for a system of `dim = 2n + ni` unknowns (rebuilt only when a
/// re-partition changes `ni`).
#[derive(Debug, Default)]
struct Work {
    /// Right-hand side, solution, and `K x` for the residual check (each `dim`).
    rhs: Vec<f64>,
    sol: Vec<f64>,
    kx: Vec<f64>,
    /// Multipliers on the independent rows (`r`).
    y: Vec<f64>,
    /// The dense factorization (systems up to `DENSE_LIMIT` unknowns).
    dense: Option<DenseLu>,
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
            work: Work::default(),
        }
    }

    /// With redundant constraints treated as errors.
    pub fn with_defaults(model: Arc<dyn MultibodySystem>) -> Self {
        Self::new(model, RedundancyTreatment::Error)
    }
}

/// `y = K x` for `K = [M −I 0; −I 0 B_i; 0 B_iᵀ 0]`, from the blocks.
fn amalgamated_mul(mass: &BlockDiagonal, b: &faer::Mat<f64>, x: &[f64], y: &mut [f64]) {
    let (n, ni) = (b.nrows(), b.ncols());
    let (x1, rest) = x.split_at(n);
    let (x2, x3) = rest.split_at(n);
    let (y1, rest) = y.split_at_mut(n);
    let (y2, y3) = rest.split_at_mut(n);
    for i in 0..n {
        y1[i] = -x2[i];
        y2[i] = -x1[i];
    }
    mass.mul_add(1.0, x1, y1);
    for j in 0..ni {
        let col = b.col_as_slice(j);
        let mut dot = 0.0;
        for i in 0..n {
            y2[i] += col[i] * x3[j];
            dot += col[i] * x2[i];
        }
        y3[j] = dot;
    }
}

/// Writes the dense amalgamated matrix `[M −I 0; −I 0 B_i; 0 B_iᵀ 0]` into `k`.
fn fill_dense(mass: &BlockDiagonal, vt: &VelocityTransform, mut k: faer::MatMut<'_, f64>) {
    let (n, ni) = (vt.b.nrows(), vt.b.ncols());
    k.fill(0.0);
    for (r, c, v) in mass.entries() {
        k[(r, c)] = v;
    }
    for i in 0..n {
        k[(i, n + i)] = -1.0;
        k[(n + i, i)] = -1.0;
        for j in 0..ni {
            k[(n + i, 2 * n + j)] = vt.b[(i, j)];
            k[(2 * n + j, n + i)] = vt.b[(i, j)];
        }
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
        let m = sys.num_equations();
        let model = Arc::clone(&self.model);
        let sys = model.constraints();
        let Amalgamated {
            tracker,
            work,
            mass,
            q_e,
            values,
            redundancy,
            stats,
            rhs,
            sparse,
            ..
        } = self;
        let transformed = tracker.transform(t, sys, values, rhs).is_some();
        stats.repartitions += (tracker.log.len() - before) as u64;
        let (true, Some((partition, vt))) = (transformed, tracker.last()) else {
            return Err(sys.redundancy_error(t, values));
        };
        let redundant = partition.rows.len() < m;
        if redundant && *redundancy == RedundancyTreatment::Error {
            return Err(sys.redundancy_error(t, values));
        }
        let ni = partition.independent.len();
        let dim = 2 * n + ni;
        if work.rhs.len() != dim || work.y.len() != partition.rows.len() {
            *work = Work {
                rhs: vec![0.0; dim],
                sol: vec![0.0; dim],
                kx: vec![0.0; dim],
                y: vec![0.0; partition.rows.len()],
                dense: (dim <= DENSE_LIMIT).then(|| DenseLu::new(dim, 1)),
            };
        }
        for i in 0..n {
            work.rhs[i] = q_e[i];
            work.rhs[n + i] = -vt.gamma[i];
        }
        work.rhs[2 * n..].iter_mut().for_each(|v| *v = 0.0);
        stats.factorizations += 1;
        work.sol.copy_from_slice(&work.rhs);
        let solved = match &mut work.dense {
            Some(lu) => {
                fill_dense(mass, vt, lu.matrix_mut());
                lu.factor();
                lu.solve_vec(&mut work.sol);
                true
            }
            None => {
                // The sparse pattern depends on the partition: a new symbolic analysis per partition.
                if sparse.as_ref().is_none_or(|s| s.independent != partition.independent) {
                    *sparse = SparseSystem::new(mass, partition);
                }
                sparse
                    .as_mut()
                    .is_some_and(|sp| sp.solve(mass, &vt.b, &mut work.sol).is_some())
            }
        };
        // Accept the solve when its residual is at round-off: ‖K x − b‖∞ ≤ 1e-9 (‖b‖∞ + s ‖x‖∞),
        // s the largest entry of K.
        amalgamated_mul(mass, &vt.b, &work.sol, &mut work.kx);
        let norm = |v: &[f64]| v.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        let res = work
            .kx
            .iter()
            .zip(&work.rhs)
            .fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
        let scale = mass.max_abs().max(1.0);
        let s_b = (0..ni).map(|j| norm(vt.b.col_as_slice(j))).fold(scale, f64::max);
        let accurate = solved && res <= 1e-9 * (norm(&work.rhs) + s_b * norm(&work.sol));
        if !accurate || work.sol.iter().any(|v| !v.is_finite()) {
            return Err(model.singular_mass_error(t, "amalgamated system singular"));
        }
        qdd.copy_from_slice(&work.sol[..n]);
        // λ on the independent rows from the dependent columns of Q_c = −C_qᵀ λ.
        for (y, &d) in work.y.iter_mut().zip(&partition.dependent) {
            *y = -work.sol[n + d];
        }
        vt.solve_dependent_transpose(&mut work.y);
        sys.scatter_multipliers(t, values, &partition.rows, &work.y, lambda)?;
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
