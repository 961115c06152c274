//! The singular value decomposition of a dense `C_q` in storage sized once: the analyses that
//! name the equations of a (nearly) singular `C_q` ([`crate::structure::near_singular`],
//! [`crate::structure::dependent_equations`]) run on it, and a run that checks its positions while
//! stepping keeps one ([`SingularityCheck`]), so that a check allocates nothing unless it finds a
//! singular position to report.

use crate::{ConstraintSet, ConstraintValues, EquationRef};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::svd::{svd, svd_scratch, ComputeSvdVectors};
use faer::{Mat, MatRef, Par};

/// Largest number of equations whose `C_q` is decomposed densely by the checks: above it a check
/// answers "not checked" (`None`).
pub const SVD_EQUATIONS_UP_TO: usize = 600;

/// `C_q = U Σ Vᵀ` of an `m × n` Jacobian: the dense matrix, its singular values (descending) and
/// the `m × m` left singular vectors, with the decomposition's scratch.
pub struct JacobianSvd {
    a: Mat<f64>,
    s: Mat<f64>,
    u: Mat<f64>,
    buf: MemBuffer,
}

impl std::fmt::Debug for JacobianSvd {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("JacobianSvd")
            .field("rows", &self.a.nrows())
            .field("cols", &self.a.ncols())
            .finish()
    }
}

impl JacobianSvd {
    /// Storage for the decomposition of an `m × n` Jacobian.
    pub fn new(m: usize, n: usize) -> Self {
        let scratch = svd_scratch::<f64>(
            m,
            n,
            ComputeSvdVectors::Full,
            ComputeSvdVectors::No,
            Par::Seq,
            Default::default(),
        );
        JacobianSvd {
            a: Mat::zeros(m, n),
            s: Mat::zeros(m.min(n), 1),
            u: Mat::zeros(m, m),
            buf: MemBuffer::new(scratch),
        }
    }

    /// Decomposes `C_q` of `sys` at `values` (whose dimensions must be those given to
    /// [`JacobianSvd::new`]); `false` when the decomposition fails to converge. Allocates nothing.
    pub fn decompose<S: ConstraintSet + ?Sized>(&mut self, sys: &S, values: &ConstraintValues) -> bool {
        sys.jacobian_dense_into(values, self.a.as_mut());
        let n = self.s.nrows();
        let s = self.s.as_mut().col_mut(0).subrows_mut(0, n).as_diagonal_mut();
        svd(
            self.a.as_ref(),
            s,
            Some(self.u.as_mut()),
            None,
            Par::Seq,
            MemStack::new(&mut self.buf),
            Default::default(),
        )
        .is_ok()
    }

    /// The singular values of the last decomposition, descending.
    pub fn singular_values(&self) -> &[f64] {
        self.s.col_as_slice(0)
    }

    /// The left singular vectors of the last decomposition (column `k` belongs to singular value
    /// `k`; the columns beyond the singular values span the rest of the row space).
    pub fn left_vectors(&self) -> MatRef<'_, f64> {
        self.u.as_ref()
    }

    /// The equations with weight above `weight` in the left singular vectors `from..to` of the
    /// last decomposition, the range chosen by `select(singular values, largest)`; `None` when
    /// `select` declines. Allocates only the answer.
    pub fn rows_of_vectors<S: ConstraintSet + ?Sized>(
        &self,
        sys: &S,
        weight: f64,
        select: impl Fn(&[f64], f64) -> Option<(usize, usize)>,
    ) -> Option<Vec<EquationRef>> {
        let s = self.singular_values();
        let largest = s.iter().cloned().fold(0.0, f64::max);
        let (from, to) = select(s, largest)?;
        let u = self.left_vectors();
        Some(
            (0..sys.num_equations())
                .filter(|&r| (from..to).any(|j| u[(r, j)].abs() > weight))
                .map(|r| sys.equation(r))
                .collect(),
        )
    }
}

/// The answer of a near-singularity check at the relative singular values `near` (nearly
/// singular) and `rank` (the numerical rank, which redundant constraints lower for good):
/// `Some((well, rank))` when fewer singular values clear `near × σ_max` than clear
/// `rank × σ_max`.
pub fn nearly_singular_range(s: &[f64], largest: f64, near: f64, rank: f64) -> Option<(usize, usize)> {
    if !(largest > 0.0 && largest.is_finite()) {
        return None;
    }
    let numerical_rank = s.iter().filter(|&&v| v > rank * largest).count();
    let well = s.iter().filter(|&&v| v > near * largest).count();
    (well < numerical_rank).then_some((well, numerical_rank))
}

/// A run's near-singularity check of `C_q` while stepping, with its evaluation and decomposition
/// storage sized at setup: a check of a well-conditioned position allocates nothing.
#[derive(Debug)]
pub struct SingularityCheck {
    values: ConstraintValues,
    /// `None` above [`SVD_EQUATIONS_UP_TO`] equations or without equations (never checked).
    svd: Option<JacobianSvd>,
}

impl SingularityCheck {
    /// The check of the constraints `sys`.
    pub fn new<S: ConstraintSet + ?Sized>(sys: &S) -> Self {
        let (m, n) = (sys.num_equations(), sys.num_coordinates());
        SingularityCheck {
            values: sys.values(),
            svd: (m > 0 && m <= SVD_EQUATIONS_UP_TO).then(|| JacobianSvd::new(m, n)),
        }
    }

    /// `C_q` at `(t, q, v)` decomposed, or `None` (not checked, or the decomposition failed).
    fn decomposed_at<S: ConstraintSet + ?Sized>(
        &mut self,
        sys: &S,
        t: f64,
        (q, v): (&[f64], &[f64]),
    ) -> Option<&JacobianSvd> {
        let svd = self.svd.as_mut()?;
        sys.evaluate(t, q, v, &mut self.values);
        svd.decompose(sys, &self.values).then_some(&*svd)
    }

    /// The equations of a nearly singular `C_q` at `(t, q, v)` (relative singular values below
    /// `near` and above `rank`, as [`crate::structure::near_singular`]), or `None` (a
    /// well-conditioned `C_q`, or not checked). Allocates only a `Some` answer.
    pub fn near_singular<S: ConstraintSet + ?Sized>(
        &mut self,
        sys: &S,
        t: f64,
        state: (&[f64], &[f64]),
        near: f64,
        rank: f64,
    ) -> Option<Vec<EquationRef>> {
        self.decomposed_at(sys, t, state)?
            .rows_of_vectors(sys, 1e-3, |s, largest| nearly_singular_range(s, largest, near, rank))
    }

    /// Whether [`SingularityCheck::near_singular`] finds a nearly singular `C_q` at `(t, q, v)`,
    /// without naming its equations: allocates nothing.
    pub fn is_near_singular<S: ConstraintSet + ?Sized>(
        &mut self,
        sys: &S,
        t: f64,
        state: (&[f64], &[f64]),
        near: f64,
        rank: f64,
    ) -> bool {
        self.decomposed_at(sys, t, state).is_some_and(|svd| {
            let s = svd.singular_values();
            let largest = s.iter().cloned().fold(0.0, f64::max);
            nearly_singular_range(s, largest, near, rank).is_some()
        })
    }
}
