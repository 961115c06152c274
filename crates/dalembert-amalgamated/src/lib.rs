//! The amalgamated formulation (`docs/equations.md` §6): accelerations `q̈`, generalized constraint
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
//! **Factorization.** The matrix is symmetric indefinite; it is factored as `L D Lᵀ` with static
//! 2 × 2 pivots on the pairs `(q̈_k, Q_c,k)` followed by the independent accelerations. Writing
//! `K = [A E; Eᵀ 0]` with `A = [M −I; −I 0]` (always invertible, `A⁻¹ = [0 −I; −I −M]`, even where
//! `M` is singular) and `E = [0; B_i]`, the Schur complement of the pivots is
//!
//! ```text
//! S = −Eᵀ A⁻¹ E = B_iᵀ M B_i       (symmetric positive definite: Cholesky)
//! ```
//!
//! and a right-hand side `(b₁, b₂, b₃)` is solved by `x₃ = S⁻¹ (b₃ + B_iᵀ (b₁ + M b₂))`,
//! `x₁ = B_i x₃ − b₂`, `x₂ = M x₁ − b₁`. No fill-in beyond `S` occurs, and `B_i` is used through
//! the sparse velocity transformation shared with the embedding formulation
//! (`dalembert_system::partition`): factored this way the amalgamated system costs the embedding's
//! reduced mass matrix plus `O(n)` (measured in `docs/formulations.md`). Every solve is checked by
//! its residual on the full system.

use dalembert_system::linalg::DenseCholesky;
use dalembert_system::minimum_norm::{scatter_minimum_norm, MinimumNorm};
use dalembert_system::partition::VelocityTransform;
use dalembert_system::{
    Baumgarte, BlockDiagonal, Data, DynamicsError, Formulation, FormulationStats, MultibodySystem, PartitionTracker,
    RedundancyTreatment, Stage,
};
use std::sync::Arc;

/// The amalgamated formulation of a model.
pub struct Amalgamated {
    model: Arc<dyn MultibodySystem>,
    redundancy: RedundancyTreatment,
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

/// Storage of one evaluation for a system of `dim = 2n + ni` unknowns (rebuilt only when a
/// re-partition changes `ni`).
#[derive(Debug)]
struct Work {
    /// The Schur complement `S = B_iᵀ M B_i` of the 2 × 2 pivots, then its Cholesky factor.
    schur: DenseCholesky,
    /// Right-hand side, solution, and `K x` for the residual check (each `dim`).
    rhs: Vec<f64>,
    sol: Vec<f64>,
    kx: Vec<f64>,
    /// Scratch of length `n`.
    tmp: Vec<f64>,
    /// Multipliers on the independent rows (`r`).
    y: Vec<f64>,
    /// The refinement's correction of `q̈_i` (`ni`).
    delta: Vec<f64>,
}

impl Work {
    fn new(n: usize, ni: usize, r: usize) -> Self {
        let dim = 2 * n + ni;
        Work {
            schur: DenseCholesky::new(ni),
            rhs: vec![0.0; dim],
            sol: vec![0.0; dim],
            kx: vec![0.0; dim],
            tmp: vec![0.0; n],
            y: vec![0.0; r],
            delta: vec![0.0; ni],
        }
    }
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
        let mut tracker = PartitionTracker::new(1e3);
        // Without the hand-over (its setup failed) coordinate partitioning projects everywhere.
        let _ = tracker.set_up_handover(&*model);
        Amalgamated {
            data: Data::new(&*model, true),
            tracker,
            redundancy,
            model,
            stats: FormulationStats::default(),
            minimum_norm: None,
            work: Work::new(0, 0, 0),
        }
    }

    /// With redundant constraints treated as errors.
    pub fn with_defaults(model: Arc<dyn MultibodySystem>) -> Self {
        Self::new(model, RedundancyTreatment::Error)
    }
}

/// Condition estimate of `S = B_iᵀ M B_i` above which its solution gets one step of iterative
/// refinement ([`refine`]): as the saddle-point back ends' Schur complement
/// (`dalembert_system::linalg::SaddlePoint::refines`), where the estimates can fall short of the
/// condition number by a factor 10–100. Below it the Cholesky solve is already accurate to about
/// 1e-10 relative, and a well-conditioned `S` (a single degree of freedom: `S` is 1 × 1) keeps the
/// rounding of the plain solve.
const ILL_CONDITIONED: f64 = 1e3;

/// One step of iterative refinement on the reduced equation: `S Δ = B_iᵀ (Q_e − M q̈)`,
/// `q̈_i += Δ`, `q̈ += B_i Δ`, `Q_c = M q̈ − Q_e` again. Forming `S` squares `B_i`'s scale, so its
/// Cholesky solve loses digits the motion does not have; the residual, taken in the absolute
/// coordinates, returns them (the embedding formulation does the same). `work.sol` holds
/// `(q̈, Q_c, q̈_i)`.
fn refine(mass: &BlockDiagonal, vt: &VelocityTransform, q_e: &[f64], work: &mut Work) {
    let n = mass.dim();
    let (x1, rest) = work.sol.split_at_mut(n);
    let (x2, x3) = rest.split_at_mut(n);
    work.tmp.copy_from_slice(q_e);
    mass.mul_add(-1.0, x1, &mut work.tmp);
    vt.mul_transpose(&work.tmp, &mut work.delta);
    work.schur.solve_vec(&mut work.delta);
    vt.mul_add(&work.delta, x1);
    for (x, d) in x3.iter_mut().zip(&work.delta) {
        *x += d;
    }
    for (x, b) in x2.iter_mut().zip(q_e) {
        *x = -b;
    }
    mass.mul_add(1.0, x1, x2);
}

/// `y = K x` for `K = [M −I 0; −I 0 B_i; 0 B_iᵀ 0]`, from the blocks.
fn amalgamated_mul(mass: &BlockDiagonal, vt: &VelocityTransform, x: &[f64], y: &mut [f64]) {
    let n = mass.dim();
    let (x1, rest) = x.split_at(n);
    let (x2, x3) = rest.split_at(n);
    let (y1, rest) = y.split_at_mut(n);
    let (y2, y3) = rest.split_at_mut(n);
    for i in 0..n {
        y1[i] = -x2[i];
        y2[i] = -x1[i];
    }
    mass.mul_add(1.0, x1, y1);
    vt.mul_add(x3, y2);
    vt.mul_transpose(x2, y3);
}

/// Solves `K x = b` with the `L D Lᵀ` factors of the module doc (`S` already factored in `schur`):
/// `x₃ = S⁻¹ (b₃ + B_iᵀ (b₁ + M b₂))`, `x₁ = B_i x₃ − b₂`, `x₂ = M x₁ − b₁`. `tmp` has length `n`.
fn amalgamated_solve(
    mass: &BlockDiagonal,
    vt: &VelocityTransform,
    schur: &mut DenseCholesky,
    b: &[f64],
    x: &mut [f64],
    tmp: &mut [f64],
) {
    let n = mass.dim();
    let (b1, rest) = b.split_at(n);
    let (b2, b3) = rest.split_at(n);
    let (x1, rest) = x.split_at_mut(n);
    let (x2, x3) = rest.split_at_mut(n);
    tmp.copy_from_slice(b1);
    mass.mul_add(1.0, b2, tmp);
    vt.mul_transpose(tmp, x3);
    for (x, b) in x3.iter_mut().zip(b3) {
        *x += b;
    }
    schur.solve_vec(x3);
    for (x, b) in x1.iter_mut().zip(b2) {
        *x = -b;
    }
    vt.mul_add(x3, x1);
    for (x, b) in x2.iter_mut().zip(b1) {
        *x = -b;
    }
    mass.mul_add(1.0, x1, x2);
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
        baumgarte: Option<Baumgarte>,
        qdd: &mut [f64],
        lambda: &mut [f64],
    ) -> Result<(), DynamicsError> {
        self.stats.evaluations += 1;
        if self.data.start(&*self.model, t, q, qd, baumgarte, qdd, lambda)? == Stage::Solved {
            return Ok(());
        }
        let n = qd.len();
        let sys = self.model.constraints();
        let before = self.tracker.count();
        let m = sys.num_equations();
        let model = Arc::clone(&self.model);
        let sys = model.constraints();
        let Amalgamated {
            tracker,
            work,
            data,
            redundancy,
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
        let redundant = partition.rows.len() < m;
        if redundant && *redundancy == RedundancyTreatment::Error {
            return Err(sys.redundancy_error(t, values));
        }
        let ni = partition.independent.len();
        let dim = 2 * n + ni;
        if work.rhs.len() != dim || work.y.len() != partition.rows.len() {
            *work = Work::new(n, ni, partition.rows.len());
        }
        for i in 0..n {
            work.rhs[i] = q_e[i];
            work.rhs[n + i] = -vt.gamma[i];
        }
        work.rhs[2 * n..].iter_mut().for_each(|v| *v = 0.0);
        stats.factorizations += 1;
        vt.reduced_mass(mass, work.schur.storage_mut());
        let factored = work.schur.factor().is_ok();
        if factored {
            amalgamated_solve(mass, vt, &mut work.schur, &work.rhs, &mut work.sol, &mut work.tmp);
            if work.schur.condition_estimate() > ILL_CONDITIONED {
                refine(mass, vt, q_e, work);
            }
        }
        // Accept the solve when its residual is at round-off: ‖K x − b‖∞ ≤ 1e-9 (‖b‖∞ + s ‖x‖∞),
        // s the largest entry of K.
        amalgamated_mul(mass, vt, &work.sol, &mut work.kx);
        let norm = |v: &[f64]| v.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        let res = work
            .kx
            .iter()
            .zip(&work.rhs)
            .fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
        let scale = mass.max_abs().max(1.0);
        let s_b = vt.max_abs().max(scale);
        let accurate = factored && res <= 1e-9 * (norm(&work.rhs) + s_b * norm(&work.sol));
        if !accurate || work.sol.iter().any(|v| !v.is_finite()) {
            return Err(model.singular_mass_error(t, "amalgamated system singular"));
        }
        qdd.copy_from_slice(&work.sol[..n]);
        // λ on the independent rows from the dependent columns of Q_c = −C_qᵀ λ.
        for (y, &d) in work.y.iter_mut().zip(&partition.dependent) {
            *y = -work.sol[n + d];
        }
        vt.solve_dependent_transpose(&mut work.y);
        scatter_minimum_norm(minimum_norm, sys, t, values, &partition.rows, &work.y, lambda)?;
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

    /// The last evaluation's factors with right-hand side `[g; 0; 0]`, and the multipliers from
    /// the dependent columns.
    fn force_response(
        &mut self,
        t: f64,
        g: &[f64],
        dqdd: &mut [f64],
        dlambda: &mut [f64],
    ) -> Result<bool, DynamicsError> {
        self.respond(t, g, None, dqdd, dlambda)
    }

    /// The last evaluation's factors with right-hand side `[g; −γ_h; 0]`, `γ_h` the particular
    /// solution of `C_q x = h` from the dependent columns' factors (false for redundant
    /// equations).
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

impl Amalgamated {
    /// The last evaluation's factors with the right-hand side `[g; −γ_h; 0]` (`γ_h = 0` when `h`
    /// is `None`), and the multipliers from the dependent columns.
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
        let Amalgamated {
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
        let n = g.len();
        let ni = partition.independent.len();
        if work.rhs.len() != 2 * n + ni || work.y.len() != partition.rows.len() {
            return Ok(false);
        }
        work.rhs.iter_mut().for_each(|v| *v = 0.0);
        work.rhs[..n].copy_from_slice(g);
        if let Some(h) = h {
            if partition.rows.len() < m || h.len() != m {
                return Ok(false);
            }
            // γ_h in `dqdd`, overwritten by the solution below.
            vt.particular(h, dqdd);
            for (r, &v) in work.rhs[n..2 * n].iter_mut().zip(dqdd.iter()) {
                *r = -v;
            }
        }
        amalgamated_solve(&data.mass, vt, &mut work.schur, &work.rhs, &mut work.sol, &mut work.tmp);
        dqdd.copy_from_slice(&work.sol[..n]);
        for (y, &d) in work.y.iter_mut().zip(&partition.dependent) {
            *y = -work.sol[n + d];
        }
        vt.solve_dependent_transpose(&mut work.y);
        let sys = model.constraints();
        scatter_minimum_norm(minimum_norm, sys, t, &data.values, &partition.rows, &work.y, dlambda)?;
        Ok(dqdd.iter().chain(dlambda.iter()).all(|v| v.is_finite()))
    }
}

/// The registry entry of the amalgamated formulation.
pub static ENTRY: dalembert_system::FormulationEntry = dalembert_system::FormulationEntry {
    name: "amalgamated",
    summary: "one symmetric system in accelerations, constraint forces and independent accelerations",
    dense_partitioning: true,
    index3_augmented: false,
    build: |system, settings| Ok(Box::new(Amalgamated::new(system, settings.redundancy))),
};
