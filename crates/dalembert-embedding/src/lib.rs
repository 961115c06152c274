//! The embedding formulation (`FORMULATIONS.md` §4–§5): with the velocity transformation
//! `q̇ = B_i q̇_i + …`, `q̈ = B_i q̈_i + γ_i`, premultiplying `M q̈ + C_qᵀ λ = Q_e` by `B_iᵀ` removes
//! the constraint forces:
//!
//! ```text
//! M_i q̈_i = Q_i,     M_i = B_iᵀ M B_i,     Q_i = B_iᵀ (Q_e − M γ_i)
//! ```
//!
//! one equation per degree of freedom, solved by Cholesky (`M_i` is symmetric positive definite
//! whenever the motion is determined). The multipliers follow after the fact from the dependent
//! columns of `C_qᵀ λ = Q_e − M q̈` ([`Multipliers::AfterTheFact`]) or in the same solve from
//! `[M B_i  C_qᵀ] [q̈_i; λ] = Q_e − M γ_i` ([`Multipliers::Elimination`]).
//!
//! The partition is chosen by LU with full pivoting of `C_q` and re-chosen when the dependent block
//! becomes ill-conditioned (see `dalembert_constraints::partition`); each change is logged with its
//! time. [`Formulation::project`] is **coordinate partitioning**: it keeps the independent
//! coordinates and recovers the dependent ones by Newton–Raphson on `C(q, t) = 0` and their
//! velocities from the velocity equation, so an integrator that projects after every step integrates
//! the independent coordinates only, with the constraints held to the Newton tolerance.

use dalembert_system::partition::Repartition;
use dalembert_system::{
    BlockDiagonal, ConstraintValues, DynamicsError, Formulation, FormulationStats, MultibodySystem, PartitionTracker,
    RedundancyTreatment, Stabilization,
};
use faer::linalg::solvers::Solve;
use faer::{Mat, Side};
use std::sync::Arc;

/// How the embedding formulation computes the multipliers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Multipliers {
    /// From the dependent columns of `C_qᵀ λ = Q_e − M q̈` after `q̈` is known.
    #[default]
    AfterTheFact,
    /// Together with `q̈_i` from the square system `[M B_i  C_qᵀ] [q̈_i; λ] = Q_e − M γ_i`.
    Elimination,
}

/// Settings of the embedding formulation.
#[derive(Debug, Clone, PartialEq)]
pub struct EmbeddingOptions {
    /// How to get the multipliers.
    pub multipliers: Multipliers,
    /// What to do with redundant constraints.
    pub redundancy: RedundancyTreatment,
    /// Condition estimate of `C_qd` (pivot ratio of its LU) above which the coordinates are
    /// re-partitioned. Default 1e3: passing a singular partition with a step of 1e-3 gives ratios
    /// of only ≈ 1e2–1e3, so a higher threshold would ride through it with digits lost.
    pub repartition_threshold: f64,
    /// User-chosen independent coordinates (indices into `q`), used while `C_qd` stays regular.
    pub independent: Option<Vec<usize>>,
}

impl Default for EmbeddingOptions {
    fn default() -> Self {
        EmbeddingOptions {
            multipliers: Multipliers::AfterTheFact,
            redundancy: RedundancyTreatment::Error,
            repartition_threshold: 1e3,
            independent: None,
        }
    }
}

/// The embedding formulation of a model.
pub struct Embedding {
    model: Arc<dyn MultibodySystem>,
    options: EmbeddingOptions,
    tracker: PartitionTracker,
    mass: BlockDiagonal,
    values: ConstraintValues,
    q_e: Vec<f64>,
    cdot: Vec<f64>,
    rhs: Vec<f64>,
    stats: FormulationStats,
}

impl std::fmt::Debug for Embedding {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Embedding")
            .field("options", &self.options)
            .field("partition", &self.tracker.current())
            .finish()
    }
}

impl Embedding {
    /// Sets up the formulation.
    pub fn new(model: Arc<dyn MultibodySystem>, options: EmbeddingOptions) -> Self {
        let mut tracker = PartitionTracker::new(options.repartition_threshold);
        if let Some(ind) = &options.independent {
            tracker = tracker.with_independent(model.constraints(), ind.clone());
        }
        let n = model.layout().n_v();
        let m = model.num_equations();
        Embedding {
            mass: model.mass_storage(),
            values: model.constraints().values(),
            q_e: vec![0.0; n],
            cdot: vec![0.0; m],
            rhs: vec![0.0; m],
            tracker,
            options,
            model,
            stats: FormulationStats::default(),
        }
    }

    /// With default options.
    pub fn with_defaults(model: Arc<dyn MultibodySystem>) -> Self {
        Self::new(model, EmbeddingOptions::default())
    }

    /// The independent coordinates in use (after the first evaluation).
    pub fn independent_coordinates(&self) -> Option<&[usize]> {
        self.tracker.current().map(|p| p.independent.as_slice())
    }

    /// Every re-partition so far: time, old and new independent coordinates.
    pub fn repartitions(&self) -> &[Repartition] {
        &self.tracker.log
    }

    fn singular(&self, t: f64) -> DynamicsError {
        self.model.constraints().redundancy_error(t, &self.values)
    }

    fn load(&mut self, t: f64, q: &[f64], qd: &[f64]) -> Result<(), DynamicsError> {
        self.model.check_state(t, q, qd)?;
        self.model.mass(q, &mut self.mass);
        self.model.applied_forces(t, q, qd, &mut self.q_e);
        self.model.check_forces(t, q, qd, &self.q_e)?;
        self.model.constraints().evaluate(t, q, qd, &mut self.values);
        self.model.constraints().check_values(t, &self.values)?;
        Ok(())
    }
}

impl Formulation for Embedding {
    fn name(&self) -> &'static str {
        "embedding"
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
        self.load(t, q, qd)?;
        let sys = self.model.constraints();
        let n = qd.len();
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
        self.stats.factorizations += 1;
        let redundant = partition.rows.len() < sys.num_equations();
        if redundant && self.options.redundancy == RedundancyTreatment::Error {
            return Err(self.singular(t));
        }
        let ni = partition.independent.len();
        // M B_i, M γ_i (M block diagonal).
        let mut mb = Mat::<f64>::zeros(n, ni);
        for j in 0..ni {
            let col: Vec<f64> = (0..n).map(|i| vt.b[(i, j)]).collect();
            let mut out = vec![0.0; n];
            self.mass.mul_add(1.0, &col, &mut out);
            for i in 0..n {
                mb[(i, j)] = out[i];
            }
        }
        let mut mg = vec![0.0; n];
        self.mass.mul_add(1.0, &vt.gamma, &mut mg);
        let rhs_full: Vec<f64> = (0..n).map(|i| self.q_e[i] - mg[i]).collect();
        let qdd_i: Vec<f64>;
        let mut lam_rows: Option<Vec<f64>> = None;
        match self.options.multipliers {
            Multipliers::AfterTheFact => {
                let mi = vt.b.transpose() * &mb;
                let qi = vt.b.transpose() * Mat::from_fn(n, 1, |i, _| rhs_full[i]);
                let llt = mi.llt(Side::Lower).map_err(|_| {
                    self.model
                        .singular_mass_error(t, "reduced mass matrix B_iᵀ M B_i not positive definite")
                })?;
                let sol = llt.solve(&qi);
                qdd_i = (0..ni).map(|i| sol[(i, 0)]).collect();
            }
            Multipliers::Elimination => {
                // [M B_i  C_q,Rᵀ] [q̈_i; λ_R] = Q_e − M γ_i   (n × n when the rows are independent).
                let r = partition.rows.len();
                let jac = sys.jacobian_dense(&self.values);
                let k = Mat::from_fn(n, ni + r, |i, j| {
                    if j < ni {
                        mb[(i, j)]
                    } else {
                        jac[(partition.rows[j - ni], i)]
                    }
                });
                let lu = k.partial_piv_lu();
                let sol = lu.solve(Mat::from_fn(n, 1, |i, _| rhs_full[i]));
                if (0..n).any(|i| !sol[(i, 0)].is_finite()) {
                    return Err(self
                        .model
                        .singular_mass_error(t, "elimination matrix [M B_i  C_qᵀ] singular"));
                }
                qdd_i = (0..ni).map(|i| sol[(i, 0)]).collect();
                lam_rows = Some((0..r).map(|i| sol[(ni + i, 0)]).collect());
            }
        }
        for i in 0..n {
            qdd[i] = vt.gamma[i] + (0..ni).map(|j| vt.b[(i, j)] * qdd_i[j]).sum::<f64>();
        }
        // Multipliers on the independent rows (minimum-norm over all rows when some are redundant).
        let lam_r = match lam_rows {
            Some(l) => l,
            None => {
                let mut f = self.q_e.clone();
                self.mass.mul_add(-1.0, qdd, &mut f);
                let mut y: Vec<f64> = partition.dependent.iter().map(|&d| f[d]).collect();
                vt.solve_dependent_transpose(&mut y);
                y
            }
        };
        sys.scatter_multipliers(t, &self.values, &partition.rows, &lam_r, lambda)?;
        if let Some(i) = qdd.iter().position(|v| !v.is_finite()) {
            return Err(self.model.non_finite_acceleration(t, i));
        }
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
