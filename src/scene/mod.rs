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
mod run_settings;
mod spatial;
mod spatial_forces;
mod strict;
mod values;

pub use error::{one_line, SceneError};
pub use overrides::{RunOverrides, Spelling};
pub use run_settings::{method_parameter, parameter_keys, RunSettings};
pub use values::SceneValue;

use crate::mechanism::Mechanism;
use crate::simulation::{FormulationKind, Simulation};
use dalembert_constraints::RedundancyTreatment;
use std::path::Path;

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
/// symplectic-euler, rk4, dopri5, generalized-alpha)`. The integrators' names come from the
/// registry ([`dalembert_integrators::method_names`]).
pub fn unknown_name(what: &str, value: &str, names: &[&str]) -> String {
    format!("unknown {what} '{value}' (expected {})", names.join(", "))
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

/// Why `mechanism` cannot run in joint coordinates (one line naming the element), or `None`.
pub(crate) fn joint_coordinates_problem(mechanism: &Mechanism) -> Option<String> {
    match mechanism.spatial() {
        None => Some("joint coordinates are for spatial scenes".to_string()),
        Some(m) => m.joint_coordinates().err().map(|e| e.to_string()),
    }
}

impl Scene {
    /// `Ok` unless the settings ask for joint coordinates that the model cannot take: then one
    /// line naming the setting as `spelling` writes it and the joint, force or body at fault (for
    /// settings changed after loading, by the command line or Python; a scene file's own are
    /// checked when it loads).
    pub fn check_settings(&self, spelling: Spelling) -> Result<(), String> {
        if self.settings.coordinates != crate::Coordinates::Joint {
            return Ok(());
        }
        match joint_coordinates_problem(&self.model) {
            None => Ok(()),
            Some(what) => {
                let setting = match spelling {
                    Spelling::Flags => "--coordinates joint",
                    Spelling::Keywords => "coordinates=\"joint\"",
                };
                Err(format!("{setting}: {what}"))
            }
        }
    }

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
            independent: self.settings.independent.clone(),
            coordinates: self.settings.coordinates,
        }
    }
}
