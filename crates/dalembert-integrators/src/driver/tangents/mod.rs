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
use crate::stepper::{Setup, StepControl, StepOutcome, Stepper};
use crate::{IntegrationError, IntegratorOptions, Stabilization};
use dalembert_system::{Baumgarte, Formulation};
use field::Work;

mod field;

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
        f.begin_step();
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
                side.f.begin_step();
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
