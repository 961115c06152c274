//! Reuse of a constraint evaluation at an unchanged state.

use crate::{ConstraintSet, ConstraintValues};

/// The state `(t, q, v)` at which a formulation's [`ConstraintValues`] were last evaluated, so that
/// two evaluations at the same state cost one: the integrators check the constraint residuals after
/// every step ([`crate::Formulation::residuals`]), and the next step's first stage evaluates at that
/// same state (one constraint evaluation saved per Runge–Kutta step; bitwise-equal states only).
#[derive(Debug, Clone)]
pub struct EvaluatedAt {
    t: f64,
    q: Vec<f64>,
    v: Vec<f64>,
    valid: bool,
}

fn same(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
}

impl EvaluatedAt {
    /// No state yet, with room for `n_q` positions and `n_v` velocities.
    pub fn new(n_q: usize, n_v: usize) -> Self {
        EvaluatedAt {
            t: f64::NAN,
            q: vec![0.0; n_q],
            v: vec![0.0; n_v],
            valid: false,
        }
    }

    /// Evaluates `sys` at `(t, q, v)` into `values` unless they already hold that state from
    /// [`Self::residuals`] (then nothing is done). Allocates nothing; the state is not recorded
    /// (copying it would cost more than it saves between stages, whose states all differ).
    pub fn evaluate(
        &mut self,
        sys: &(impl ConstraintSet + ?Sized),
        t: f64,
        q: &[f64],
        v: &[f64],
        values: &mut ConstraintValues,
    ) {
        if self.holds(t, q, v) {
            return;
        }
        sys.evaluate(t, q, v, values);
        self.valid = false;
    }

    /// `C` and `Ċ = C_q v + C_t` at `(t, q, v)`, evaluated through [`Self::evaluate`], and the state
    /// recorded for the next [`Self::evaluate`].
    pub fn residuals(
        &mut self,
        sys: &(impl ConstraintSet + ?Sized),
        (t, q, v): (f64, &[f64], &[f64]),
        values: &mut ConstraintValues,
        c: &mut [f64],
        cdot: &mut [f64],
    ) {
        self.evaluate(sys, t, q, v, values);
        self.valid = self.q.len() == q.len() && self.v.len() == v.len();
        if self.valid {
            self.t = t;
            self.q.copy_from_slice(q);
            self.v.copy_from_slice(v);
        }
        c.copy_from_slice(&values.c);
        sys.velocity_residual(values, v, cdot);
    }

    fn holds(&self, t: f64, q: &[f64], v: &[f64]) -> bool {
        self.valid && self.t.to_bits() == t.to_bits() && same(&self.q, q) && same(&self.v, v)
    }

    /// Forgets the state: to be called when the values were written by anything else.
    pub fn invalidate(&mut self) {
        self.valid = false;
    }
}

#[cfg(test)]
mod tests {
    use super::EvaluatedAt;
    use crate::{ConstraintPattern, ConstraintSet, ConstraintValues, EquationRef, Layout};
    use std::sync::atomic::{AtomicUsize, Ordering};

    /// One particle on a line moving with time, `C = x − t`, counting its evaluations.
    #[derive(Debug)]
    struct Counting {
        pattern: ConstraintPattern,
        calls: AtomicUsize,
    }

    impl ConstraintSet for Counting {
        fn pattern(&self) -> &ConstraintPattern {
            &self.pattern
        }
        fn equation(&self, _row: usize) -> EquationRef {
            EquationRef {
                constraint: 0,
                name: "moving".into(),
                equation: 0,
                label: "x",
            }
        }
        fn values(&self) -> ConstraintValues {
            ConstraintValues::new(&self.pattern, 0)
        }
        fn evaluate(&self, t: f64, q: &[f64], _v: &[f64], out: &mut ConstraintValues) {
            self.calls.fetch_add(1, Ordering::Relaxed);
            out.c[0] = q[0] - t;
            out.c_t[0] = -1.0;
            out.jacobian[0] = 1.0;
        }
    }

    /// The state of a residual check costs no second evaluation; any changed bit of `t`, `q` or
    /// `v` (also `0.0` against `−0.0`), an evaluation elsewhere, and an invalidation, cost one more;
    /// the residuals are those of the state asked for (`C = x − t`, `Ċ = v − 1`).
    #[test]
    fn evaluates_once_per_state() {
        let layout = Layout::new([("particle", &["x"][..], &["vx"][..])]);
        let sys = Counting {
            pattern: ConstraintPattern::from_segments(1, &layout, [(0, 0)]),
            calls: AtomicUsize::new(0),
        };
        let mut values = sys.values();
        let mut at = EvaluatedAt::new(1, 1);
        let (mut c, mut cdot) = ([0.0], [0.0]);
        let calls = || sys.calls.load(Ordering::Relaxed);
        at.residuals(&sys, (0.5, &[2.0], &[3.0]), &mut values, &mut c, &mut cdot);
        assert_eq!((calls(), c[0], cdot[0]), (1, 1.5, 2.0));
        at.evaluate(&sys, 0.5, &[2.0], &[3.0], &mut values);
        at.evaluate(&sys, 0.5, &[2.0], &[3.0], &mut values);
        assert_eq!(calls(), 1);
        for (t, v) in [(0.5, -0.0), (0.5, 0.0), (0.5 + f64::EPSILON, 0.0)] {
            at.residuals(&sys, (0.5, &[2.0], &[3.0]), &mut values, &mut c, &mut cdot);
            at.evaluate(&sys, t, &[2.0], &[v], &mut values);
        }
        assert_eq!(calls(), 6);
        at.residuals(&sys, (0.25, &[2.0], &[0.0]), &mut values, &mut c, &mut cdot);
        assert_eq!((calls(), c[0], cdot[0]), (7, 1.75, -1.0));
        at.evaluate(&sys, 0.3, &[2.0], &[0.0], &mut values);
        at.residuals(&sys, (0.25, &[2.0], &[0.0]), &mut values, &mut c, &mut cdot);
        assert_eq!(calls(), 9);
        at.invalidate();
        at.evaluate(&sys, 0.25, &[2.0], &[0.0], &mut values);
        assert_eq!(calls(), 10);
    }
}
