//! The tangent of the dynamic residual `r = M(q) q̈ + C_qᵀ λ − Q(t, q, v)` at a state:
//! [`ResidualTangent`], the system's analytic derivatives where every element gives them
//! ([`MultibodySystem::residual_tangent`]), central differences of the residual otherwise. The
//! implicit integrators' iteration matrix and the static and modal analyses take it from here.

use crate::{BlockDiagonal, ConstraintValues, MultibodySystem, TangentPattern, TangentValues};

/// `∂r/∂q` (along the velocity coordinates, `q ⊕ ε e_j`) and `∂r/∂v` on the system's
/// [`TangentPattern`], with the work vectors of their differences (allocation-free after
/// [`ResidualTangent::new`]).
pub struct ResidualTangent {
    pattern: TangentPattern,
    dr_dq: Vec<f64>,
    dr_dv: Vec<f64>,
    step: Vec<f64>,
    q: Vec<f64>,
    v: Vec<f64>,
    plus: Vec<f64>,
    minus: Vec<f64>,
}

/// The state a tangent is taken at: `(t, q, v, q̈, λ)`.
pub struct TangentAt<'a> {
    /// Time.
    pub t: f64,
    /// Positions.
    pub q: &'a [f64],
    /// Velocities.
    pub v: &'a [f64],
    /// Accelerations.
    pub qdd: &'a [f64],
    /// Multipliers.
    pub lambda: &'a [f64],
}

impl ResidualTangent {
    /// Storage for `system`'s tangent.
    pub fn new(system: &dyn MultibodySystem) -> Self {
        let pattern = TangentPattern::new(system);
        let n = pattern.dim();
        ResidualTangent {
            dr_dq: vec![0.0; pattern.len()],
            dr_dv: vec![0.0; pattern.len()],
            step: vec![0.0; n],
            q: vec![0.0; system.layout().n_q()],
            v: vec![0.0; n],
            plus: vec![0.0; n],
            minus: vec![0.0; n],
            pattern,
        }
    }

    /// The pattern the values are on.
    pub fn pattern(&self) -> &TangentPattern {
        &self.pattern
    }

    /// `∂r/∂q` over the pattern's entries.
    pub fn dr_dq(&self) -> &[f64] {
        &self.dr_dq
    }

    /// `∂r/∂v` over the pattern's entries.
    pub fn dr_dv(&self) -> &[f64] {
        &self.dr_dv
    }

    /// The tangent at `at`: analytic where the system gives it (returns `true`), otherwise by
    /// central differences of the residual, the columns of each of the pattern's passes at once
    /// (`4 × passes` residual evaluations, `mass` and `values` used as the residual's storage
    /// and left at an unspecified state).
    pub fn differentiate(
        &mut self,
        system: &dyn MultibodySystem,
        mass: &mut BlockDiagonal,
        values: &mut ConstraintValues,
        at: &TangentAt<'_>,
    ) -> bool {
        let mut out = TangentValues::new(&self.pattern, &mut self.dr_dq, &mut self.dr_dv);
        if system.residual_tangent(at.t, (at.q, at.v), (at.qdd, at.lambda), &mut out) {
            return true;
        }
        self.differences(system, mass, values, at);
        false
    }

    /// [`ResidualTangent::differentiate`], then `mass` and `values` evaluated at `at` again (the
    /// differences leave them elsewhere): whether the tangent was the analytic one, and the
    /// residual evaluations spent (0 for the analytic one). What an implicit integrator's matrix
    /// calls before it is built at `at`.
    pub fn differentiate_at(
        &mut self,
        system: &dyn MultibodySystem,
        mass: &mut BlockDiagonal,
        values: &mut ConstraintValues,
        at: &TangentAt<'_>,
    ) -> (bool, u64) {
        let analytic = self.differentiate(system, mass, values, at);
        system.mass(at.q, mass);
        system.constraints().evaluate(at.t, at.q, at.v, values);
        let cost = if analytic {
            0
        } else {
            4 * self.pattern.passes().len() as u64
        };
        (analytic, cost)
    }

    /// `∂r/∂q` and `∂r/∂v` by central differences of the residual, column passes at a time,
    /// whether or not the system has analytic derivatives (which they check).
    pub fn differences(
        &mut self,
        system: &dyn MultibodySystem,
        mass: &mut BlockDiagonal,
        values: &mut ConstraintValues,
        at: &TangentAt<'_>,
    ) {
        let largest_position = at.q.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let rates = at.q.len() == at.v.len();
        for pass in self.pattern.passes() {
            for velocity in [false, true] {
                // Relative steps: to the velocity, or to the position coordinate when `v = q̇`
                // (otherwise to the largest position: the direction mixes coordinates).
                for &j in pass {
                    let size = match (velocity, rates) {
                        (true, _) => at.v[j].abs(),
                        (false, true) => at.q[j].abs(),
                        (false, false) => largest_position,
                    };
                    self.step[j] = 1e-7 * (1.0 + size);
                }
                for (sign, out) in [(1.0, &mut self.plus), (-1.0, &mut self.minus)] {
                    self.q.copy_from_slice(at.q);
                    self.v.copy_from_slice(at.v);
                    if velocity {
                        for &j in pass {
                            self.v[j] += sign * self.step[j];
                        }
                    } else {
                        system.integrate_positions(&mut self.q, &self.step, sign);
                    }
                    system.dynamics_residual(at.t, (&self.q, &self.v), (at.qdd, at.lambda), (mass, values), out);
                }
                let target = if velocity { &mut self.dr_dv } else { &mut self.dr_dq };
                for &j in pass {
                    let h = self.step[j];
                    for (e, &i) in self.pattern.column(j).zip(self.pattern.rows(j)) {
                        target[e] = (self.plus[i] - self.minus[i]) / (2.0 * h);
                    }
                    self.step[j] = 0.0;
                }
            }
        }
    }
}
