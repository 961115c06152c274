//! How the constraints are kept during integration: the one name of that choice in the library,
//! the scene format (`stabilization = "…"`), the command line (`--stabilization`) and `trade`.

use dalembert_system::Baumgarte;

/// How the constraints are kept during integration by a method that does not keep them itself
/// (the explicit ones; generalized-α solves the position constraints and ignores this).
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum Stabilization {
    /// Integrate `q̈` as is: `C` and `Ċ` drift.
    None,
    /// Baumgarte stabilization of the acceleration equation with the default gains for the run's
    /// step, [`Baumgarte::for_step`].
    Baumgarte,
    /// Baumgarte stabilization with the given gains.
    BaumgarteGains(Baumgarte),
    /// Project `q` (Newton, to `tolerance`) and `q̇` onto the manifold after every accepted step
    /// (with the embedding formulation: coordinate partitioning).
    Projection {
        /// Position tolerance on `‖C‖∞`.
        tolerance: f64,
    },
}

impl Stabilization {
    /// The names a scene, the command line or Python may use, as [`Stabilization::parse`] reads
    /// them.
    pub const NAMES: &'static [&'static str] = &["none", "baumgarte", "projection"];

    /// Projection to `‖C‖∞ ≤ 1e-10` (the default of scenes).
    pub fn projection() -> Self {
        Stabilization::Projection { tolerance: 1e-10 }
    }

    /// Reads a name of [`Stabilization::NAMES`]: Baumgarte with the default gains for the step,
    /// projection to 1e-10.
    pub fn parse(name: &str) -> Option<Self> {
        Some(match name {
            "none" => Stabilization::None,
            "baumgarte" => Stabilization::Baumgarte,
            "projection" => Stabilization::projection(),
            _ => return None,
        })
    }

    /// Name used in reports (one of [`Stabilization::NAMES`]).
    pub fn name(&self) -> &'static str {
        match self {
            Stabilization::None => "none",
            Stabilization::Baumgarte | Stabilization::BaumgarteGains(_) => "baumgarte",
            Stabilization::Projection { .. } => "projection",
        }
    }

    /// The Baumgarte gains this treatment adds to the acceleration equation for a run with step
    /// `step`.
    pub fn gains(&self, step: f64) -> Option<Baumgarte> {
        match *self {
            Stabilization::Baumgarte => Some(Baumgarte::for_step(step)),
            Stabilization::BaumgarteGains(g) => Some(g),
            _ => None,
        }
    }

    /// The projection tolerance, if this treatment projects.
    pub fn projection_tolerance(&self) -> Option<f64> {
        match *self {
            Stabilization::Projection { tolerance } => Some(tolerance),
            _ => None,
        }
    }
}
