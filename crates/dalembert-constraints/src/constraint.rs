//! The constraint trait and the per-constraint evaluation record.

use dalembert_kinematics::{BodyRef, BodyState, Vec2};

/// The largest number of equations one constraint may contribute (a rigid joint has three).
pub const MAX_EQUATIONS: usize = 3;

/// What one constraint reports at `(q, q̇, t)`. Rows past [`Constraint::num_equations`] are unused.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ConstraintEval {
    /// Residual `C`.
    pub c: [f64; MAX_EQUATIONS],
    /// Partial time derivative `C_t`.
    pub c_t: [f64; MAX_EQUATIONS],
    /// `Q_d`: right-hand side of `C_q q̈ = Q_d`.
    pub gamma: [f64; MAX_EQUATIONS],
    /// Jacobian blocks: `jac[k][side][c]` is `∂C_k / ∂(coordinate c of body side)`, side 0 the first
    /// body and 1 the second, `c` in `x, y, θ`. Blocks of the ground are ignored.
    pub jac: [[[f64; 3]; 2]; MAX_EQUATIONS],
}

impl ConstraintEval {
    /// Writes one scalar equation into row `k`.
    #[inline]
    pub fn set_row(&mut self, k: usize, row: &crate::primitives::Row) {
        self.c[k] = row.c;
        self.c_t[k] = row.c_t;
        self.gamma[k] = row.gamma;
        self.jac[k] = [row.first, row.second];
    }
}

/// Whether a constraint is a passive joint or a driver (rheonomic constraint), and what its
/// reaction carries.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ConstraintRole {
    /// A joint; `carries_torque` is true when it transmits a moment (prismatic, rigid, gear, …).
    Joint {
        /// True when the reaction includes a torque about the reaction point.
        carries_torque: bool,
    },
    /// A driver: one equation `s(q) − f(t) = 0`; its effort is `−λ`.
    Driver,
}

/// A kinematic constraint on at most two bodies.
///
/// Implementations must not allocate in [`Constraint::evaluate`]: it runs in the stepping loop.
pub trait Constraint: Send + Sync + std::fmt::Debug {
    /// The name that errors and output use.
    fn name(&self) -> &str;

    /// The two bodies, `[first, second]`; either may be the ground, not both the same body.
    fn bodies(&self) -> [BodyRef; 2];

    /// Number of scalar equations (1 to [`MAX_EQUATIONS`]).
    fn num_equations(&self) -> usize;

    /// Joint or driver.
    fn role(&self) -> ConstraintRole;

    /// A short label for equation `k`, used when naming violated or redundant equations.
    fn equation_label(&self, k: usize) -> &'static str;

    /// Evaluates `C`, the Jacobian blocks, `C_t` and `Q_d` at time `t` for the two body states.
    fn evaluate(&self, t: f64, first: &BodyState, second: &BodyState, out: &mut ConstraintEval);

    /// The global point about which the reaction torque is reported.
    fn reaction_point(&self, first: &BodyState, second: &BodyState) -> Vec2;

    /// `Σ_k λ_k ∂²C_k/∂p²` over the two bodies' coordinates `p = [x_i, y_i, θ_i, x_j, y_j, θ_j]`
    /// (row-major; the ground's rows and columns are ignored), for the multipliers `lambda` of this
    /// constraint's equations: its part of `∂(C_qᵀ λ)/∂q`, which implicit integrators need.
    /// `None` (the default, as for a user-written constraint) when not provided: they then
    /// difference the residual.
    fn weighted_hessian(
        &self,
        _t: f64,
        _first: &BodyState,
        _second: &BodyState,
        _lambda: &[f64],
    ) -> Option<dalembert_kinematics::second_derivatives::Pair6> {
        None
    }

    /// Checks the constraint's own parameters (finite geometry, non-zero axes, …).
    fn validate(&self) -> Result<(), dalembert_system::ModelError> {
        Ok(())
    }
}

/// A shared constraint is a constraint: lets one definition be used in several systems.
impl<C: Constraint + ?Sized> Constraint for std::sync::Arc<C> {
    fn name(&self) -> &str {
        (**self).name()
    }
    fn bodies(&self) -> [BodyRef; 2] {
        (**self).bodies()
    }
    fn num_equations(&self) -> usize {
        (**self).num_equations()
    }
    fn role(&self) -> ConstraintRole {
        (**self).role()
    }
    fn equation_label(&self, k: usize) -> &'static str {
        (**self).equation_label(k)
    }
    fn evaluate(&self, t: f64, first: &BodyState, second: &BodyState, out: &mut ConstraintEval) {
        (**self).evaluate(t, first, second, out)
    }
    fn reaction_point(&self, first: &BodyState, second: &BodyState) -> Vec2 {
        (**self).reaction_point(first, second)
    }
    fn weighted_hessian(
        &self,
        t: f64,
        first: &BodyState,
        second: &BodyState,
        lambda: &[f64],
    ) -> Option<dalembert_kinematics::second_derivatives::Pair6> {
        (**self).weighted_hessian(t, first, second, lambda)
    }
    fn validate(&self) -> Result<(), dalembert_system::ModelError> {
        (**self).validate()
    }
}
