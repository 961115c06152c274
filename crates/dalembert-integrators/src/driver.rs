//! The integration loop: steps, output scheduling, monitoring and failure reporting.

use crate::branch::{near_singular, BranchMonitor};
use crate::stepper::{Setup, StepControl, Stepper};
use crate::{IntegrationError, IntegrationFailure, IntegratorOptions, Stabilization, Statistics};
use bridge::Bridge;
use dalembert_system::{Baumgarte, DynamicsError, Formulation, FormulationStats};
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

mod bridge;

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
    /// The Baumgarte gains the method integrates with (the samples' `q̈` and `λ` use them too).
    baumgarte: Option<Baumgarte>,
    /// Stops the run where it leaves its branch at a singular position.
    branch: BranchMonitor,
}

fn inf_norm(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |a, x| a.max(x.abs()))
}

impl Run<'_> {
    /// Updates the monitors after an accepted step; fails on blow-up.
    fn monitor(&mut self, f: &mut dyn Formulation, t: f64, y: &[f64], h: f64) -> Result<(), IntegrationError> {
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
                hint: String::new(),
            });
        }
        let (q, qd) = y.split_at(self.n);
        f.residuals(t, q, qd, &mut self.c, &mut self.cdot);
        let s = &mut self.stats;
        s.max_constraint_violation = s.max_constraint_violation.max(inf_norm(&self.c));
        s.max_velocity_violation = s.max_velocity_violation.max(inf_norm(&self.cdot));
        let energy = f.energy(t, q, qd);
        s.max_energy_change = s.max_energy_change.max((energy.total() - self.energy0).abs());
        self.branch.after_step(f, t, (q, qd), energy, s.steps == 0)?;
        s.steps += 1;
        s.min_step_taken = s.min_step_taken.min(h);
        s.max_step_taken = s.max_step_taken.max(h);
        if self.cancel.load(Ordering::Relaxed) {
            return Err(IntegrationError::Interrupted { time: t });
        }
        Ok(())
    }

    /// Evaluates `q̈, λ` at an output state and hands the sample to the observer.
    fn emit(&mut self, f: &mut dyn Formulation, t: f64, y: &[f64]) -> Result<(), IntegrationError> {
        let (q, qd) = y.split_at(self.n);
        f.accelerations(t, q, qd, self.baumgarte, &mut self.qdd, &mut self.lambda)?;
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

    fn finish(&mut self, f: &dyn Formulation, wall: Instant) {
        let now = f.stats();
        let s = &mut self.stats;
        s.evaluations = now.evaluations - self.start.evaluations + self.extra.evaluations;
        s.factorizations = now.factorizations - self.start.factorizations + self.extra.factorizations;
        s.newton_iterations = now.newton_iterations - self.start.newton_iterations + self.extra.newton_iterations;
        s.repartitions = now.repartitions - self.start.repartitions;
        s.handovers = now.handovers - self.start.handovers;
        s.wall_time = wall.elapsed().saturating_sub(self.observer_time);
        if s.steps == 0 {
            s.min_step_taken = 0.0;
        }
    }
}

/// Restores the position invariants of `y = [q; v]` (`n_q` positions) that a step does not keep
/// (unit Euler parameters): [`dalembert_system::MultibodySystem::normalize`].
fn normalize(f: &dyn Formulation, y: &mut [f64], n_q: usize) {
    f.system().normalize(&mut y[..n_q]);
}

/// Projects `y = [q; v]` (`n_q` positions) when the stabilization asks for it; returns true if it
/// did.
fn project(
    f: &mut dyn Formulation,
    t: f64,
    y: &mut [f64],
    n_q: usize,
    stabilization: Stabilization,
) -> Result<bool, DynamicsError> {
    if let Some(tolerance) = stabilization.projection_tolerance() {
        let (q, qd) = y.split_at_mut(n_q);
        f.project(t, q, qd, tolerance)?;
        return Ok(true);
    }
    Ok(false)
}

impl Run<'_> {
    /// [`project`] after an accepted step at `t`, measuring the share of the kinetic energy the
    /// velocity projection removed ([`Statistics::max_projection_share`]).
    fn project_step(
        &mut self,
        f: &mut dyn Formulation,
        t: f64,
        y: &mut [f64],
        stabilization: Stabilization,
    ) -> Result<bool, IntegrationError> {
        let n_q = self.n;
        self.branch.before_projection(&y[n_q..]);
        if !project(f, t, y, n_q, stabilization)? {
            return Ok(false);
        }
        let (q, v) = y.split_at(n_q);
        self.branch.after_projection(f, t, q, v, &mut self.stats)?;
        Ok(true)
    }
}

/// Integrates from `(t0, q0, q̇0)` to `t_end`, calling `observer` at `t0` and every
/// `opts.output_every` (and at `t_end`). The initial state should be consistent; with projection it
/// is projected first.
///
/// Returns the run's statistics, or the failure with the statistics up to it (every sample before
/// the failure has already been observed).
pub fn integrate(
    f: &mut dyn Formulation,
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
#[allow(clippy::too_many_arguments)]
pub fn integrate_cancellable(
    f: &mut dyn Formulation,
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
        baumgarte: None,
        branch: BranchMonitor::new(
            f,
            q0,
            qd0,
            energy0,
            f.system().is_conservative() && opts.method.entry().control == StepControl::Fixed,
        ),
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
    opts.method.check().map_err(IntegrationError::Options)
}

/// The output times: `t0 + k · every` for `k < n_out`, then `t_end`.
struct Schedule {
    t0: f64,
    t_end: f64,
    every: f64,
    n_out: u64,
}

impl Schedule {
    fn time(&self, k: u64) -> f64 {
        if k >= self.n_out {
            self.t_end
        } else {
            self.t0 + k as f64 * self.every
        }
    }
}

fn run_loop(
    f: &mut dyn Formulation,
    t0: f64,
    t_end: f64,
    y: &mut [f64],
    opts: &IntegratorOptions,
    run: &mut Run<'_>,
) -> Result<(), IntegrationError> {
    check_options(t0, t_end, opts)?;
    let entry = opts.method.entry();
    if let Some(why) = entry.refuses(f.name(), f.is_index3_augmented()) {
        return Err(IntegrationError::Options(why));
    }
    // A method that keeps the constraints itself is not projected.
    let stabilization = if entry.keeps_constraints {
        Stabilization::None
    } else {
        opts.stabilization
    };
    let n_q = run.n;
    run.baumgarte = stabilization.gains(opts.step);
    project(f, t0, y, n_q, stabilization)?;
    run.emit(f, t0, y)?;
    let schedule = Schedule {
        t0,
        t_end,
        every: opts.output_every,
        n_out: ((t_end - t0) / opts.output_every - 1e-9).ceil().max(0.0) as u64,
    };
    let mut stepper = (entry.build)(
        &opts.method,
        Setup {
            formulation: &mut *f,
            t0,
            y0: y,
            n_q,
            baumgarte: run.baumgarte,
        },
    )?;
    let result = match entry.control {
        StepControl::Fixed => fixed_loop(f, stepper.as_mut(), y, opts, stabilization, run, &schedule),
        StepControl::Adaptive => adaptive_loop(f, stepper.as_mut(), y, opts, stabilization, run, &schedule),
    };
    // The method says what a divergence likely means for it.
    let result = result.map_err(|e| match e {
        IntegrationError::Diverged { time, what, step, .. } => IntegrationError::Diverged {
            time,
            what,
            step,
            hint: stepper.divergence_hint(step),
        },
        other => other,
    });
    let work = stepper.work();
    run.extra.newton_iterations += work.newton_iterations;
    run.extra.factorizations += work.factorizations;
    run.extra.evaluations += work.evaluations;
    result
}

/// The number of equal steps no longer than `h` that span `span`, and their size.
fn split(span: f64, h: f64) -> (u64, f64) {
    let steps = (span / h - 1e-9).ceil().max(1.0) as u64;
    (steps, span / steps as f64)
}

impl Run<'_> {
    /// Counts a rejected step; fails when the next step would fall below the minimum.
    fn rejected(&mut self, t: f64, next: f64, error: f64, min_step: f64) -> Result<(), IntegrationError> {
        self.stats.rejected += 1;
        if next < min_step {
            return Err(IntegrationError::StepSizeTooSmall {
                time: t,
                step: next,
                min_step,
                error,
            });
        }
        Ok(())
    }
}

/// A step that failed down to the minimum at `(t, y)`: where `C_q` is nearly singular there, the
/// cause is the singular position (an implicit method's Newton matrix `[… C_qᵀ; C_q 0]` loses rank
/// with it), said with the equations involved; otherwise `e` as it is. Allocates (on failure only).
fn singular_or(e: IntegrationError, f: &dyn Formulation, t: f64, y: &[f64], method: &'static str) -> IntegrationError {
    let IntegrationError::StepSizeTooSmall { step, .. } = e else {
        return e;
    };
    let n_v = f.system().layout().n_v();
    match near_singular(f, t, y.split_at(y.len() - n_v), SingularPassGuard::NEAR) {
        Some(involved) => IntegrationError::SingularPass {
            time: t,
            method,
            step,
            involved,
            advice: "its Newton iteration does not converge there (the iteration matrix [M C_qᵀ; C_q 0] loses rank with C_q) and halving the step only lands nearer, so the run stops: pass singular positions with a fixed-step rk4 with projection (docs/stability.md)",
        },
        None => e,
    }
}

/// Fixed steps: each output interval is spanned by a whole number of equal steps no longer than
/// the current step; a rejected step halves the current step (down to `min_step`), four accepted
/// ones double it back toward `opts.step`.
fn fixed_loop(
    f: &mut dyn Formulation,
    stepper: &mut dyn Stepper,
    y: &mut [f64],
    opts: &IntegratorOptions,
    stabilization: Stabilization,
    run: &mut Run<'_>,
    schedule: &Schedule,
) -> Result<(), IntegrationError> {
    let n_q = run.n;
    let mut h = opts.step;
    let mut t = schedule.t0;
    let mut successes = 0u32;
    for k in 1..=schedule.n_out {
        let t_next = schedule.time(k);
        let t_start = t;
        // Steps of this interval at the current step size, and how many are done.
        let (mut steps, mut hh) = split(t_next - t_start, h);
        let mut done = 0u64;
        let mut base = t_start;
        while done < steps {
            let ts = base + done as f64 * hh;
            let outcome = stepper.step(f, ts, hh, y)?;
            if !outcome.accepted {
                successes = 0;
                h = 0.5 * hh;
                if let Err(e) = run.rejected(ts, h, outcome.error, opts.min_step) {
                    return Err(singular_or(e, f, ts, y, opts.method.name()));
                }
                // The rest of the interval at the halved step.
                base = ts;
                done = 0;
                (steps, hh) = split(t_next - base, h);
                continue;
            }
            done += 1;
            let t_after = if done == steps { t_next } else { base + done as f64 * hh };
            normalize(f, y, n_q);
            run.project_step(f, t_after, y, stabilization)?;
            run.monitor(f, t_after, y, hh)?;
            successes += 1;
            if successes >= 4 && h < opts.step && done < steps {
                // Grow back: the rest of the interval at the doubled step.
                h = (2.0 * h).min(opts.step);
                successes = 0;
                base = t_after;
                done = 0;
                (steps, hh) = split(t_next - base, h);
            }
        }
        t = t_next;
        run.emit(f, t, y)?;
    }
    Ok(())
}

/// Adaptive steps proposed by the method; output samples from its dense output.
fn adaptive_loop(
    f: &mut dyn Formulation,
    stepper: &mut dyn Stepper,
    y: &mut [f64],
    opts: &IntegratorOptions,
    stabilization: Stabilization,
    run: &mut Run<'_>,
    schedule: &Schedule,
) -> Result<(), IntegrationError> {
    let (n_q, t0, t_end, n_out) = (run.n, schedule.t0, schedule.t_end, schedule.n_out);
    let max_step = opts.max_step.min(t_end - t0).max(opts.min_step);
    let mut h = opts.step.min(max_step);
    let mut t = t0;
    let mut k_out = 1;
    let mut guard = SingularPassGuard::default();
    let mut bridge = Bridge::new(y.len(), &opts.method);
    let name = opts.method.name();
    while t < t_end && k_out <= n_out {
        let last = t + h >= t_end - 1e-12 * (1.0 + t_end.abs());
        if last {
            h = t_end - t;
        }
        let outcome = stepper.step(f, t, h, y)?;
        let collapse = guard.check(f, t, y, n_q, outcome.next_step, name).err();
        if outcome.accepted {
            let t_new = if last { t_end } else { t + h };
            emit_dense(f, stepper, run, schedule, &mut k_out, stabilization, (t, h, t_new))?;
            normalize(f, y, n_q);
            if run.project_step(f, t_new, y, stabilization)? {
                stepper.state_changed();
            }
            run.monitor(f, t_new, y, h)?;
            guard.accepted(h);
            bridge.steady();
            t = t_new;
            h = outcome.next_step.min(max_step);
        } else if collapse.is_none() {
            run.rejected(t, outcome.next_step, outcome.error, opts.min_step)?;
            h = outcome.next_step;
        }
        if let Some(stop) = collapse {
            if t >= t_end || k_out > n_out {
                break;
            }
            // Across the singular position with checked steps of the size the run had before its
            // steps collapsed, or stop with the cause.
            let largest = guard.largest.min(t_end - t);
            match bridge.across(f, stepper, y, t, largest, run, schedule, &mut k_out, stabilization)? {
                Some(step) => {
                    t = (t + step).min(t_end);
                    h = step.min(max_step);
                    guard.rearm();
                }
                None => return Err(stop),
            }
        }
    }
    Ok(())
}

/// Samples of the dense output of the last accepted step `(t, h, t_new)` at every output time in
/// `(t, t_new]`, each normalized and projected.
fn emit_dense(
    f: &mut dyn Formulation,
    stepper: &mut dyn Stepper,
    run: &mut Run<'_>,
    schedule: &Schedule,
    k_out: &mut u64,
    stabilization: Stabilization,
    (t, h, t_new): (f64, f64, f64),
) -> Result<(), IntegrationError> {
    let n_q = run.n;
    while *k_out <= schedule.n_out && schedule.time(*k_out) <= t_new + 1e-12 * (1.0 + t_new.abs()) {
        let to = schedule.time(*k_out);
        let mut y_out = std::mem::take(&mut run.y_out);
        stepper.interpolate(((to - t) / h).clamp(0.0, 1.0), &mut y_out);
        normalize(f, &mut y_out, n_q);
        project(f, to, &mut y_out, n_q, stabilization)?;
        let r = run.emit(f, to, &y_out);
        run.y_out = y_out;
        r?;
        *k_out += 1;
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
/// value `NEAR`); at a nearly singular `C_q` the loop bridges the position with checked steps
/// ([`bridge`]) or, when no checked step passes, stops with the time and the equations involved.
/// A well-conditioned one (a stiff model) re-arms the check a factor 10 lower, so a stiff run pays
/// one SVD per decade of step size.
///
#[derive(Default)]
struct SingularPassGuard {
    largest: f64,
    /// Steps below this fraction of the largest are checked.
    armed_below: f64,
}

impl SingularPassGuard {
    const COLLAPSE: f64 = 1e-3;
    const NEAR: f64 = 1e-3;

    /// After a bridge across the singular position: the next collapse is checked again.
    fn rearm(&mut self) {
        self.armed_below = self.armed_below.max(Self::COLLAPSE);
    }

    fn accepted(&mut self, h: f64) {
        if h > self.largest {
            self.largest = h;
            self.armed_below = self.armed_below.max(Self::COLLAPSE);
        }
    }

    fn check(
        &mut self,
        f: &dyn Formulation,
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
        match near_singular(f, t, y.split_at(n_q), Self::NEAR) {
            Some(involved) => Err(IntegrationError::SingularPass {
                time: t,
                method,
                step: next,
                involved,
                advice: "an adaptive error-controlled step resolves the perturbed geometry there and may leave on the other branch, and no checked step bridged it, so the run stops: pass singular positions with a fixed-step rk4 with projection (docs/stability.md)",
            }),
            None => Ok(()),
        }
    }
}
