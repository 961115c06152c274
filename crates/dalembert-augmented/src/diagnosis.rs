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

/// Solves with a maximal independent set of constraint rows, then returns in `x` the accelerations
/// and the minimum-norm multipliers `λ = (C_qᵀ)⁺ (C_q,Rᵀ λ_R)`. Dense; allocates (a fallback path,
/// taken only when the caller opted into it and the matrix is singular).
pub(crate) fn minimum_norm_solve(
    t: f64,
    model: &dyn MultibodySystem,
    mass: &BlockDiagonal,
    vals: &ConstraintValues,
    b: &[f64],
    x: &mut [f64],
    n: usize,
) -> Result<(), DynamicsError> {
    let sys = model.constraints();
    let s = sys.analyse_structure(vals, MINIMUM_NORM_RANK_TOLERANCE)?;
    let rows = &s.independent_rows;
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
    let mut f = Mat::<f64>::zeros(n, 1);
    for (ii, &row) in rows.iter().enumerate() {
        for c in 0..n {
            f[(c, 0)] += jac[(row, c)] * sol[(n + ii, 0)];
        }
    }
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
    let f: Vec<f64> = (0..n).map(|c| f[(c, 0)]).collect();
    let lambda = sys
        .minimum_norm_multipliers(vals, &f)
        .ok_or(DynamicsError::Factorization {
            time: t,
            what: "minimum-norm multipliers: the constraint force is not in the range of C_qᵀ".into(),
        })?;
    for i in 0..n {
        x[i] = sol[(i, 0)];
    }
    x[n..n + m].copy_from_slice(&lambda);
    Ok(())
}
