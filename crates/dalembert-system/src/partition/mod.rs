//! Generalized coordinate partitioning and the velocity transformation (`docs/equations.md` §4).
//!
//! `q` is split into `r` dependent coordinates `q_d` (the pivot columns of an LU factorization of
//! `C_q` with full pivoting, over a maximal independent set of `r` equations) and `n − r` independent
//! ones `q_i`. With `C_qd` non-singular:
//!
//! ```text
//! q̇ = B_i q̇_i + P[−C_qd⁻¹ C_t ; 0]       q̈ = B_i q̈_i + γ_i
//! B_i = P[−C_qd⁻¹ C_qi ; I]               γ_i = P[C_qd⁻¹ Q_d ; 0]
//! ```
//!
//! `C_qd⁻¹` is never formed: `C_qd` is factored (LU with partial pivoting, dense or sparse) and
//! solved against ([`VelocityTransform`], which also keeps `B_i` sparse by rows). The conditioning
//! of `C_qd` is estimated from the ratio of the factor's pivots; the embedding and amalgamated
//! formulations re-partition when it exceeds a threshold.

mod choice;
mod handover;
mod reduced_mass;
mod transform;
pub use choice::{PartitionChoice, KEPT_UP_TO};
pub use handover::{MassOrthogonalProjection, HANDOVER_CONDITION};
pub use transform::{VelocityTransform, DENSE_LIMIT};

use crate::{ConstraintSet, ConstraintValues, MultibodySystem};

/// A choice of dependent and independent coordinates and of independent equations.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Partition {
    /// Dependent coordinates (one per independent equation), in pivot order.
    pub dependent: Vec<usize>,
    /// Independent coordinates, ascending.
    pub independent: Vec<usize>,
    /// A maximal independent set of equations (system rows), in pivot order.
    pub rows: Vec<usize>,
}

impl Partition {
    /// Whether `C_qd` is square: one dependent coordinate per equation kept. A partition named on
    /// redundant equations ([`PartitionTracker::with_independent`]) is not.
    pub fn is_square(&self) -> bool {
        self.rows.len() == self.dependent.len()
    }

    /// Chooses the partition by LU with full pivoting of `C_q` (rows) and of the selected rows'
    /// columns: the pivot columns become the dependent coordinates.
    pub fn choose(sys: &(impl ConstraintSet + ?Sized), values: &ConstraintValues, rank_tolerance: f64) -> Partition {
        Self::choose_ranked(sys, values, rank_tolerance, None)
    }

    /// [`Partition::choose`] with `rank` independent equations where given: the `rank` first pivots
    /// of the full pivoting, whatever the rank that the tolerance would find at this state. Along
    /// a regular motion the number of degrees of freedom does not change; a redundancy that holds
    /// only on the mechanism's motion (Bricard's loop, `docs/stability.md`) looks like full rank at
    /// a state slightly off it (an integrator's stage), and a partition chosen there with one
    /// equation more would have one degree of freedom less.
    pub fn choose_ranked(
        sys: &(impl ConstraintSet + ?Sized),
        values: &ConstraintValues,
        rank_tolerance: f64,
        rank: Option<usize>,
    ) -> Partition {
        let mut out = Partition::default();
        PartitionChoice::new(sys.num_equations(), sys.num_coordinates()).choose(
            sys,
            values,
            rank_tolerance,
            rank,
            &mut out,
        );
        out
    }

    /// Number of independent coordinates (degrees of freedom).
    pub fn dof(&self) -> usize {
        self.independent.len()
    }
}

/// One change of partition.
#[derive(Debug, Clone, PartialEq)]
pub struct Repartition {
    /// Time of the change.
    pub time: f64,
    /// Independent coordinates before.
    pub old: Vec<usize>,
    /// Independent coordinates after.
    pub new: Vec<usize>,
}

/// How many re-partitions a tracker logs with their coordinates ([`PartitionTracker::log`]); later
/// ones are counted only.
pub const LOGGED_REPARTITIONS: usize = 8;

/// Keeps a partition across evaluations and re-chooses it when `C_qd` becomes ill-conditioned.
///
/// Its first choice sets up the storage of the next ones: the choice's dense matrices
/// ([`PartitionChoice`], for Jacobians up to [`KEPT_UP_TO`] entries), a spare partition and, for a
/// dense `C_qd` factor, a spare velocity transformation laid out again in place
/// ([`VelocityTransform::rebuild`]), and the log's entries. So an evaluation or projection
/// allocates nothing, also when it re-partitions, except where `C_qd` is factored sparse (more
/// than [`DENSE_LIMIT`] dependent coordinates: the new partition's symbolic analysis), the
/// Jacobian exceeds [`KEPT_UP_TO`] entries, or the rank changes.
#[derive(Debug)]
pub struct PartitionTracker {
    current: Option<Partition>,
    vt: Option<VelocityTransform>,
    /// The storage of the next choice and the workspace it replaces, swapped with the current ones
    /// at a re-partition.
    choice: Option<PartitionChoice>,
    spare: Partition,
    spare_vt: Option<VelocityTransform>,
    /// The first [`LOGGED_REPARTITIONS`] re-partitions (the first choice is not logged), their
    /// entries reserved at the first choice; [`PartitionTracker::count`] counts them all.
    log: Vec<Repartition>,
    logged: usize,
    count: u64,
    /// Condition estimate of `C_qd` above which the partition is re-chosen.
    pub threshold: f64,
    /// Rank tolerance of the partition choice.
    pub rank_tolerance: f64,
    /// If given, the user's choice of independent coordinates (used while `C_qd` stays regular).
    preferred: Option<Vec<usize>>,
    /// The projection handed over to at singular positions ([`handover`]), if set up.
    handover: Option<MassOrthogonalProjection>,
    /// Scratch of the projection: Ċ (m), a row-sized vector, a coordinate-sized one.
    cdot: Vec<f64>,
    y: Vec<f64>,
    delta: Vec<f64>,
    /// Set by [`PartitionTracker::begin_step`]: the run tells the tracker where its steps begin,
    /// and the partition then changes only between steps.
    stepping: bool,
    /// The next factorization is the first of a step (or of a projection between steps): it may
    /// re-partition at the threshold.
    free: bool,
}

/// Condition estimate of `C_qd` up to which a step's later evaluations keep the partition its
/// first chose ([`PartitionTracker::begin_step`]), above the re-partition threshold: 1e8 ≈ 1/√ε,
/// where a solve has lost half its digits (the same bound as the saddle-point solve's
/// `SCHUR_FALLBACK_CONDITION`). Beyond it, or where `C_qd` is singular, the partition is chosen
/// again there, with the number of independent equations it had. On IFToMM A02 (N = 2, RK4 +
/// projection, h = 2 … 0.1 ms, embedding and amalgamated) 1e5, 1e7 and 1e10 gave the same
/// errors to the printed digits (`cargo run --release --example n_four_bar -- 2 20 rk4`).
pub const HELD_CONDITION: f64 = 1e8;

impl PartitionTracker {
    /// A tracker that re-partitions above condition estimate `threshold`.
    pub fn new(threshold: f64) -> Self {
        PartitionTracker {
            current: None,
            vt: None,
            choice: None,
            spare: Partition::default(),
            spare_vt: None,
            log: Vec::new(),
            logged: 0,
            count: 0,
            threshold,
            rank_tolerance: 1e-9,
            preferred: None,
            handover: None,
            cdot: Vec::new(),
            y: Vec::new(),
            delta: Vec::new(),
            stepping: false,
            free: true,
        }
    }

    /// A step begins at an accepted state: its first factorization may re-partition (at the
    /// threshold), the step's other evaluations keep that partition up to [`HELD_CONDITION`].
    /// Without it (a caller that does not say where its steps begin) every factorization may
    /// re-partition. A partition that changes between the stages of one step changes which
    /// coordinates a stage's accelerations are solved for while the step is taken; the
    /// accelerations are the same only on the constraint manifold, which a stage is not.
    pub fn begin_step(&mut self) {
        self.stepping = true;
        self.free = true;
    }

    /// Starts from user-named independent coordinates (e.g. the joint angles of a manipulator).
    pub fn with_independent(mut self, sys: &(impl ConstraintSet + ?Sized), independent: Vec<usize>) -> Self {
        let n = sys.num_coordinates();
        let mut ind = independent;
        ind.sort_unstable();
        let dependent: Vec<usize> = (0..n).filter(|c| ind.binary_search(c).is_err()).collect();
        let rows = (0..sys.num_equations()).collect();
        self.preferred = Some(ind.clone());
        self.current = Some(Partition {
            dependent,
            independent: ind,
            rows,
        });
        self.vt = None;
        self
    }

    /// The partition in use, if any.
    pub fn current(&self) -> Option<&Partition> {
        self.current.as_ref()
    }

    /// `B_i`, `γ_i` for `rhs` at the current state, re-partitioning first if `C_qd` is singular or
    /// its condition estimate exceeds the threshold. `None` if even a fresh partition is singular.
    /// Allocates only when it re-partitions.
    pub fn transform(
        &mut self,
        t: f64,
        sys: &(impl ConstraintSet + ?Sized),
        values: &ConstraintValues,
        rhs: &[f64],
    ) -> Option<(&Partition, &mut VelocityTransform)> {
        self.factor(t, sys, values)?;
        let (p, vt) = self.last()?;
        vt.compute(rhs);
        Some((p, vt))
    }

    /// The factorization of `C_qd` at the current state (without `B_i` and `γ_i`), re-partitioning
    /// as [`PartitionTracker::transform`] does. `None` if even a fresh partition is singular.
    pub fn factor(
        &mut self,
        t: f64,
        sys: &(impl ConstraintSet + ?Sized),
        values: &ConstraintValues,
    ) -> Option<(&Partition, &mut VelocityTransform)> {
        let mut kept = false;
        let held = self.stepping && !self.free;
        self.free = false;
        // A named partition on redundant equations has more rows than dependent coordinates: its
        // `C_qd` is not square, so it is chosen again here as where it is singular.
        if let Some(p) = self.current.as_ref().filter(|p| p.is_square()) {
            let vt = self.vt.get_or_insert_with(|| VelocityTransform::new(p, sys));
            let limit = if held {
                HELD_CONDITION.max(self.threshold)
            } else {
                self.threshold
            };
            kept = vt.refactor(values) && vt.condition <= limit;
            if kept && self.choice.is_none() && self.log.is_empty() {
                // A partition the user named, kept at its first evaluation.
                let first = self.current.take();
                let vt = self.vt.take();
                if let (Some(first), Some(vt)) = (&first, &vt) {
                    self.set_up_next(sys, first, vt);
                }
                self.current = first;
                self.vt = vt;
            }
        }
        if !kept {
            // A new partition keeps the number of independent equations of the one it replaces;
            // only where that is singular (a rank loss of the mechanism itself) is the rank found
            // again at this state.
            let same_rank = self.current.as_ref().filter(|p| p.is_square()).map(|p| p.rows.len());
            let mut fresh = std::mem::take(&mut self.spare);
            match &mut self.choice {
                Some(choice) => choice.choose(sys, values, self.rank_tolerance, same_rank, &mut fresh),
                None => fresh = Partition::choose_ranked(sys, values, self.rank_tolerance, same_rank),
            }
            let mut vt = match self.spare_vt.take() {
                Some(mut spare) => {
                    if spare.rebuild(&fresh, sys) {
                        spare
                    } else {
                        VelocityTransform::new(&fresh, sys)
                    }
                }
                None => VelocityTransform::new(&fresh, sys),
            };
            if !vt.refactor(values) && same_rank.is_some() {
                fresh = Partition::choose(sys, values, self.rank_tolerance);
                vt = VelocityTransform::new(&fresh, sys);
            }
            if !vt.refactor(values) {
                self.spare = fresh;
                self.spare_vt = Some(vt);
                return None;
            }
            if let Some(old) = &self.current {
                if old.independent != fresh.independent || old.rows.len() != fresh.rows.len() {
                    self.count += 1;
                    if let Some(entry) = self.log.get_mut(self.logged) {
                        entry.time = t;
                        entry.old.clear();
                        entry.old.extend_from_slice(&old.independent);
                        entry.new.clear();
                        entry.new.extend_from_slice(&fresh.independent);
                        self.logged += 1;
                    }
                }
            }
            if self.log.is_empty() {
                self.set_up_next(sys, &fresh, &vt);
            }
            if let Some(old) = self.current.replace(fresh) {
                self.spare = old;
            }
            if let Some(old) = self.vt.replace(vt) {
                self.spare_vt = Some(old);
            }
        }
        self.last()
    }

    /// [`PartitionTracker::factor`] in a projection, between steps: it may re-partition at the
    /// threshold ([`PartitionTracker::begin_step`]).
    fn factor_between_steps(
        &mut self,
        t: f64,
        sys: &(impl ConstraintSet + ?Sized),
        values: &ConstraintValues,
    ) -> Option<(&Partition, &mut VelocityTransform)> {
        self.free = true;
        self.factor(t, sys, values)
    }

    /// After the first choice: the storage of the next ones (see [`PartitionTracker`]).
    fn set_up_next(&mut self, sys: &(impl ConstraintSet + ?Sized), first: &Partition, vt: &VelocityTransform) {
        let (m, n) = (sys.num_equations(), sys.num_coordinates());
        if m.saturating_mul(n) <= KEPT_UP_TO {
            self.choice = Some(PartitionChoice::new(m, n));
        }
        self.spare = Partition {
            dependent: Vec::with_capacity(n),
            independent: Vec::with_capacity(n),
            rows: Vec::with_capacity(m),
        };
        if self.spare_vt.is_none() && vt.is_dense() {
            self.spare_vt = Some(VelocityTransform::new(first, sys));
        }
        self.log = (0..LOGGED_REPARTITIONS)
            .map(|_| Repartition {
                time: 0.0,
                old: Vec::with_capacity(n),
                new: Vec::with_capacity(n),
            })
            .collect();
    }

    /// Every re-partition so far (the first choice is not one).
    pub fn count(&self) -> u64 {
        self.count
    }

    /// The first [`LOGGED_REPARTITIONS`] re-partitions, with their times and coordinates.
    pub fn log(&self) -> &[Repartition] {
        &self.log[..self.logged]
    }

    /// The partition and velocity transformation of the last successful
    /// [`PartitionTracker::transform`].
    pub fn last(&mut self) -> Option<(&Partition, &mut VelocityTransform)> {
        match (&self.current, &mut self.vt) {
            (Some(p), Some(vt)) => Some((p, vt)),
            _ => None,
        }
    }
}

impl PartitionTracker {
    /// Sets up the mass-orthogonal projection that [`PartitionTracker::project_or_hand_over`]
    /// hands over to at singular positions (its saddle-point factorization: allocated here).
    ///
    /// When it cannot be set up (its saddle-point analysis fails) the tracker keeps coordinate
    /// partitioning everywhere, as before the hand-over existed, and this says why.
    pub fn set_up_handover(&mut self, model: &dyn MultibodySystem) -> Result<(), crate::linalg::LinalgError> {
        self.handover = Some(MassOrthogonalProjection::new(model)?);
        Ok(())
    }

    /// Coordinate partitioning ([`PartitionTracker::project`]), or, when the partition's `C_qd`
    /// stays ill-conditioned after re-partitioning (condition estimate above
    /// [`HANDOVER_CONDITION`], or singular) and [`PartitionTracker::set_up_handover`] set it up, the
    /// mass-orthogonal projection ([`MassOrthogonalProjection`]). Adds Newton iterations,
    /// re-partitions and hand-overs to `stats`. It runs between steps: every factorization in it
    /// may re-partition ([`PartitionTracker::begin_step`]).
    pub fn project_or_hand_over(
        &mut self,
        t: f64,
        model: &dyn MultibodySystem,
        values: &mut ConstraintValues,
        (q, qd): (&mut [f64], &mut [f64]),
        tolerance: f64,
        stats: &mut crate::FormulationStats,
    ) -> Result<usize, crate::DynamicsError> {
        let sys = model.constraints();
        if self.handover.is_some() {
            let before = self.count;
            sys.evaluate(t, q, qd, values);
            let singular = match self.factor_between_steps(t, sys, values) {
                None => true,
                Some((_, vt)) => vt.condition > HANDOVER_CONDITION || vt.condition.is_nan(),
            };
            stats.repartitions += self.count - before;
            if let (true, Some(h)) = (singular, self.handover.as_mut()) {
                // With redundant equations (kept under `RedundancyTreatment::MinimumNorm`) the
                // saddle-point matrix is singular: partitioning, which projects on a maximal
                // independent set of equations, goes on from wherever the hand-over stopped.
                if let Ok(it) = h.project(t, model, values, q, qd, tolerance) {
                    stats.handovers += 1;
                    stats.newton_iterations += it as u64;
                    return Ok(it);
                }
            }
        }
        self.project_counted(t, sys, values, (q, qd), tolerance, stats)
    }

    /// [`PartitionTracker::project`], adding its Newton iterations and re-partitions to `stats`.
    pub fn project_counted(
        &mut self,
        t: f64,
        sys: &(impl ConstraintSet + ?Sized),
        values: &mut ConstraintValues,
        (q, qd): (&mut [f64], &mut [f64]),
        tolerance: f64,
        stats: &mut crate::FormulationStats,
    ) -> Result<usize, crate::DynamicsError> {
        let before = self.count;
        let it = self.project(t, sys, values, q, qd, tolerance)?;
        stats.repartitions += self.count - before;
        stats.newton_iterations += it as u64;
        Ok(it)
    }

    /// Coordinate partitioning: with the independent coordinates held, Newton–Raphson on the
    /// dependent ones (`C_qd Δq_d = −C` over the independent equations) until `‖C‖∞ ≤ tolerance`,
    /// then the dependent velocities from `C_qd q̇_d = −C_t − C_qi q̇_i`. `values` is scratch and ends
    /// holding the constraints at the projected state. Returns the Newton iterations. Allocates
    /// nothing after the first call unless it re-partitions.
    pub fn project(
        &mut self,
        t: f64,
        sys: &(impl ConstraintSet + ?Sized),
        values: &mut ConstraintValues,
        q: &mut [f64],
        qd: &mut [f64],
        tolerance: f64,
    ) -> Result<usize, crate::DynamicsError> {
        const MAX_ITERATIONS: usize = 25;
        let (n, m) = (sys.num_coordinates(), sys.num_equations());
        self.cdot.resize(m, 0.0);
        self.delta.resize(n, 0.0);
        let mut y = std::mem::take(&mut self.y);
        let mut delta = std::mem::take(&mut self.delta);
        let mut cdot = std::mem::take(&mut self.cdot);
        let result = (|| {
            let mut iterations = 0;
            loop {
                sys.evaluate(t, q, qd, values);
                let res = values.c.iter().fold(0.0f64, |a, v| a.max(v.abs()));
                if res <= tolerance {
                    break;
                }
                if iterations == MAX_ITERATIONS || !res.is_finite() {
                    return Err(crate::ConstraintError::not_converged(sys, &values.c, t, iterations, tolerance).into());
                }
                let Some((p, vt)) = self.factor_between_steps(t, sys, values) else {
                    return Err(sys.redundancy_error(t, values));
                };
                y.clear();
                y.extend(p.rows.iter().map(|&r| -values.c[r]));
                vt.solve_dependent(&mut y);
                delta.iter_mut().for_each(|d| *d = 0.0);
                for (k, &d) in p.dependent.iter().enumerate() {
                    delta[d] = y[k];
                }
                sys.correct_positions(q, &delta);
                iterations += 1;
            }
            let Some((p, vt)) = self.factor_between_steps(t, sys, values) else {
                return Err(sys.redundancy_error(t, values));
            };
            for &d in &p.dependent {
                qd[d] = 0.0;
            }
            sys.velocity_residual(values, qd, &mut cdot);
            y.clear();
            y.extend(p.rows.iter().map(|&r| -cdot[r]));
            vt.solve_dependent(&mut y);
            for (k, &d) in p.dependent.iter().enumerate() {
                qd[d] = y[k];
            }
            Ok(iterations)
        })();
        self.y = y;
        self.delta = delta;
        self.cdot = cdot;
        result
    }
}
