//! Sensitivities of a run to parameters, carried along with it: [`Perturbed`] models given by the
//! caller, and the tangents the run keeps ([`Tangents`]).
//!
//! For a parameter `p` the run keeps `S = ∂y/∂p` (`y = [q; v]`) and advances it with each of the
//! run's own accepted steps: from the run's state at the start of the step, the step is taken again
//! from `y ± δ S` on the model with `p ± δ`, by the same method with the same size (a fixed step,
//! or an adaptive one taken whatever its error estimate says), normalized (unit Euler parameters)
//! but not projected, and `S ← (y₊ − y₋) / 2δ`. The run's projection only removes its step's
//! drift, of the order of the local error; differencing two projections would add their
//! tolerance's noise to `S` instead (`docs/sensitivities.md`). This is the derivative of the method's own step map
//! (internal differentiation: the sensitivity equations discretized exactly as the state is, with
//! the run's step sizes and decisions), by central differences recentred on the run at every step,
//! so that the perturbed states never drift from it (`docs/sensitivities.md`). Output samples of
//! either side come from its own dense output (adaptive methods) or its state at the step's end.

use super::{normalize, project};
use crate::stepper::{Setup, StepControl, StepOutcome, Stepper, TangentField};
use crate::{IntegrationError, IntegratorOptions, Stabilization};
use dalembert_system::{Baumgarte, BlockDiagonal, ConstraintValues, Formulation};

/// One parameter's perturbed models, given to [`super::Integration::with_sensitivities`].
pub struct Perturbed {
    /// The parameter's name (in errors).
    pub name: String,
    /// The formulation on the model with `p + δ`.
    pub plus: Box<dyn Formulation>,
    /// The formulation on the model with `p − δ`.
    pub minus: Box<dyn Formulation>,
    /// The consistent initial state `[q; v]` of the `p + δ` model (its scene's state, assembled).
    pub y_plus: Vec<f64>,
    /// The same for `p − δ`.
    pub y_minus: Vec<f64>,
    /// The change `δ` of the parameter (positive, in its units).
    pub delta: f64,
}

impl std::fmt::Debug for Perturbed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Perturbed({}, δ = {})", self.name, self.delta)
    }
}

/// One side (`p + δ` or `p − δ`) of a tangent: its formulation, its own copy of the method, and
/// its state after the last step (or at the time shown).
struct Side {
    f: Box<dyn Formulation>,
    stepper: Box<dyn Stepper>,
    y: Vec<f64>,
    shown: Vec<f64>,
}

/// A tangent `S = ∂y/∂p` and its two sides.
struct Tangent {
    name: String,
    delta: f64,
    s: Vec<f64>,
    sides: [Side; 2],
    /// The tangent at the end of the step a method carried it through
    /// ([`Stepper::step_tangents`]), when `carried` is that step's start and size.
    next: Vec<f64>,
    carried: Option<(f64, f64)>,
    /// True when the run's state was projected after the last step and the tangent not yet.
    project: bool,
    work: Work,
}

/// The storage of a stage's tangent derivative ([`TangentField::derivative`]), sized with the
/// run.
struct Work {
    /// A side's state `y ± δ s`.
    y: Vec<f64>,
    mass: BlockDiagonal,
    values: ConstraintValues,
    cdot: Vec<f64>,
    rhs: Vec<f64>,
    /// Each side's dynamic residual `M q̈ + C_qᵀ λ − Q`, constraint residual `C_q q̈ − γ` and
    /// position rates `T(q) v`.
    r: [Vec<f64>; 2],
    c: [Vec<f64>; 2],
    rates: [Vec<f64>; 2],
    g: Vec<f64>,
    h: Vec<f64>,
    dqdd: Vec<f64>,
    dlambda: Vec<f64>,
    /// Positions moved along a correction (velocity coordinates), each way.
    q_moved: [Vec<f64>; 2],
}

impl Work {
    fn new(f: &dyn Formulation, len: usize, n_q: usize) -> Self {
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
            rates: [vec![0.0; n_q], vec![0.0; n_q]],
            g: vec![0.0; n_v],
            h: vec![0.0; m],
            dqdd: vec![0.0; n_v],
            dlambda: vec![0.0; m],
            q_moved: [vec![0.0; n_q], vec![0.0; n_q]],
        }
    }
}

/// The tangents a run keeps (none for a plain run). Allocated with the run; nothing while
/// stepping beyond what the methods and formulations of the sides do.
#[derive(Default)]
pub(super) struct Tangents {
    tangents: Vec<Tangent>,
    /// The run's state at the start of the step in progress.
    start: Vec<f64>,
    adaptive: bool,
    /// True when the sides' `shown` states are at the time shown (dense output); otherwise their
    /// `y` are.
    shown_between: bool,
    n_q: usize,
    /// Steps whose tangents were carried by the method and differenced as whole steps.
    carried: u64,
    differenced: u64,
    /// True when the last step's tangents were carried by the method.
    last_carried: bool,
    /// True when the run projects its state after each step.
    projects: bool,
}

impl Tangents {
    /// The tangents of `perturbed`, started from the run's initial state `y0` at `t0`: each side's
    /// state projected as the run's was, and `S₀ = (y₊ − y₋) / 2δ`.
    pub fn new(
        perturbed: Vec<Perturbed>,
        t0: f64,
        y0: &[f64],
        n_q: usize,
        opts: &IntegratorOptions,
        stabilization: Stabilization,
        baumgarte: Option<Baumgarte>,
    ) -> Result<Self, IntegrationError> {
        let entry = opts.method.entry();
        let mut tangents = Vec::with_capacity(perturbed.len());
        for p in perturbed {
            if p.y_plus.len() != y0.len() || p.y_minus.len() != y0.len() {
                return Err(IntegrationError::Options(format!(
                    "the models changed in '{}' have {} and {} state coordinates, the run has {}",
                    p.name,
                    p.y_plus.len(),
                    p.y_minus.len(),
                    y0.len()
                )));
            }
            if !(p.delta.is_finite() && p.delta > 0.0) {
                return Err(IntegrationError::Options(format!(
                    "the change of '{}' must be positive and finite, got {}",
                    p.name, p.delta
                )));
            }
            let side = |mut f: Box<dyn Formulation>, mut y: Vec<f64>| -> Result<Side, IntegrationError> {
                project(f.as_mut(), t0, &mut y, n_q, stabilization)?;
                let stepper = (entry.build)(
                    &opts.method,
                    Setup {
                        formulation: f.as_mut(),
                        t0,
                        y0: &y,
                        n_q,
                        baumgarte,
                    },
                )?;
                Ok(Side {
                    f,
                    stepper,
                    shown: y.clone(),
                    y,
                })
            };
            let plus = side(p.plus, p.y_plus)?;
            let minus = side(p.minus, p.y_minus)?;
            let s: Vec<f64> = (plus.y.iter().zip(&minus.y))
                .map(|(a, b)| (a - b) / (2.0 * p.delta))
                .collect();
            let work = Work::new(plus.f.as_ref(), y0.len(), n_q);
            tangents.push(Tangent {
                name: p.name,
                delta: p.delta,
                next: s.clone(),
                s,
                sides: [plus, minus],
                carried: None,
                project: false,
                work,
            });
        }
        Ok(Tangents {
            tangents,
            start: vec![0.0; y0.len()],
            adaptive: entry.control == StepControl::Adaptive,
            shown_between: false,
            n_q,
            carried: 0,
            differenced: 0,
            last_carried: false,
            projects: stabilization.projection_tolerance().is_some(),
        })
    }

    /// True when the run has no tangent.
    pub fn is_empty(&self) -> bool {
        self.tangents.is_empty()
    }

    /// Keeps the run's state `y` at the start of a step.
    pub fn mark(&mut self, y: &[f64]) {
        if !self.is_empty() {
            self.start.copy_from_slice(y);
        }
        self.discard();
        self.shown_between = false;
    }

    /// Forgets the tangents a method carried through the step in progress: the step is taken
    /// again (to end at an event), and [`Tangents::follow`] then follows the step taken last.
    pub fn discard(&mut self) {
        for tangent in &mut self.tangents {
            tangent.carried = None;
        }
    }

    /// The run's step from `(t, y)`, of size `h`, carrying the tangents
    /// through it where the method can ([`Stepper::step_tangents`]); [`Tangents::follow`] then
    /// takes them, or differences the step where they were not carried.
    pub fn step(
        &mut self,
        stepper: &mut dyn Stepper,
        f: &mut dyn Formulation,
        t: f64,
        h: f64,
        y: &mut [f64],
    ) -> Result<StepOutcome, IntegrationError> {
        if self.is_empty() {
            return stepper.step(f, t, h, y);
        }
        match stepper.step_tangents(f, t, h, y, self)? {
            Some(outcome) => Ok(outcome),
            None => stepper.step(f, t, h, y),
        }
    }

    /// Follows the run's accepted step of size `h` from `t` (begun at the state [`Tangents::mark`]
    /// kept), where `projected` says whether the run's state was projected after it (each side's
    /// method is then told that its state changed, as the run's is).
    pub fn follow(&mut self, t: f64, h: f64, n_q: usize, projected: bool) -> Result<(), IntegrationError> {
        let (start, adaptive, projects) = (&self.start, self.adaptive, self.projects);
        let mut all_carried = true;
        for tangent in &mut self.tangents {
            // A fixed-step run's projection is not reported to `follow`: its stabilization says.
            tangent.project = projected || (projects && !adaptive);
            let Tangent {
                name,
                delta,
                s,
                sides,
                next,
                carried,
                ..
            } = tangent;
            if carried.take() == Some((t, h)) {
                // Carried through the step by the method; the sides' states were set then, and
                // what their own methods kept of a step is stale.
                s.copy_from_slice(next);
                sides.iter_mut().for_each(|side| side.stepper.state_changed());
                continue;
            }
            all_carried = false;
            for (side, sign) in sides.iter_mut().zip([1.0, -1.0]) {
                for i in 0..start.len() {
                    side.y[i] = start[i] + sign * *delta * s[i];
                }
                let taken = if adaptive {
                    side.stepper.step_unchecked(side.f.as_mut(), t, h, &mut side.y)?
                } else {
                    side.stepper.step(side.f.as_mut(), t, h, &mut side.y)?.accepted
                };
                if !taken {
                    return Err(IntegrationError::Sensitivity {
                        time: t,
                        parameter: name.clone(),
                        what: format!(
                            "the step of {h:e} s the run took was not taken on the model changed by {}{delta:e}",
                            if sign > 0.0 { "+" } else { "-" }
                        ),
                    });
                }
                normalize(side.f.as_ref(), &mut side.y, n_q);
                if projected {
                    side.stepper.state_changed();
                }
            }
            let [plus, minus] = &*sides;
            for i in 0..s.len() {
                s[i] = (plus.y[i] - minus.y[i]) / (2.0 * *delta);
            }
        }
        if !self.tangents.is_empty() {
            match all_carried {
                true => self.carried += 1,
                false => self.differenced += 1,
            }
        }
        self.last_carried = all_carried;
        Ok(())
    }

    /// The steps whose tangents a method carried, and those differenced as whole steps.
    pub fn counts(&self) -> (u64, u64) {
        (self.carried, self.differenced)
    }

    /// Shows each side at fraction `theta` of the last step (dense output of an adaptive method),
    /// normalized but not projected, as the sides' steps are.
    /// After a step the run's method carried the tangents through, each side is the run's dense
    /// output `± δ` the tangent's (`run`, the run's method).
    pub fn show(&mut self, run: &dyn Stepper, theta: f64, n_q: usize) {
        let last_carried = self.last_carried;
        for (j, tangent) in self.tangents.iter_mut().enumerate() {
            let Tangent { delta, sides, work, .. } = tangent;
            if last_carried && run.interpolate_tangent(j, theta, &mut work.y) {
                let [plus, minus] = sides;
                run.interpolate(theta, &mut plus.shown);
                for i in 0..work.y.len() {
                    let (y, s) = (plus.shown[i], *delta * work.y[i]);
                    plus.shown[i] = y + s;
                    minus.shown[i] = y - s;
                }
                for side in sides.iter_mut() {
                    normalize(side.f.as_ref(), &mut side.shown, n_q);
                }
                continue;
            }
            for side in sides.iter_mut() {
                side.stepper.interpolate(theta, &mut side.shown);
                normalize(side.f.as_ref(), &mut side.shown, n_q);
            }
        }
        self.shown_between = !self.is_empty();
    }

    /// The run is shown at its own state: so are the sides.
    pub fn show_run(&mut self) {
        self.shown_between = false;
    }

    /// The number of tangents.
    pub fn len(&self) -> usize {
        self.tangents.len()
    }

    /// Tangent `j`'s side (`plus`: `p + δ`) at the time shown: its formulation and state `[q; v]`.
    pub fn side(&mut self, j: usize, plus: bool) -> (&mut dyn Formulation, &[f64], f64) {
        let between = self.shown_between;
        let tangent = &mut self.tangents[j];
        let side = &mut tangent.sides[usize::from(!plus)];
        let y = if between { &side.shown } else { &side.y };
        (side.f.as_mut(), y, tangent.delta)
    }

    /// The sensitivity `∂y/∂p` of tangent `j` at the run's own state (after the last step).
    pub fn tangent(&self, j: usize) -> &[f64] {
        &self.tangents[j].s
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
    let largest = |v: &[f64]| v.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    let size = largest(s);
    (size > 0.0 && size.is_finite()).then(|| STATE_STEP * (1.0 + largest(y)) / size)
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
    let largest = |v: &[f64]| v.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    delta * largest(s) <= COMBINED_UP_TO * (1.0 + largest(y))
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

/// The constraints `C` (or `Ċ = C_q v + C_t`, `velocities`) of `system` at `y` into `out`.
fn constraint_residual(
    system: &dyn dalembert_system::MultibodySystem,
    t: f64,
    (y, n_q): (&[f64], usize),
    velocities: bool,
    values: &mut ConstraintValues,
    out: &mut [f64],
) {
    let (q, v) = y.split_at(n_q);
    let constraints = system.constraints();
    constraints.evaluate(t, q, v, values);
    match velocities {
        false => out.copy_from_slice(&values.c),
        true => constraints.velocity_residual(values, v, out),
    }
}

/// `out ← scale (a − b)` added to `out` (`add`) or written.
fn difference(out: &mut [f64], a: &[f64], b: &[f64], scale: f64, add: bool) {
    for (o, (a, b)) in out.iter_mut().zip(a.iter().zip(b)) {
        *o = if add { *o } else { 0.0 } + scale * (a - b);
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
    /// then velocities the same way with `Ċ = C_q v + C_t`; the derivatives along the tangent by
    /// differences on the run's model with the step `ε` of [`state_step`], those along the
    /// parameter by the two changed models at the run's state (`docs/sensitivities.md`, (S6)).
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
            for velocities in [false, true] {
                work.h.iter_mut().for_each(|h| *h = 0.0);
                if let Some(eps) = state_step(y, s) {
                    for (k, sign) in [1.0, -1.0].into_iter().enumerate() {
                        for i in 0..y.len() {
                            work.y[i] = y[i] + sign * eps * s[i];
                        }
                        constraint_residual(
                            f.system(),
                            t,
                            (&work.y, n_q),
                            velocities,
                            &mut work.values,
                            &mut work.c[k],
                        );
                    }
                    difference(&mut work.h, &work.c[0], &work.c[1], -0.5 / eps, false);
                }
                for (k, side) in sides.iter().enumerate() {
                    let c = &mut work.c[k];
                    constraint_residual(side.f.system(), t, (y, n_q), velocities, &mut work.values, c);
                }
                difference(&mut work.h, &work.c[0], &work.c[1], -0.5 / delta, true);
                work.g.iter_mut().for_each(|g| *g = 0.0);
                if !f.linear_response(t, &work.g, &work.h, &mut work.dqdd, &mut work.dlambda)? {
                    return Ok(false);
                }
                let (s_q, s_v) = s.split_at_mut(n_q);
                if velocities {
                    s_v.iter_mut().zip(&work.dqdd).for_each(|(a, x)| *a += x);
                } else {
                    // The correction `x` is in velocity coordinates: its change of the
                    // positions is `d(q ⊕ ε x)/dε`, differenced.
                    let largest = work.dqdd.iter().fold(0.0f64, |a, x| a.max(x.abs()));
                    if largest > 0.0 {
                        let eps = STATE_STEP * (1.0 + y[..n_q].iter().fold(0.0f64, |a, x| a.max(x.abs()))) / largest;
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
        if combined(delta, y, s) {
            // One difference along `(s, 1)`: the two changed models at `y ± δ s`.
            for (k, (side, sign)) in sides.iter().zip([1.0, -1.0]).enumerate() {
                for i in 0..y.len() {
                    work.y[i] = y[i] + sign * delta * s[i];
                }
                let moved = std::mem::take(&mut work.y);
                residuals(side.f.system(), t, &moved, n_q, baumgarte, solution, work, k);
                let (q, v) = moved.split_at(n_q);
                side.f.system().position_rates(q, v, &mut work.rates[k]);
                work.y = moved;
            }
            difference(&mut work.g, &work.r[0], &work.r[1], -0.5 / delta, false);
            difference(&mut work.h, &work.c[0], &work.c[1], -0.5 / delta, false);
            difference(rates, &work.rates[0], &work.rates[1], 0.5 / delta, false);
            if !f.linear_response(t, &work.g, &work.h, &mut work.dqdd, &mut work.dlambda)? {
                return Ok(false);
            }
            vdot.copy_from_slice(&work.dqdd);
            return Ok(vdot.iter().chain(rates.iter()).all(|v| v.is_finite()));
        }
        work.g.iter_mut().for_each(|g| *g = 0.0);
        work.h.iter_mut().for_each(|h| *h = 0.0);
        rates.iter_mut().for_each(|r| *r = 0.0);
        if let Some(eps) = state_step(y, s) {
            for (k, sign) in [1.0, -1.0].into_iter().enumerate() {
                for i in 0..y.len() {
                    work.y[i] = y[i] + sign * eps * s[i];
                }
                let moved = std::mem::take(&mut work.y);
                residuals(f.system(), t, &moved, n_q, baumgarte, solution, work, k);
                let (q, v) = moved.split_at(n_q);
                f.system().position_rates(q, v, &mut work.rates[k]);
                work.y = moved;
            }
            difference(&mut work.g, &work.r[0], &work.r[1], -0.5 / eps, false);
            difference(&mut work.h, &work.c[0], &work.c[1], -0.5 / eps, false);
            difference(rates, &work.rates[0], &work.rates[1], 0.5 / eps, false);
        }
        for (k, side) in sides.iter().enumerate() {
            residuals(side.f.system(), t, y, n_q, baumgarte, solution, work, k);
        }
        difference(&mut work.g, &work.r[0], &work.r[1], -0.5 / delta, true);
        difference(&mut work.h, &work.c[0], &work.c[1], -0.5 / delta, true);
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
