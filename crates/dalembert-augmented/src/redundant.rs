//! Redundant constraints under the minimum-norm treatment, at the cost of a regular evaluation.
//!
//! When `C_q` is rank deficient (an over-constrained mechanism such as Bricard's loop or a
//! parallelogram with a third crank), the saddle-point matrix is singular. The structure analysis
//! (`crate::diagnosis::independent_rows`, dense, run once where the redundancy is found) picks a
//! maximal independent set `R` of equations; [`Independent`] then keeps, for the following
//! evaluations, the saddle-point factorization of `[M C_Rᵀ; C_R 0]` (the same back ends, symbolic
//! analysis once) and solves
//!
//! ```text
//! [M  C_Rᵀ] [q̈ ]   [Q  ]
//! [C_R  0 ] [λ_R] = [γ_R]
//! ```
//!
//! then turns `λ_R` into the minimum-norm multipliers of the same constraint force
//! ([`dalembert_system::minimum_norm::MinimumNorm`], which also checks that the dropped rows still
//! depend on the kept ones). Nothing is allocated. The set is given up (and the structure analysed
//! again) when its factorization fails or a dropped row is no longer dependent.

use crate::AugmentedOptions;
use dalembert_system::linalg::saddle_point::{kkt_mul, kkt_scale};
use dalembert_system::linalg::{LinalgError, SaddlePoint};
use dalembert_system::minimum_norm::MinimumNorm;
use dalembert_system::{BlockDiagonal, ConstraintPattern, ConstraintValues, MultibodySystem};

/// Solves `K x = b` with the factors in `solver`, checking the residual where the back end asks for
/// it (one step of iterative refinement when the residual is above round-off). `matrix` is
/// `(M, pattern, values)` of the factored `K`; `(x, r)` the solution and a work vector. Returns
/// `false` when the solution is not accepted (non-finite, or residual above `residual_tolerance`
/// relative after the refinement).
pub(crate) fn checked_solve(
    solver: &mut SaddlePoint,
    (mass, pattern, values): (&BlockDiagonal, &ConstraintPattern, &ConstraintValues),
    b: &[f64],
    (x, r): (&mut [f64], &mut [f64]),
    residual_tolerance: f64,
) -> bool {
    x.copy_from_slice(b);
    solver.solve(pattern, x);
    // Every back end checks its pivots (or a condition probe) when factoring, so a
    // well-conditioned solve is accepted as is; an ill-conditioned Schur complement gets the
    // residual check and one refinement step below.
    if !solver.refines() && x.iter().all(|v| v.is_finite()) {
        return true;
    }
    let scale = kkt_scale(mass, values);
    let bn = b.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    // Check the residual; one step of iterative refinement when it is above round-off (the
    // Schur complement squares the condition number of C_q M^-1/2).
    for refinement in 0..2 {
        kkt_mul(mass, pattern, values, x, r);
        let xn = x.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let mut res = 0.0f64;
        for (r, b) in r.iter_mut().zip(b) {
            *r = b - *r;
            res = res.max(r.abs());
        }
        let size = (bn + scale * xn).max(f64::MIN_POSITIVE);
        if !(res.is_finite() && xn.is_finite()) {
            return false;
        }
        let round_off = res <= 1e-13 * size && !(refinement == 0 && solver.refines());
        if round_off || (refinement == 1 && res <= residual_tolerance * size) {
            return true;
        }
        if refinement == 1 {
            break;
        }
        solver.solve(pattern, r);
        for (x, d) in x.iter_mut().zip(r.iter()) {
            *x += d;
        }
    }
    false
}

/// The saddle-point factorization on a maximal independent set of equations, and the minimum-norm
/// multipliers (see the module documentation). The pattern and values of `C_R` are the
/// [`MinimumNorm`]'s.
pub(crate) struct Independent {
    solver: SaddlePoint,
    /// Right-hand side, solution and residual of the reduced system (`n + |R|`).
    b: Vec<f64>,
    x: Vec<f64>,
    r: Vec<f64>,
    minimum_norm: MinimumNorm,
}

impl Independent {
    /// Sets up the factorization of `model`'s saddle-point matrix on the equations `rows` (with the
    /// back end options of the formulation).
    pub fn new(
        model: &dyn MultibodySystem,
        mass: &BlockDiagonal,
        rows: Vec<usize>,
        options: &AugmentedOptions,
    ) -> Result<Self, LinalgError> {
        let full = model.constraints().pattern();
        let minimum_norm = MinimumNorm::new(full, &rows).map_err(|e| LinalgError::Singular(e.0))?;
        let solver = SaddlePoint::on_pattern(
            options.backend,
            mass,
            model.mass_is_constant(),
            minimum_norm.pattern(),
            options.dense_limit,
            options.pivot_tolerance,
        )?;
        let k = full.cols() + rows.len();
        Ok(Independent {
            solver,
            b: vec![0.0; k],
            x: vec![0.0; k],
            r: vec![0.0; k],
            minimum_norm,
        })
    }

    /// Solves `K x = b` of the whole system (`b`, `x` of length `n + m`) on the independent
    /// equations: `x` gets the accelerations and the minimum-norm multipliers. `false` when the
    /// factorization fails, the solve is not accepted, or a dropped equation is no longer dependent.
    pub fn solve(
        &mut self,
        mass: &BlockDiagonal,
        full: &ConstraintValues,
        b: &[f64],
        x: &mut [f64],
        residual_tolerance: f64,
    ) -> bool {
        let n = mass.dim();
        let m = full.c.len();
        let mn = &mut self.minimum_norm;
        mn.load(full);
        if self.solver.factor(mass, mn.pattern(), mn.values()).is_err() {
            return false;
        }
        self.b[..n].copy_from_slice(&b[..n]);
        for (j, &row) in mn.rows().iter().enumerate() {
            self.b[n + j] = b[n + row];
        }
        let matrix = (mass, mn.pattern(), mn.values());
        if !checked_solve(
            &mut self.solver,
            matrix,
            &self.b,
            (&mut self.x, &mut self.r),
            residual_tolerance,
        ) {
            return false;
        }
        x[..n].copy_from_slice(&self.x[..n]);
        let lambda = &mut x[n..n + m];
        for (j, &row) in mn.rows().iter().enumerate() {
            lambda[row] = self.x[n + j];
        }
        mn.apply_loaded(full, lambda).is_ok()
    }
}
