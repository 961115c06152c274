//! Generalized coordinate partitioning and the velocity transformation (`FORMULATIONS.md` §4).
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
//! `C_qd⁻¹` is never formed: `C_qd` is factored (LU with partial pivoting) and solved against.
//! The conditioning of `C_qd` is estimated from the ratio of the factor's pivots; the embedding and
//! amalgamated formulations re-partition when it exceeds a threshold.

use crate::structure::column_rank;
use crate::{ConstraintSet, ConstraintValues};
use faer::linalg::solvers::{PartialPivLu, Solve};
use faer::Mat;

/// A choice of dependent and independent coordinates and of independent equations.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Partition {
    /// Dependent coordinates (one per independent equation), in pivot order.
    pub dependent: Vec<usize>,
    /// Independent coordinates, ascending.
    pub independent: Vec<usize>,
    /// A maximal independent set of equations (system rows), in pivot order.
    pub rows: Vec<usize>,
}

impl Partition {
    /// Chooses the partition by LU with full pivoting of `C_q` (rows) and of the selected rows'
    /// columns: the pivot columns become the dependent coordinates.
    pub fn choose(sys: &(impl ConstraintSet + ?Sized), values: &ConstraintValues, rank_tolerance: f64) -> Partition {
        let jac = sys.jacobian_dense(values);
        let n = jac.ncols();
        // Independent rows: pivot columns of C_qᵀ.
        let jt = jac.transpose().to_owned();
        let (rank, row_order) = column_rank(jt.as_ref(), rank_tolerance);
        let rows: Vec<usize> = row_order[..rank].to_vec();
        // Dependent coordinates: pivot columns of the selected rows.
        let sel = Mat::from_fn(rank, n, |i, j| jac[(rows[i], j)]);
        let (_, col_order) = column_rank(sel.as_ref(), rank_tolerance);
        let dependent: Vec<usize> = col_order[..rank].to_vec();
        let mut independent: Vec<usize> = col_order[rank..].to_vec();
        independent.sort_unstable();
        Partition {
            dependent,
            independent,
            rows,
        }
    }

    /// Number of independent coordinates (degrees of freedom).
    pub fn dof(&self) -> usize {
        self.independent.len()
    }
}

/// `B_i`, `γ_i` and the factorization of `C_qd` at one state.
#[derive(Debug)]
pub struct VelocityTransform {
    /// `B_i`, `n × (n − r)`.
    pub b: Mat<f64>,
    /// `γ_i`, length `n`.
    pub gamma: Vec<f64>,
    /// LU of `C_qd` (`r × r`, rows = `partition.rows`, columns = `partition.dependent`).
    pub lu: PartialPivLu<f64>,
    /// Ratio largest / smallest pivot of `C_qd`'s LU: a cheap condition estimate.
    pub condition: f64,
}

impl VelocityTransform {
    /// Computes `B_i` and `γ_i` for the acceleration right-hand side `rhs` (length `m`: `Q_d`, or
    /// its Baumgarte-modified form). Returns `None` if `C_qd` is singular.
    pub fn new(
        partition: &Partition,
        sys: &(impl ConstraintSet + ?Sized),
        values: &ConstraintValues,
        rhs: &[f64],
    ) -> Option<Self> {
        let jac = sys.jacobian_dense(values);
        let n = jac.ncols();
        let r = partition.rows.len();
        let cqd = Mat::from_fn(r, r, |i, j| jac[(partition.rows[i], partition.dependent[j])]);
        let lu = cqd.partial_piv_lu();
        let u = lu.U();
        let (mut big, mut small) = (0.0f64, f64::INFINITY);
        for k in 0..r {
            big = big.max(u[(k, k)].abs());
            small = small.min(u[(k, k)].abs());
        }
        let condition = if r == 0 { 1.0 } else { big / small };
        if !condition.is_finite() {
            return None;
        }
        let ni = partition.independent.len();
        let cqi = Mat::from_fn(r, ni, |i, j| jac[(partition.rows[i], partition.independent[j])]);
        let x = lu.solve(&cqi);
        let mut b = Mat::zeros(n, ni);
        for (k, &dep) in partition.dependent.iter().enumerate() {
            for j in 0..ni {
                b[(dep, j)] = -x[(k, j)];
            }
        }
        for (j, &ind) in partition.independent.iter().enumerate() {
            b[(ind, j)] = 1.0;
        }
        let g = Mat::from_fn(r, 1, |i, _| rhs[partition.rows[i]]);
        let gd = lu.solve(&g);
        let mut gamma = vec![0.0; n];
        for (k, &dep) in partition.dependent.iter().enumerate() {
            gamma[dep] = gd[(k, 0)];
        }
        Some(VelocityTransform {
            b,
            gamma,
            lu,
            condition,
        })
    }

    /// Solves `C_qd x = y` (length `r`) in place.
    pub fn solve_dependent(&self, y: &mut [f64]) {
        let mut m = Mat::from_fn(y.len(), 1, |i, _| y[i]);
        self.lu.solve_in_place(&mut m);
        for (i, v) in y.iter_mut().enumerate() {
            *v = m[(i, 0)];
        }
    }

    /// Solves `C_qdᵀ x = y` (length `r`) in place.
    pub fn solve_dependent_transpose(&self, y: &mut [f64]) {
        let mut m = Mat::from_fn(y.len(), 1, |i, _| y[i]);
        self.lu.solve_transpose_in_place(&mut m);
        for (i, v) in y.iter_mut().enumerate() {
            *v = m[(i, 0)];
        }
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

/// Keeps a partition across evaluations and re-chooses it when `C_qd` becomes ill-conditioned.
#[derive(Debug, Clone)]
pub struct PartitionTracker {
    current: Option<Partition>,
    /// Every re-partition so far (the first choice is not logged).
    pub log: Vec<Repartition>,
    /// Condition estimate of `C_qd` above which the partition is re-chosen.
    pub threshold: f64,
    /// Rank tolerance of the partition choice.
    pub rank_tolerance: f64,
    /// If given, the user's choice of independent coordinates (used while `C_qd` stays regular).
    preferred: Option<Vec<usize>>,
}

impl PartitionTracker {
    /// A tracker that re-partitions above condition estimate `threshold`.
    pub fn new(threshold: f64) -> Self {
        PartitionTracker {
            current: None,
            log: Vec::new(),
            threshold,
            rank_tolerance: 1e-9,
            preferred: None,
        }
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
        self
    }

    /// The partition in use, if any.
    pub fn current(&self) -> Option<&Partition> {
        self.current.as_ref()
    }

    /// `B_i`, `γ_i` for `rhs` at the current state, re-partitioning first if `C_qd` is singular or
    /// its condition estimate exceeds the threshold. `None` if even a fresh partition is singular.
    pub fn transform(
        &mut self,
        t: f64,
        sys: &(impl ConstraintSet + ?Sized),
        values: &ConstraintValues,
        rhs: &[f64],
    ) -> Option<(&Partition, VelocityTransform)> {
        if let Some(p) = &self.current {
            if let Some(vt) = VelocityTransform::new(p, sys, values, rhs) {
                if vt.condition <= self.threshold {
                    return self.current.as_ref().map(|p| (p, vt));
                }
            }
        }
        let fresh = Partition::choose(sys, values, self.rank_tolerance);
        if let Some(old) = &self.current {
            if old.independent != fresh.independent || old.rows.len() != fresh.rows.len() {
                self.log.push(Repartition {
                    time: t,
                    old: old.independent.clone(),
                    new: fresh.independent.clone(),
                });
            }
        }
        let vt = VelocityTransform::new(&fresh, sys, values, rhs)?;
        self.current = Some(fresh);
        self.current.as_ref().map(|p| (p, vt))
    }
}

impl PartitionTracker {
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
        let before = self.log.len();
        let it = self.project(t, sys, values, q, qd, tolerance)?;
        stats.repartitions += (self.log.len() - before) as u64;
        stats.newton_iterations += it as u64;
        Ok(it)
    }

    /// Coordinate partitioning: with the independent coordinates held, Newton–Raphson on the
    /// dependent ones (`C_qd Δq_d = −C` over the independent equations) until `‖C‖∞ ≤ tolerance`,
    /// then the dependent velocities from `C_qd q̇_d = −C_t − C_qi q̇_i`. `values` is scratch and ends
    /// holding the constraints at the projected state. Returns the Newton iterations.
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
        let zeros = vec![0.0; sys.num_equations()];
        let singular = |values: &ConstraintValues| sys.redundancy_error(t, values);
        let mut iterations = 0;
        loop {
            sys.evaluate(t, q, qd, values);
            let res = values.c.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            if res <= tolerance {
                break;
            }
            if iterations == MAX_ITERATIONS || !res.is_finite() {
                let violated = (0..values.c.len())
                    .filter(|&r| values.c[r].abs() > tolerance || values.c[r].is_nan())
                    .map(|r| (sys.equation(r), values.c[r]))
                    .collect();
                return Err(crate::ConstraintError::NotConverged {
                    time: t,
                    iterations,
                    violated,
                }
                .into());
            }
            let Some((p, vt)) = self.transform(t, sys, values, &zeros) else {
                return Err(singular(values));
            };
            let mut y: Vec<f64> = p.rows.iter().map(|&r| -values.c[r]).collect();
            vt.solve_dependent(&mut y);
            let mut delta = vec![0.0; sys.num_coordinates()];
            for (k, &d) in p.dependent.iter().enumerate() {
                delta[d] = y[k];
            }
            sys.correct_positions(q, &delta);
            iterations += 1;
        }
        let Some((p, vt)) = self.transform(t, sys, values, &zeros) else {
            return Err(singular(values));
        };
        let p = p.clone();
        for &d in &p.dependent {
            qd[d] = 0.0;
        }
        let mut cdot = vec![0.0; sys.num_equations()];
        sys.velocity_residual(values, qd, &mut cdot);
        let mut y: Vec<f64> = p.rows.iter().map(|&r| -cdot[r]).collect();
        vt.solve_dependent(&mut y);
        for (k, &d) in p.dependent.iter().enumerate() {
            qd[d] = y[k];
        }
        Ok(iterations)
    }
}
