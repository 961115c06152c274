//! The integration loop: steps, output scheduling, monitoring and failure reporting. A run is an
//! [`Integration`] advanced from output time to output time; [`integrate`] is that loop.

use crate::branch::near_singular;
use crate::{IntegrationError, IntegrationFailure, IntegratorOptions, Stabilization, Statistics};
use dalembert_system::{DynamicsError, Formulation};
use guard::SingularPassGuard;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

mod bridge;
mod events;
mod guard;
mod integration;
mod monitors;
mod tangents;
mod work;

pub use integration::Integration;
pub use tangents::Perturbed;

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
    /// The friction force of each friction element of the system at this state
    /// ([`dalembert_system::MultibodySystem::frictions`]; empty without friction).
    pub friction: &'a [f64],
    /// The force of each joint limit of the system at this state
    /// ([`dalembert_system::MultibodySystem::limits`]; empty without limits, zero where free).
    pub limit: &'a [f64],
    /// The kinetic energy impacts at joint limits took from the motion since the run began (J).
    pub impact_loss: f64,
    /// The work `W` of the non-conservative forces, drivers and joint friction since the run
    /// began (J), integrated along the run's steps, for a model whose forces switch (contacts,
    /// friction, limits: `docs/energy.md`, "Along the steps"); NaN where the run does not carry
    /// it (the energy balance then integrates the samples' power).
    pub work: f64,
    /// `‖C‖∞` at this state.
    pub constraint_violation: f64,
    /// `‖Ċ‖∞` at this state.
    pub velocity_violation: f64,
    /// Total energy `T + V`.
    pub energy: f64,
}

fn inf_norm(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |a, x| a.max(x.abs()))
}

/// Restores the position invariants of `y = [q; v]` (`n_q` positions) that a step does not keep
/// (unit Euler parameters): [`dalembert_system::MultibodySystem::normalize`].
fn normalize(f: &dyn Formulation, y: &mut [f64], n_q: usize) {
    f.system().normalize(&mut y[..n_q]);
}

/// Projects `y = [q; v]` (`n_q` positions) when the stabilization asks for it and the system has
/// constraint equations to project on; returns true if it did. (A system without equations, such
/// as a tree in joint coordinates, has nothing to project: its projection would factor the mass
/// matrix to solve for a zero correction: a chain of 16 in joint coordinates ran 58 % longer.)
fn project(
    f: &mut dyn Formulation,
    t: f64,
    y: &mut [f64],
    n_q: usize,
    stabilization: Stabilization,
) -> Result<bool, DynamicsError> {
    if f.system().num_equations() == 0 {
        return Ok(false);
    }
    if let Some(tolerance) = stabilization.projection_tolerance() {
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
    let mut observe = |s: &Sample<'_>, _: Option<PerturbedSide>| observer(s);
    integrate_sensitivities(f, t0, t_end, q0, qd0, opts, Vec::new(), &mut observe, cancel)
}

/// Which perturbed model a sample of [`integrate_sensitivities`] is of.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PerturbedSide {
    /// The parameter's index in the list given.
    pub parameter: usize,
    /// True for `p + δ`, false for `p − δ`.
    pub plus: bool,
    /// The change `δ`: a column's derivative is `(value₊ − value₋) / 2δ`.
    pub delta: f64,
}

/// [`integrate_cancellable`] carrying the sensitivities of the run to the parameters `perturbed`
/// change (`docs/sensitivities.md`): at every output time `observer` gets the run's sample (with
/// `None`), then for each parameter the samples of its `p + δ` and `p − δ` models there.
#[allow(clippy::too_many_arguments)]
pub fn integrate_sensitivities(
    f: &mut dyn Formulation,
    t0: f64,
    t_end: f64,
    q0: &[f64],
    qd0: &[f64],
    opts: &IntegratorOptions,
    perturbed: Vec<Perturbed>,
    observer: &mut dyn FnMut(&Sample<'_>, Option<PerturbedSide>),
    cancel: &AtomicBool,
) -> Result<Statistics, IntegrationFailure> {
    let started = Integration::new(f, t0, t_end, q0, qd0, opts).and_then(|run| {
        if perturbed.is_empty() {
            Ok(run)
        } else {
            run.with_sensitivities(perturbed)
        }
    });
    let mut run = match started {
        Ok(run) => run,
        Err(error) => {
            return Err(IntegrationFailure {
                error,
                statistics: Box::default(),
            })
        }
    };
    let mut observer_time = Duration::ZERO;
    let mut observe = |run: &mut Integration, f: &mut dyn Formulation| -> Result<(), IntegrationError> {
        let sample = run.sample(f)?;
        let started = Instant::now();
        observer(&sample, None);
        observer_time += started.elapsed();
        for parameter in 0..run.sensitivities() {
            for plus in [true, false] {
                let (sample, delta) = run.perturbed_sample(parameter, plus)?;
                let started = Instant::now();
                observer(&sample, Some(PerturbedSide { parameter, plus, delta }));
                observer_time += started.elapsed();
            }
        }
        crate::vector_state::clear_upper_state();
        Ok(())
    };
    let mut result = observe(&mut run, f);
    for k in 1..=run.outputs() {
        if result.is_err() {
            break;
        }
        let t = run.output_time(k);
        result = run.advance_to(f, t, cancel).and_then(|()| observe(&mut run, f));
    }
    let statistics = run.statistics(f);
    match result {
        Ok(()) => Ok(statistics),
        Err(error) => Err(IntegrationFailure {
            error,
            statistics: Box::new(statistics),
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

/// The output times: `t0 + k · every` for `k < n_out`, then `t_end`, then on from `t_end` at the
/// same interval (a run advanced beyond its end).
struct Schedule {
    t0: f64,
    t_end: f64,
    every: f64,
    n_out: u64,
}

impl Schedule {
    fn time(&self, k: u64) -> f64 {
        match k.cmp(&self.n_out) {
            std::cmp::Ordering::Less => self.t0 + k as f64 * self.every,
            std::cmp::Ordering::Equal => self.t_end,
            std::cmp::Ordering::Greater => self.t_end + (k - self.n_out) as f64 * self.every,
        }
    }
}

/// The number of equal steps no longer than `h` that span `span`, and their size.
fn split(span: f64, h: f64) -> (u64, f64) {
    let steps = (span / h - 1e-9).ceil().max(1.0) as u64;
    (steps, span / steps as f64)
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
            advice: if method == crate::methods::ali3p::ENTRY.name {
                "its Newton iteration does not converge there and halving the step only lands nearer, so the run stops: take a larger step, or rk4 with projection (docs/stability.md)"
            } else {
                "its Newton iteration does not converge there (the iteration matrix [M C_qᵀ; C_q 0] loses rank with C_q) and halving the step only lands nearer, so the run stops: pass singular positions with ali3-p (augmented formulation), whose matrix stays regular there, or a fixed-step rk4 with projection (docs/stability.md)"
            },
        },
        None => e,
    }
}
