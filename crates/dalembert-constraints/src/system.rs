//! Assembly of all constraints into `C`, `C_q` (sparse, fixed pattern), `C_t` and `Q_d`.

use crate::{Constraint, ConstraintError, ConstraintEval, EquationRef};
use dalembert_kinematics::{BodyRef, BodyState, Coordinates};

/// Every constraint of a model, with the row layout and the sparsity pattern of `C_q`.
///
/// Rows follow the constraints in order. The pattern lists, per constraint, the entries of each
/// moving body's 3-column block, row by row; it is computed once and never changes, so consumers
/// can map entries into their own sparse matrices once at setup.
#[derive(Debug)]
pub struct ConstraintSystem {
    constraints: Vec<Box<dyn Constraint>>,
    coordinates: Coordinates,
    row_offsets: Vec<usize>,
    entry_offsets: Vec<usize>,
    pattern: Vec<(usize, usize)>,
}

/// The assembled constraint quantities at one `(t, q, q̇)`. Created once, refilled in place.
#[derive(Debug, Clone, PartialEq)]
pub struct ConstraintValues {
    /// `C(q, t)`, length `m`.
    pub c: Vec<f64>,
    /// `C_t`, length `m`.
    pub c_t: Vec<f64>,
    /// `Q_d`, length `m`.
    pub gamma: Vec<f64>,
    /// Values of `C_q` in the order of [`ConstraintSystem::pattern`].
    pub jacobian: Vec<f64>,
    /// Scratch: the state of every body at the last evaluation (one `sin_cos` per body).
    states: Vec<BodyState>,
}

impl ConstraintSystem {
    /// Builds the system for `bodies` moving bodies; validates every constraint.
    pub fn new(bodies: usize, constraints: Vec<Box<dyn Constraint>>) -> Result<Self, ConstraintError> {
        let mut row_offsets = vec![0];
        let mut entry_offsets = vec![0];
        let mut pattern = Vec::new();
        for c in &constraints {
            let name = c.name().to_string();
            // Bodies first: a joint built against a body the model lacks is named as such.
            for body in c.bodies() {
                dalembert_kinematics::forces::check_body(&format!("constraint '{name}'"), body, bodies)?;
            }
            c.validate()?;
            let ne = c.num_equations();
            if !(1..=crate::MAX_EQUATIONS).contains(&ne) {
                return Err(ConstraintError::EquationCount { name, count: ne });
            }
            let [a, b] = c.bodies();
            if a == b {
                return Err(ConstraintError::SameBody { name });
            }
            let r0 = *row_offsets.last().unwrap_or(&0);
            for body in [a, b] {
                if let BodyRef::Body(id) = body {
                    for k in 0..ne {
                        for col in 0..3 {
                            pattern.push((r0 + k, id.offset() + col));
                        }
                    }
                }
            }
            row_offsets.push(r0 + ne);
            entry_offsets.push(pattern.len());
        }
        Ok(ConstraintSystem {
            constraints,
            coordinates: Coordinates::new(bodies),
            row_offsets,
            entry_offsets,
            pattern,
        })
    }

    /// Number of constraint equations `m`.
    #[inline]
    pub fn num_equations(&self) -> usize {
        *self.row_offsets.last().unwrap_or(&0)
    }

    /// Number of coordinates `n`.
    #[inline]
    pub fn num_coordinates(&self) -> usize {
        self.coordinates.len()
    }

    /// The coordinate layout.
    pub fn coordinates(&self) -> Coordinates {
        self.coordinates
    }

    /// The constraints, in row order.
    pub fn constraints(&self) -> &[Box<dyn Constraint>] {
        &self.constraints
    }

    /// First row of constraint `k`.
    #[inline]
    pub fn row_offset(&self, k: usize) -> usize {
        self.row_offsets[k]
    }

    /// `(row, column)` of every stored entry of `C_q`.
    pub fn pattern(&self) -> &[(usize, usize)] {
        &self.pattern
    }

    /// The equation at system row `row`.
    pub fn equation(&self, row: usize) -> EquationRef {
        let k = self.row_offsets.partition_point(|&r| r <= row) - 1;
        let c = &self.constraints[k];
        let e = row - self.row_offsets[k];
        EquationRef {
            constraint: k,
            name: c.name().to_string(),
            equation: e,
            label: c.equation_label(e),
        }
    }

    /// Storage for the assembled values, sized for this system.
    pub fn values(&self) -> ConstraintValues {
        let m = self.num_equations();
        ConstraintValues {
            c: vec![0.0; m],
            c_t: vec![0.0; m],
            gamma: vec![0.0; m],
            jacobian: vec![0.0; self.pattern.len()],
            states: vec![BodyState::GROUND; self.coordinates.bodies()],
        }
    }

    /// Evaluates every constraint at `(t, q, q̇)` into `out` (`qd` may be empty for zero velocity,
    /// in which case `Q_d` holds only the `C_tt` part). Allocates nothing.
    pub fn evaluate(&self, t: f64, q: &[f64], qd: &[f64], out: &mut ConstraintValues) {
        let mut eval = ConstraintEval::default();
        for (i, st) in out.states.iter_mut().enumerate() {
            *st = BodyState::of(BodyRef::Body(dalembert_kinematics::BodyId(i)), q, qd);
        }
        let state = |b: BodyRef| match b {
            BodyRef::Ground => BodyState::GROUND,
            BodyRef::Body(id) => out.states[id.0],
        };
        for (k, c) in self.constraints.iter().enumerate() {
            let [a, b] = c.bodies();
            let (sa, sb) = (state(a), state(b));
            c.evaluate(t, &sa, &sb, &mut eval);
            let r0 = self.row_offsets[k];
            let ne = self.row_offsets[k + 1] - r0;
            out.c[r0..r0 + ne].copy_from_slice(&eval.c[..ne]);
            out.c_t[r0..r0 + ne].copy_from_slice(&eval.c_t[..ne]);
            out.gamma[r0..r0 + ne].copy_from_slice(&eval.gamma[..ne]);
            let mut e = self.entry_offsets[k];
            for (side, body) in [a, b].into_iter().enumerate() {
                if body != BodyRef::Ground {
                    for row in eval.jac.iter().take(ne) {
                        out.jacobian[e..e + 3].copy_from_slice(&row[side]);
                        e += 3;
                    }
                }
            }
        }
    }

    /// `Ok` when every assembled value is finite; otherwise the error names the first equation
    /// whose `C`, `C_t`, `Q_d` or Jacobian row overflows (e.g. `Q_d` with velocities near 1e200).
    pub fn check_values(&self, t: f64, values: &ConstraintValues) -> Result<(), crate::DynamicsError> {
        let bad_row = (0..self.num_equations())
            .find(|&r| {
                ![values.c[r], values.c_t[r], values.gamma[r]]
                    .iter()
                    .all(|x| x.is_finite())
            })
            .or_else(|| {
                self.pattern
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

    /// The Jacobian blocks of constraint `k` from assembled values: `(first, second)`, each a slice
    /// of `3 × equations` entries row by row, or `None` for the ground.
    pub fn blocks<'a>(&self, k: usize, values: &'a ConstraintValues) -> [Option<&'a [f64]>; 2] {
        let [a, b] = self.constraints[k].bodies();
        let ne = self.row_offsets[k + 1] - self.row_offsets[k];
        let mut e = self.entry_offsets[k];
        let mut out = [None, None];
        for (side, body) in [a, b].into_iter().enumerate() {
            if body != BodyRef::Ground {
                out[side] = Some(&values.jacobian[e..e + 3 * ne]);
                e += 3 * ne;
            }
        }
        out
    }

    /// `y ← C_q x`.
    pub fn jacobian_mul(&self, values: &ConstraintValues, x: &[f64], y: &mut [f64]) {
        y.iter_mut().for_each(|v| *v = 0.0);
        for (&(r, c), &v) in self.pattern.iter().zip(&values.jacobian) {
            y[r] += v * x[c];
        }
    }

    /// `y ← y + α C_qᵀ λ`.
    pub fn jacobian_transpose_mul_add(&self, values: &ConstraintValues, alpha: f64, lambda: &[f64], y: &mut [f64]) {
        for (&(r, c), &v) in self.pattern.iter().zip(&values.jacobian) {
            y[c] += alpha * v * lambda[r];
        }
    }

    /// `C_q` as a dense `m × n` matrix.
    pub fn jacobian_dense(&self, values: &ConstraintValues) -> faer::Mat<f64> {
        let mut a = faer::Mat::zeros(self.num_equations(), self.num_coordinates());
        for (&(r, c), &v) in self.pattern.iter().zip(&values.jacobian) {
            a[(r, c)] += v;
        }
        a
    }

    /// Evaluates at `(t, q, q̇)` into the scratch `values` and writes `C` and `Ċ = C_q q̇ + C_t`.
    pub fn residuals(
        &self,
        t: f64,
        q: &[f64],
        qd: &[f64],
        values: &mut ConstraintValues,
        c: &mut [f64],
        cdot: &mut [f64],
    ) {
        self.evaluate(t, q, qd, values);
        c.copy_from_slice(&values.c);
        self.velocity_residual(values, qd, cdot);
    }

    /// Velocity-level residual `Ċ = C_q q̇ + C_t` into `out`.
    pub fn velocity_residual(&self, values: &ConstraintValues, qd: &[f64], out: &mut [f64]) {
        self.jacobian_mul(values, qd, out);
        for (o, ct) in out.iter_mut().zip(&values.c_t) {
            *o += ct;
        }
    }
}
