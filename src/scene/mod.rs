//! Scene files: a mechanism and its run, described in TOML (format: `docs/scenes.md`).
//!
//! A scene states only what it needs. The ground exists implicitly (`"ground"`); joint points may be
//! given once, in global coordinates of the configuration written in the file; positions need only
//! be approximate (the scene is assembled by position analysis) and velocities are made consistent
//! (least change) before the run.

mod build;
mod error;
mod format;
mod functions;
mod names;
mod overrides;
mod spatial;
mod spatial_forces;
mod strict;
mod values;

pub use error::{one_line, SceneError};
pub use overrides::{RunOverrides, Spelling};
pub use values::SceneValue;

use crate::mechanism::Mechanism;
use crate::simulation::{FormulationKind, Simulation};
use dalembert_constraints::{RedundancyTreatment, Stabilization};
use dalembert_integrators::{ConstraintTreatment, IntegratorOptions, Method};
use std::path::Path;

/// Settings of the `[simulation]` table, with defaults for everything but `end`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunSettings {
    /// End time (s). Default 1.
    pub end: f64,
    /// Formulation. Default augmented.
    pub formulation: FormulationKind,
    /// Integrator name: `symplectic-euler`, `rk4` (default), `dopri5`, `generalized-alpha`.
    pub integrator: IntegratorKind,
    /// Fixed step, or the initial step of an adaptive method. Default 1e-3 s.
    pub step: f64,
    /// Output interval. Default 1e-2 s.
    pub output_every: f64,
    /// Constraint treatment: `none`, `baumgarte` (default gains for the step), `projection` (default).
    pub stabilization: StabilizationKind,
    /// Relative tolerance of adaptive methods. Default 1e-8.
    pub rtol: f64,
    /// Absolute tolerance of adaptive methods. Default 1e-10.
    pub atol: f64,
    /// Spectral radius at infinity of generalized-α. Default 0.8.
    pub rho_inf: f64,
    /// Redundant constraints (`redundant = "error" | "minimum-norm"`). Default: an error naming
    /// them.
    pub redundancy: RedundancyTreatment,
}

/// The integrators a scene can name.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum IntegratorKind {
    /// Semi-implicit Euler.
    SymplecticEuler,
    /// Classic Runge–Kutta.
    Rk4,
    /// Dormand–Prince 5(4).
    Dopri5,
    /// Generalized-α (index 3, implicit).
    GeneralizedAlpha,
}

/// The constraint treatments a scene can name.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StabilizationKind {
    /// None.
    None,
    /// Baumgarte with `Stabilization::for_step(step)`.
    Baumgarte,
    /// Projection to 1e-10 after every step.
    Projection,
}

impl IntegratorKind {
    /// The names a scene or the command line may use.
    pub const NAMES: &'static [&'static str] = &["symplectic-euler", "rk4", "dopri5", "generalized-alpha"];

    /// Name, as in [`IntegratorKind::NAMES`].
    pub fn name(&self) -> &'static str {
        match self {
            IntegratorKind::SymplecticEuler => "symplectic-euler",
            IntegratorKind::Rk4 => "rk4",
            IntegratorKind::Dopri5 => "dopri5",
            IntegratorKind::GeneralizedAlpha => "generalized-alpha",
        }
    }

    /// Parses a scene or command-line name.
    pub fn parse(s: &str) -> Option<Self> {
        Some(match s {
            "symplectic-euler" | "euler" => IntegratorKind::SymplecticEuler,
            "rk4" => IntegratorKind::Rk4,
            "dopri5" | "dormand-prince" => IntegratorKind::Dopri5,
            "generalized-alpha" => IntegratorKind::GeneralizedAlpha,
            _ => return None,
        })
    }
}

impl StabilizationKind {
    /// The names a scene or the command line may use.
    pub const NAMES: &'static [&'static str] = &["none", "baumgarte", "projection"];

    /// Parses a scene or command-line name.
    pub fn parse(s: &str) -> Option<Self> {
        Some(match s {
            "none" => StabilizationKind::None,
            "baumgarte" => StabilizationKind::Baumgarte,
            "projection" => StabilizationKind::Projection,
            _ => return None,
        })
    }

    /// Name.
    pub fn name(&self) -> &'static str {
        match self {
            StabilizationKind::None => "none",
            StabilizationKind::Baumgarte => "baumgarte",
            StabilizationKind::Projection => "projection",
        }
    }
}

impl FormulationKind {
    /// The names a scene or the command line may use.
    pub const NAMES: &'static [&'static str] = &["augmented", "embedding", "amalgamated"];

    /// Parses a scene or command-line name.
    pub fn parse(s: &str) -> Option<Self> {
        Some(match s {
            "augmented" => FormulationKind::Augmented,
            "embedding" => FormulationKind::Embedding,
            "amalgamated" => FormulationKind::Amalgamated,
            _ => return None,
        })
    }
}

/// The names of the redundancy treatments in scenes and on the command line.
pub const REDUNDANCY_NAMES: &[&str] = &["error", "minimum-norm"];

/// Parses a redundancy treatment name (`error`, `minimum-norm`).
pub fn parse_redundancy(s: &str) -> Option<RedundancyTreatment> {
    match s {
        "error" => Some(RedundancyTreatment::Error),
        "minimum-norm" => Some(RedundancyTreatment::MinimumNorm),
        _ => None,
    }
}

/// The one-line error for a name that is not one of `names`: `unknown integrator 'rk5' (expected
/// symplectic-euler, rk4, dopri5, generalized-alpha)`.
pub fn unknown_name(what: &str, value: &str, names: &[&str]) -> String {
    format!("unknown {what} '{value}' (expected {})", names.join(", "))
}

impl RunSettings {
    /// The integrator options these settings describe.
    pub fn integrator_options(&self) -> IntegratorOptions {
        let method = match self.integrator {
            IntegratorKind::SymplecticEuler => Method::SymplecticEuler,
            IntegratorKind::Rk4 => Method::Rk4,
            IntegratorKind::Dopri5 => Method::DormandPrince {
                rtol: self.rtol,
                atol: self.atol,
            },
            IntegratorKind::GeneralizedAlpha => Method::GeneralizedAlpha { rho_inf: self.rho_inf },
        };
        let treatment = match self.stabilization {
            StabilizationKind::None => ConstraintTreatment::None,
            StabilizationKind::Baumgarte => ConstraintTreatment::Baumgarte(Stabilization::for_step(self.step)),
            StabilizationKind::Projection => ConstraintTreatment::Projection { tolerance: 1e-10 },
        };
        IntegratorOptions::fixed(method, self.step, self.output_every).with_treatment(treatment)
    }
}

/// True when the scene's `[scene] gravity` has three components: a spatial scene.
fn is_spatial(text: &str) -> bool {
    let Ok(table) = toml::from_str::<toml::Table>(text) else {
        return false;
    };
    let gravity = table.get("scene").and_then(|s| s.get("gravity"));
    matches!(gravity, Some(toml::Value::Array(a)) if a.len() == 3)
}

/// A loaded, assembled scene.
#[derive(Debug, Clone)]
pub struct Scene {
    /// `[scene] name`, or the file name.
    pub name: String,
    /// The model (planar, or spatial when the scene's gravity has three components).
    pub model: Mechanism,
    /// Assembled positions.
    pub q: Vec<f64>,
    /// Consistent velocities.
    pub qd: Vec<f64>,
    /// The run settings.
    pub settings: RunSettings,
    /// What the scene looks like (shapes, attachment points, pins, guides, springs), for
    /// [`crate::animation`].
    pub drawing: crate::animation::Drawing,
    /// The TOML text the scene was built from ([`Scene::with_values`] edits it; a scene sent to
    /// another process is this text).
    pub source: String,
    /// The name of the scene's origin in errors (the file's path).
    pub origin: String,
}

impl Scene {
    /// Reads, builds and assembles a scene file.
    pub fn from_path(path: impl AsRef<Path>) -> Result<Scene, SceneError> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|e| SceneError::io(path, e))?;
        Scene::from_toml(&text, &path.display().to_string())
    }

    /// Builds and assembles a scene from TOML text; `origin` names it in errors.
    pub fn from_toml(text: &str, origin: &str) -> Result<Scene, SceneError> {
        if is_spatial(text) {
            let file: spatial::SpatialFile = toml::from_str(text).map_err(|e| {
                spatial::planar_body_in_spatial_scene(text, origin)
                    .unwrap_or_else(|| SceneError::parse(origin, text, &e))
            })?;
            return spatial::build(file, text, origin);
        }
        let file: format::SceneFile = toml::from_str(text).map_err(|e| SceneError::parse(origin, text, &e))?;
        build::build(file, text, origin)
    }

    /// A simulation of this scene with its settings.
    pub fn simulation(&self) -> Simulation {
        Simulation {
            model: self.model.clone(),
            q: self.q.clone(),
            qd: self.qd.clone(),
            start: 0.0,
            end: self.settings.end,
            formulation: self.settings.formulation,
            redundancy: self.settings.redundancy,
            integrator: self.settings.integrator_options(),
            velocity_weights: None,
        }
    }
}
