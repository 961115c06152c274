//! What went wrong when the saddle-point matrix is singular, and the minimum-norm treatment of
//! redundant constraints.

use dalembert_system::structure::MINIMUM_NORM_RANK_TOLERANCE;
use dalembert_system::{BlockDiagonal, ConstraintValues, DynamicsError, MultibodySystem};
use faer::linalg::solvers::Solve;
use faer::Mat;

/// Rank threshold of `C_q` used in diagnosis (relative to the largest pivot).
const RANK_TOLERANCE: f64 = 1e-9;

/// Explains a singular KKT matrix: redundant constraints (rank-deficient `C_q`, naming the equations
/// in the dependent set), a mass matrix singular on the admissible motions (naming massless bodies),
/// or else a generic singular system.
pub(crate) fn diagnose(
    t: f64,
    model: &dyn MultibodySystem,
    vals: &ConstraintValues,
    pivot_tolerance: f64,
) -> DynamicsError {
    let sys = model.constraints();
    match sys.analyse_structure(vals, RANK_TOLERANCE) {
        Ok(s) if s.is_full_rank() => {}
        Ok(_) => return sys.redundancy_error(t, vals),
        Err(e) => return e.into(),
    }
    model.singular_mass_error(
        t,
        &format!("saddle-point matrix singular (pivot tolerance {pivot_tolerance:e})"),
    )
}

/// A maximal independent set of constraint rows for the minimum-norm treatment of a singular
/// saddle-point matrix (the structure analysis at rank tolerance
/// [`MINIMUM_NORM_RANK_TOLERANCE`]), checked where it is found: the saddle-point matrix on those
/// rows must be regular, and the dropped rows consistent, `C_q,d q̈ = b_d`, to the rank tolerance
/// (otherwise the equations are contradictory, not redundant, and the error names them). Dense;
/// allocates (run once where a redundancy is found; [`crate::redundant::Independent`] then keeps
/// the rows).
pub(crate) fn independent_rows(
    t: f64,
    model: &dyn MultibodySystem,
    mass: &BlockDiagonal,
    vals: &ConstraintValues,
    b: &[f64],
    n: usize,
) -> Result<Vec<usize>, DynamicsError> {
    let sys = model.constraints();
    let s = sys.analyse_structure(vals, MINIMUM_NORM_RANK_TOLERANCE)?;
    let rows = s.independent_rows;
    let r = rows.len();
    let jac = sys.jacobian_dense(vals);
    let mut k = Mat::<f64>::zeros(n + r, n + r);
    for (r, c, v) in mass.entries() {
        k[(r, c)] = v;
    }
    for (ii, &row) in rows.iter().enumerate() {
        for c in 0..n {
            k[(n + ii, c)] = jac[(row, c)];
            k[(c, n + ii)] = jac[(row, c)];
        }
    }
    let mut rhs = Mat::<f64>::zeros(n + r, 1);
    for i in 0..n {
        rhs[(i, 0)] = b[i];
    }
    for (ii, &row) in rows.iter().enumerate() {
        rhs[(n + ii, 0)] = b[n + row];
    }
    let sol = k.partial_piv_lu().solve(&rhs);
    // Residual check of the reduced system.
    let res = &k * &sol - &rhs;
    let scale = rhs.norm_max() + k.norm_max() * sol.norm_max();
    let ok = res.norm_max() <= 1e-9 * scale.max(f64::MIN_POSITIVE);
    if !ok {
        return Err(model.singular_mass_error(t, "reduced saddle-point matrix singular"));
    }
    // Dropped rows must be consistent: C_q,dropped q̈ = rhs_dropped.
    let m = sys.num_equations();
    for row in 0..m {
        let lhs: f64 = (0..n).map(|c| jac[(row, c)] * sol[(c, 0)]).sum();
        // Consistent to the rank tolerance: a row counted as dependent at singular values below
        // MINIMUM_NORM_RANK_TOLERANCE × σ_max may miss its right-hand side by as much, relative.
        if (lhs - b[n + row]).abs() > MINIMUM_NORM_RANK_TOLERANCE * (1.0 + b[n + row].abs() + scale) {
            return Err(DynamicsError::RedundantConstraints {
                time: t,
                rank: r,
                equations: m,
                involved: sys.dependent_equations(vals, RANK_TOLERANCE),
            });
        }
    }
    Ok(rows)
}
