//! Events: where a contact begins or ends, a step of an adaptive method is shortened to end
//! there (`docs/contact.md`, "Events").
//!
//! The system's event functions ([`dalembert_system::MultibodySystem::events`], each contact's
//! gap) are evaluated after every accepted step. Where one changed sign within the step, the loop
//! finds the first fraction `θ` of the step where one vanishes, on the method's dense output
//! (bisection to `10⁻¹²` of the step; a fixed-step method, which has none, on the chord of the
//! values at the step's ends), and takes the step again from its start with size `θ h`:
//! the force's kink (a contact force starts from zero with an unbounded derivative) then falls on
//! a step boundary instead of inside a step, and no contact is stepped over. The shortened step
//! is accepted without another check, so that a root found slightly past the crossing cannot
//! shorten it again.

use crate::methods::first_order::derivative;
use crate::stepper::Stepper;
use dalembert_system::{Baumgarte, DynamicsError, Formulation};

/// Bisection steps on `θ ∈ [0, 1]`: `2⁻⁴⁰ ≈ 10⁻¹²` of the step.
const BISECTIONS: usize = 40;

/// How far from zero, in multiples of its [`Formulation::event_tolerance`], the function a step
/// was shortened for may end and still count as crossed ([`Events::settle`]): the round-off of a
/// step taken to the located fraction (a stop's function there is within 10⁻¹³ rad of zero, a
/// slip's rate within a hundredth of its margin), far below an interpolant's error.
const AIMED_SLACK: f64 = 1e3;

/// True where an event function went from `a` to `b` across zero (from or to zero exactly does
/// not count).
fn changed_sign(a: f64, b: f64) -> bool {
    (a > 0.0 && b < 0.0) || (a < 0.0 && b > 0.0)
}

/// The event functions of a run and the state at the start of the step in progress.
#[derive(Default)]
pub(super) struct Events {
    /// The event functions at the run's state.
    g0: Vec<f64>,
    /// Work space.
    g: Vec<f64>,
    /// The run's state at the start of the step in progress.
    start: Vec<f64>,
    /// A state on the dense output.
    y: Vec<f64>,
    /// Which functions changed sign over the step just located ([`Events::settle`]).
    crossed: Vec<bool>,
    /// The function a fixed step was shortened to end at: it counts as crossed at the step's
    /// end even where the step fell short of it by round-off ([`Events::settle`]).
    aimed: Option<usize>,
    /// The rate `ẏ` at the start of the step ([`Events::tangent`]).
    rate: Vec<f64>,
    /// The functions a little way along that rate.
    ahead: Vec<f64>,
    /// True while the step in progress was shortened to end at an event.
    pub located: bool,
    /// True when a step ended at an event that is not yet settled ([`Events::defer`]).
    pending: bool,
    /// The fractions of a fixed step around the aimed function's zero, with its values there
    /// ([`Events::refine`]).
    bracket: ((f64, f64), (f64, f64)),
    /// Which end of the bracket the last refinement moved (true: the far one).
    last_side: Option<bool>,
    /// The fraction tried before the last one and the aimed function's value there (the step's
    /// start at first): the secant through it and the last ([`Events::refine`]).
    previous: (f64, f64),
    /// True while [`Events::settle_at_start`] settles: the aimed function counts as crossed.
    at_start: bool,
    /// The functions [`Events::crossing`] passes over ([`Events::skip_start`]).
    skip: Vec<bool>,
}

impl Events {
    /// The events of the system `f` integrates, at its initial state `y0` (`n_q` positions).
    pub fn new(f: &mut dyn Formulation, t0: f64, y0: &[f64], n_q: usize) -> Self {
        let m = f.system().num_events();
        if m == 0 {
            return Events::default();
        }
        let mut g0 = vec![0.0; m];
        let (q, v) = y0.split_at(n_q);
        f.start_events(t0, q, v);
        f.events(t0, q, v, &mut g0);
        Events {
            g: vec![0.0; m],
            g0,
            start: vec![0.0; y0.len()],
            y: vec![0.0; y0.len()],
            crossed: vec![false; m],
            aimed: None,
            rate: vec![0.0; y0.len()],
            ahead: vec![0.0; m],
            located: false,
            pending: false,
            bracket: ((0.0, 0.0), (1.0, 0.0)),
            last_side: None,
            previous: (0.0, 0.0),
            at_start: false,
            skip: vec![false; m],
        }
    }

    /// True when the system has no event function.
    pub fn is_empty(&self) -> bool {
        self.g0.is_empty()
    }

    /// Keeps the run's state `y` at the start of a step.
    pub fn mark(&mut self, y: &[f64]) {
        if !self.is_empty() {
            self.start.copy_from_slice(y);
        }
    }

    /// A step from `t` crossed an event so near its start (`θ h` below the smallest step) that
    /// it cannot end there: the event is settled at the start instead ([`Events::settle`] on the
    /// state kept by [`Events::mark`]), the function located counting as crossed there whatever
    /// its value (the step that ended short of its zero, an interpolant's error away, ended
    /// within the smallest step of it: a limit's force 3.6e-11 N short of zero, measured, where
    /// its tolerance is 10⁻¹⁴; left unsettled, the crossing would be stepped over and lost). Where the formulation changed the state or its law, `y`
    /// is that state, its functions start the step again, and the result is true (the step is
    /// to be taken again); otherwise `y` is left as the step ended.
    pub fn settle_at_start(
        &mut self,
        f: &mut dyn Formulation,
        t: f64,
        y: &mut [f64],
        n_q: usize,
    ) -> Result<bool, DynamicsError> {
        let mut start = std::mem::take(&mut self.start);
        self.at_start = true;
        let settled = self.settle(f, t, &mut start, n_q);
        self.at_start = false;
        self.start = start;
        self.aimed = None;
        if !settled? {
            return Ok(false);
        }
        y.copy_from_slice(&self.start);
        let (q, v) = y.split_at(n_q);
        f.events(t, q, v, &mut self.g0);
        Ok(true)
    }

    /// The run's state at the start of the step in progress, into `y` (the step is taken again).
    pub fn restore(&self, y: &mut [f64]) {
        y.copy_from_slice(&self.start);
    }

    /// After a step from `t` of size `h` ending at `y` (its dense output in `stepper`): the first
    /// fraction `θ ∈ (0, 1)` of the step where an event function that changed sign vanishes, or
    /// `None` when none changed sign.
    pub fn crossing(
        &mut self,
        f: &mut dyn Formulation,
        stepper: &dyn Stepper,
        t: f64,
        h: f64,
        y: &[f64],
        n_q: usize,
    ) -> Option<f64> {
        if self.is_empty() {
            return None;
        }
        let (q, v) = y.split_at(n_q);
        f.events(t + h, q, v, &mut self.g);
        let skip = &self.skip;
        let changed = |(i, (&a, &b)): (usize, (&f64, &f64))| !skip[i] && changed_sign(a, b);
        if !(self.g0.iter().zip(&self.g)).enumerate().any(changed) {
            return None;
        }
        // The first θ where any function that changed over the step has changed: bisection on
        // "some function changed sign between 0 and θ".
        let (mut lo, mut hi) = (0.0, 1.0);
        for _ in 0..BISECTIONS {
            let mid = 0.5 * (lo + hi);
            stepper.interpolate(mid, &mut self.y);
            let (q, v) = self.y.split_at(n_q);
            f.events(t + mid * h, q, v, &mut self.g);
            if (self.g0.iter().zip(&self.g)).enumerate().any(changed) {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        // The function that changed first: the step taken again to `hi` ends at its zero, even
        // where that step falls short of it by round-off ([`Events::settle`]).
        stepper.interpolate(hi, &mut self.y);
        let (q, v) = self.y.split_at(n_q);
        f.events(t + hi * h, q, v, &mut self.g);
        self.aimed = (self.g0.iter().zip(&self.g)).enumerate().position(changed);
        Some(hi)
    }

    /// A step from `t` of size `h` (its dense output in `stepper`) crossed an event within its
    /// first fraction `theta` (the smallest step), and settling it at the start
    /// ([`Events::settle_at_start`]) changed nothing, or was done already: the functions that
    /// changed sign by `theta` are passed over by the next [`Events::crossing`], which then finds
    /// the first crossing after them. Without it the whole step was taken with every later
    /// crossing in it lost: a corner let go from a floor a little below it, its function
    /// crossing zero as it rose, and two other corners of the box landing within the step went
    /// through the floor. [`Events::accepted`] clears it.
    pub fn skip_start(
        &mut self,
        f: &mut dyn Formulation,
        stepper: &dyn Stepper,
        (t, h, theta): (f64, f64, f64),
        n_q: usize,
    ) {
        if self.is_empty() {
            return;
        }
        let theta = theta.min(1.0);
        stepper.interpolate(theta, &mut self.y);
        let (q, v) = self.y.split_at(n_q);
        f.events(t + theta * h, q, v, &mut self.g);
        for ((s, &a), &b) in self.skip.iter_mut().zip(&self.g0).zip(&self.g) {
            *s = changed_sign(a, b);
        }
    }

    /// After a fixed step from `t` of size `h` ending at `y`: the fraction `θ ∈ (0, 1)` of the
    /// step where the first event function that changed sign vanishes on the chord of its values
    /// at the step's ends (a fixed-step method has no dense output), or `None`. The step taken
    /// again to there ends near the event; where it falls short, the next step finds the rest.
    pub fn chord(&mut self, f: &mut dyn Formulation, t: f64, h: f64, y: &[f64], n_q: usize) -> Option<f64> {
        if self.is_empty() {
            return None;
        }
        let (q, v) = y.split_at(n_q);
        f.events(t + h, q, v, &mut self.g);
        let first = (self.g0.iter().zip(&self.g).enumerate())
            .filter(|&(i, (&a, &b))| changed_sign(a, b) && f.event_needs_location(i))
            .map(|(i, (&a, &b))| (i, a / (a - b)))
            .min_by(|x, y| x.1.total_cmp(&y.1));
        if let Some((i, _)) = first {
            self.aimed = Some(i);
            self.bracket = ((0.0, self.g0[i]), (1.0, self.g[i]));
            self.last_side = None;
            self.previous = (0.0, self.g0[i]);
        }
        first.map(|(_, theta)| theta)
    }

    /// After a fixed step shortened to the fraction `theta` of the step `chord` located (from its
    /// start `t`, ending at `y`): the next fraction to try for the aimed function's zero, or
    /// `None` when the step ends at the zero (within the function's
    /// [`Formulation::event_tolerance`] or a bracket of 10⁻¹² of the step).
    /// The secant through the last two fractions tried (the first through the step's start),
    /// where it falls inside the bracket of fractions tried so far: both are steps taken with
    /// the law before the event, where the full step's end is not (its stages past the event
    /// followed the law after it, a friction that reversed). Otherwise regula falsi with the
    /// Illinois rule on the bracket (the chord's fixed end stalls on a curved function: a body
    /// falling onto a stop).
    pub fn refine(&mut self, f: &mut dyn Formulation, t: f64, theta: f64, y: &[f64], n_q: usize) -> Option<f64> {
        let i = self.aimed?;
        let (q, v) = y.split_at(n_q);
        f.events(t, q, v, &mut self.g);
        let (a, g) = (self.g0[i], self.g[i]);
        if g.abs() <= f.event_tolerance(i) || !g.is_finite() {
            return None;
        }
        let ((lo, glo), (hi, ghi)) = (&mut self.bracket.0, &mut self.bracket.1);
        if (g > 0.0) == (a > 0.0) {
            *lo = theta;
            *glo = g;
            if self.last_side == Some(false) {
                *ghi *= 0.5;
            }
            self.last_side = Some(false);
        } else {
            *hi = theta;
            *ghi = g;
            if self.last_side == Some(true) {
                *glo *= 0.5;
            }
            self.last_side = Some(true);
        }
        if *hi - *lo <= 1e-12 {
            return None;
        }
        let (before, g_before) = std::mem::replace(&mut self.previous, (theta, g));
        let secant = theta - g * (theta - before) / (g - g_before);
        if secant > *lo && secant < *hi {
            return Some(secant);
        }
        Some(*lo + (*hi - *lo) * *glo / (*glo - *ghi))
    }

    /// After a step shortened to end at an event, ending at `y` at `t`: the formulation does what
    /// the events that changed sign over it ask of the state
    /// ([`Formulation::at_event`], a slip that stopped made to stick). True when it changed `y`.
    pub fn settle(
        &mut self,
        f: &mut dyn Formulation,
        t: f64,
        y: &mut [f64],
        n_q: usize,
    ) -> Result<bool, DynamicsError> {
        if self.is_empty() {
            return Ok(false);
        }
        let (q, v) = y.split_at_mut(n_q);
        f.events(t, q, v, &mut self.g);
        for (i, ((c, &a), &b)) in self.crossed.iter_mut().zip(&self.g0).zip(&self.g).enumerate() {
            // The aimed function counts where the step fell short of its zero by round-off
            // (within `AIMED_SLACK` times its tolerance), not where it stopped short of it: an
            // interpolant off by more (a law that changed inside the step it came from) must
            // not put the event where the function is not zero (a stop struck 6.7e-6 rad before
            // it was reached); the next step finds the crossing.
            let aimed = self.aimed == Some(i) && (self.at_start || b.abs() <= AIMED_SLACK * f.event_tolerance(i));
            *c = changed_sign(a, b) || aimed;
        }
        if !self.crossed.iter().any(|&c| c) {
            return Ok(false);
        }
        f.at_event(t, q, v, &self.crossed)
    }

    /// After a fixed step from `t` of size `h` that [`Events::chord`] found crossing: the first
    /// fraction `θ ∈ (0, 1]` where a function that changed sign vanishes on its tangent at the
    /// step's start, `θ = −g₀ / (ġ₀ h)`, with `ġ₀` a difference along the state's rate there
    /// (one evaluation of the formulation). Exact where the function is linear in time (a slip
    /// under constant force), where the chord of the end values is not: the method's stages past
    /// the event make the end value wrong (a friction that reversed in them). `None` where no
    /// tangent points into the step.
    pub fn tangent(
        &mut self,
        f: &mut dyn Formulation,
        (t, h, n_q): (f64, f64, usize),
        baumgarte: Option<Baumgarte>,
        qdd: &mut [f64],
        lambda: &mut [f64],
    ) -> Result<Option<f64>, DynamicsError> {
        derivative(f, t, &self.start, baumgarte, qdd, lambda, &mut self.rate)?;
        let eps = 1e-6 * h;
        for ((y, s), r) in self.y.iter_mut().zip(&self.start).zip(&self.rate) {
            *y = s + eps * r;
        }
        let (q, v) = self.y.split_at(n_q);
        f.events(t + eps, q, v, &mut self.ahead);
        let first = (self.g0.iter().zip(&self.g).zip(&self.ahead).enumerate())
            .filter(|&(i, ((&a, &b), _))| changed_sign(a, b) && f.event_needs_location(i))
            .map(|(i, ((&a, _), &c))| (i, -a * eps / ((c - a) * h)))
            .filter(|(_, th)| *th > 0.0 && *th <= 1.0)
            .min_by(|x, y| x.1.total_cmp(&y.1));
        if let Some((i, _)) = first {
            self.aimed = Some(i);
        }
        Ok(first.map(|(_, theta)| theta))
    }

    /// The run accepted a step that ended at an event: the event is settled
    /// ([`Events::settle_pending`]) when the run goes on from it, not now, so that the states
    /// shown within the step (output samples, on its dense output) are evaluated with the law
    /// that held over it (a slip's friction before it stopped, the kinetic energy before an
    /// impact).
    pub fn defer(&mut self) {
        self.pending = true;
    }

    /// The run goes on from `y` at `t`: an event a step ended at ([`Events::defer`]) is settled
    /// there ([`Events::settle`]) and its functions start the next step. True when the state or
    /// the law changed.
    pub fn settle_pending(
        &mut self,
        f: &mut dyn Formulation,
        t: f64,
        y: &mut [f64],
        n_q: usize,
    ) -> Result<bool, DynamicsError> {
        if !self.pending {
            return Ok(false);
        }
        self.pending = false;
        let changed = self.settle(f, t, y, n_q)?;
        self.accepted(f, t, y, n_q);
        Ok(changed)
    }

    /// After a fixed step ending at `y` at `t` that [`Events::chord`] did not shorten: the
    /// functions that changed sign over it without asking for a location
    /// ([`Formulation::event_needs_location`]) are settled at its end ([`Formulation::at_event`]).
    /// True when that changed `y` or the law.
    pub fn settle_unlocated(
        &mut self,
        f: &mut dyn Formulation,
        t: f64,
        y: &mut [f64],
        n_q: usize,
    ) -> Result<bool, DynamicsError> {
        // No function was aimed at: only the sign changes count.
        self.aimed = None;
        self.settle(f, t, y, n_q)
    }

    /// The run accepted its step, ending at `y` at `t`: the functions there start the next step.
    pub fn accepted(&mut self, f: &mut dyn Formulation, t: f64, y: &[f64], n_q: usize) {
        self.pending = false;
        if self.is_empty() {
            return;
        }
        let (q, v) = y.split_at(n_q);
        f.events(t, q, v, &mut self.g0);
        self.located = false;
        self.aimed = None;
        self.skip.iter_mut().for_each(|s| *s = false);
    }
}
