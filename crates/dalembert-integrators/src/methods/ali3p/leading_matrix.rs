//! The leading matrix of ALI3-P's Newton iteration,
//!
//! ```text
//! f_q = M + (h/2) ∂r/∂v + (h²/4) (∂r/∂q + α C_qᵀ C_q),    r = M q̈ + C_qᵀ (λ* + α C) − Q,
//! ```
//!
//! `n_v × n_v` on the system's [`TangentPattern`] (which holds every mass block and every pair of
//! bodies sharing a constraint equation, so `C_qᵀ C_q` falls inside it), factored by [`PatternLu`]
//! (dense up to [`PatternLu::DENSE_LIMIT`] unknowns, sparse with one symbolic analysis above).
//! Unlike the saddle-point matrix it has no multiplier rows: `α C_qᵀ C_q` is positive
//! semi-definite whatever the rank of `C_q`, so `f_q` stays regular at singular positions and with
//! redundant constraints.

use dalembert_system::linalg::{LinalgError, PatternLu};
use dalembert_system::{BlockDiagonal, ConstraintValues, MultibodySystem, ResidualTangent, TangentAt};

/// The tangent, the scatter maps of the mass and of `C_qᵀ C_q` into it, and the factors.
pub(super) struct LeadingMatrix {
    tangent: ResidualTangent,
    /// Whether the tangent holds a differentiation.
    differentiated: bool,
    /// Whether that differentiation was the system's analytic one (then it is cheap to repeat).
    analytic: bool,
    /// Per mass entry (in [`BlockDiagonal::entries`] order), its index in the pattern.
    mass_at: Vec<usize>,
    /// `(pattern index, Jacobian entry a, Jacobian entry b)`: `C_qᵀ C_q` adds `J_a J_b` there, for
    /// every ordered pair of entries of one constraint row.
    pairs: Vec<(usize, usize, usize)>,
    lu: PatternLu,
    /// `M + (h²/4) α C_qᵀ C_q` for the projections (the same pattern).
    projection: PatternLu,
}

impl LeadingMatrix {
    /// Storage and scatter maps for `system` (setup only). `Err` when the sparse symbolic analysis
    /// fails.
    pub fn new(system: &dyn MultibodySystem, mass: &BlockDiagonal) -> Result<Self, LinalgError> {
        let tangent = ResidualTangent::new(system);
        let pattern = tangent.pattern();
        let outside = |what: &str, i: usize, j: usize| {
            LinalgError::Singular(format!(
                "ALI3-P: the {what} entry ({i}, {j}) is outside the tangent pattern"
            ))
        };
        let mass_at = mass
            .entries()
            .map(|(i, j, _)| pattern.position(i, j).ok_or_else(|| outside("mass", i, j)))
            .collect::<Result<Vec<_>, _>>()?;
        let constraints = system.constraints().pattern();
        let mut by_row: Vec<Vec<usize>> = vec![Vec::new(); constraints.rows()];
        for (e, &(r, _)) in constraints.entries().iter().enumerate() {
            by_row[r].push(e);
        }
        let entries = constraints.entries();
        let mut pairs = Vec::new();
        for row in &by_row {
            for &a in row {
                for &b in row {
                    let (i, j) = (entries[a].1, entries[b].1);
                    let at = pattern.position(i, j).ok_or_else(|| outside("C_qᵀ C_q", i, j))?;
                    pairs.push((at, a, b));
                }
            }
        }
        let lu = PatternLu::new(pattern.dim(), pattern.entries().collect(), PatternLu::DENSE_LIMIT)?;
        let projection = PatternLu::new(pattern.dim(), pattern.entries().collect(), PatternLu::DENSE_LIMIT)?;
        Ok(LeadingMatrix {
            tangent,
            differentiated: false,
            analytic: false,
            mass_at,
            pairs,
            lu,
            projection,
        })
    }

    /// Whether a tangent is held that the next factorization may reuse: a differenced one is kept
    /// across steps, an analytic one is taken afresh (it costs about one residual).
    pub fn reusable(&self) -> bool {
        self.differentiated && !self.analytic
    }

    /// Forgets the tangent (after a failed step).
    pub fn invalidate(&mut self) {
        self.differentiated = false;
    }

    /// The tangent of `r` at `at` (analytic where the system has it, otherwise by differences);
    /// returns the residual evaluations spent. Leaves `mass` and `values` at `at`.
    pub fn differentiate(
        &mut self,
        system: &dyn MultibodySystem,
        mass: &mut BlockDiagonal,
        values: &mut ConstraintValues,
        at: &TangentAt<'_>,
    ) -> u64 {
        let (analytic, cost) = self.tangent.differentiate_at(system, mass, values, at);
        self.analytic = analytic;
        self.differentiated = true;
        cost
    }

    /// Builds `f_q` from `mass` and `values` (at the state the tangent was taken at or near) with
    /// `(β', γ') = (h²/4, h/2)` and the penalty weight `β' α`, and factors it.
    pub fn factor(
        &mut self,
        mass: &BlockDiagonal,
        values: &ConstraintValues,
        (beta, gamma): (f64, f64),
        weight: f64,
    ) -> Result<(), LinalgError> {
        let out = self.lu.values_mut();
        for ((o, dq), dv) in out.iter_mut().zip(self.tangent.dr_dq()).zip(self.tangent.dr_dv()) {
            *o = beta * dq + gamma * dv;
        }
        add_mass_and_penalty(out, (&self.mass_at, &self.pairs), mass, values, weight);
        self.lu.factor()
    }

    /// Builds the projection matrix `M + weight C_qᵀ C_q` from `mass` and `values` and factors it.
    pub fn factor_projection(
        &mut self,
        mass: &BlockDiagonal,
        values: &ConstraintValues,
        weight: f64,
    ) -> Result<(), LinalgError> {
        let out = self.projection.values_mut();
        out.fill(0.0);
        add_mass_and_penalty(out, (&self.mass_at, &self.pairs), mass, values, weight);
        self.projection.factor()
    }

    /// `x ← P⁻¹ x` with the last projection factors.
    pub fn solve_projection(&mut self, x: &mut [f64]) {
        self.projection.solve_in_place(x);
    }

    /// `x ← f_q⁻¹ x` with the last factors.
    pub fn solve(&mut self, x: &mut [f64]) {
        self.lu.solve_in_place(x);
    }
}

/// `out += M + weight C_qᵀ C_q` on the pattern's entries (`mass_at`, `pairs`: the scatter maps of
/// [`LeadingMatrix`]), for both the Newton and the projection matrix.
fn add_mass_and_penalty(
    out: &mut [f64],
    (mass_at, pairs): (&[usize], &[(usize, usize, usize)]),
    mass: &BlockDiagonal,
    values: &ConstraintValues,
    weight: f64,
) {
    for (&at, (_, _, m)) in mass_at.iter().zip(mass.entries()) {
        out[at] += m;
    }
    let j = &values.jacobian;
    for &(at, a, b) in pairs {
        out[at] += weight * j[a] * j[b];
    }
}
