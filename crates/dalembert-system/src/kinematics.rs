//! Kinematic analysis: position (Newton–Raphson), velocity and acceleration analysis
//! (`docs/equations.md` §2, §7).
//!
//! All three solve `C_q Δ = r` for the **minimum-norm** correction Δ over a maximal independent set
//! of rows (QR of `C_q,Rᵀ`, so no normal equations are formed):
//!
//! * positions: `q ← q + Δ`, `C_q Δ = −C(q, t)`, repeated until `‖C‖∞ ≤ tolerance` — this assembles
//!   a mechanism from an approximate configuration, moving it as little as possible;
//! * velocities: `q̇ ← q̇ + Δ`, `C_q Δ = −C_t − C_q q̇` — exact for a fully driven system, the
//!   least change that makes given velocities consistent otherwise;
//! * accelerations: `q̈ ← q̈ + Δ`, `C_q Δ = Q_d − C_q q̈`.
//!
//! Redundant rows are left out of the solve and then checked: if the dropped equations are not
//! satisfied (rank loss with inconsistent equations: a toggle, a dead centre, a locked mechanism) the
//! analysis returns [`ConstraintError::Singular`] naming the equations involved.
//!
//! Models with [`SPARSE_FROM`] coordinates or more take the sparse path first: `Δ = W C_qᵀ y` with
//! `(C_q W C_qᵀ) y = rhs` by sparse Cholesky ([`SparseGram`], `W` the squared column scales), plus
//! one step of iterative refinement; cost and memory linear in the model's size for chains and
//! trees. A rank-deficient `C_q` falls back to the dense path when it fits in memory, and is
//! otherwise reported as [`ConstraintError::TooLarge`].

use crate::gram::SparseGram;
use crate::structure::{column_rank, dense_fits, SPARSE_FROM};

/// Why a minimum-norm step failed.
enum StepError {
    /// The dropped (redundant) rows are not satisfied; the numerical rank.
    Inconsistent(usize),
    /// The dense fallback would not fit in memory.
    TooLarge(ConstraintError),
}
use crate::{ConstraintError, ConstraintSet, ConstraintValues};
use faer::Mat;

/// Settings of the kinematic analyses.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KinematicOptions {
    /// Convergence of position analysis: `‖C‖∞` at most this (units of the constraints: m or rad).
    pub tolerance: f64,
    /// Newton iterations allowed.
    pub max_iterations: usize,
    /// Relative pivot threshold for the rank of `C_q` (see [`crate::structure`]).
    pub rank_tolerance: f64,
    /// Relative residual above which dropped (redundant) equations are inconsistent.
    pub consistency_tolerance: f64,
}

impl Default for KinematicOptions {
    fn default() -> Self {
        KinematicOptions {
            tolerance: 1e-12,
            max_iterations: 50,
            rank_tolerance: 1e-9,
            consistency_tolerance: 1e-8,
        }
    }
}

/// What a position analysis did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KinematicReport {
    /// Newton iterations taken.
    pub iterations: usize,
    /// Final `‖C‖∞`.
    pub residual: f64,
}

fn inf_norm(x: &[f64]) -> f64 {
    x.iter().fold(0.0, |a, v| a.max(v.abs()))
}

/// Minimum-norm `Δ` with `C_q Δ = rhs` on an independent row set; `Ok(residual on all rows)`.
/// With `scale`, the step minimises `Σ (Δ_i / s_i)²` instead (columns scaled by `s`).
fn min_norm_step<S: ConstraintSet + ?Sized>(
    sys: &S,
    values: &ConstraintValues,
    rhs: &[f64],
    delta: &mut [f64],
    opts: &KinematicOptions,
    scale: Option<&[f64]>,
    gram: &mut Option<SparseGram>,
) -> Result<f64, StepError> {
    if sys.num_coordinates() >= SPARSE_FROM {
        if gram.is_none() {
            *gram = SparseGram::new(sys).ok();
        }
        if let Some(g) = gram.as_mut() {
            if let Some(worst) = min_norm_step_sparse(sys, g, values, rhs, delta, scale) {
                return Ok(worst);
            }
        }
    }
    if !dense_fits(sys.num_equations(), sys.num_coordinates()) {
        return Err(StepError::TooLarge(ConstraintError::TooLarge {
            what: "kinematic analysis".into(),
            hint: crate::structure::RANK_DEFICIENT_HINT,
            rows: sys.num_equations(),
            cols: sys.num_coordinates(),
        }));
    }
    let mut a = sys.jacobian_dense(values);
    if let Some(s) = scale {
        for j in 0..a.ncols() {
            for i in 0..a.nrows() {
                a[(i, j)] *= s[j];
            }
        }
    }
    let (m, n) = (a.nrows(), a.ncols());
    delta.iter_mut().for_each(|d| *d = 0.0);
    if m == 0 {
        return Ok(0.0);
    }
    let at = a.transpose().to_owned();
    let (rank, order) = column_rank(at.as_ref(), opts.rank_tolerance);
    let rows = &order[..rank];
    // A_Rᵀ = Q R  (n × r);  A_R Δ = b_R  ⇒  Rᵀ z = b_R,  Δ = Q z.
    let art = Mat::from_fn(n, rank, |i, j| at[(i, rows[j])]);
    let qr = art.qr();
    let r = qr.thin_R();
    let q = qr.compute_thin_Q();
    let mut z = vec![0.0; rank];
    for i in 0..rank {
        let mut s = rhs[rows[i]];
        for k in 0..i {
            s -= r[(k, i)] * z[k];
        }
        z[i] = s / r[(i, i)];
    }
    for i in 0..n {
        delta[i] = (0..rank).map(|k| q[(i, k)] * z[k]).sum::<f64>() * scale.map_or(1.0, |s| s[i]);
    }
    // Residual over every row, including the dropped ones.
    let mut res = vec![0.0; m];
    sys.jacobian_mul(values, delta, &mut res);
    let scale = inf_norm(rhs).max(1e-300);
    let worst = res.iter().zip(rhs).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    if rank < m && worst > opts.consistency_tolerance * scale.max(1.0) {
        return Err(StepError::Inconsistent(rank));
    }
    Ok(worst)
}

/// The sparse minimum-norm step; `None` when `C_q W C_qᵀ` is singular to working precision
/// (then the dense path decides, naming the equations involved).
fn min_norm_step_sparse<S: ConstraintSet + ?Sized>(
    sys: &S,
    gram: &mut SparseGram,
    values: &ConstraintValues,
    rhs: &[f64],
    delta: &mut [f64],
    scale: Option<&[f64]>,
) -> Option<f64> {
    let m = sys.num_equations();
    let mut first_col = vec![0; sys.pattern().bodies()];
    for s in sys.pattern().segments() {
        first_col[s.body] = s.col;
    }
    let w = |b: usize, r: usize, c: usize| {
        if r != c {
            0.0
        } else {
            scale.map_or(1.0, |s| s[first_col[b] + r] * s[first_col[b] + r])
        }
    };
    // Up to 1e12 the refined step is accurate; a duplicated equation gives 1e15 or more (see
    // `analyse_structure`), and the dense path then names the dependent equations.
    gram.factor(&values.jacobian, w, 1e12).ok()?;
    let mut y = vec![0.0; m];
    let mut r = rhs.to_vec();
    let mut step = vec![0.0; delta.len()];
    delta.iter_mut().for_each(|d| *d = 0.0);
    // Δ += W Cᵀ G⁻¹ r, twice: the second pass refines with the residual r = rhs − C Δ.
    for _ in 0..2 {
        y.copy_from_slice(&r);
        gram.solve_in_place(&mut y);
        step.iter_mut().for_each(|v| *v = 0.0);
        sys.jacobian_transpose_mul_add(values, 1.0, &y, &mut step);
        for (i, (d, v)) in delta.iter_mut().zip(&step).enumerate() {
            *d += v * scale.map_or(1.0, |s| s[i] * s[i]);
        }
        sys.jacobian_mul(values, delta, &mut r);
        r.iter_mut().zip(rhs).for_each(|(ri, b)| *ri = b - *ri);
    }
    Some(inf_norm(&r))
}

fn step_error<S: ConstraintSet + ?Sized>(
    sys: &S,
    t: f64,
    values: &ConstraintValues,
    e: StepError,
    opts: &KinematicOptions,
) -> ConstraintError {
    match e {
        StepError::Inconsistent(rank) => singular(sys, t, values, rank, opts),
        StepError::TooLarge(e) => e,
    }
}

fn singular<S: ConstraintSet + ?Sized>(
    sys: &S,
    t: f64,
    values: &ConstraintValues,
    rank: usize,
    opts: &KinematicOptions,
) -> ConstraintError {
    ConstraintError::Singular {
        time: t,
        rank,
        equations_count: sys.num_equations(),
        involved: sys.dependent_equations(values, opts.rank_tolerance),
    }
}

/// Position analysis: Newton–Raphson on `C(q, t) = 0` from the approximate `q`, with
/// minimum-norm steps. Errors name the equations still violated.
pub fn solve_positions<S: ConstraintSet + ?Sized>(
    sys: &S,
    t: f64,
    q: &mut [f64],
    opts: &KinematicOptions,
) -> Result<KinematicReport, ConstraintError> {
    if let Some(i) = q.iter().position(|v| !v.is_finite()) {
        return Err(ConstraintError::NonFinite {
            time: t,
            what: sys.describe_position(i),
        });
    }
    let mut values = sys.values();
    let mut delta = vec![0.0; sys.num_coordinates()];
    let mut rhs = vec![0.0; sys.num_equations()];
    let mut gram = None;
    for it in 0..=opts.max_iterations {
        sys.evaluate(t, q, &[], &mut values);
        let res = inf_norm(&values.c);
        if !res.is_finite() {
            return Err(ConstraintError::NonFinite {
                time: t,
                what: "constraint residual".into(),
            });
        }
        if res <= opts.tolerance {
            return Ok(KinematicReport {
                iterations: it,
                residual: res,
            });
        }
        if it == opts.max_iterations {
            break;
        }
        rhs.iter_mut().zip(&values.c).for_each(|(r, c)| *r = -c);
        // Newton keeps going through redundant rows: consistency is judged by the final residual.
        let relaxed = KinematicOptions {
            consistency_tolerance: f64::INFINITY,
            ..*opts
        };
        if let Err(StepError::TooLarge(e)) = min_norm_step(sys, &values, &rhs, &mut delta, &relaxed, None, &mut gram) {
            return Err(e);
        }
        sys.correct_positions(q, &delta);
    }
    Err(ConstraintError::not_converged(
        sys,
        &values.c,
        t,
        opts.max_iterations,
        opts.tolerance,
    ))
}

/// Velocity analysis minimising the weighted change `Σ w_i Δq̇_i²`: coordinates with a large
/// weight (velocities the user gave) change least. A weight of `f64::INFINITY` holds the velocity
/// exactly when the constraints allow it; when they forbid the held values, those weigh
/// [`HELD_FALLBACK_WEIGHT`] against the others instead. `None` weighs all equally.
pub fn solve_velocities_weighted<S: ConstraintSet + ?Sized>(
    sys: &S,
    t: f64,
    q: &[f64],
    qd: &mut [f64],
    weights: Option<&[f64]>,
    opts: &KinematicOptions,
) -> Result<(), ConstraintError> {
    let scale = |held: f64| -> Option<Vec<f64>> {
        weights.map(|w| {
            w.iter()
                .map(|&w| {
                    1.0 / if w.is_infinite() {
                        held
                    } else {
                        w.max(f64::MIN_POSITIVE)
                    }
                    .sqrt()
                })
                .collect()
        })
    };
    let mut values = sys.values();
    sys.evaluate(t, q, qd, &mut values);
    let mut rhs = vec![0.0; sys.num_equations()];
    sys.velocity_residual(&values, qd, &mut rhs);
    rhs.iter_mut().for_each(|r| *r = -*r);
    let mut delta = vec![0.0; sys.num_coordinates()];
    let exact = min_norm_step(
        sys,
        &values,
        &rhs,
        &mut delta,
        opts,
        scale(f64::INFINITY).as_deref(),
        &mut None,
    );
    let holds = weights.is_some_and(|w| w.iter().any(|w| w.is_infinite()));
    if exact.is_err() && holds {
        min_norm_step(
            sys,
            &values,
            &rhs,
            &mut delta,
            opts,
            scale(HELD_FALLBACK_WEIGHT).as_deref(),
            &mut None,
        )
    } else {
        exact
    }
    .map_err(|e| step_error(sys, t, &values, e, opts))?;
    qd.iter_mut().zip(&delta).for_each(|(x, d)| *x += d);
    Ok(())
}

/// Weight of a held velocity (`f64::INFINITY` in [`solve_velocities_weighted`]) that the
/// constraints do not allow to hold exactly, against 1 for the others.
pub const HELD_FALLBACK_WEIGHT: f64 = 1e6;

/// Acceleration analysis: the least change to `q̈` that satisfies `C_q q̈ = Q_d(q, q̇, t)`.
pub fn solve_accelerations<S: ConstraintSet + ?Sized>(
    sys: &S,
    t: f64,
    q: &[f64],
    qd: &[f64],
    qdd: &mut [f64],
    opts: &KinematicOptions,
) -> Result<(), ConstraintError> {
    let mut values = sys.values();
    sys.evaluate(t, q, qd, &mut values);
    let mut rhs = vec![0.0; sys.num_equations()];
    sys.jacobian_mul(&values, qdd, &mut rhs);
    rhs.iter_mut().zip(&values.gamma).for_each(|(r, g)| *r = g - *r);
    let mut delta = vec![0.0; sys.num_coordinates()];
    min_norm_step(sys, &values, &rhs, &mut delta, opts, None, &mut None)
        .map_err(|e| step_error(sys, t, &values, e, opts))?;
    qdd.iter_mut().zip(&delta).for_each(|(x, d)| *x += d);
    Ok(())
}
