//! The embedding formulation (`docs/equations.md` §4–§5): with the velocity transformation
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
//! becomes ill-conditioned (see `dalembert_system::partition`); each change is logged with its
//! time. [`Formulation::project`] is **coordinate partitioning**: it keeps the independent
//! coordinates and recovers the dependent ones by Newton–Raphson on `C(q, t) = 0` and their
//! velocities from the velocity equation, so an integrator that projects after every step integrates
//! the independent coordinates only, with the constraints held to the Newton tolerance.

use dalembert_system::linalg::{DenseCholesky, DenseLu};
use dalembert_system::minimum_norm::{scatter_minimum_norm, MinimumNorm};
use dalembert_system::partition::{Partition, Repartition};
use dalembert_system::{
    Baumgarte, Data, DynamicsError, Formulation, FormulationStats, MultibodySystem, PartitionTracker,
    RedundancyTreatment, Stage,
};
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
    /// `M`, `Q`, the constraint values and the right-hand side (the stages before the solve; a
    /// tree in joint coordinates without constraint equations, `M q̈ = Q` with `B_i = I`, is
    /// solved there by the articulated-body algorithm).
    data: Data,
    stats: FormulationStats,
    /// The minimum-norm multipliers of a redundant system, for the current independent equations.
    minimum_norm: Option<MinimumNorm>,
    work: Work,
}

/// Storage of one evaluation, sized for a partition with `ni` independent coordinates (rebuilt only
/// when a re-partition changes the sizes).
struct Work {
    ni: usize,
    /// `M_i = B_iᵀ M B_i` and its Cholesky factor.
    mi: DenseCholesky,
    /// `Q_e − M γ_i`, `n`.
    rhs_full: Vec<f64>,
    /// `q̈_i` (or `[q̈_i; λ_R]` with elimination), `n`; a column of `B_i` while the elimination
    /// matrix is filled.
    sol: Vec<f64>,
    /// `Q_e − M q̈`, `n`; a column of `M B_i` while the elimination matrix is filled.
    f: Vec<f64>,
    /// Multipliers on the independent rows, `r`.
    lam_r: Vec<f64>,
    /// The correction of `q̈_i` by one step of iterative refinement, `ni`.
    refine: Vec<f64>,
    /// `[M B_i  C_q,Rᵀ]` (elimination only), `n × n`.
    elimination: Option<DenseLu>,
    /// Row of each system equation among the partition's rows (elimination only).
    row_slot: Vec<Option<usize>>,
}

impl Work {
    fn new(n: usize, partition: &Partition, m: usize, multipliers: Multipliers) -> Self {
        let ni = partition.independent.len();
        let mut row_slot = vec![None; m];
        for (i, &row) in partition.rows.iter().enumerate() {
            row_slot[row] = Some(i);
        }
        Work {
            ni,
            mi: DenseCholesky::new(ni),
            rhs_full: vec![0.0; n],
            sol: vec![0.0; n],
            f: vec![0.0; n],
            lam_r: vec![0.0; partition.rows.len()],
            refine: vec![0.0; ni],
            elimination: (multipliers == Multipliers::Elimination).then(|| DenseLu::new(n, 1)),
            row_slot,
        }
    }
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
        // Without the hand-over (its setup failed) coordinate partitioning projects everywhere.
        let _ = tracker.set_up_handover(&*model);
        Embedding {
            data: Data::new(&*model, true),
            tracker,
            options,
            model,
            stats: FormulationStats::default(),
            minimum_norm: None,
            work: Work::new(0, &Partition::default(), 0, Multipliers::AfterTheFact),
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
        self.tracker.log()
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
        baumgarte: Option<Baumgarte>,
        qdd: &mut [f64],
        lambda: &mut [f64],
    ) -> Result<(), DynamicsError> {
        self.stats.evaluations += 1;
        if self.data.start(&*self.model, t, q, qd, baumgarte, qdd, lambda)? == Stage::Solved {
            return Ok(());
        }
        let sys = self.model.constraints();
        let n = qd.len();
        let before = self.tracker.count();
        let m = sys.num_equations();
        let model = Arc::clone(&self.model);
        let sys = model.constraints();
        let Embedding {
            tracker,
            work,
            data,
            options,
            stats,
            minimum_norm,
            ..
        } = self;
        let Data {
            mass, q_e, values, rhs, ..
        } = data;
        let transformed = tracker.transform(t, sys, values, rhs).is_some();
        stats.repartitions += tracker.count() - before;
        let (true, Some((partition, vt))) = (transformed, tracker.last()) else {
            return Err(sys.redundancy_error(t, values));
        };
        stats.factorizations += 1;
        let redundant = partition.rows.len() < m;
        if redundant && options.redundancy == RedundancyTreatment::Error {
            return Err(sys.redundancy_error(t, values));
        }
        let ni = partition.independent.len();
        let r = partition.rows.len();
        if work.ni != ni || work.lam_r.len() != r || work.rhs_full.len() != n || work.row_slot.len() != m {
            *work = Work::new(n, partition, m, options.multipliers);
        }
        if work.elimination.is_some() {
            // The row map follows the partition's rows (same sizes, possibly other rows).
            work.row_slot.iter_mut().for_each(|s| *s = None);
            for (i, &row) in partition.rows.iter().enumerate() {
                work.row_slot[row] = Some(i);
            }
        }
        // Q_e − M γ_i.
        work.rhs_full.copy_from_slice(q_e);
        mass.mul_add(-1.0, &vt.gamma, &mut work.rhs_full);
        match &mut work.elimination {
            None => {
                // M_i q̈_i = B_iᵀ (Q_e − M γ_i),   M_i = B_iᵀ M B_i (Cholesky), both over the
                // column ranges of B_i's rows.
                vt.mul_transpose(&work.rhs_full, &mut work.sol[..ni]);
                vt.reduced_mass(mass, work.mi.storage_mut());
                if work.mi.factor().is_err() {
                    return Err(model.singular_mass_error(t, "reduced mass matrix B_iᵀ M B_i not positive definite"));
                }
                work.mi.solve_vec(&mut work.sol[..ni]);
            }
            Some(lu) => {
                // [M B_i  C_q,Rᵀ] [q̈_i; λ_R] = Q_e − M γ_i   (n × n when the rows are independent).
                {
                    let mut k = lu.matrix_mut();
                    k.fill(0.0);
                    for j in 0..ni {
                        // Column j of M B_i (in f) from column j of B_i (in sol, overwritten below).
                        work.f.iter_mut().for_each(|v| *v = 0.0);
                        for (i, b) in work.sol.iter_mut().enumerate() {
                            *b = vt.b_row(i)[j];
                        }
                        mass.mul_add(1.0, &work.sol, &mut work.f);
                        for i in 0..n {
                            k[(i, j)] = work.f[i];
                        }
                    }
                    for (&(row, col), &v) in sys.pattern().entries().iter().zip(&values.jacobian) {
                        if let Some(i) = work.row_slot[row] {
                            k[(col, ni + i)] += v;
                        }
                    }
                }
                lu.factor();
                work.sol.copy_from_slice(&work.rhs_full);
                lu.solve_vec(&mut work.sol);
                if work.sol.iter().any(|v| !v.is_finite()) {
                    return Err(model.singular_mass_error(t, "elimination matrix [M B_i  C_qᵀ] singular"));
                }
                work.lam_r.copy_from_slice(&work.sol[ni..ni + r]);
            }
        }
        // q̈ = B_i q̈_i + γ_i
        qdd.copy_from_slice(&vt.gamma);
        vt.mul_add(&work.sol[..ni], qdd);
        if work.elimination.is_none() {
            // One step of iterative refinement: M_i Δ = B_iᵀ (Q_e − M q̈), q̈ += B_i Δ. Forming
            // M_i squares B_i's scale, so its Cholesky solve loses digits a well-conditioned
            // motion does not have; the residual, taken in the absolute coordinates, returns them.
            work.f.copy_from_slice(q_e);
            mass.mul_add(-1.0, qdd, &mut work.f);
            vt.mul_transpose(&work.f, &mut work.refine);
            work.mi.solve_vec(&mut work.refine);
            vt.mul_add(&work.refine, qdd);
        }
        if work.elimination.is_none() {
            // Multipliers on the independent rows from the dependent columns of C_qᵀ λ = Q_e − M q̈.
            work.f.copy_from_slice(q_e);
            mass.mul_add(-1.0, qdd, &mut work.f);
            for (l, &d) in work.lam_r.iter_mut().zip(&partition.dependent) {
                *l = work.f[d];
            }
            vt.solve_dependent_transpose(&mut work.lam_r);
        }
        scatter_minimum_norm(minimum_norm, sys, t, values, &partition.rows, &work.lam_r, lambda)?;
        if let Some(i) = qdd.iter().position(|v| !v.is_finite()) {
            return Err(model.non_finite_acceleration(t, i));
        }
        Ok(())
    }

    fn residuals(&mut self, t: f64, q: &[f64], qd: &[f64], c: &mut [f64], cdot: &mut [f64]) {
        self.data.residuals(&*self.model, (t, q, qd), c, cdot);
    }

    /// Coordinate partitioning (`PartitionTracker::project`): independent coordinates held,
    /// dependent positions by Newton–Raphson, dependent velocities from the velocity equation; at
    /// singular positions, where no partition is well conditioned, the mass-orthogonal projection
    /// (`PartitionTracker::project_or_hand_over`, counted in `FormulationStats::handovers`).
    fn project(&mut self, t: f64, q: &mut [f64], qd: &mut [f64], tolerance: f64) -> Result<usize, DynamicsError> {
        self.data.invalidate();
        self.tracker.project_or_hand_over(
            t,
            &*self.model,
            &mut self.data.values,
            (q, qd),
            tolerance,
            &mut self.stats,
        )
    }

    /// The partition may change at this step's first evaluation, and is then kept through its
    /// stages ([`dalembert_system::PartitionTracker::begin_step`]).
    fn begin_step(&mut self) {
        self.tracker.begin_step();
    }

    fn stats(&self) -> FormulationStats {
        self.stats
    }

    fn set_extra_force(&mut self, extra: Option<&[f64]>) -> bool {
        self.data.set_extra_force(extra)
    }

    /// The last evaluation's solve with `g` for `Q_e` and no `γ_i`: `Δq̈ = B_i M_i⁻¹ B_iᵀ g`
    /// (or the elimination matrix's factors) and the multipliers from the dependent columns.
    fn force_response(
        &mut self,
        t: f64,
        g: &[f64],
        dqdd: &mut [f64],
        dlambda: &mut [f64],
    ) -> Result<bool, DynamicsError> {
        self.respond(t, g, None, dqdd, dlambda)
    }

    /// The last evaluation's solve with `g` for `Q_e` and `h` for the constraints' right-hand
    /// side: its particular solution `γ_h` from the dependent columns' factors, then as
    /// [`Formulation::force_response`] with `g − M γ_h` (false for redundant equations).
    fn linear_response(
        &mut self,
        t: f64,
        g: &[f64],
        h: &[f64],
        dqdd: &mut [f64],
        dlambda: &mut [f64],
    ) -> Result<bool, DynamicsError> {
        self.respond(t, g, Some(h), dqdd, dlambda)
    }
}

impl Embedding {
    /// The last evaluation's factors with the right-hand side `[g; h]` (`h = 0` when `None`).
    fn respond(
        &mut self,
        t: f64,
        g: &[f64],
        h: Option<&[f64]>,
        dqdd: &mut [f64],
        dlambda: &mut [f64],
    ) -> Result<bool, DynamicsError> {
        // A tree solved outright by the articulated-body algorithm: no factorization to reuse.
        if let Some(solved) = self.data.tree_response(&*self.model, g, dqdd) {
            return Ok(solved && dlambda.is_empty());
        }
        let Embedding {
            tracker,
            work,
            data,
            minimum_norm,
            model,
            ..
        } = self;
        let m = model.constraints().num_equations();
        let Some((partition, vt)) = tracker.last() else {
            return Ok(false);
        };
        let ni = partition.independent.len();
        let r = partition.rows.len();
        if work.ni != ni || work.lam_r.len() != r || work.rhs_full.len() != g.len() {
            return Ok(false);
        }
        // `dqdd` holds `γ_h` until `B_i q̈_i` is added to it.
        work.rhs_full.copy_from_slice(g);
        match h {
            None => dqdd.iter_mut().for_each(|v| *v = 0.0),
            Some(h) => {
                if r < m || h.len() != m {
                    return Ok(false);
                }
                vt.particular(h, dqdd);
                data.mass.mul_add(-1.0, dqdd, &mut work.rhs_full);
            }
        }
        match &mut work.elimination {
            None => {
                vt.mul_transpose(&work.rhs_full, &mut work.sol[..ni]);
                work.mi.solve_vec(&mut work.sol[..ni]);
            }
            Some(lu) => {
                work.sol.copy_from_slice(&work.rhs_full);
                lu.solve_vec(&mut work.sol);
                work.lam_r.copy_from_slice(&work.sol[ni..ni + r]);
            }
        }
        vt.mul_add(&work.sol[..ni], dqdd);
        if work.elimination.is_none() {
            work.f.copy_from_slice(g);
            data.mass.mul_add(-1.0, dqdd, &mut work.f);
            for (l, &d) in work.lam_r.iter_mut().zip(&partition.dependent) {
                *l = work.f[d];
            }
            vt.solve_dependent_transpose(&mut work.lam_r);
        }
        let sys = model.constraints();
        scatter_minimum_norm(
            minimum_norm,
            sys,
            t,
            &data.values,
            &partition.rows,
            &work.lam_r,
            dlambda,
        )?;
        Ok(dqdd.iter().chain(dlambda.iter()).all(|v| v.is_finite()))
    }
}

/// The registry entry of the embedding formulation.
pub static ENTRY: dalembert_system::FormulationEntry = dalembert_system::FormulationEntry {
    name: "embedding",
    summary:
        "the velocity transformation: one equation per degree of freedom (with projection: coordinate partitioning)",
    dense_partitioning: true,
    index3_augmented: false,
    build: |system, settings| {
        let options = EmbeddingOptions {
            redundancy: settings.redundancy,
            independent: settings.independent.clone(),
            ..Default::default()
        };
        Ok(Box::new(Embedding::new(system, options)))
    },
};
