//! The power that changes a model's energy `E = T + V` (`docs/energy.md`, eqs. E2, E3 and the
//! friction's power): written once for the energy balance over output samples and for the work
//! a run integrates along its steps. Its buffers are allocated with it; nothing after.

use crate::{ConstraintValues, MultibodySystem, SlipRow};

/// Work buffers of [`MultibodySystem::nonconservative_power`]: the applied forces and two
/// position vectors for `dV/dt` ([`crate::system::potential_rate`]).
#[derive(Debug, Clone, Default)]
pub struct PowerScratch {
    /// Generalized forces (`n_v`).
    pub forces: Vec<f64>,
    /// Positions a little ahead along the motion (`n_q`).
    pub ahead: Vec<f64>,
    /// Positions a little behind along the motion (`n_q`).
    pub behind: Vec<f64>,
}

impl PowerScratch {
    /// Buffers for `system`'s layout.
    pub fn new(system: &dyn MultibodySystem) -> Self {
        let l = system.layout();
        PowerScratch {
            forces: vec![0.0; l.n_v()],
            ahead: vec![0.0; l.n_q()],
            behind: vec![0.0; l.n_q()],
        }
    }
}

/// `P = P_nc + P_c + P_f` at a state: the non-conservative applied forces
/// ([`MultibodySystem::nonconservative_power`]), the constraint forces `−λᵀ C_q v` (drivers; a
/// joint's is zero on its constraints) and the joint friction `Σ F_k w_k` (`docs/energy.md`).
#[derive(Debug, Clone)]
pub struct PowerProbe {
    scratch: PowerScratch,
    values: ConstraintValues,
    c_q_v: Vec<f64>,
    row: SlipRow,
}

impl PowerProbe {
    /// A probe for `system`.
    pub fn new(system: &dyn MultibodySystem) -> Self {
        let sys = system.constraints();
        PowerProbe {
            scratch: PowerScratch::new(system),
            values: sys.values(),
            c_q_v: vec![0.0; sys.num_equations()],
            row: SlipRow::default(),
        }
    }

    /// The power at `(t, q, v)` with multipliers `lambda` (empty: the constraint forces' power is
    /// left out, as for a model without drivers) and joint friction forces `friction` (one per
    /// [`MultibodySystem::frictions`], or empty).
    pub fn power(
        &mut self,
        system: &dyn MultibodySystem,
        (t, q, v): (f64, &[f64], &[f64]),
        lambda: &[f64],
        friction: &[f64],
    ) -> f64 {
        let mut p = system.nonconservative_power(t, q, v, &mut self.scratch);
        for (k, f) in friction.iter().enumerate() {
            system.slip_row(k, t, q, v, &mut self.row);
            p += f * self.row.dot(v);
        }
        if !self.c_q_v.is_empty() && lambda.len() == self.c_q_v.len() {
            let sys = system.constraints();
            sys.evaluate(t, q, v, &mut self.values);
            sys.jacobian_mul(&self.values, v, &mut self.c_q_v);
            p -= lambda.iter().zip(&self.c_q_v).map(|(l, c)| l * c).sum::<f64>();
        }
        p
    }
}
