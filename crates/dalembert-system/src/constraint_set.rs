//! Constraints as the formulations see them: a fixed sparsity pattern of `C_q` plus values
//! (`docs/equations.md` §2), and the analyses written once on that view.
//!
//! The Jacobian's columns are the **velocity** coordinates. Its entries come in *segments*: a row of
//! a constraint that touches a body has an entry for each of that body's velocity coordinates,
//! stored contiguously. A correction `Δ` in velocity coordinates is applied to the positions with
//! [`ConstraintSet::correct_positions`] (`q ← q + Δ` unless the system says otherwise).

use crate::{ConstraintError, EquationRef, Layout};

/// The sparsity pattern of `C_q`: `rows × cols`, entries listed segment by segment.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct ConstraintPattern {
    rows: usize,
    cols: usize,
    entries: Vec<(usize, usize)>,
    segments: Vec<Segment>,
}

/// A row's entries on one body: `len` consecutive columns from `col`, stored from entry `first`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Segment {
    /// Equation (row).
    pub row: usize,
    /// The body (its index in the layout).
    pub body: usize,
    /// First column (the body's velocity offset).
    pub col: usize,
    /// Number of columns (the body's velocity block length).
    pub len: usize,
    /// Index of the segment's first entry in the values.
    pub first: usize,
}

impl ConstraintPattern {
    /// A pattern with `rows` equations over the velocity coordinates of `layout`, from
    /// `(row, body)` segments in storage order.
    pub fn from_segments(rows: usize, layout: &Layout, segments: impl IntoIterator<Item = (usize, usize)>) -> Self {
        let mut p = ConstraintPattern {
            rows,
            cols: layout.n_v(),
            ..Default::default()
        };
        for (row, body) in segments {
            let b = &layout.bodies()[body];
            p.segments.push(Segment {
                row,
                body,
                col: b.v_offset,
                len: b.v_len(),
                first: p.entries.len(),
            });
            p.entries.extend((0..b.v_len()).map(|k| (row, b.v_offset + k)));
        }
        p
    }

    /// The pattern of the equations `rows` alone (row `k` of the result is system row `rows[k]`),
    /// with the index in this pattern's values of each of its entries.
    pub fn subset(&self, rows: &[usize]) -> (ConstraintPattern, Vec<usize>) {
        let mut slot = vec![usize::MAX; self.rows];
        for (k, &row) in rows.iter().enumerate() {
            slot[row] = k;
        }
        let mut p = ConstraintPattern {
            rows: rows.len(),
            cols: self.cols,
            ..Default::default()
        };
        let mut map = Vec::new();
        for s in self.segments.iter().filter(|s| slot[s.row] != usize::MAX) {
            p.segments.push(Segment {
                row: slot[s.row],
                first: p.entries.len(),
                ..*s
            });
            p.entries.extend((0..s.len).map(|k| (slot[s.row], s.col + k)));
            map.extend(s.first..s.first + s.len);
        }
        (p, map)
    }

    /// Number of equations `m`.
    #[inline]
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// Number of velocity coordinates `n_v`.
    #[inline]
    pub fn cols(&self) -> usize {
        self.cols
    }

    /// `(row, column)` of every stored entry.
    #[inline]
    pub fn entries(&self) -> &[(usize, usize)] {
        &self.entries
    }

    /// The segments, in storage order.
    #[inline]
    pub fn segments(&self) -> &[Segment] {
        &self.segments
    }

    /// Number of bodies the columns belong to (one more than the largest body index in a segment).
    pub fn bodies(&self) -> usize {
        self.segments.iter().map(|s| s.body + 1).max().unwrap_or(0)
    }
}

/// The constraint quantities at one `(t, q, v)`. Created once by [`ConstraintSet::values`], refilled
/// in place.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ConstraintValues {
    /// `C(q, t)`, length `m`.
    pub c: Vec<f64>,
    /// `C_t`, length `m`.
    pub c_t: Vec<f64>,
    /// `Q_d`, the right-hand side of `C_q v̇ = Q_d`, length `m`.
    pub gamma: Vec<f64>,
    /// Values of `C_q` in the order of [`ConstraintPattern::entries`].
    pub jacobian: Vec<f64>,
    /// Workspace of the implementation (e.g. one sine and cosine per planar body).
    pub scratch: Vec<f64>,
}

impl ConstraintValues {
    /// Zeroed storage for `pattern`, with `scratch` entries of workspace.
    pub fn new(pattern: &ConstraintPattern, scratch: usize) -> Self {
        let m = pattern.rows();
        ConstraintValues {
            c: vec![0.0; m],
            c_t: vec![0.0; m],
            gamma: vec![0.0; m],
            jacobian: vec![0.0; pattern.entries().len()],
            scratch: vec![0.0; scratch],
        }
    }
}

/// A system's constraints: pattern, equation names, and evaluation. Everything else (products with
/// `C_q`, structure, kinematic analyses) is provided, written once for planar and spatial systems.
pub trait ConstraintSet: Send + Sync + std::fmt::Debug {
    /// The sparsity pattern of `C_q` (fixed for the system's lifetime).
    fn pattern(&self) -> &ConstraintPattern;

    /// The equation at system row `row`.
    fn equation(&self, row: usize) -> EquationRef;

    /// Storage for the values, sized for this system.
    fn values(&self) -> ConstraintValues;

    /// Evaluates `C`, `C_q`, `C_t` and `Q_d` at `(t, q, v)` into `out` (`v` may be empty for zero
    /// velocity, in which case `Q_d` holds only the `C_tt` part). Must not allocate. The values must
    /// depend on `(t, q, v)` alone: the formulations reuse them at an unchanged state
    /// ([`crate::EvaluatedAt`]).
    fn evaluate(&self, t: f64, q: &[f64], v: &[f64], out: &mut ConstraintValues);

    /// `q ← q ⊕ Δ` for a correction `Δ` in velocity coordinates (default `q + Δ`).
    fn correct_positions(&self, q: &mut [f64], delta: &[f64]) {
        q.iter_mut().zip(delta).for_each(|(x, d)| *x += d);
    }

    /// A name for position coordinate `i` in messages.
    fn describe_position(&self, i: usize) -> String {
        format!("position coordinate {i}")
    }

    /// Number of constraint equations `m`.
    #[inline]
    fn num_equations(&self) -> usize {
        self.pattern().rows()
    }

    /// Number of velocity coordinates `n_v` (columns of `C_q`).
    #[inline]
    fn num_coordinates(&self) -> usize {
        self.pattern().cols()
    }

    /// `y ← C_q x`.
    fn jacobian_mul(&self, values: &ConstraintValues, x: &[f64], y: &mut [f64]) {
        y.iter_mut().for_each(|v| *v = 0.0);
        for (&(r, c), &v) in self.pattern().entries().iter().zip(&values.jacobian) {
            y[r] += v * x[c];
        }
    }

    /// `y ← y + α C_qᵀ λ`.
    fn jacobian_transpose_mul_add(&self, values: &ConstraintValues, alpha: f64, lambda: &[f64], y: &mut [f64]) {
        for (&(r, c), &v) in self.pattern().entries().iter().zip(&values.jacobian) {
            y[c] += alpha * v * lambda[r];
        }
    }

    /// `C_q` as a dense `m × n_v` matrix (analyses and fallbacks, never the stepping loop).
    fn jacobian_dense(&self, values: &ConstraintValues) -> faer::Mat<f64> {
        let mut a = faer::Mat::zeros(self.num_equations(), self.num_coordinates());
        self.jacobian_dense_into(values, a.as_mut());
        a
    }

    /// `C_q` written into the dense `m × n_v` storage `out` (a transposed view takes `C_qᵀ`).
    /// Allocates nothing.
    fn jacobian_dense_into(&self, values: &ConstraintValues, mut out: faer::MatMut<'_, f64>) {
        out.fill(0.0);
        for (&(r, c), &v) in self.pattern().entries().iter().zip(&values.jacobian) {
            out[(r, c)] += v;
        }
    }

    /// Velocity-level residual `Ċ = C_q v + C_t` into `out`.
    fn velocity_residual(&self, values: &ConstraintValues, v: &[f64], out: &mut [f64]) {
        self.jacobian_mul(values, v, out);
        for (o, ct) in out.iter_mut().zip(&values.c_t) {
            *o += ct;
        }
    }

    /// Evaluates at `(t, q, v)` into the scratch `values` and writes `C` and `Ċ`.
    fn residuals(&self, t: f64, q: &[f64], v: &[f64], values: &mut ConstraintValues, c: &mut [f64], cdot: &mut [f64]) {
        self.evaluate(t, q, v, values);
        c.copy_from_slice(&values.c);
        self.velocity_residual(values, v, cdot);
    }

    /// `Ok` when every value is finite; otherwise the error names the first equation whose `C`,
    /// `C_t`, `Q_d` or Jacobian row overflows (e.g. `Q_d` with velocities near 1e200).
    fn check_values(&self, t: f64, values: &ConstraintValues) -> Result<(), crate::DynamicsError> {
        if [&values.c, &values.c_t, &values.gamma, &values.jacobian]
            .iter()
            .all(|x| crate::all_finite(x))
        {
            return Ok(());
        }
        let bad_row = (0..self.num_equations())
            .find(|&r| {
                ![values.c[r], values.c_t[r], values.gamma[r]]
                    .iter()
                    .all(|x| x.is_finite())
            })
            .or_else(|| {
                self.pattern()
                    .entries()
                    .iter()
                    .zip(&values.jacobian)
                    .find(|(_, v)| !v.is_finite())
                    .map(|(&(r, _), _)| r)
            });
        match bad_row {
            None => Ok(()),
            Some(r) => {
                let e = self.equation(r);
                Err(crate::DynamicsError::NonFinite {
                    time: t,
                    what: format!(
                        "or overflowing constraint values of '{}' ({}): positions or velocities too large",
                        e.name, e.label
                    ),
                })
            }
        }
    }

    /// Rank, degrees of freedom and redundant equations of `C_q` held in `values`
    /// ([`crate::structure`]).
    fn analyse_structure(
        &self,
        values: &ConstraintValues,
        rank_tolerance: f64,
    ) -> Result<crate::StructureReport, ConstraintError> {
        crate::structure::analyse_structure(self, values, rank_tolerance)
    }

    /// Equations involved in a rank loss ([`crate::structure`]).
    fn dependent_equations(&self, values: &ConstraintValues, rank_tolerance: f64) -> Vec<EquationRef> {
        crate::structure::dependent_equations(self, values, rank_tolerance)
    }

    /// The error for a rank-deficient `C_q` at `values`: rank, and the equations in the dependent set.
    fn redundancy_error(&self, t: f64, values: &ConstraintValues) -> crate::DynamicsError {
        crate::structure::redundancy_error(self, t, values)
    }

    /// Writes multipliers `lam_rows` solved on the independent `rows` into `lambda` (zero
    /// elsewhere); when some rows were left out (redundant constraints), replaces them by the
    /// minimum-norm multipliers of the same generalized constraint force `C_qᵀ λ`.
    fn scatter_multipliers(
        &self,
        t: f64,
        values: &ConstraintValues,
        rows: &[usize],
        lam_rows: &[f64],
        lambda: &mut [f64],
    ) -> Result<(), crate::DynamicsError> {
        crate::structure::scatter_multipliers(self, t, values, rows, lam_rows, lambda)
    }

    /// The minimum-norm multipliers `λ = (C_qᵀ)⁺ f` for a generalized constraint force `f` in the
    /// range of `C_qᵀ` ([`crate::structure::minimum_norm_multipliers`]).
    fn minimum_norm_multipliers(&self, values: &ConstraintValues, f: &[f64]) -> Option<Vec<f64>> {
        crate::structure::minimum_norm_multipliers(self, values, f)
    }

    /// Position analysis ([`crate::kinematics`]).
    fn solve_positions(
        &self,
        t: f64,
        q: &mut [f64],
        opts: &crate::KinematicOptions,
    ) -> Result<crate::KinematicReport, ConstraintError> {
        crate::kinematics::solve_positions(self, t, q, opts)
    }

    /// Velocity analysis: the least change to `v` that satisfies `C_q v = −C_t` at `(q, t)`.
    fn solve_velocities(
        &self,
        t: f64,
        q: &[f64],
        v: &mut [f64],
        opts: &crate::KinematicOptions,
    ) -> Result<(), ConstraintError> {
        crate::kinematics::solve_velocities_weighted(self, t, q, v, None, opts)
    }

    /// Velocity analysis minimising the weighted change `Σ w_i Δv_i²` ([`crate::kinematics`]).
    fn solve_velocities_weighted(
        &self,
        t: f64,
        q: &[f64],
        v: &mut [f64],
        weights: Option<&[f64]>,
        opts: &crate::KinematicOptions,
    ) -> Result<(), ConstraintError> {
        crate::kinematics::solve_velocities_weighted(self, t, q, v, weights, opts)
    }

    /// Acceleration analysis: the least change to `v̇` that satisfies `C_q v̇ = Q_d(q, v, t)`.
    fn solve_accelerations(
        &self,
        t: f64,
        q: &[f64],
        v: &[f64],
        vdot: &mut [f64],
        opts: &crate::KinematicOptions,
    ) -> Result<(), ConstraintError> {
        crate::kinematics::solve_accelerations(self, t, q, v, vdot, opts)
    }
}
