//! What to integrate with, and how.

use dalembert_system::Stabilization;

/// The integration method.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Method {
    /// Semi-implicit (symplectic) Euler, fixed step.
    SymplecticEuler,
    /// Classic fourth-order Runge–Kutta, fixed step.
    Rk4,
    /// Dormand–Prince 5(4), adaptive, with dense output at the output times.
    DormandPrince {
        /// Relative tolerance.
        rtol: f64,
        /// Absolute tolerance.
        atol: f64,
    },
    /// Generalized-α on the index-3 form, implicit, with Newton iterations; the step is halved on
    /// Newton failure and grows back to `step` after successes.
    GeneralizedAlpha {
        /// Spectral radius at infinite frequency, 0 (maximal damping) to 1 (none).
        rho_inf: f64,
    },
}

impl Method {
    /// Name used in reports.
    pub fn name(&self) -> &'static str {
        match self {
            Method::SymplecticEuler => "symplectic-euler",
            Method::Rk4 => "rk4",
            Method::DormandPrince { .. } => "dopri5",
            Method::GeneralizedAlpha { .. } => "generalized-alpha",
        }
    }
}

/// How the constraints are kept during integration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ConstraintTreatment {
    /// Integrate `q̈` as is: `C` and `Ċ` drift.
    None,
    /// Baumgarte stabilization of the acceleration equation.
    Baumgarte(Stabilization),
    /// Project `q` (Newton, to `tolerance`) and `q̇` onto the manifold after every accepted step.
    Projection {
        /// Position tolerance on `‖C‖∞`.
        tolerance: f64,
    },
}

impl ConstraintTreatment {
    /// Baumgarte with the default gains for step `h` ([`Stabilization::for_step`]).
    pub fn baumgarte_for_step(h: f64) -> Self {
        ConstraintTreatment::Baumgarte(Stabilization::for_step(h))
    }

    /// Name used in reports.
    pub fn name(&self) -> &'static str {
        match self {
            ConstraintTreatment::None => "none",
            ConstraintTreatment::Baumgarte(_) => "baumgarte",
            ConstraintTreatment::Projection { .. } => "projection",
        }
    }

    pub(crate) fn stabilization(&self) -> Stabilization {
        match self {
            ConstraintTreatment::Baumgarte(s) => *s,
            _ => Stabilization::None,
        }
    }
}

/// Settings of one integration run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IntegratorOptions {
    /// Method.
    pub method: Method,
    /// Constraint treatment.
    pub treatment: ConstraintTreatment,
    /// Fixed step, or the initial step of an adaptive method (s). A fixed step is shortened, if
    /// needed, so that a whole number of steps spans each output interval.
    pub step: f64,
    /// Interval between output samples (s).
    pub output_every: f64,
    /// Smallest step an adaptive method may take before it gives up (s).
    pub min_step: f64,
    /// Largest step an adaptive method may take (s); defaults to the output interval.
    pub max_step: f64,
    /// Integration stops with an error when the state grows past this many times its initial
    /// scale (blow-up of an unstable step), before non-finite numbers appear.
    pub divergence_factor: f64,
}

impl IntegratorOptions {
    /// Fixed-step `method` with step `h`, output every `every`, no constraint treatment.
    pub fn fixed(method: Method, h: f64, every: f64) -> Self {
        IntegratorOptions {
            method,
            treatment: ConstraintTreatment::None,
            step: h,
            output_every: every,
            min_step: 1e-12,
            max_step: every,
            divergence_factor: 1e8,
        }
    }

    /// The same options with another constraint treatment.
    pub fn with_treatment(mut self, treatment: ConstraintTreatment) -> Self {
        self.treatment = treatment;
        self
    }
}
