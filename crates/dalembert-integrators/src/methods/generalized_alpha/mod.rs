//! Generalized-α on the index-3 form (Arnold & Brüls, *Multibody Syst. Dyn.* 18, 2007):
//!
//! ```text
//! q_{n+1} = q_n ⊕ h Δq_n,   Δq_n = v_n + h(½ − β) a_n + h β a_{n+1}
//! v_{n+1} = v_n + h(1 − γ) a_n + h γ a_{n+1}
//! (1 − α_m) a_{n+1} + α_m a_n = (1 − α_f) q̈_{n+1} + α_f q̈_n
//! M(q) q̈ + C_qᵀ λ = Q_e(q, q̇, t),   C(q, t) = 0            at t_{n+1}
//! ```
//!
//! with `α_m = (2ρ∞ − 1)/(ρ∞ + 1)`, `α_f = ρ∞/(ρ∞ + 1)`, `γ = ½ + α_f − α_m`, `β = ¼(γ + ½)²`:
//! second order, unconditionally stable, numerical damping of the highest frequencies set by the
//! spectral radius at infinity `ρ∞ ∈ [0, 1]`. `q ⊕ h Δq` is the system's position update
//! ([`MultibodySystem::integrate_positions`]): `q + h Δq` for planar bodies, and for Euler parameters
//! with angular velocities the Lie-group form of Brüls, Cardona & Arnold (*Mech. Mach. Theory* 48,
//! 2012), which keeps the method's second order. Newton iterates on `(q̈_{n+1}, λ_{n+1})` with
//!
//! ```text
//! [ M + β' K + γ' D   C_qᵀ ] [Δq̈]     [ M q̈ + C_qᵀ λ − Q_e ]
//! [ C_q               0    ] [Δλ] = − [ C / β'              ]
//! ```
//!
//! `β' = h² β (1 − α_f)/(1 − α_m)`, `γ' = h γ (1 − α_f)/(1 − α_m)`, `K = ∂(M q̈ + C_qᵀ λ − Q_e)/∂q`,
//! `D = −∂Q_e/∂v` (`∂/∂q` along the velocity coordinates: `q ⊕ ε e_j`). The matrix is sparse, on
//! the pattern the system declares, and `K`, `D` come from the system's analytic tangent
//! ([`dalembert_system::MultibodySystem::residual_tangent`]) where it gives one, otherwise from
//! central differences of the residual with structurally independent columns perturbed together
//! ([`iteration_matrix`]). Newton is modified: the factors are reused across
//! iterations and steps while they contract fast; a slow contraction first refreshes the matrix
//! (mass and `C_q` at the current state, kept `K`, `D`), then differentiates again. Newton stops
//! when the position update and `‖C‖∞` are below the tolerance **and** the acceleration update is
//! below 1e-10 of the acceleration scale (or has stalled at the round-off floor of `C/β'`, below
//! 1e-6 of it): a test on the positions alone (`β' ∝ h²`) accepts one inexact iteration at small
//! steps, and the velocity error then grows as `1/h` (`tests/ga_order_small_steps.rs`: second order
//! from h = 3.2e-4 down to 1e-5). The positions satisfy `C = 0` to the Newton tolerance at every
//! step: no drift. On Newton failure the step is halved (down to the minimum step) and grows back
//! after successful steps.
//!
//! This method always solves the index-3 system of the model; the formulation supplies the initial
//! accelerations and the accelerations and multipliers reported at the output times.

mod iteration_matrix;

use crate::registry::{unit_interval, Applies, MethodEntry, Parameter, TradeAxis};
use crate::stepper::{Setup, StepControl, StepOutcome, Stepper};
use crate::{IntegrationError, Method};
use dalembert_system::linalg::{LinalgError, SaddlePoint};
use dalembert_system::{
    BlockDiagonal, ConstraintValues, DynamicsError, Formulation, FormulationStats, MultibodySystem,
};
use iteration_matrix::{IterationMatrix, Trial};

/// The registry entry.
pub(crate) static ENTRY: MethodEntry = MethodEntry {
    name: "generalized-alpha",
    aliases: &[],
    summary: "generalized-alpha on the index-3 augmented equations: order 2, implicit, C = 0 to the Newton tolerance",
    order: 2,
    control: StepControl::Fixed,
    keeps_constraints: true,
    applies: Applies::AugmentedIndex3,
    parameters: &[Parameter {
        key: "rho_inf",
        default: 0.8,
        doc: "spectral radius at infinite frequency: 0 damps the highest frequencies most, 1 not at all",
        valid: unit_interval,
        expected: "must lie in [0, 1]",
    }],
    trade: TradeAxis::Steps,
    advice,
    build,
};

impl Method {
    /// Generalized-α on the index-3 form, implicit, with Newton iterations; the step is halved on
    /// Newton failure and grows back after successes. `rho_inf`: spectral radius at infinite
    /// frequency, 0 (maximal damping) to 1 (none).
    pub fn generalized_alpha(rho_inf: f64) -> Self {
        let mut m = Method::of(&ENTRY);
        m.set(0, rho_inf);
        m
    }
}

fn advice(m: &Method) -> Option<String> {
    let rho = m.value(0);
    (rho > 0.99).then(|| {
        format!(
            "rho_inf = {rho} leaves the index-3 form without numerical damping: the velocity constraints drift and the run can fail (docs/integrators.md); 0.99 or less is stable"
        )
    })
}

fn build(m: &Method, s: Setup<'_>) -> Result<Box<dyn Stepper>, IntegrationError> {
    let f = s.formulation;
    let (q0, qd0) = s.y0.split_at(s.n_q);
    let (n_v, m_eq) = (qd0.len(), f.system().num_equations());
    // Its iteration matrix is sparse on the couplings the system declares; a force element that
    // does not declare its bodies couples all of them (a dense matrix): refuse sizes that cannot
    // hold it, by name, instead of failing in the allocator.
    let k = n_v + m_eq;
    if f.system().force_coupling().is_none() && !dalembert_system::structure::dense_fits(k, k) {
        return Err(IntegrationError::Options(format!(
            "generalized-alpha: a force element does not declare the bodies it acts on (ForceElement::bodies), so its iteration matrix couples every body: {k} × {k} dense ({:.1} GiB) is too large; declare the bodies, or use rk4 or dopri5",
            (k as f64) * (k as f64) * 8.0 / 1073741824.0
        )));
    }
    let (mut qdd, mut lambda) = (vec![0.0; n_v], vec![0.0; m_eq]);
    f.accelerations(s.t0, q0, qd0, None, &mut qdd, &mut lambda)?;
    // The formulation accepted the start, so a singular saddle-point matrix here means redundant
    // constraints under the minimum-norm treatment: iterate on an independent set of equations.
    let independent = independent_equations(f.system(), s.t0, q0, qd0);
    let ga = GeneralizedAlpha::new(f.system(), m.value(0), &qdd, &lambda, q0, independent).map_err(|e| {
        DynamicsError::Singular {
            time: s.t0,
            what: format!("generalized-alpha's iteration matrix: {e}"),
        }
    })?;
    Ok(Box::new(ga))
}

/// `None` when `[M C_qᵀ; C_q 0]` factors at `(t, q, v)` (as the augmented formulation factors it);
/// otherwise the independent equations of the structure analysis at the minimum-norm rank
/// tolerance (`None` too when that finds full rank, or the analysis cannot run). Setup only.
fn independent_equations(model: &dyn MultibodySystem, t: f64, q: &[f64], v: &[f64]) -> Option<Vec<usize>> {
    let sys = model.constraints();
    let mut values = sys.values();
    sys.evaluate(t, q, v, &mut values);
    let mut mass = model.mass_storage();
    model.mass(q, &mut mass);
    let kkt = SaddlePoint::new(
        dalembert_system::linalg::Backend::Auto,
        &mass,
        model.mass_is_constant(),
        sys,
        iteration_matrix::KKT_DENSE_LIMIT,
        iteration_matrix::KKT_PIVOT_TOLERANCE,
    );
    if kkt.is_ok_and(|mut k| k.factor(&mass, sys.pattern(), &values).is_ok()) {
        return None;
    }
    let s = sys
        .analyse_structure(&values, dalembert_system::structure::MINIMUM_NORM_RANK_TOLERANCE)
        .ok()?;
    (s.rank < s.equations).then_some(s.independent_rows)
}

impl Stepper for GeneralizedAlpha {
    fn step(
        &mut self,
        f: &mut dyn Formulation,
        t: f64,
        h: f64,
        y: &mut [f64],
    ) -> Result<StepOutcome, IntegrationError> {
        let (q, qd) = y.split_at_mut(y.len() - self.qdd.len());
        if self.restart {
            self.start_at(f, t, q, qd)?;
        }
        Ok(match self.advance(f.system(), t, h, q, qd) {
            Ok(()) => StepOutcome::taken(h),
            Err(NotConverged) => StepOutcome {
                accepted: false,
                error: f64::NAN,
                next_step: 0.5 * h,
            },
        })
    }

    /// Not a stability limit: the method is unconditionally stable on linear problems. Without
    /// numerical damping (ρ∞ = 1) the index-3 form lets the velocity constraints drift until the
    /// run blows up (docs/integrators.md); otherwise the model itself grows, or Newton followed a
    /// wrong branch.
    fn divergence_hint(&self, _h: f64) -> String {
        if self.rho_inf > 0.99 {
            format!(
                "generalized-alpha has no stability limit, but with rho_inf = {} it does not damp the index-3 form's highest frequencies and the velocity constraints drift until the run blows up: use rho_inf = 0.99 or less (docs/integrators.md)",
                self.rho_inf
            )
        } else {
            "generalized-alpha has no stability limit on linear problems: the model's own motion grows here, or Newton followed a wrong solution; a smaller step tells which".into()
        }
    }

    /// The state was set from outside (a simulator's `set_state`, or an input changed between
    /// two steps): the next step starts again from consistent `q̈`, `λ` there, as at the start
    /// of a run, without the history of the steps before.
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

/// Coefficients of the method for a spectral radius `ρ∞`.
#[derive(Debug, Clone, Copy)]
struct Coefficients {
    alpha_m: f64,
    alpha_f: f64,
    gamma: f64,
    beta: f64,
}

impl Coefficients {
    pub fn new(rho_inf: f64) -> Self {
        let r = rho_inf.clamp(0.0, 1.0);
        let alpha_m = (2.0 * r - 1.0) / (r + 1.0);
        let alpha_f = r / (r + 1.0);
        let gamma = 0.5 + alpha_f - alpha_m;
        let beta = 0.25 * (gamma + 0.5).powi(2);
        Coefficients {
            alpha_m,
            alpha_f,
            gamma,
            beta,
        }
    }
}

/// State carried between steps: the pseudo-acceleration `a` and the last `q̈`, `λ`.
struct GeneralizedAlpha {
    coef: Coefficients,
    rho_inf: f64,
    a: Vec<f64>,
    qdd: Vec<f64>,
    lambda: Vec<f64>,
    /// `q̈`, `λ` of the step before and that step's size (NaN: no history): Newton starts from
    /// their linear extrapolation.
    qdd_prev: Vec<f64>,
    lambda_prev: Vec<f64>,
    h_prev: f64,
    mass: BlockDiagonal,
    values: ConstraintValues,
    work: Work,
    matrix: IterationMatrix,
    /// Step size the current factors were built for (NaN: none), and how many steps they have
    /// served (modified Newton: kept across steps while Newton contracts fast).
    matrix_h: f64,
    matrix_age: u32,
    /// The next step starts from consistent `q̈`, `λ` at its state ([`Stepper::state_changed`]).
    restart: bool,
    /// Newton tolerance on the position update and on `‖C‖∞`.
    pub tolerance: f64,
    /// Newton iterations spent (cumulative).
    pub iterations: u64,
    /// Iteration-matrix factorizations (cumulative).
    pub factorizations: u64,
    /// Residual evaluations (cumulative).
    pub evaluations: u64,
}

/// Storage allocated once: trial state, residual and Newton update.
struct Work {
    qdd: Vec<f64>,
    lam: Vec<f64>,
    q1: Vec<f64>,
    qd1: Vec<f64>,
    /// `Δq_n` of the position update.
    delta: Vec<f64>,
    res: Vec<f64>,
    dx: Vec<f64>,
}

impl Work {
    fn new(n_q: usize, n: usize, m: usize) -> Self {
        let k = n + m;
        Work {
            qdd: vec![0.0; n],
            lam: vec![0.0; m],
            q1: vec![0.0; n_q],
            qd1: vec![0.0; n],
            delta: vec![0.0; n],
            res: vec![0.0; k],
            dx: vec![0.0; k],
        }
    }
}

/// `r = M q̈ + C_qᵀ λ − Q_e` and `C / β'` at `(t, q, q̇)` into `out`; refreshes `mass` and `values`.
#[allow(clippy::too_many_arguments)]
fn residual(
    mass: &mut BlockDiagonal,
    values: &mut ConstraintValues,
    model: &dyn MultibodySystem,
    t: f64,
    (q, qd): (&[f64], &[f64]),
    (qdd, lambda): (&[f64], &[f64]),
    bp: f64,
    out: &mut [f64],
) {
    let (r, c) = out.split_at_mut(qd.len());
    model.dynamics_residual(t, (q, qd), (qdd, lambda), (mass, values), r);
    for (ci, v) in c.iter_mut().zip(&values.c) {
        *ci = v / bp;
    }
}

/// Newton did not converge (or produced non-finite values) within the iteration limit.
struct NotConverged;

impl GeneralizedAlpha {
    /// Starts from consistent `q̈₀`, `λ₀` (from the formulation). `Err` when the sparse analysis of
    /// the iteration matrix fails.
    pub fn new(
        model: &dyn MultibodySystem,
        rho_inf: f64,
        qdd0: &[f64],
        lambda0: &[f64],
        q0: &[f64],
        independent: Option<Vec<usize>>,
    ) -> Result<Self, LinalgError> {
        let mut mass = model.mass_storage();
        model.mass(q0, &mut mass);
        let matrix = IterationMatrix::new(model, &mass, independent)?;
        // Masked (dropped) equations carry no multiplier in the iteration.
        let m = lambda0.len();
        let mut lambda0 = lambda0.to_vec();
        for &d in matrix.dropped() {
            lambda0[d] = 0.0;
        }
        Ok(GeneralizedAlpha {
            coef: Coefficients::new(rho_inf),
            rho_inf,
            a: qdd0.to_vec(),
            qdd: qdd0.to_vec(),
            lambda: lambda0.clone(),
            qdd_prev: qdd0.to_vec(),
            lambda_prev: lambda0,
            h_prev: f64::NAN,
            matrix,
            mass,
            values: model.constraints().values(),
            work: Work::new(q0.len(), qdd0.len(), m),
            restart: false,
            tolerance: 1e-10,
            iterations: 0,
            factorizations: 0,
            matrix_h: f64::NAN,
            matrix_age: 0,
            evaluations: 0,
        })
    }

    /// Starts again at `(t, q, q̇)` as [`GeneralizedAlpha::new`] does: `a = q̈`, no history.
    fn start_at(&mut self, f: &mut dyn Formulation, t: f64, q: &[f64], qd: &[f64]) -> Result<(), DynamicsError> {
        f.accelerations(t, q, qd, None, &mut self.qdd, &mut self.lambda)?;
        for &d in self.matrix.dropped() {
            self.lambda[d] = 0.0;
        }
        self.a.copy_from_slice(&self.qdd);
        self.qdd_prev.copy_from_slice(&self.qdd);
        self.lambda_prev.copy_from_slice(&self.lambda);
        self.h_prev = f64::NAN;
        self.restart = false;
        Ok(())
    }

    /// Positions and velocities for the trial `q̈_{n+1}` in `work.qdd` (into `work.q1`, `work.qd1`).
    fn predict(&mut self, model: &dyn MultibodySystem, h: f64, q: &[f64], qd: &[f64]) {
        let c = self.coef;
        let w = &mut self.work;
        for i in 0..qd.len() {
            let a_new =
                ((1.0 - c.alpha_f) * w.qdd[i] + c.alpha_f * self.qdd[i] - c.alpha_m * self.a[i]) / (1.0 - c.alpha_m);
            w.delta[i] = qd[i] + h * ((0.5 - c.beta) * self.a[i] + c.beta * a_new);
            w.qd1[i] = qd[i] + h * ((1.0 - c.gamma) * self.a[i] + c.gamma * a_new);
        }
        w.q1.copy_from_slice(q);
        model.integrate_positions(&mut w.q1, &w.delta, h);
    }

    /// One step from `(t, q, q̇)` to `t + h`; on success `q`, `qd` hold the new state (the loop
    /// normalizes it).
    fn advance(
        &mut self,
        model: &dyn MultibodySystem,
        t: f64,
        h: f64,
        q: &mut [f64],
        qd: &mut [f64],
    ) -> Result<(), NotConverged> {
        const MAX_ITERATIONS: usize = 12;
        // Relative acceleration update at convergence, and the level below which an update that
        // no longer halves counts as converged to round-off.
        const ACCELERATION_TOLERANCE: f64 = 1e-10;
        const STALL_FLOOR: f64 = 1e-6;
        const ROUND_OFF_ULPS: f64 = 8.0;
        // Contraction rate above which the matrix is rebuilt (measured on chains of 16 and 64
        // links: 0.3 lets Newton fail and halve the step a few times in 10 s, 0.05 rebuilds a third
        // more often than 0.1 for no fewer iterations).
        const SLOW_RATE: f64 = 0.1;
        // Steps the factors with the tangent terms serve at most (the saddle-point factors without
        // them are rebuilt every step: they cost about what one Newton iteration does).
        const MATRIX_LIFETIME: u32 = 20;
        let mut last_rel = f64::INFINITY;
        let mut last_contraction = 0.0f64;
        let n = qd.len();
        let m = self.lambda.len();
        let c = self.coef;
        let bp = h * h * c.beta * (1.0 - c.alpha_f) / (1.0 - c.alpha_m);
        let gp = h * c.gamma * (1.0 - c.alpha_f) / (1.0 - c.alpha_m);
        let t1 = t + h;
        // Start from the linear extrapolation of the last two steps' q̈ and λ: its error is O(h²)
        // against O(h) for the last values (measured on a chain of 16 links at h = 1e-3: the first
        // update falls from 1.7e-2 to ~1e-4 of the acceleration scale).
        let ratio = super::step_ratio(h, self.h_prev);
        super::extrapolate(&mut self.work.qdd, &self.qdd, &self.qdd_prev, ratio);
        super::extrapolate(&mut self.work.lam, &self.lambda, &self.lambda_prev, ratio);
        // Factors built for this step size are reused (modified Newton) until they have served
        // `MATRIX_LIFETIME` steps.
        if self.matrix_h != h || self.matrix_age >= MATRIX_LIFETIME || self.matrix.uses_kkt() {
            self.matrix_h = f64::NAN;
        }
        // Escalation on a slow contraction (the update shrank by less than `SLOW_RATE` in the
        // last iteration), once each per step: 1 rebuilds the matrix at the current state with
        // the kept tangent, 2 differentiates again, 3 keeps the tangent terms whatever their size.
        let mut escalation = 0u8;
        for it in 0..MAX_ITERATIONS {
            self.predict(model, h, q, qd);
            let w = &mut self.work;
            residual(
                &mut self.mass,
                &mut self.values,
                model,
                t1,
                (&w.q1, &w.qd1),
                (&w.qdd, &w.lam),
                bp,
                &mut w.res,
            );
            self.evaluations += 1;
            for &d in self.matrix.dropped() {
                w.res[n + d] = 0.0;
            }
            if w.res.iter().any(|v| !v.is_finite()) {
                return Err(self.fail());
            }
            let slow = it >= 2 && last_contraction > SLOW_RATE;
            if self.matrix_h.is_nan() || (slow && escalation < 3) {
                if slow {
                    escalation += 1;
                }
                let trial = Trial {
                    t: t1,
                    q: &w.q1,
                    v: &w.qd1,
                    qdd: &w.qdd,
                    lambda: &w.lam,
                };
                if !self.matrix.is_differentiated() || escalation == 2 {
                    self.evaluations += self
                        .matrix
                        .differentiate(model, &mut self.mass, &mut self.values, &trial);
                }
                if self
                    .matrix
                    .refresh(model, &self.mass, &self.values, (bp, gp), escalation == 3)
                    .is_err()
                {
                    return Err(self.fail());
                }
                self.factorizations += 1;
                self.matrix_h = h;
                self.matrix_age = 0;
            }
            let w = &mut self.work;
            for (d, r) in w.dx.iter_mut().zip(&w.res) {
                *d = -r;
            }
            self.matrix.solve(model, &mut w.dx);
            self.iterations += 1;
            let mut dq = 0.0f64;
            let mut da = 0.0f64;
            for i in 0..n {
                w.qdd[i] += w.dx[i];
                dq = dq.max((bp * w.dx[i]).abs());
                da = da.max(w.dx[i].abs());
            }
            // The acceleration update relative to the acceleration scale: the velocities move by
            // γ' Δq̈ and the positions by β' Δq̈, so a test on the positions alone (β' ∝ h²) stops
            // after one inexact iteration at small steps, and the error then grows as 1/h.
            let ascale = 1.0 + w.qdd.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            let rel = da / ascale;
            // Converged, at the round-off floor of the index-3 residual, or stalled above it. `C/β'`
            // carries the round-off of `C` (`ε` times the position scale) amplified by `1/β' ∝ 1/h²`:
            // an acceleration update below `ROUND_OFF_ULPS` of those units moves the positions by
            // less than that many units in the last place and cannot be resolved (measured on a
            // chain of 16 links at h = 1e-3: the updates stall at 1–4 of them).
            let qscale = 1.0 + w.q1.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            let floor = ROUND_OFF_ULPS * f64::EPSILON * qscale / (bp * ascale);
            // The error left after this update is about `θ/(1 − θ)` times it for a contraction
            // rate `θ` (Hairer & Wanner, *Solving ODEs II*, IV.8): a fast contraction accepts
            // without one more iteration that would only confirm it.
            let tol = ACCELERATION_TOLERANCE.max(floor);
            let theta = rel / last_rel;
            let accurate = rel <= tol
                || (it > 0 && theta < 0.5 && theta / (1.0 - theta) * rel <= tol)
                || (it > 0 && rel <= STALL_FLOOR && rel >= 0.5 * last_rel);
            last_contraction = rel / last_rel;
            last_rel = rel;
            for j in 0..m {
                w.lam[j] += w.dx[n + j];
            }
            if !dq.is_finite() {
                return Err(self.fail());
            }
            if dq <= self.tolerance * qscale && accurate {
                self.predict(model, h, q, qd);
                let w = &self.work;
                model.constraints().evaluate(t1, &w.q1, &w.qd1, &mut self.values);
                let cmax = self.values.c.iter().fold(0.0f64, |a, v| a.max(v.abs()));
                if cmax <= self.tolerance {
                    // Accept: advance a, q̈, λ.
                    for i in 0..n {
                        self.a[i] = ((1.0 - c.alpha_f) * w.qdd[i] + c.alpha_f * self.qdd[i] - c.alpha_m * self.a[i])
                            / (1.0 - c.alpha_m);
                    }
                    std::mem::swap(&mut self.qdd_prev, &mut self.qdd);
                    std::mem::swap(&mut self.lambda_prev, &mut self.lambda);
                    self.qdd.copy_from_slice(&w.qdd);
                    self.lambda.copy_from_slice(&w.lam);
                    self.h_prev = h;
                    q.copy_from_slice(&w.q1);
                    qd.copy_from_slice(&w.qd1);
                    self.matrix_age += 1;
                    return Ok(());
                }
            }
        }
        Err(self.fail())
    }

    /// Forgets the factors and the tangent after a failed step.
    fn fail(&mut self) -> NotConverged {
        self.matrix_h = f64::NAN;
        self.h_prev = f64::NAN;
        self.matrix.invalidate();
        NotConverged
    }
}
