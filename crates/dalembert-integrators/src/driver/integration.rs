//! A run of a method on a formulation, advanced on demand: [`Integration`].
//!
//! The run's steps do not depend on where it is asked to stop. A fixed-step method steps on the
//! run's grid (the step, shortened so that a whole number of equal steps spans each output
//! interval; halved on a rejection and doubled back after four accepted steps), an adaptive one
//! takes the steps its error control proposes. Asked for a time between two steps, the run takes
//! the step across it and shows the state there without moving its own: the method's dense output
//! (adaptive methods) or the cubic Hermite interpolant of the step's end states and rates (fixed
//! ones), normalized and projected as an output sample is. So a run advanced in any chunks is the
//! same run, bitwise, as one advanced to its end at once. Only a change made at such an
//! in-between time (an input set, a state set) moves the run there: [`Integration::commit`]
//! restarts the method from the state shown, and the grid goes on from that time.

use super::bridge::Bridge;
use super::events::Events;
use super::guard::SingularPassGuard;
use super::monitors::Monitors;
use super::tangents::{Perturbed, Tangents};
use super::work::WorkAlongSteps;
use super::{check_options, inf_norm, normalize, project, singular_or, split, Sample, Schedule};
use crate::branch::BranchMonitor;
use crate::methods::first_order::derivative;
use crate::stepper::{Setup, StepControl, Stepper};
use crate::{IntegrationError, IntegratorOptions, Stabilization, Statistics};
use dalembert_system::Formulation;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

/// The fixed-step grid: the output interval `k` in progress (it ends at `schedule.time(k)`),
/// spanned from `base` by `steps` steps of `hh`, `done` of them taken.
struct Grid {
    h: f64,
    k: u64,
    steps: u64,
    hh: f64,
    done: u64,
    base: f64,
    successes: u32,
}

/// A singular position being bridged: the two half steps of `step` from `start` still to take.
struct Forced {
    start: f64,
    step: f64,
    left: u8,
    /// The failure if a half step cannot be taken.
    stop: Option<IntegrationError>,
}

/// The adaptive method's step control.
struct Adaptive {
    h: f64,
    max_step: f64,
    guard: SingularPassGuard,
    bridge: Bridge,
    /// The collapse found after the last step: bridged before the next step.
    pending: Option<IntegrationError>,
    forced: Option<Forced>,
    /// `(t, h)` of the last step, whose dense output is valid (`None` after a commit).
    dense: Option<(f64, f64)>,
}

enum Control {
    Fixed(Grid),
    Adaptive(Box<Adaptive>),
}

/// A run of a method on a formulation, advanced step by step or to any time
/// ([`Integration::advance_to`]); the run [`crate::integrate`] makes is a loop over one.
///
/// Every method takes the formulation the run was built with: the run keeps the method's state
/// and its own, the formulation keeps the model's work buffers. Nothing is allocated after
/// [`Integration::new`].
pub struct Integration {
    mon: Monitors,
    stepper: Box<dyn Stepper>,
    opts: IntegratorOptions,
    stabilization: Stabilization,
    schedule: Schedule,
    control: Control,
    method: &'static str,
    /// The run's own state and its time.
    t: f64,
    y: Vec<f64>,
    /// The state shown ([`Integration::state`]) and its time; `shown_is_run` when it is the
    /// run's own.
    shown_t: f64,
    shown: Vec<f64>,
    shown_is_run: bool,
    /// Fixed methods: the state and rate at the start of the last step, and the rate at its end
    /// (for the Hermite interpolant); `t_prev` is NaN when they are not of the last step.
    t_prev: f64,
    y_prev: Vec<f64>,
    rate_prev: Vec<f64>,
    rate: Vec<f64>,
    /// Time spent in the run's own work.
    busy: Duration,
    /// The sensitivities carried along ([`Integration::with_sensitivities`]; none by default).
    tangents: Tangents,
    /// The system's events (contacts beginning or ending), where a step is shortened to end.
    events: Events,
    /// The work integrated along the steps, for a model whose forces switch (`None` otherwise).
    work: Option<WorkAlongSteps>,
}

/// `q̈`, `λ`, the residuals and the energy of `f` at `(t, y = [q; q̇])`, as an output sample in
/// `mon`'s buffers.
fn evaluated<'a>(
    f: &mut dyn Formulation,
    mon: &'a mut Monitors,
    (t, y): (f64, &'a [f64]),
    work: f64,
) -> Result<Sample<'a>, IntegrationError> {
    let (q, qd) = y.split_at(mon.n);
    f.accelerations(t, q, qd, mon.baumgarte, &mut mon.qdd, &mut mon.lambda)?;
    f.residuals(t, q, qd, &mut mon.c, &mut mon.cdot);
    let energy = f.energy(t, q, qd).total();
    let forces = f.friction_forces();
    if forces.len() == mon.friction.len() {
        mon.friction.copy_from_slice(forces);
    }
    let forces = f.limit_forces();
    if forces.len() == mon.limit.len() {
        mon.limit.copy_from_slice(forces);
    }
    Ok(Sample {
        t,
        q,
        qd,
        qdd: &mon.qdd,
        lambda: &mon.lambda,
        friction: &mon.friction,
        limit: &mon.limit,
        impact_loss: f.impact_loss(),
        work,
        constraint_violation: inf_norm(&mon.c),
        velocity_violation: inf_norm(&mon.cdot),
        energy,
    })
}

/// How many times a fixed step is shortened to end at an event.
const RELOCATIONS: usize = 8;

fn tolerance(t: f64) -> f64 {
    1e-12 * (1.0 + t.abs())
}

impl Integration {
    /// A run of `opts` on `f` from `(t0, q0, q̇0)` with output times `t0 + k · opts.output_every`
    /// up to `t_end` (the grid of a fixed-step method, and where an adaptive one shortens a step
    /// to land on `t_end`); it may be advanced beyond `t_end`, with output intervals of the same
    /// length after it. With projection the initial state is projected first.
    pub fn new(
        f: &mut dyn Formulation,
        t0: f64,
        t_end: f64,
        q0: &[f64],
        qd0: &[f64],
        opts: &IntegratorOptions,
    ) -> Result<Self, IntegrationError> {
        let wall = Instant::now();
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
        let (n, n_v) = (q0.len(), qd0.len());
        let m = f.system().num_equations();
        let mut y = [q0, qd0].concat();
        let energy0 = f.energy(t0, q0, qd0).total();
        let conservative_fixed = f.system().is_conservative() && entry.control == StepControl::Fixed;
        let mon = Monitors {
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
            friction: vec![0.0; f.system().frictions().len()],
            limit: vec![0.0; f.system().limits().len()],
            energy0,
            scale0: 1.0 + inf_norm(&y),
            divergence_factor: opts.divergence_factor,
            baumgarte: stabilization.gains(opts.step),
            branch: BranchMonitor::new(f, q0, qd0, energy0, conservative_fixed),
        };
        crate::vector_state::clear_upper_state();
        project(f, t0, &mut y, n, stabilization)?;
        let stepper = (entry.build)(
            &opts.method,
            Setup {
                formulation: &mut *f,
                t0,
                y0: &y,
                n_q: n,
                baumgarte: mon.baumgarte,
            },
        )?;
        let schedule = Schedule {
            t0,
            t_end,
            every: opts.output_every,
            n_out: ((t_end - t0) / opts.output_every - 1e-9).ceil().max(0.0) as u64,
        };
        let control = match entry.control {
            StepControl::Fixed => Control::Fixed(Grid {
                h: opts.step,
                k: 0,
                steps: 0,
                hh: opts.step,
                done: 0,
                base: t0,
                successes: 0,
            }),
            StepControl::Adaptive => {
                let max_step = opts.max_step.min(t_end - t0).max(opts.min_step);
                Control::Adaptive(Box::new(Adaptive {
                    h: opts.step.min(max_step),
                    max_step,
                    guard: SingularPassGuard::default(),
                    bridge: Bridge::new(y.len(), &opts.method),
                    pending: None,
                    forced: None,
                    dense: None,
                }))
            }
        };
        let len = y.len();
        let events = Events::new(f, t0, &y, n);
        let work = match opts.work_along_steps {
            true => WorkAlongSteps::new(f, (t0, &y, n), mon.baumgarte)?,
            false => None,
        };
        Ok(Integration {
            mon,
            stepper,
            opts: *opts,
            stabilization,
            schedule,
            control,
            method: entry.name,
            t: t0,
            shown_t: t0,
            shown: y.clone(),
            y,
            shown_is_run: true,
            t_prev: f64::NAN,
            y_prev: vec![0.0; len],
            rate_prev: vec![0.0; len],
            rate: vec![0.0; len],
            busy: wall.elapsed(),
            tangents: Tangents::default(),
            events,
            work,
        })
    }

    /// The run carrying the sensitivities of its state to the parameters that `perturbed` change
    /// (`docs/sensitivities.md`): each accepted step is taken again from `y ± δ S` on the models
    /// with `p ± δ`, and [`Integration::perturbed_sample`] gives each side at an output time.
    /// Only at the run's start, and for a run sampled at its output times (not moved by
    /// [`Integration::commit`] or [`Integration::set_state`]).
    pub fn with_sensitivities(mut self, perturbed: Vec<Perturbed>) -> Result<Self, IntegrationError> {
        if !self.shown_is_run || self.mon.stats.steps > 0 {
            return Err(IntegrationError::Options(
                "sensitivities are set up at the start of a run, before its first step".into(),
            ));
        }
        self.tangents = Tangents::new(
            perturbed,
            self.t,
            &self.y,
            self.mon.n,
            &self.opts,
            self.stabilization,
            self.mon.baumgarte,
        )?;
        Ok(self)
    }

    /// The number of parameters whose sensitivities the run carries.
    pub fn sensitivities(&self) -> usize {
        self.tangents.len()
    }

    /// `∂y/∂p` (`y = [q; v]`) of sensitivity `j` at the run's own state (after its last step).
    pub fn sensitivity(&self, j: usize) -> &[f64] {
        self.tangents.tangent(j)
    }

    /// Sensitivity `j`'s model with `p + δ` (`plus`) or `p − δ` at the time shown, as an output
    /// sample, and `δ`: a column's derivative is `(value₊ − value₋) / 2δ`.
    pub fn perturbed_sample(&mut self, j: usize, plus: bool) -> Result<(Sample<'_>, f64), IntegrationError> {
        let started = Instant::now();
        let (f, y, delta) = self.tangents.side(j, plus);
        let sample = evaluated(f, &mut self.mon, (self.shown_t, y), f64::NAN)?;
        self.busy += started.elapsed();
        Ok((sample, delta))
    }

    /// The time of the state shown.
    pub fn time(&self) -> f64 {
        self.shown_t
    }

    /// The state shown `(q, q̇)`: the run's own after a step, or between two steps the state at
    /// the time asked for.
    pub fn state(&self) -> (&[f64], &[f64]) {
        let y = if self.shown_is_run { &self.y } else { &self.shown };
        y.split_at(self.mon.n)
    }

    /// The `k`-th output time: `t0 + k · output_every` before `t_end`, `t_end`, then on from
    /// `t_end` at the same interval.
    pub fn output_time(&self, k: u64) -> f64 {
        self.schedule.time(k)
    }

    /// The number of output intervals up to `t_end`.
    pub fn outputs(&self) -> u64 {
        self.schedule.n_out
    }

    /// One step of the method (an adaptive method: one accepted step); between two steps (after
    /// [`Integration::advance_to`] stopped inside one), to the end of the step in progress.
    /// `cancel` set stops it with [`IntegrationError::Interrupted`] after the step.
    pub fn step(&mut self, f: &mut dyn Formulation, cancel: &AtomicBool) -> Result<(), IntegrationError> {
        let started = Instant::now();
        crate::vector_state::clear_upper_state();
        let result = if self.shown_is_run {
            self.unit(f, cancel)
        } else {
            Ok(())
        };
        self.shown_t = self.t;
        self.shown_is_run = true;
        self.t_prev = f64::NAN;
        self.busy += started.elapsed();
        result
    }

    /// Advances to exactly `t` (not before the time shown): every step of the run up to `t`, and
    /// the state at `t` from the step across it when `t` falls between two steps. `cancel` set
    /// stops it with [`IntegrationError::Interrupted`] after the step in progress (the time and
    /// state shown are then the run's own at that step).
    pub fn advance_to(&mut self, f: &mut dyn Formulation, t: f64, cancel: &AtomicBool) -> Result<(), IntegrationError> {
        if !t.is_finite() || t < self.shown_t - tolerance(self.shown_t) {
            return Err(IntegrationError::Options(format!(
                "cannot advance to t = {}: the run is at t = {} (a run goes forward only)",
                dalembert_system::Shortest(t),
                dalembert_system::Shortest(self.shown_t)
            )));
        }
        let started = Instant::now();
        crate::vector_state::clear_upper_state();
        let result = self.advance(f, t, cancel);
        if result.is_err() {
            self.shown_t = self.t;
            self.shown_is_run = true;
        }
        self.busy += started.elapsed();
        result
    }

    fn advance(&mut self, f: &mut dyn Formulation, t: f64, cancel: &AtomicBool) -> Result<(), IntegrationError> {
        let tol = tolerance(t);
        while self.t < t - tol {
            // An event the last step ended at, settled as the run goes on from it.
            self.settle(f)?;
            let across = match &self.control {
                Control::Fixed(_) => self.next_end() > t + tol,
                Control::Adaptive(_) => false,
            };
            if across {
                self.t_prev = self.t;
                self.y_prev.copy_from_slice(&self.y);
                derivative(
                    f,
                    self.t,
                    &self.y_prev,
                    self.mon.baumgarte,
                    &mut self.mon.qdd,
                    &mut self.mon.lambda,
                    &mut self.rate_prev,
                )?;
            } else {
                self.t_prev = f64::NAN;
            }
            self.unit(f, cancel)?;
        }
        self.show(f, t)
    }

    /// Shows the state at `t`, within the last step (or at the run's own time).
    fn show(&mut self, f: &mut dyn Formulation, t: f64) -> Result<(), IntegrationError> {
        let n_q = self.mon.n;
        let dense = match &self.control {
            Control::Adaptive(a) => a.dense,
            Control::Fixed(_) => None,
        };
        self.shown_t = t;
        if let Some((ts, h)) = dense.filter(|&(ts, _)| t >= ts) {
            let theta = ((t - ts) / h).clamp(0.0, 1.0);
            self.stepper.interpolate(theta, &mut self.shown);
            self.tangents.show(self.stepper.as_ref(), theta, n_q);
        } else if (self.t - t).abs() <= tolerance(t) || self.t_prev.is_nan() {
            self.shown_is_run = true;
            self.tangents.show_run();
            return Ok(());
        } else if !self.tangents.is_empty() {
            return Err(IntegrationError::Options(format!(
                "a run with sensitivities is shown at its steps only, not at t = {}",
                dalembert_system::Shortest(t)
            )));
        } else {
            // The cubic Hermite interpolant of the step's end states and rates.
            derivative(
                f,
                self.t,
                &self.y,
                self.mon.baumgarte,
                &mut self.mon.qdd,
                &mut self.mon.lambda,
                &mut self.rate,
            )?;
            let h = self.t - self.t_prev;
            let s = ((t - self.t_prev) / h).clamp(0.0, 1.0);
            let (s2, s3) = (s * s, s * s * s);
            let (h00, h10, h01, h11) = (
                2.0 * s3 - 3.0 * s2 + 1.0,
                s3 - 2.0 * s2 + s,
                -2.0 * s3 + 3.0 * s2,
                s3 - s2,
            );
            for i in 0..self.shown.len() {
                self.shown[i] =
                    h00 * self.y_prev[i] + h10 * h * self.rate_prev[i] + h01 * self.y[i] + h11 * h * self.rate[i];
            }
        }
        self.shown_is_run = false;
        normalize(f, &mut self.shown, n_q);
        project(f, t, &mut self.shown, n_q, self.stabilization)?;
        Ok(())
    }

    /// Where the next step of the fixed grid ends.
    fn next_end(&self) -> f64 {
        let Control::Fixed(g) = &self.control else {
            return f64::INFINITY;
        };
        if g.done == g.steps {
            let t_next = self.schedule.time(g.k + 1);
            let (steps, hh) = split(t_next - self.t, g.h);
            if steps == 1 {
                t_next
            } else {
                self.t + hh
            }
        } else if g.done + 1 == g.steps {
            self.schedule.time(g.k)
        } else {
            g.base + (g.done + 1) as f64 * g.hh
        }
    }

    /// Makes the state shown the run's own: the method starts again from it at its time (an
    /// input is about to change there). Nothing when it already is.
    pub fn commit(&mut self) {
        if self.shown_is_run {
            return;
        }
        self.y.copy_from_slice(&self.shown);
        self.restart_at(self.shown_t);
    }

    /// Replaces the state at the time shown with `(q, q̇)` (consistent with the constraints: the
    /// caller assembles it) and starts the method and the monitors again from there. Allocates
    /// (the monitors are rebuilt).
    pub fn set_state(&mut self, f: &mut dyn Formulation, q: &[f64], qd: &[f64]) -> Result<(), IntegrationError> {
        let n = self.mon.n;
        if q.len() != n || qd.len() != self.y.len() - n {
            return Err(IntegrationError::Options(format!(
                "a state of {} positions and {} velocities was given where the model has {} and {}",
                q.len(),
                qd.len(),
                n,
                self.y.len() - n
            )));
        }
        self.y[..n].copy_from_slice(q);
        self.y[n..].copy_from_slice(qd);
        let t = self.shown_t;
        let energy = f.energy(t, q, qd).total();
        self.mon.energy0 = energy;
        self.mon.scale0 = 1.0 + inf_norm(&self.y);
        let conservative_fixed = self.mon.branch.watches_energy();
        self.mon.branch = BranchMonitor::new(f, q, qd, energy, conservative_fixed);
        // The modes (a limit held or free, a joint stuck or slipping) and the coordinates a
        // limit follows across half turns are the new state's, not those of the state before.
        f.start_events(t, q, qd);
        self.events.accepted(f, t, &self.y, n);
        self.restart_at(t);
        Ok(())
    }

    /// The method goes on from the run's state `y` at `t`: told so, with the grid spanning the
    /// rest of its output interval from `t`.
    fn restart_at(&mut self, t: f64) {
        if let Some(w) = self.work.as_mut() {
            w.move_to(t);
        }
        self.t = t;
        self.shown_t = t;
        self.shown_is_run = true;
        self.t_prev = f64::NAN;
        self.stepper.state_changed();
        match &mut self.control {
            Control::Fixed(g) => {
                if g.done == g.steps && t >= self.schedule.time(g.k) {
                    g.k += 1;
                }
                g.base = t;
                g.done = 0;
                (g.steps, g.hh) = split(self.schedule.time(g.k) - t, g.h);
            }
            Control::Adaptive(a) => {
                a.dense = None;
                a.pending = None;
                a.forced = None;
            }
        }
    }

    /// `q̈`, `λ`, the residuals and the energy at the state shown, as an output sample.
    pub fn sample(&mut self, f: &mut dyn Formulation) -> Result<Sample<'_>, IntegrationError> {
        let started = Instant::now();
        let t = self.shown_t;
        let y = if self.shown_is_run { &self.y } else { &self.shown };
        let work = self.work.as_ref().map_or(f64::NAN, |w| w.at(t));
        let sample = evaluated(f, &mut self.mon, (t, y), work)?;
        self.busy += started.elapsed();
        Ok(sample)
    }

    /// The statistics of the run so far (wall time: the run's own work, without the caller's).
    pub fn statistics(&self, f: &dyn Formulation) -> Statistics {
        let mut s = self.mon.statistics(f, self.stepper.work());
        (s.tangents_carried, s.tangents_differenced) = self.tangents.counts();
        s.wall_time = self.busy;
        s
    }

    /// Settles an event the last step ended at (an impulse may change the state: the work's
    /// quadrature starts again there, as it does where the run was moved).
    fn settle(&mut self, f: &mut dyn Formulation) -> Result<(), IntegrationError> {
        let n_q = self.mon.n;
        let settled = self.events.settle_pending(f, self.t, &mut self.y, n_q)?;
        if settled {
            self.stepper.state_changed();
        }
        if let Some(w) = self.work.as_mut().filter(|w| settled || w.moved()) {
            w.restart(f, (self.t, &self.y, n_q), self.mon.baumgarte)?;
        }
        Ok(())
    }

    /// One step of the run (a fixed step, an accepted adaptive step, or half of a bridge).
    fn unit(&mut self, f: &mut dyn Formulation, cancel: &AtomicBool) -> Result<(), IntegrationError> {
        self.settle(f)?;
        let events = self.mon.stats.events;
        let result = match self.control {
            Control::Fixed(_) => self.fixed_unit(f, cancel),
            Control::Adaptive(_) => self.adaptive_unit(f, cancel),
        };
        if result.is_ok() {
            if let Some(w) = self.work.as_mut() {
                let at_event = self.mon.stats.events > events;
                w.step(f, (self.t, &self.y, self.mon.n), self.mon.baumgarte, at_event)?;
            }
        }
        // The method says what a divergence likely means for it.
        result.map_err(|e| match e {
            IntegrationError::Diverged { time, what, step, .. } => IntegrationError::Diverged {
                time,
                what,
                step,
                hint: self.stepper.divergence_hint(step),
            },
            other => other,
        })
    }

    fn fixed_unit(&mut self, f: &mut dyn Formulation, cancel: &AtomicBool) -> Result<(), IntegrationError> {
        let Integration {
            mon,
            stepper,
            opts,
            stabilization,
            schedule,
            control: Control::Fixed(g),
            method,
            t,
            y,
            tangents,
            events,
            work,
            ..
        } = self
        else {
            unreachable!("a fixed step of an adaptive method")
        };
        loop {
            if g.done == g.steps {
                g.k += 1;
                g.base = *t;
                (g.steps, g.hh) = split(schedule.time(g.k) - g.base, g.h);
                g.done = 0;
            }
            let ts = g.base + g.done as f64 * g.hh;
            tangents.mark(y);
            events.mark(y);
            let mut h = g.hh;
            let mut outcome = tangents.step(stepper.as_mut(), f, ts, h, y)?;
            // An event inside the step (a contact beginning or ending, a slip stopping, an
            // impact): the step again, to end there (the rest of the output interval is then
            // spanned anew from it), first where the event's tangent at the step's start says,
            // then by regula falsi on the fractions tried ([`Events::refine`], at most
            // `RELOCATIONS` times).
            let mut located = false;
            let mut restarted = false;
            'locate: while outcome.accepted && !events.located {
                let Some(chord) = events.chord(f, ts, h, y, mon.n) else {
                    break;
                };
                let full = h;
                let at = (ts, h, mon.n);
                let tangent = events.tangent(f, at, mon.baumgarte, &mut mon.qdd, &mut mon.lambda)?;
                let mut theta = tangent.unwrap_or(chord);
                let mut tries = 0;
                while tries < RELOCATIONS {
                    if theta * full <= opts.min_step {
                        if tries == 0 && !restarted && events.settle_at_start(f, ts, y, mon.n)? {
                            // The event at the step's start changed the law: the step again,
                            // and its events looked for anew; the work's quadrature starts
                            // there again.
                            if let Some(w) = work.as_mut() {
                                w.restart(f, (ts, y, mon.n), mon.baumgarte)?;
                            }
                            stepper.state_changed();
                            tangents.discard();
                            f.begin_step();
                            outcome = stepper.step(f, ts, h, y)?;
                            restarted = true;
                            continue 'locate;
                        }
                        break;
                    }
                    events.restore(y);
                    stepper.state_changed();
                    tangents.discard();
                    h = theta * full;
                    f.begin_step();
                    outcome = stepper.step(f, ts, h, y)?;
                    located = true;
                    tries += 1;
                    if !outcome.accepted {
                        break;
                    }
                    match events.refine(f, ts + h, theta, y, mon.n) {
                        Some(next) => theta = next,
                        None => break,
                    }
                }
                break;
            }
            if !outcome.accepted {
                g.successes = 0;
                g.h = 0.5 * g.hh;
                if let Err(e) = mon.rejected(ts, g.h, outcome.error, opts.min_step) {
                    return Err(singular_or(e, f, ts, y, method));
                }
                // The rest of the interval at the halved step.
                g.base = ts;
                g.done = 0;
                (g.steps, g.hh) = split(schedule.time(g.k) - g.base, g.h);
                continue;
            }
            let t_after = if located {
                ts + h
            } else {
                g.done += 1;
                if g.done == g.steps {
                    schedule.time(g.k)
                } else {
                    g.base + g.done as f64 * g.hh
                }
            };
            normalize(f, y, mon.n);
            mon.project_step(f, t_after, y, *stabilization)?;
            // Like the projection, not told to the method.
            let energy = mon.undo_kick(f, t_after, y);
            // The loop does not tell a fixed-step method that its state was projected.
            tangents.follow(ts, h, mon.n, false)?;
            if located {
                events.defer();
            } else {
                // A switch that does not change the law (a stuck joint already slipping by
                // (F3)) is made at the step's end, without taking the step again.
                if events.settle_unlocated(f, t_after, y, mon.n)? {
                    stepper.state_changed();
                    mon.stats.events += 1;
                }
                events.accepted(f, t_after, y, mon.n);
            }
            *t = t_after;
            mon.monitor(f, t_after, y, h, energy, cancel)?;
            if located {
                mon.stats.events += 1;
                // The rest of the interval from the event, at the run's step.
                g.base = t_after;
                g.done = 0;
                (g.steps, g.hh) = split(schedule.time(g.k) - g.base, g.h);
                return Ok(());
            }
            g.successes += 1;
            if g.successes >= 4 && g.h < opts.step && g.done < g.steps {
                // Grow back: the rest of the interval at the doubled step.
                g.h = (2.0 * g.h).min(opts.step);
                g.successes = 0;
                g.base = t_after;
                g.done = 0;
                (g.steps, g.hh) = split(schedule.time(g.k) - g.base, g.h);
            }
            return Ok(());
        }
    }

    fn adaptive_unit(&mut self, f: &mut dyn Formulation, cancel: &AtomicBool) -> Result<(), IntegrationError> {
        let Integration {
            mon,
            stepper,
            opts,
            stabilization,
            schedule,
            control: Control::Adaptive(a),
            method,
            t,
            y,
            tangents,
            events,
            work,
            ..
        } = self
        else {
            unreachable!("an adaptive step of a fixed-step method")
        };
        let (n_q, t_end, stab) = (mon.n, schedule.t_end, *stabilization);
        let mut settled = false;
        loop {
            // A bridge in progress: its next half step, a step of the run.
            if let Some(forced) = a.forced.as_mut() {
                let half = 0.5 * forced.step;
                tangents.mark(y);
                if !stepper.step_unchecked(f, *t, half, y)? {
                    y.copy_from_slice(a.bridge.saved());
                    *t = forced.start;
                    stepper.state_changed();
                    let stop = forced.stop.take();
                    a.forced = None;
                    return Err(stop.unwrap_or(IntegrationError::Options("a bridge step failed".into())));
                }
                let te = *t + half;
                a.dense = Some((*t, half));
                normalize(f, y, n_q);
                // Checked by the agreement of the bridge, not by the branch monitor's projection
                // share: a step across the singular instant drifts more than the steps it watches
                // (2.1e-2 of the kinetic energy on the driven four-bar, on the branch).
                project(f, te, y, n_q, stab)?;
                stepper.state_changed();
                tangents.follow(*t, half, n_q, true)?;
                *t = te;
                forced.left -= 1;
                if forced.left == 0 {
                    let (start, step) = (forced.start, forced.step);
                    a.forced = None;
                    mon.stats.bridges += 1;
                    *t = if start < t_end {
                        (start + step).min(t_end)
                    } else {
                        start + step
                    };
                    a.h = step.min(a.max_step);
                    a.guard.rearm();
                }
                mon.monitor(f, te, y, half, None, cancel)?;
                return Ok(());
            }
            // A collapse found after the last step: across the singular position with checked
            // steps of the size the run had before its steps collapsed, or stop with the cause.
            if let Some(stop) = a.pending.take() {
                let largest = if *t < t_end {
                    a.guard.largest.min(t_end - *t)
                } else {
                    a.guard.largest
                };
                match a.bridge.find(f, stepper.as_mut(), y, *t, largest, n_q, stab) {
                    Some(step) => {
                        a.forced = Some(Forced {
                            start: *t,
                            step,
                            left: 2,
                            stop: Some(stop),
                        });
                        continue;
                    }
                    None => return Err(stop),
                }
            }
            let last = *t < t_end && *t + a.h >= t_end - tolerance(t_end);
            if last {
                a.h = t_end - *t;
            }
            tangents.mark(y);
            events.mark(y);
            let outcome = tangents.step(stepper.as_mut(), f, *t, a.h, y)?;
            if outcome.accepted && !events.located {
                // A contact beginning or ending inside the step: the step again, to end there.
                let mut found = events.crossing(f, stepper.as_ref(), *t, a.h, y, n_q);
                if found.is_some_and(|theta| theta * a.h <= opts.min_step) {
                    // At the step's start: settled there (once), and the step taken again.
                    if !settled && events.settle_at_start(f, *t, y, n_q)? {
                        // The power may jump there too: the work's quadrature starts again.
                        if let Some(w) = work.as_mut() {
                            w.restart(f, (*t, y, n_q), mon.baumgarte)?;
                        }
                        settled = true;
                        stepper.state_changed();
                        mon.stats.events += 1;
                        continue;
                    }
                    // Settled, or nothing to settle: the first crossing after the start's.
                    events.skip_start(f, stepper.as_ref(), (*t, a.h, opts.min_step / a.h), n_q);
                    found = events.crossing(f, stepper.as_ref(), *t, a.h, y, n_q);
                }
                if let Some(theta) = found.filter(|theta| theta * a.h > opts.min_step) {
                    events.restore(y);
                    stepper.state_changed();
                    a.h *= theta;
                    events.located = true;
                    continue;
                }
            }
            let collapse = a
                .guard
                .check(f, *t, y, n_q, outcome.next_step, method, &mut mon.branch.check)
                .err();
            if outcome.accepted {
                let t_new = if last { t_end } else { *t + a.h };
                a.dense = Some((*t, a.h));
                normalize(f, y, n_q);
                let projected = mon.project_step(f, t_new, y, stab)?;
                if projected {
                    stepper.state_changed();
                }
                tangents.follow(*t, a.h, n_q, projected)?;
                if events.located {
                    mon.stats.events += 1;
                    events.defer();
                } else {
                    events.accepted(f, t_new, y, n_q);
                }
                let h = a.h;
                *t = t_new;
                a.guard.accepted(h);
                a.bridge.steady();
                a.h = outcome.next_step.min(a.max_step);
                a.pending = collapse;
                mon.monitor(f, t_new, y, h, None, cancel)?;
                return Ok(());
            } else if collapse.is_none() {
                mon.rejected(*t, outcome.next_step, outcome.error, opts.min_step)?;
                a.h = outcome.next_step;
            } else {
                a.pending = collapse;
            }
        }
    }
}
