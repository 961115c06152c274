//! The interface between the integration loop ([`crate::integrate`]) and a method: the loop owns
//! the output schedule, the step-size bookkeeping of its [`StepControl`], normalization,
//! projection, monitoring and failure reporting; a [`Stepper`] takes one step.

use crate::IntegrationError;
use dalembert_system::{Baumgarte, Formulation, FormulationStats};

/// How the loop chooses the steps of a method.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum StepControl {
    /// The run's step, shortened so that a whole number of steps spans each output interval;
    /// halved when the method rejects a step and doubled back after four accepted ones.
    Fixed,
    /// The method proposes every next step from its error estimate; output samples come from its
    /// dense output ([`Stepper::interpolate`]).
    Adaptive,
}

/// The outcome of one attempted step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepOutcome {
    /// True when the step was taken (the state moved); false when it was rejected (the state is
    /// unchanged).
    pub accepted: bool,
    /// The method's scaled error estimate (accept when ≤ 1); NaN when it has none.
    pub error: f64,
    /// The step the method proposes next (s); for a fixed-step method, the step it was given.
    pub next_step: f64,
}

impl StepOutcome {
    /// An accepted step of a method without an error estimate.
    pub fn taken(h: f64) -> Self {
        StepOutcome {
            accepted: true,
            error: f64::NAN,
            next_step: h,
        }
    }
}

/// What a method is built from (see [`crate::MethodEntry::build`]).
pub struct Setup<'a> {
    /// The formulation the run integrates.
    pub formulation: &'a mut dyn Formulation,
    /// Start time.
    pub t0: f64,
    /// The consistent initial state `y = [q; v]`.
    pub y0: &'a [f64],
    /// Number of positions `n_q` (`y` splits there).
    pub n_q: usize,
    /// The Baumgarte gains of the run's [`crate::Stabilization`], if any.
    pub baumgarte: Option<Baumgarte>,
}

/// One integration method. It allocates its storage when it is built and nothing while stepping.
pub trait Stepper: Send {
    /// Attempts a step of size `h` from `(t, y = [q; v])`. When the outcome is accepted `y` holds
    /// the state at `t + h` (before normalization and projection, which the loop does); when it
    /// is rejected `y` is unchanged. Errors stop the run.
    fn step(&mut self, f: &mut dyn Formulation, t: f64, h: f64, y: &mut [f64])
        -> Result<StepOutcome, IntegrationError>;

    /// Takes a step of size `h` from `(t, y)` whatever the method's error estimate says, with dense
    /// output over it as after an accepted step; `Ok(false)` (and `y` unchanged) when the method
    /// cannot or the step is not finite. The loop bridges a singular position of a closed chain
    /// with it, where the error control would shrink the steps until the drift decides the branch,
    /// and checks such steps itself (a step against two half steps). Default: cannot.
    fn step_unchecked(
        &mut self,
        f: &mut dyn Formulation,
        t: f64,
        h: f64,
        y: &mut [f64],
    ) -> Result<bool, IntegrationError> {
        let _ = (f, t, h, y);
        Ok(false)
    }

    /// [`Stepper::step`] carrying the run's sensitivities `S = ∂y/∂p` through the step with it:
    /// each stage's tangent derivative `f_y S + f_p` from `tangents` right after the stage's
    /// evaluation (whose factorization it reuses), combined by the method's own weights, and the
    /// step's new tangents handed to [`TangentField::stepped`]. `Ok(None)` (nothing done) when
    /// the method does not carry tangents; the loop then differences whole steps instead
    /// (`docs/sensitivities.md`). Default: does not.
    fn step_tangents(
        &mut self,
        f: &mut dyn Formulation,
        t: f64,
        h: f64,
        y: &mut [f64],
        tangents: &mut dyn TangentField,
    ) -> Result<Option<StepOutcome>, IntegrationError> {
        let _ = (f, t, h, y, tangents);
        Ok(None)
    }

    /// Dense output at fraction `theta ∈ [0, 1]` of the last accepted step, into `out`. Called only
    /// for [`StepControl::Adaptive`] methods.
    fn interpolate(&self, theta: f64, out: &mut [f64]) {
        let _ = (theta, out);
    }

    /// Dense output of tangent `j` ([`Stepper::step_tangents`]) at fraction `theta` of the last
    /// accepted step, into `out`; false when that step did not carry the tangents. Default
    /// false.
    fn interpolate_tangent(&self, j: usize, theta: f64, out: &mut [f64]) -> bool {
        let _ = (j, theta, out);
        false
    }

    /// The loop changed the state after the last step (a projection): anything the method kept
    /// about it is stale.
    fn state_changed(&mut self) {}

    /// The likely cause when the state grows without bound at step `h`, for
    /// [`IntegrationError::Diverged`]: for an explicit method, a step beyond its stability limit.
    fn divergence_hint(&self, h: f64) -> String {
        let _ = h;
        "the step is probably beyond the method's stability limit: take a smaller one".into()
    }

    /// Work done outside the formulation (Newton iterations, factorizations and residual
    /// evaluations of an implicit method), added to the run's statistics.
    fn work(&self) -> FormulationStats {
        FormulationStats::default()
    }
}

/// The sensitivities a run carries, as a method that steps them with its state sees them
/// ([`Stepper::step_tangents`]): for tangent `j`, `S_j = ∂y/∂p_j` at the step's start and the
/// derivative of the first-order form `ẏ = [T(q) v; v̇]` along it.
pub trait TangentField {
    /// The number of tangents.
    fn count(&self) -> usize;

    /// Tangent `j` at the start of the step.
    fn tangent(&self, j: usize) -> &[f64];

    /// The change `δ` of tangent `j`'s parameter: a method that differences a map of its own
    /// along the tangent (`(g(y + δ s) − g(y − δ s)) / 2δ`) takes the same.
    fn delta(&self, j: usize) -> f64;

    /// The run's step begins at `(t, y)`, `f` just evaluated there: where the run's state was
    /// projected after the last step, each tangent is made to hold the projected state's
    /// constraints too (the derivative of the projection, solved with that evaluation's
    /// factorization). Called before the first [`TangentField::derivative`] of a step. Returns
    /// false where the formulation cannot solve it.
    fn begin(&mut self, f: &mut dyn Formulation, t: f64, y: &[f64]) -> Result<bool, IntegrationError>;

    /// `out = f_y(t, y) s + f_p(t, y)` for tangent `j`, right after `f` was evaluated at
    /// `(t, y)` (`qdd`, `lambda` its results, `baumgarte` the gains it was given): the change of
    /// the accelerations solved with that evaluation's factorization. `Ok(false)` where it
    /// cannot (the step's tangents are then found otherwise).
    #[allow(clippy::too_many_arguments)]
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
    ) -> Result<bool, IntegrationError>;

    /// Tangent `j` at the end of the step the method took from `(t, h)` (before the loop's
    /// normalization and projection of the state `y` it ended at).
    fn stepped(&mut self, j: usize, t: f64, h: f64, y: &[f64], s: &[f64]);
}
