//! The integration loop: steps, output scheduling, monitoring and failure reporting.

use crate::dopri5::Dopri5;
use crate::explicit::{rk4_step, symplectic_euler_step, FixedWork};
use crate::generalized_alpha::{GeneralizedAlpha, NotConverged};
use crate::{ConstraintTreatment, IntegrationError, IntegrationFailure, IntegratorOptions, Method, Statistics};
use dalembert_system::{DynamicsError, Formulation, FormulationStats};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// One output sample handed to the observer.
#[derive(Debug, Clone, Copy)]
pub struct Sample<'a> {
    /// Time.
    pub t: f64,
    /// Positions.
    pub q: &'a [f64],
    /// Velocities.
    pub qd: &'a [f64],
    /// Accelerations at this state.
    pub qdd: &'a [f64],
    /// Multipliers at this state.
    pub lambda: &'a [f64],
    /// `‖C‖∞` at this state.
    pub constraint_violation: f64,
    /// `‖Ċ‖∞` at this state.
    pub velocity_violation: f64,
    /// Total energy `T + V`.
    pub energy: f64,
}

/// Monitors, output buffers and counters shared by all methods.
struct Run<'o> {
    /// Number of positions `n_q` (`y = [q; v]` splits there).
    n: usize,
    stats: Statistics,
    start: FormulationStats,
    c: Vec<f64>,
    cdot: Vec<f64>,
    qdd: Vec<f64>,
    lambda: Vec<f64>,
    y_out: Vec<f64>,
    energy0: f64,
    scale0: f64,
    divergence_factor: f64,
    observer: &'o mut dyn FnMut(&Sample<'_>),
    observer_time: Duration,
    /// Work done outside the formulation (the implicit method's own Newton solves).
    extra: FormulationStats,
    /// Set by the caller to stop the run after the current step.
    cancel: &'o AtomicBool,
}

fn inf_norm(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |a, x| a.max(x.abs()))
}

impl Run<'_> {
    /// Updates the monitors after an accepted step; fails on blow-up.
    fn monitor<F: Formulation + ?Sized>(
        &mut self,
        f: &mut F,
        t: f64,
        y: &[f64],
        h: f64,
    ) -> Result<(), IntegrationError> {
        let size = inf_norm(y);
        if !size.is_finite() {
            return Err(DynamicsError::NonFinite {
                time: t,
                what: "state after the step".into(),
            }
            .into());
        }
        if size > self.divergence_factor * self.scale0 {
            return Err(IntegrationError::Diverged {
                time: t,
                what: format!("state magnitude {size:.3e} vs initial {:.3e}", self.scale0),
                step: h,
            });
        }
        let (q, qd) = y.split_at(self.n);
        f.residuals(t, q, qd, &mut self.c, &mut self.cdot);
        let s = &mut self.stats;
        s.max_constraint_violation = s.max_constraint_violation.max(inf_norm(&self.c));
        s.max_velocity_violation = s.max_velocity_violation.max(inf_norm(&self.cdot));
        let e = f.energy(t, q, qd).total();
        s.max_energy_change = s.max_energy_change.max((e - self.energy0).abs());
        s.steps += 1;
        s.min_step_taken = s.min_step_taken.min(h);
        s.max_step_taken = s.max_step_taken.max(h);
        if self.cancel.load(Ordering::Relaxed) {
            return Err(IntegrationError::Interrupted { time: t });
        }
        Ok(())
    }

    /// Evaluates `q̈, λ` at an output state and hands the sample to the observer.
    fn emit<F: Formulation + ?Sized>(
        &mut self,
        f: &mut F,
        t: f64,
        y: &[f64],
        opts: &IntegratorOptions,
    ) -> Result<(), IntegrationError> {
        let (q, qd) = y.split_at(self.n);
        f.accelerations(
            t,
            q,
            qd,
            opts.treatment.stabilization(),
            &mut self.qdd,
            &mut self.lambda,
        )?;
        f.residuals(t, q, qd, &mut self.c, &mut self.cdot);
        let sample = Sample {
            t,
            q,
            qd,
            qdd: &self.qdd,
            lambda: &self.lambda,
            constraint_violation: inf_norm(&self.c),
            velocity_violation: inf_norm(&self.cdot),
            energy: f.energy(t, q, qd).total(),
        };
        let t0 = Instant::now();
        (self.observer)(&sample);
        crate::vector_state::clear_upper_state();
        self.observer_time += t0.elapsed();
        Ok(())
    }

    fn finish<F: Formulation + ?Sized>(&mut self, f: &F, wall: Instant) {
        let now = f.stats();
        let s = &mut self.stats;
        s.evaluations = now.evaluations - self.start.evaluations + self.extra.evaluations;
        s.factorizations = now.factorizations - self.start.factorizations + self.extra.factorizations;
        s.newton_iterations = now.newton_iterations - self.start.newton_iterations + self.extra.newton_iterations;
        s.repartitions = now.repartitions - self.start.repartitions;
        s.wall_time = wall.elapsed().saturating_sub(self.observer_time);
        if s.steps == 0 {
            s.min_step_taken = 0.0;
        }
    }
}

/// Restores the position invariants of `y = [q; v]` (`n_q` positions) that an explicit step does
/// not keep (unit Euler parameters): [`dalembert_system::MultibodySystem::normalize`].
fn normalize<F: Formulation + ?Sized>(f: &F, y: &mut [f64], n_q: usize) {
    f.system().normalize(&mut y[..n_q]);
}

/// Projects `y = [q; v]` (`n_q` positions) when the treatment asks for it; returns true if it did.
fn project<F: Formulation + ?Sized>(
    f: &mut F,
    t: f64,
    y: &mut [f64],
    n_q: usize,
    treatment: ConstraintTreatment,
) -> Result<bool, DynamicsError> {
    if let ConstraintTreatment::Projection { tolerance } = treatment {
        let (q, qd) = y.split_at_mut(n_q);
        f.project(t, q, qd, tolerance)?;
        return Ok(true);
    }
    Ok(false)
}

/// Integrates from `(t0, q0, q̇0)` to `t_end`, calling `observer` at `t0` and every
/// `opts.output_every` (and at `t_end`). The initial state should be consistent; with projection it
/// is projected first.
///
/// Returns the run's statistics, or the failure with the statistics up to it (every sample before
/// the failure has already been observed).
pub fn integrate<F: Formulation + ?Sized>(
    f: &mut F,
    t0: f64,
    t_end: f64,
    q0: &[f64],
    qd0: &[f64],
    opts: &IntegratorOptions,
    observer: &mut dyn FnMut(&Sample<'_>),
) -> Result<Statistics, IntegrationFailure> {
    integrate_cancellable(f, t0, t_end, q0, qd0, opts, observer, &AtomicBool::new(false))
}

/// [`integrate`] that stops with [`IntegrationError::Interrupted`] after the first accepted step
/// that finds `cancel` set (a signal handler or another thread sets it). The flag is read once per
/// step; samples observed before the stop are complete.
pub fn integrate_cancellable<F: Formulation + ?Sized>(
    f: &mut F,
    t0: f64,
    t_end: f64,
    q0: &[f64],
    qd0: &[f64],
    opts: &IntegratorOptions,
    observer: &mut dyn FnMut(&Sample<'_>),
    cancel: &AtomicBool,
) -> Result<Statistics, IntegrationFailure> {
    let (n, n_v) = (q0.len(), qd0.len());
    let m = f.system().num_equations();
    let wall = Instant::now();
    let mut y = [q0, qd0].concat();
    let energy0 = f.energy(t0, q0, qd0).total();
    let mut run = Run {
        n,
        stats: Statistics {
            min_step_taken: f64::INFINITY,
            ..Default::default()
        },
        start: f.stats(),
        c: vec![0.0; m],
        cdot: vec![0.0; m],
        qdd: vec![0.0; n_v],
        lambda: vec![0.0; m],
        y_out: vec![0.0; n + n_v],
        energy0,
        scale0: 1.0 + inf_norm(&y),
        divergence_factor: opts.divergence_factor,
        observer,
        observer_time: Duration::ZERO,
        extra: FormulationStats::default(),
        cancel,
    };
    crate::vector_state::clear_upper_state();
    let result = run_loop(f, t0, t_end, &mut y, opts, &mut run);
    run.finish(f, wall);
    match result {
        Ok(()) => Ok(run.stats),
        Err(error) => Err(IntegrationFailure {
            error,
            statistics: Box::new(run.stats),
        }),
    }
}

fn check_options(t0: f64, t_end: f64, opts: &IntegratorOptions) -> Result<(), IntegrationError> {
    let bad = |s: &str| Err(IntegrationError::Options(s.to_string()));
    if !(opts.step.is_finite() && opts.step > 0.0) {
        return bad("step must be positive and finite");
    }
    if !(opts.output_every.is_finite() && opts.output_every > 0.0) {
        return bad("output interval must be positive and finite");
    }
    if !(t_end.is_finite() && t0.is_finite() && t_end >= t0) {
        return bad("end time must be finite and not before the start");
    }
    if let Method::DormandPrince { rtol, atol } = opts.method {
        if !(rtol > 0.0 && atol > 0.0) {
            return bad("rtol and atol must be positive");
        }
    }
    if let Method::GeneralizedAlpha { rho_inf } = opts.method {
        if !(0.0..=1.0).contains(&rho_inf) {
            return bad("rho_inf must lie in [0, 1]");
        }
    }
    Ok(())
}

fn run_loop<F: Formulation + ?Sized>(
    f: &mut F,
    t0: f64,
    t_end: f64,
    y: &mut [f64],
    opts: &IntegratorOptions,
    run: &mut Run<'_>,
) -> Result<(), IntegrationError> {
    check_options(t0, t_end, opts)?;
    let n_q = run.n;
    project(f, t0, y, n_q, opts.treatment)?;
    run.emit(f, t0, y, opts)?;
    let stab = opts.treatment.stabilization();
    let n_out = ((t_end - t0) / opts.output_every - 1e-9).ceil().max(0.0) as u64;
    let out_time = |k: u64| {
        if k >= n_out {
            t_end
        } else {
            t0 + k as f64 * opts.output_every
        }
    };
    match opts.method {
        Method::SymplecticEuler | Method::Rk4 => {
            let mut work = FixedWork::new(n_q, run.qdd.len(), run.lambda.len());
            let mut t = t0;
            for k in 1..=n_out {
                let t_next = out_time(k);
                let span = t_next - t;
                let steps = (span / opts.step - 1e-9).ceil().max(1.0) as u64;
                let h = span / steps as f64;
                for s in 0..steps {
                    let ts = t + s as f64 * h;
                    match opts.method {
                        Method::Rk4 => rk4_step(f, &mut work, ts, h, y, stab)?,
                        _ => symplectic_euler_step(f, &mut work, ts, h, y, stab)?,
                    }
                    let t_after = if s + 1 == steps { t_next } else { ts + h };
                    normalize(f, y, n_q);
                    project(f, t_after, y, n_q, opts.treatment)?;
                    run.monitor(f, t_after, y, h)?;
                }
                t = t_next;
                run.emit(f, t, y, opts)?;
            }
        }
        Method::GeneralizedAlpha { rho_inf } => {
            if !f.is_index3_augmented() {
                return Err(IntegrationError::Options(format!(
                    "generalized-alpha integrates the augmented index-3 equations and the {0} formulation has no implicit form of its own yet: use formulation augmented with generalized-alpha, or rk4 / dopri5 with {0}",
                    f.name()
                )));
            }
            let n = run.n;
            // Its iteration matrix is sparse on the couplings the system declares; a force element
            // that does not declare its bodies couples all of them (a dense matrix): refuse sizes
            // that cannot hold it, by name, instead of failing in the allocator.
            let k = run.qdd.len() + run.lambda.len();
            if f.system().force_coupling().is_none() && !dalembert_system::structure::dense_fits(k, k) {
                return Err(IntegrationError::Options(format!(
                    "generalized-alpha: a force element does not declare the bodies it acts on (ForceElement::bodies), so its iteration matrix couples every body: {k} × {k} dense ({:.1} GiB) is too large; declare the bodies, or use rk4 or dopri5",
                    (k as f64) * (k as f64) * 8.0 / 1073741824.0
                )));
            }
            let (q0, qd0) = y.split_at(n);
            f.accelerations(
                t0,
                q0,
                qd0,
                dalembert_system::Stabilization::None,
                &mut run.qdd,
                &mut run.lambda,
            )?;
            let mut ga = GeneralizedAlpha::new(f.system(), rho_inf, &run.qdd, &run.lambda, q0).map_err(|e| {
                DynamicsError::Singular {
                    time: t0,
                    what: format!("generalized-alpha's iteration matrix: {e}"),
                }
            })?;
            let result = generalized_alpha_loop(f, &mut ga, t0, y, opts, run, n_out, &out_time);
            run.extra.newton_iterations += ga.iterations;
            run.extra.factorizations += ga.factorizations;
            run.extra.evaluations += ga.evaluations;
            result?;
        }
        Method::DormandPrince { rtol, atol } => {
            let mut dp = Dopri5::new(n_q, run.qdd.len(), run.lambda.len(), rtol, atol);
            let max_step = opts.max_step.min(t_end - t0).max(opts.min_step);
            let mut h = opts.step.min(max_step);
            let mut t = t0;
            let mut k_out = 1;
            let mut guard = SingularPassGuard::default();
            while t < t_end && k_out <= n_out {
                let last = t + h >= t_end - 1e-12 * (1.0 + t_end.abs());
                if last {
                    h = t_end - t;
                }
                let attempt = dp.attempt(f, t, h, y, stab)?;
                guard.check(f, t, y, n_q, attempt.next_step, "dopri5")?;
                if attempt.error > 1.0 {
                    run.stats.rejected += 1;
                    let next = attempt.next_step;
                    if next < opts.min_step {
                        return Err(IntegrationError::StepSizeTooSmall {
                            time: t,
                            step: next,
                            min_step: opts.min_step,
                            error: attempt.error,
                        });
                    }
                    h = next;
                    continue;
                }
                let t_new = if last { t_end } else { t + h };
                dp.accept(h, attempt.error, y);
                // Dense output at every output time inside (t, t_new].
                while k_out <= n_out && out_time(k_out) <= t_new + 1e-12 * (1.0 + t_new.abs()) {
                    let to = out_time(k_out);
                    let mut y_out = std::mem::take(&mut run.y_out);
                    dp.interpolate(((to - t) / h).clamp(0.0, 1.0), &mut y_out);
                    normalize(f, &mut y_out, n_q);
                    project(f, to, &mut y_out, n_q, opts.treatment)?;
                    let r = run.emit(f, to, &y_out, opts);
                    run.y_out = y_out;
                    r?;
                    k_out += 1;
                }
                // The stored last stage stays valid after a normalization (it moves `q` by the
                // order of the local error); a projection moves it further and invalidates it.
                normalize(f, y, n_q);
                if project(f, t_new, y, n_q, opts.treatment)? {
                    dp.invalidate();
                }
                run.monitor(f, t_new, y, h)?;
                guard.accepted(h);
                t = t_new;
                h = attempt.next_step.min(max_step);
            }
        }
    }
    Ok(())
}

/// Stops an adaptive method whose steps collapse at a singular position of a closed chain.
///
/// Near a position where links line up (a change point, the horizontal N-four-bar) the two motion
/// branches are `O(√ε)` apart in time for a constraint violation `ε`: an error-controlled step shrinks
/// toward the singular point (the accelerations grow as `1/σ_min(C_q)`) until it resolves the
/// slightly perturbed geometry of the drifted state, which decides the branch by that perturbation
/// (measured on `scenes/driven-four-bar.toml` with dopri5: steps of 1e-6 s, the rocker turning back
/// 3e-5 rad before the line, i.e. a silent switch to the other assembly). When a step falls below
/// `COLLAPSE` × the largest accepted step, `C_q` is checked ([`near_singular`], relative singular
/// value `NEAR`); a nearly singular `C_q` stops the run with the time and the equations involved.
/// A well-conditioned one (a stiff model) re-arms the check a factor 10 lower, so a stiff run pays
/// one SVD per decade of step size.
///
/// [`near_singular`]: dalembert_system::structure::near_singular
#[derive(Default)]
struct SingularPassGuard {
    largest: f64,
    /// Steps below this fraction of the largest are checked.
    armed_below: f64,
}

impl SingularPassGuard {
    const COLLAPSE: f64 = 1e-3;
    const NEAR: f64 = 1e-3;

    fn accepted(&mut self, h: f64) {
        if h > self.largest {
            self.largest = h;
            self.armed_below = self.armed_below.max(Self::COLLAPSE);
        }
    }

    fn check<F: Formulation + ?Sized>(
        &mut self,
        f: &F,
        t: f64,
        y: &[f64],
        n_q: usize,
        next: f64,
        method: &'static str,
    ) -> Result<(), IntegrationError> {
        if next.is_nan() || next >= self.armed_below * self.largest {
            return Ok(());
        }
        self.armed_below = next / self.largest / 10.0;
        let sys = f.system().constraints();
        let mut values = sys.values();
        let (q, qd) = y.split_at(n_q);
        sys.evaluate(t, q, qd, &mut values);
        match dalembert_system::structure::near_singular(sys, &values, Self::NEAR, 1e-9) {
            Some(involved) => Err(IntegrationError::SingularPass {
                time: t,
                method,
                step: next,
                involved,
            }),
            None => Ok(()),
        }
    }
}

#[allow(clippy::too_many_arguments)]
fn generalized_alpha_loop<F: Formulation + ?Sized>(
    f: &mut F,
    ga: &mut GeneralizedAlpha,
    t0: f64,
    y: &mut [f64],
    opts: &IntegratorOptions,
    run: &mut Run<'_>,
    n_out: u64,
    out_time: &dyn Fn(u64) -> f64,
) -> Result<(), IntegrationError> {
    let n = run.n;
    let mut h = opts.step;
    let mut t = t0;
    let mut successes = 0u32;
    for k in 1..=n_out {
        let t_next = out_time(k);
        while t < t_next - 1e-12 * (1.0 + t_next.abs()) {
            let remaining = t_next - t;
            // Avoid a sliver of a step before the output time.
            let hh = if h >= remaining * (1.0 - 1e-9) || remaining - h < 1e-3 * h {
                remaining
            } else {
                h
            };
            let (q, qd) = y.split_at_mut(n);
            match ga.step(f.system(), t, hh, q, qd) {
                Ok(()) => {
                    t = if hh == remaining { t_next } else { t + hh };
                    run.monitor(f, t, y, hh)?;
                    successes += 1;
                    if successes >= 4 && h < opts.step {
                        h = (2.0 * h).min(opts.step);
                        successes = 0;
                    }
                }
                Err(NotConverged) => {
                    run.stats.rejected += 1;
                    successes = 0;
                    h = 0.5 * hh;
                    if h < opts.min_step {
                        return Err(IntegrationError::StepSizeTooSmall {
                            time: t,
                            step: h,
                            min_step: opts.min_step,
                            error: f64::NAN,
                        });
                    }
                }
            }
        }
        run.emit(f, t, y, opts)?;
    }
    Ok(())
}
