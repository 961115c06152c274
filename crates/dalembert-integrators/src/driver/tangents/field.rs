//! How the run's method sees its tangents ([`TangentField`]): each stage's derivative along a
//! tangent solved with the run's own factorization, the tangent through the run's projection and
//! normalization (`docs/sensitivities.md`, (S5) and (S6)).

use super::super::inf_norm;
use super::{normalize, Tangent, Tangents};
use crate::stepper::TangentField;
use crate::IntegrationError;
use dalembert_system::{Baumgarte, BlockDiagonal, ConstraintValues, Formulation};

/// The storage of a stage's tangent derivative ([`TangentField::derivative`]), sized with the
/// run.
pub(super) struct Work {
    /// A side's state `y ± δ s`.
    pub(super) y: Vec<f64>,
    mass: BlockDiagonal,
    values: ConstraintValues,
    cdot: Vec<f64>,
    rhs: Vec<f64>,
    /// Each side's dynamic residual `M q̈ + C_qᵀ λ − Q`, constraint residual `C_q q̈ − γ` and
    /// position rates `T(q) v`.
    r: [Vec<f64>; 2],
    c: [Vec<f64>; 2],
    /// Each side's `Ċ` (the projection's derivative).
    cv: [Vec<f64>; 2],
    rates: [Vec<f64>; 2],
    g: Vec<f64>,
    h: Vec<f64>,
    /// The velocity constraints' right-hand side of the projection's derivative.
    hv: Vec<f64>,
    dqdd: Vec<f64>,
    dlambda: Vec<f64>,
    /// Positions moved along a correction (velocity coordinates), each way.
    q_moved: [Vec<f64>; 2],
}

impl Work {
    pub(super) fn new(f: &dyn Formulation, len: usize, n_q: usize) -> Self {
        let system = f.system();
        let (n_v, m) = (len - n_q, system.num_equations());
        Work {
            y: vec![0.0; len],
            mass: system.mass_storage(),
            values: system.constraints().values(),
            cdot: vec![0.0; m],
            rhs: vec![0.0; m],
            r: [vec![0.0; n_v], vec![0.0; n_v]],
            c: [vec![0.0; m], vec![0.0; m]],
            cv: [vec![0.0; m], vec![0.0; m]],
            rates: [vec![0.0; n_q], vec![0.0; n_q]],
            g: vec![0.0; n_v],
            h: vec![0.0; m],
            hv: vec![0.0; m],
            dqdd: vec![0.0; n_v],
            dlambda: vec![0.0; m],
            q_moved: [vec![0.0; n_q], vec![0.0; n_q]],
        }
    }
}

/// The largest change of a coordinate, relative to `1 + ‖y‖∞`, of a difference along a tangent:
/// central differences' truncation `(10⁻⁶)²` and round-off `10⁻¹⁶ / 10⁻⁶` stay near `10⁻¹⁰`
/// (measured against whole runs, `docs/sensitivities.md`: `10⁻⁷` lets round-off accumulate to
/// 2e-7 over a 10 s four-bar, `10⁻⁵` truncation to 7e-5 on the spatial slider-crank).
const STATE_STEP: f64 = 1e-6;

/// The step `ε` of a difference along the tangent `s` at the state `y`: its largest change of a
/// coordinate [`STATE_STEP`]` (1 + ‖y‖∞)` however large the tangent grows
/// (`docs/sensitivities.md`, (S5)). `None` for a zero tangent.
fn state_step(y: &[f64], s: &[f64]) -> Option<f64> {
    let size = inf_norm(s);
    (size > 0.0 && size.is_finite()).then(|| STATE_STEP * (1.0 + inf_norm(y)) / size)
}

/// The largest change of a coordinate, relative to `1 + ‖y‖∞`, for which a stage's derivative
/// differences the two changed models at `y ± δ s` in one go (two residual evaluations); beyond
/// it the tangent's own direction and the parameter are differenced apart (four), so that the
/// truncation stays below `(10⁻⁴)²` of the residual's curvature however large the tangent grows
/// (`docs/sensitivities.md`, (S5)).
const COMBINED_UP_TO: f64 = 1e-4;

/// True when the change `δ s` of the state is small enough for the one difference along
/// `(s, 1)` ([`COMBINED_UP_TO`]).
fn combined(delta: f64, y: &[f64], s: &[f64]) -> bool {
    delta * inf_norm(s) <= COMBINED_UP_TO * (1.0 + inf_norm(y))
}

/// The residuals `(M q̈ + C_qᵀ λ − Q, C_q q̈ − γ)` of `system` at `y` (`γ` with the Baumgarte
/// terms when given), with `(q̈, λ)` held, into `r` and `c`.
#[allow(clippy::too_many_arguments)]
fn residuals(
    system: &dyn dalembert_system::MultibodySystem,
    t: f64,
    y: &[f64],
    n_q: usize,
    baumgarte: Option<Baumgarte>,
    (qdd, lambda): (&[f64], &[f64]),
    work: &mut Work,
    k: usize,
) {
    let (q, v) = y.split_at(n_q);
    let constraints = system.constraints();
    system.dynamics_residual(
        t,
        (q, v),
        (qdd, lambda),
        (&mut work.mass, &mut work.values),
        &mut work.r[k],
    );
    constraints.jacobian_mul(&work.values, qdd, &mut work.c[k]);
    if baumgarte.is_some() {
        constraints.velocity_residual(&work.values, v, &mut work.cdot);
    }
    Baumgarte::apply(baumgarte, &work.values.gamma, &work.values.c, &work.cdot, &mut work.rhs);
    for (c, r) in work.c[k].iter_mut().zip(&work.rhs) {
        *c -= r;
    }
}

/// The constraints `C` and `Ċ = C_q v + C_t` of `system` at `y` into `(c, cdot)`.
fn constraint_residuals(
    system: &dyn dalembert_system::MultibodySystem,
    t: f64,
    (y, n_q): (&[f64], usize),
    values: &mut ConstraintValues,
    (c, cdot): (&mut [f64], &mut [f64]),
) {
    let (q, v) = y.split_at(n_q);
    let constraints = system.constraints();
    constraints.evaluate(t, q, v, values);
    c.copy_from_slice(&values.c);
    constraints.velocity_residual(values, v, cdot);
}

/// `−(C(y + e s) − C(y − e s)) / 2d` into `work.h` and the same of `Ċ` into `work.hv` (added to
/// them with `add`), `models[0]` at the `+` side and `models[1]` at the `−` side: the projection's
/// right-hand sides along `s` ([`TangentField::begin`]), as [`Along::difference`] takes a
/// stage's.
fn constraints_difference(
    work: &mut Work,
    models: [&dyn dalembert_system::MultibodySystem; 2],
    (t, y, n_q): (f64, &[f64], usize),
    (s, e, d): (&[f64], f64, f64),
    add: bool,
) {
    for (k, (model, sign)) in models.into_iter().zip([1.0, -1.0]).enumerate() {
        for i in 0..y.len() {
            work.y[i] = y[i] + sign * e * s[i];
        }
        let (c, cv) = (&mut work.c[k], &mut work.cv[k]);
        constraint_residuals(model, t, (&work.y, n_q), &mut work.values, (c, cv));
    }
    difference(&mut work.h, &work.c[0], &work.c[1], -0.5 / d, add);
    difference(&mut work.hv, &work.cv[0], &work.cv[1], -0.5 / d, add);
}

/// `out ← scale (a − b)` added to `out` (`add`) or written.
fn difference(out: &mut [f64], a: &[f64], b: &[f64], scale: f64, add: bool) {
    for (o, (a, b)) in out.iter_mut().zip(a.iter().zip(b)) {
        *o = if add { *o } else { 0.0 } + scale * (a - b);
    }
}

/// Where a stage's residuals are differenced: the time, the state, the run's gains and its
/// solution `(q̈, λ)`.
struct Along<'a> {
    t: f64,
    y: &'a [f64],
    n_q: usize,
    baumgarte: Option<Baumgarte>,
    solution: (&'a [f64], &'a [f64]),
}

impl Along<'_> {
    /// `−(R(y + e s) − R(y − e s)) / 2d` into `work.g` and `work.h` (added to them with `add`),
    /// `models[0]` at the `+` side and `models[1]` at the `−` side, `(s, e)` the direction and the
    /// state's step, `d` the divisor (`e`, or the parameter's change between the two models); the
    /// position rates' difference into `rates` when given.
    fn difference(
        &self,
        work: &mut Work,
        models: [&dyn dalembert_system::MultibodySystem; 2],
        (s, e, d): (&[f64], f64, f64),
        rates: Option<&mut [f64]>,
        add: bool,
    ) {
        self.evaluate(work, models, (s, e), rates.is_some());
        difference(&mut work.g, &work.r[0], &work.r[1], -0.5 / d, add);
        difference(&mut work.h, &work.c[0], &work.c[1], -0.5 / d, add);
        if let Some(rates) = rates {
            difference(rates, &work.rates[0], &work.rates[1], 0.5 / d, add);
        }
    }

    /// The residuals (and, with `rates`, the position rates) of `models[k]` at `y ± e s`.
    fn evaluate(
        &self,
        work: &mut Work,
        models: [&dyn dalembert_system::MultibodySystem; 2],
        (s, e): (&[f64], f64),
        rates: bool,
    ) {
        let Along {
            t,
            y,
            n_q,
            baumgarte,
            solution,
        } = *self;
        for (k, (model, sign)) in models.into_iter().zip([1.0, -1.0]).enumerate() {
            let mut moved = std::mem::take(&mut work.y);
            for i in 0..y.len() {
                moved[i] = y[i] + sign * e * s[i];
            }
            residuals(model, t, &moved, n_q, baumgarte, solution, work, k);
            if rates {
                let (q, v) = moved.split_at(n_q);
                model.position_rates(q, v, &mut work.rates[k]);
            }
            work.y = moved;
        }
    }
}

impl TangentField for Tangents {
    fn count(&self) -> usize {
        self.tangents.len()
    }

    fn tangent(&self, j: usize) -> &[f64] {
        &self.tangents[j].s
    }

    fn delta(&self, j: usize) -> f64 {
        self.tangents[j].delta
    }

    /// The derivative of the run's projection along each tangent that has not followed it:
    /// positions first, `S_q ← S_q ⊕ x` with `[M C_qᵀ; C_q 0] [x; μ] = [0; −(C_q S_q + C_p)]`,
    /// then velocities the same way with `Ċ = C_q v + C_t`; `C_q S_q + C_p` (and `Ċ`'s) by one
    /// difference of the two changed models at `y ± δ s` while that change is small
    /// ([`COMBINED_UP_TO`]), as a stage's derivative takes it, and otherwise along the tangent
    /// on the run's model with the step `ε` of [`state_step`] and along the parameter by the two
    /// changed models at the run's state (`docs/sensitivities.md`, (S6)).
    fn begin(&mut self, f: &mut dyn Formulation, t: f64, y: &[f64]) -> Result<bool, IntegrationError> {
        let n_q = self.n_q;
        for tangent in &mut self.tangents {
            if !tangent.project {
                continue;
            }
            let Tangent {
                delta, sides, work, s, ..
            } = tangent;
            let delta = *delta;
            // `C` and `Ċ` along the tangent, from the same evaluations: the velocity residual is
            // taken along the tangent before its position correction, which changes it by the
            // order of that correction times the residual's curvature (the order the
            // linearization at the projected state already leaves).
            work.h.iter_mut().for_each(|h| *h = 0.0);
            work.hv.iter_mut().for_each(|h| *h = 0.0);
            let at = (t, y, n_q);
            if combined(delta, y, s) {
                // One difference along `(s, 1)`: the two changed models at `y ± δ s`, as a
                // stage's derivative takes it (two evaluations of the constraints instead of four).
                let models = [sides[0].f.system(), sides[1].f.system()];
                constraints_difference(work, models, at, (s, delta, delta), false);
            } else {
                // The tangent's own direction on the run's model, then the parameter by the two
                // changed models at the run's state.
                if let Some(eps) = state_step(y, s) {
                    constraints_difference(work, [f.system(); 2], at, (s, eps, eps), false);
                }
                let models = [sides[0].f.system(), sides[1].f.system()];
                constraints_difference(work, models, at, (s, 0.0, delta), true);
            }
            work.g.iter_mut().for_each(|g| *g = 0.0);
            for velocities in [false, true] {
                let h = if velocities { &work.hv } else { &work.h };
                if !f.linear_response(t, &work.g, h, &mut work.dqdd, &mut work.dlambda)? {
                    return Ok(false);
                }
                let (s_q, s_v) = s.split_at_mut(n_q);
                if velocities {
                    s_v.iter_mut().zip(&work.dqdd).for_each(|(a, x)| *a += x);
                    continue;
                }
                // The correction `x` is in velocity coordinates: its change of the positions is
                // `d(q ⊕ ε x)/dε`, differenced.
                if let Some(eps) = state_step(&y[..n_q], &work.dqdd) {
                    let system = f.system();
                    for (k, sign) in [1.0, -1.0].into_iter().enumerate() {
                        work.q_moved[k].copy_from_slice(&y[..n_q]);
                        system.integrate_positions(&mut work.q_moved[k], &work.dqdd, sign * eps);
                    }
                    let [plus, minus] = &work.q_moved;
                    for i in 0..n_q {
                        s_q[i] += (plus[i] - minus[i]) / (2.0 * eps);
                    }
                }
            }
            tangent.project = false;
        }
        Ok(true)
    }

    /// The change of `q̈` along `(s, 1)`: the right-hand side `−(R_y s + R_p)` of the dynamic and
    /// constraint residuals `R` with the run's `q̈` and `λ` held, solved with the run's
    /// factorization ([`Formulation::linear_response`]). `R_y s` by central differences on the
    /// run's model with the step `ε` of [`state_step`], `R_p` by the two changed models at the
    /// run's state (`(R₊ − R₋) / 2δ`); the position rates `T(q) v` along `s` the same way
    /// (`docs/sensitivities.md`, (S5)).
    fn derivative(
        &mut self,
        f: &mut dyn Formulation,
        j: usize,
        t: f64,
        y: &[f64],
        baumgarte: Option<Baumgarte>,
        solution: (&[f64], &[f64]),
        s: &[f64],
        out: &mut [f64],
    ) -> Result<bool, IntegrationError> {
        let n_q = self.n_q;
        let Tangent { delta, sides, work, .. } = &mut self.tangents[j];
        let delta = *delta;
        let (rates, vdot) = out.split_at_mut(n_q);
        let at = Along {
            t,
            y,
            n_q,
            baumgarte,
            solution,
        };
        let models = [sides[0].f.system(), sides[1].f.system()];
        if combined(delta, y, s) {
            // One difference along `(s, 1)`: the two changed models at `y ± δ s`.
            at.difference(work, models, (s, delta, delta), Some(rates), false);
        } else {
            match state_step(y, s) {
                Some(eps) => at.difference(work, [f.system(); 2], (s, eps, eps), Some(&mut *rates), false),
                None => {
                    (work.g.iter_mut().chain(work.h.iter_mut())).for_each(|v| *v = 0.0);
                    rates.iter_mut().for_each(|r| *r = 0.0);
                }
            }
            // The parameter at the run's state (the position rates do not depend on it).
            at.difference(work, models, (s, 0.0, delta), None, true);
        }
        if !f.linear_response(t, &work.g, &work.h, &mut work.dqdd, &mut work.dlambda)? {
            return Ok(false);
        }
        vdot.copy_from_slice(&work.dqdd);
        Ok(vdot.iter().chain(rates.iter()).all(|v| v.is_finite()))
    }

    /// The tangent at the step's end through the normalization of the positions (unit Euler
    /// parameters; the same map on every model), differenced with the step `ε` of
    /// [`state_step`]; each side's state `y ± δ S` for its output samples.
    fn stepped(&mut self, j: usize, t: f64, h: f64, y: &[f64], s: &[f64]) {
        let n_q = self.n_q;
        let Tangent {
            delta,
            sides,
            next,
            carried,
            ..
        } = &mut self.tangents[j];
        next.copy_from_slice(s);
        if let Some(eps) = state_step(y, s) {
            // The sides' states hold `y ± ε s` until they are set below.
            for (side, sign) in sides.iter_mut().zip([1.0, -1.0]) {
                for i in 0..y.len() {
                    side.y[i] = y[i] + sign * eps * s[i];
                }
                normalize(side.f.as_ref(), &mut side.y, n_q);
            }
            let [plus, minus] = &*sides;
            difference(&mut next[..n_q], &plus.y[..n_q], &minus.y[..n_q], 0.5 / eps, false);
        }
        for (side, sign) in sides.iter_mut().zip([1.0, -1.0]) {
            for i in 0..y.len() {
                side.y[i] = y[i] + sign * *delta * next[i];
            }
            normalize(side.f.as_ref(), &mut side.y, n_q);
        }
        *carried = Some((t, h));
    }
}
