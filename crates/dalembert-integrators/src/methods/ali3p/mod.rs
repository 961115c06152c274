//! The index-3 augmented Lagrangian formulation with projections, ALI3-P (Bayo, García de Jalón &
//! Serna, *Comput. Methods Appl. Mech. Eng.* 71, 1988; Bayo & Ledesma, *Nonlinear Dyn.* 9, 1996;
//! Cuadrado, Cardenal, Morer & Bayo, *Multibody Syst. Dyn.* 4, 2000), the method of the IFToMM
//! benchmark's reference solutions. The equations of motion with a penalty `α` on the constraints
//! and multipliers `λ*` found by iteration,
//!
//! ```text
//! M(q) q̈ + C_qᵀ (λ* + α C) = Q(t, q, v),      λ* ← λ* + α C   (each Newton iteration)
//! ```
//!
//! are discretized by the trapezoidal rule (Newmark β = ¼, γ = ½) with the system's position
//! update `q ⊕ h Δq` (`q + h Δq` for planar bodies, the Lie-group update for Euler parameters):
//!
//! ```text
//! q_{n+1} = q_n ⊕ h Δq,   Δq = v_n + (h/4)(a_n + a_{n+1}),   v_{n+1} = v_n + (h/2)(a_n + a_{n+1})
//! ```
//!
//! Newton iterates on `a_{n+1}` with the leading matrix ([`leading_matrix`])
//!
//! ```text
//! f_q = M + (h/2) ∂r/∂v + (h²/4) (∂r/∂q + α C_qᵀ C_q),   r = M a + C_qᵀ (λ* + α C) − Q,
//! ```
//!
//! `∂r/∂q`, `∂r/∂v` from the system's analytic tangent (differences where it has none). The
//! penalty term keeps `f_q` regular where `C_q` loses rank (singular positions) or has dependent
//! rows (redundant constraints): no rank decision is taken, the inertia of the bodies carries the
//! motion through the pass. After Newton the velocities and accelerations are projected with the
//! same matrix (Cuadrado et al. 2000, eqs. 9–10):
//!
//! ```text
//! f_q v = f_q v* − (h²/4) α C_qᵀ (C_q v* + C_t),     f_q a = f_q a* − (h²/4) α C_qᵀ (C_q a* − Q_d)
//! ```
//!
//! `α` is a stiffness (N/m for an equation in metres); the default (`penalty = 0`) chooses it per
//! step so that `(h²/4) α` is [`ALI3P_AUTOMATIC_RATIO`] times the largest diagonal entry of the mass
//! matrix: the multipliers then converge by that factor per iteration, and the matrix keeps ten
//! digits for the motion. Second order; `C = 0` to the Newton tolerance at every step. On Newton
//! failure the step is halved and grows back after successful steps.

mod leading_matrix;

use crate::registry::{no_advice, Applies, MethodEntry, Parameter, TradeAxis};
use crate::stepper::{Setup, StepControl, StepOutcome, Stepper};
use crate::{IntegrationError, Method};
use dalembert_system::linalg::LinalgError;
use dalembert_system::{
    BlockDiagonal, ConstraintValues, DynamicsError, Formulation, FormulationStats, MultibodySystem, TangentAt,
};
use leading_matrix::LeadingMatrix;

/// `(h²/4) α` over the largest diagonal entry of `M` with the automatic penalty.
pub const ALI3P_AUTOMATIC_RATIO: f64 = 1e6;

/// The registry entry.
pub(crate) static ENTRY: MethodEntry = MethodEntry {
    name: "ali3-p",
    aliases: &["ali3p"],
    summary: "augmented Lagrangian index-3 with projections (trapezoidal rule): order 2, implicit, passes singular positions and redundant constraints",
    order: 2,
    control: StepControl::Fixed,
    keeps_constraints: true,
    applies: Applies::AugmentedIndex3,
    parameters: &[Parameter {
        key: "penalty",
        default: 0.0,
        doc: "penalty stiffness alpha on the constraints (N/m for an equation in metres); 0 chooses (h^2/4) alpha = 1e6 times the largest diagonal entry of M",
        valid: non_negative,
        expected: "must be positive, or 0 for the automatic value",
    }],
    trade: TradeAxis::Steps,
    advice: no_advice,
    build,
};

fn non_negative(v: f64) -> bool {
    v.is_finite() && v >= 0.0
}

impl Method {
    /// ALI3-P: the trapezoidal rule on the index-3 augmented Lagrangian equations with velocity
    /// and acceleration projections. `penalty`: the stiffness `α` (N/m for an equation in metres),
    /// or 0 for the automatic value (`(h²/4) α` = [`ALI3P_AUTOMATIC_RATIO`] × the largest diagonal entry
    /// of the mass matrix).
    pub fn ali3p(penalty: f64) -> Self {
        let mut m = Method::of(&ENTRY);
        m.set(0, penalty);
        m
    }
}

fn build(m: &Method, s: Setup<'_>) -> Result<Box<dyn Stepper>, IntegrationError> {
    let f = s.formulation;
    let (q0, qd0) = s.y0.split_at(s.n_q);
    let (n_v, m_eq) = (qd0.len(), f.system().num_equations());
    if f.system().force_coupling().is_none() && !dalembert_system::structure::dense_fits(n_v, n_v) {
        return Err(IntegrationError::Options(format!(
            "ali3-p: a force element does not declare the bodies it acts on (ForceElement::bodies), so its leading matrix couples every body: {n_v} × {n_v} dense is too large; declare the bodies, or use rk4 or dopri5"
        )));
    }
    let system = f.system();
    let mut mass = system.mass_storage();
    system.mass(q0, &mut mass);
    let largest = mass
        .entries()
        .filter(|(i, j, _)| i == j)
        .fold(0.0f64, |a, (_, _, v)| a.max(v));
    let matrix = LeadingMatrix::new(system, &mass).map_err(|e| DynamicsError::Singular {
        time: s.t0,
        what: format!("ALI3-P's leading matrix: {e}"),
    })?;
    let mut stepper = Ali3p {
        penalty: m.value(0),
        mass_scale: largest,
        a: vec![0.0; n_v],
        lambda: vec![0.0; m_eq],
        a_prev: vec![0.0; n_v],
        lambda_prev: vec![0.0; m_eq],
        h_prev: f64::NAN,
        matrix,
        values: system.constraints().values(),
        mass,
        work: Work {
            a: vec![0.0; n_v],
            q1: vec![0.0; s.n_q],
            v1: vec![0.0; n_v],
            delta: vec![0.0; n_v],
            res: vec![0.0; n_v],
            dx: vec![0.0; n_v],
            lam: vec![0.0; m_eq],
            eq: vec![0.0; m_eq],
        },
        restart: false,
        tolerance: 1e-10,
        iterations: 0,
        factorizations: 0,
        evaluations: 0,
    };
    stepper.start_at(f, s.t0, q0, qd0)?;
    Ok(Box::new(stepper))
}

/// State carried between steps and the storage of one step.
struct Ali3p {
    /// The parameter `α` (0: automatic).
    penalty: f64,
    /// The largest diagonal entry of `M` at the start (the automatic penalty's scale).
    mass_scale: f64,
    /// Accelerations `a_n` and multipliers `λ*_n` of the last step.
    a: Vec<f64>,
    lambda: Vec<f64>,
    /// Those of the step before and its size (NaN: no history), for the predictor.
    a_prev: Vec<f64>,
    lambda_prev: Vec<f64>,
    h_prev: f64,
    matrix: LeadingMatrix,
    values: ConstraintValues,
    mass: BlockDiagonal,
    work: Work,
    /// The next step starts from consistent accelerations at its state.
    restart: bool,
    /// Newton tolerance on the position update and on `‖C‖∞`.
    tolerance: f64,
    iterations: u64,
    factorizations: u64,
    evaluations: u64,
}

/// Storage allocated once.
struct Work {
    /// The trial `a_{n+1}`, positions, velocities, `Δq`.
    a: Vec<f64>,
    q1: Vec<f64>,
    v1: Vec<f64>,
    delta: Vec<f64>,
    /// Residual and Newton update (`n_v`).
    res: Vec<f64>,
    dx: Vec<f64>,
    /// The trial `λ*` and the multipliers `λ* + α C` the residual uses (`m`); then `Ċ`, `C̈`.
    lam: Vec<f64>,
    eq: Vec<f64>,
}

/// Newton did not converge (or produced non-finite values).
struct NotConverged;

impl Ali3p {
    /// Starts at `(t, q, v)` from the formulation's consistent accelerations and multipliers.
    fn start_at(&mut self, f: &mut dyn Formulation, t: f64, q: &[f64], v: &[f64]) -> Result<(), DynamicsError> {
        f.accelerations(t, q, v, None, &mut self.a, &mut self.lambda)?;
        self.h_prev = f64::NAN;
        self.restart = false;
        Ok(())
    }

    /// The penalty `α` for step `h`.
    fn alpha(&self, h: f64) -> f64 {
        if self.penalty > 0.0 {
            self.penalty
        } else {
            ALI3P_AUTOMATIC_RATIO * self.mass_scale / (0.25 * h * h)
        }
    }

    /// Positions and velocities of the trial `a_{n+1}` in `work.a`.
    fn predict(&mut self, system: &dyn MultibodySystem, h: f64, q: &[f64], v: &[f64]) {
        let w = &mut self.work;
        for i in 0..v.len() {
            w.delta[i] = v[i] + 0.25 * h * (self.a[i] + w.a[i]);
            w.v1[i] = v[i] + 0.5 * h * (self.a[i] + w.a[i]);
        }
        w.q1.copy_from_slice(q);
        system.integrate_positions(&mut w.q1, &w.delta, h);
    }

    /// One step from `(t, q, v)` to `t + h`; on success `q`, `v` hold the new state.
    fn advance(
        &mut self,
        system: &dyn MultibodySystem,
        t: f64,
        h: f64,
        q: &mut [f64],
        v: &mut [f64],
    ) -> Result<(), NotConverged> {
        // Iterations per step; in a steady linear phase (contraction below `LINEAR_RATE`) up to
        // `MAX_LINEAR_ITERATIONS`: halving the step at a singular position only lands nearer it,
        // where the contraction is slower still.
        const MAX_ITERATIONS: usize = 20;
        const MAX_LINEAR_ITERATIONS: usize = 200;
        const LINEAR_RATE: f64 = 0.995;
        // Relative acceleration update at convergence, as generalized-α's; the round-off floor of
        // the positions (`ROUND_OFF_ULPS` units in the last place) in acceleration units.
        const ACCELERATION_TOLERANCE: f64 = 1e-10;
        const ROUND_OFF_ULPS: f64 = 8.0;
        // Contraction rate above which the iteration is in its linear phase (see `accurate`), and
        // the matrix is rebuilt once at the current iterate with a fresh tangent.
        const SLOW_RATE: f64 = 0.5;
        // Largest growth of the acceleration scale within one step.
        const GROWTH: f64 = 100.0;
        let (beta, gamma) = (0.25 * h * h, 0.5 * h);
        let alpha = self.alpha(h);
        let t1 = t + h;
        let sys = system.constraints();
        // Start from the linear extrapolation of the last two steps' accelerations and
        // multipliers (their error is O(h²) against O(h) for the last values).
        let ratio = super::step_ratio(h, self.h_prev);
        super::extrapolate(&mut self.work.a, &self.a, &self.a_prev, ratio);
        super::extrapolate(&mut self.work.lam, &self.lambda, &self.lambda_prev, ratio);
        let start_scale = 1.0 + self.a.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let mut factored = false;
        let mut rebuilt = false;
        let mut last_rel = f64::INFINITY;
        let mut budget = MAX_ITERATIONS;
        let mut it = 0;
        while it < budget {
            self.predict(system, h, q, v);
            let w = &mut self.work;
            sys.evaluate(t1, &w.q1, &w.v1, &mut self.values);
            // λ* ← λ* + α C after each Newton update; the residual takes λ* + α C.
            if it > 0 {
                for (l, c) in w.lam.iter_mut().zip(&self.values.c) {
                    *l += alpha * c;
                }
            }
            for ((e, l), c) in w.eq.iter_mut().zip(&w.lam).zip(&self.values.c) {
                *e = l + alpha * c;
            }
            system.dynamics_residual_evaluated(
                t1,
                (&w.q1, &w.v1),
                (&w.a, &w.eq),
                (&mut self.mass, &self.values),
                &mut w.res,
            );
            self.evaluations += 1;
            if w.res.iter().any(|x| !x.is_finite()) {
                return Err(self.fail());
            }
            // The matrix is built at the first iterate of each step, and once more (with a fresh
            // tangent) when the iteration contracts slowly.
            if !factored {
                if !self.matrix.reusable() {
                    let at = TangentAt {
                        t: t1,
                        q: &w.q1,
                        v: &w.v1,
                        qdd: &w.a,
                        lambda: &w.eq,
                    };
                    self.evaluations += self.matrix.differentiate(system, &mut self.mass, &mut self.values, &at);
                }
                if self
                    .matrix
                    .factor(&self.mass, &self.values, (beta, gamma), beta * alpha)
                    .is_err()
                {
                    return Err(self.fail());
                }
                self.factorizations += 1;
                factored = true;
            }
            let w = &mut self.work;
            for (d, r) in w.dx.iter_mut().zip(&w.res) {
                *d = -r;
            }
            self.matrix.solve(&mut w.dx);
            self.iterations += 1;
            let mut da = 0.0f64;
            for (a, d) in w.a.iter_mut().zip(&w.dx) {
                *a += d;
                da = da.max(d.abs());
            }
            if !da.is_finite() {
                return Err(self.fail());
            }
            let ascale = 1.0 + w.a.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            // Accelerations grown by orders of magnitude within one step: Newton has left its
            // region of convergence and may settle on a spurious solution of the discrete
            // equations (the chain of 8 links' whip did, at 3e11 m/s²); halve the step.
            if ascale > GROWTH * start_scale {
                return Err(self.fail());
            }
            let qscale = 1.0 + w.q1.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            let rel = da / ascale;
            let floor = ROUND_OFF_ULPS * f64::EPSILON * qscale / (beta * ascale);
            let contraction = rel / last_rel;
            last_rel = rel;
            // The accelerations have converged (or converge fast enough that the error left,
            // about `θ/(1 − θ)` times the update for a contraction rate `θ`, is below the
            // tolerance), or the iteration is in its linear phase: near a singular position the
            // multiplier update `λ* ← λ* + α C` contracts by `1/(1 + (h²/4) α σ²/m)` along the
            // directions where `C_q`'s singular value `σ` vanishes. There the constraints hold
            // only to second order whatever the accelerations, so once the positions have
            // converged the step is taken and the projections with `M + (h²/4) α C_qᵀ C_q` set
            // the velocities and accelerations (Bayo & Ledesma 1996).
            let accurate = rel <= ACCELERATION_TOLERANCE.max(floor)
                || (it > 0 && contraction < 0.5 && contraction / (1.0 - contraction) * rel <= ACCELERATION_TOLERANCE)
                || (it >= 2 && contraction >= SLOW_RATE);
            if beta * da <= self.tolerance * qscale && accurate {
                self.predict(system, h, q, v);
                let w = &mut self.work;
                sys.evaluate(t1, &w.q1, &w.v1, &mut self.values);
                let cmax = self.values.c.iter().fold(0.0f64, |m, c| m.max(c.abs()));
                if cmax <= self.tolerance {
                    for (l, c) in w.lam.iter_mut().zip(&self.values.c) {
                        *l += alpha * c;
                    }
                    if self.project(system, t1, beta * alpha).is_err() {
                        return Err(self.fail());
                    }
                    let w = &self.work;
                    q.copy_from_slice(&w.q1);
                    v.copy_from_slice(&w.v1);
                    std::mem::swap(&mut self.a_prev, &mut self.a);
                    std::mem::swap(&mut self.lambda_prev, &mut self.lambda);
                    self.a.copy_from_slice(&w.a);
                    self.lambda.copy_from_slice(&w.lam);
                    self.h_prev = h;
                    return Ok(());
                }
            }
            if it >= 2 && contraction > SLOW_RATE && !rebuilt {
                rebuilt = true;
                factored = false;
                self.matrix.invalidate();
            }
            if it >= 2 && rebuilt && (SLOW_RATE..LINEAR_RATE).contains(&contraction) {
                budget = MAX_LINEAR_ITERATIONS;
            }
            it += 1;
        }
        Err(self.fail())
    }

    /// Projects `work.v1` and then `work.a` onto the velocity and acceleration constraints at
    /// `(t1, work.q1)` with `P = M + weight C_qᵀ C_q` (`weight = (h²/4) α`): `P v = M v* − weight
    /// C_qᵀ C_t`, the same for the accelerations with `−Q_d`. `values` must hold `(t1, q1, v1)`.
    fn project(&mut self, system: &dyn MultibodySystem, t1: f64, weight: f64) -> Result<(), LinalgError> {
        let sys = system.constraints();
        system.mass(&self.work.q1, &mut self.mass);
        self.matrix.factor_projection(&self.mass, &self.values, weight)?;
        let w = &mut self.work;
        // `P v = M v* − weight C_qᵀ C_t` is `v = v* − P⁻¹ weight C_qᵀ (C_q v* + C_t)`.
        sys.velocity_residual(&self.values, &w.v1, &mut w.eq);
        w.dx.fill(0.0);
        sys.jacobian_transpose_mul_add(&self.values, -weight, &w.eq, &mut w.dx);
        self.matrix.solve_projection(&mut w.dx);
        for (x, d) in w.v1.iter_mut().zip(&w.dx) {
            *x += d;
        }
        // Accelerations: `Q_d` depends on the projected velocities.
        sys.evaluate(t1, &w.q1, &w.v1, &mut self.values);
        sys.jacobian_mul(&self.values, &w.a, &mut w.eq);
        for (e, g) in w.eq.iter_mut().zip(&self.values.gamma) {
            *e -= g;
        }
        w.dx.fill(0.0);
        sys.jacobian_transpose_mul_add(&self.values, -weight, &w.eq, &mut w.dx);
        self.matrix.solve_projection(&mut w.dx);
        for (x, d) in w.a.iter_mut().zip(&w.dx) {
            *x += d;
        }
        Ok(())
    }

    /// Forgets the tangent and the history after a failed step.
    fn fail(&mut self) -> NotConverged {
        self.matrix.invalidate();
        self.h_prev = f64::NAN;
        NotConverged
    }
}

impl Stepper for Ali3p {
    fn step(
        &mut self,
        f: &mut dyn Formulation,
        t: f64,
        h: f64,
        y: &mut [f64],
    ) -> Result<StepOutcome, IntegrationError> {
        let n_v = self.a.len();
        let (q, v) = y.split_at_mut(y.len() - n_v);
        if self.restart {
            self.start_at(f, t, q, v)?;
        }
        Ok(match self.advance(f.system(), t, h, q, v) {
            Ok(()) => StepOutcome::taken(h),
            Err(NotConverged) => StepOutcome {
                accepted: false,
                error: f64::NAN,
                next_step: 0.5 * h,
            },
        })
    }

    /// The trapezoidal rule is unconditionally stable on linear problems: growth is the model's
    /// own, or Newton followed a wrong solution.
    fn divergence_hint(&self, _h: f64) -> String {
        "ali3-p has no stability limit on linear problems: the model's own motion grows here, or Newton followed a wrong solution; a smaller step tells which".into()
    }

    /// The state was set from outside: the next step starts from consistent accelerations there.
    fn state_changed(&mut self) {
        self.restart = true;
    }

    fn work(&self) -> FormulationStats {
        FormulationStats {
            evaluations: self.evaluations,
            factorizations: self.factorizations,
            newton_iterations: self.iterations,
            repartitions: 0,
            handovers: 0,
        }
    }
}
