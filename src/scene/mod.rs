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
mod initial;
mod limit_keys;
mod mjcf;
mod names;
mod overrides;
mod run_settings;
mod spatial;
mod spatial_forces;
mod strict;
mod tree;
mod urdf;
pub(crate) mod values;
mod visuals;
mod xml;

pub use error::{one_line, SceneError};
pub use overrides::{RunOverrides, Spelling};
pub use run_settings::{method_parameter, parameter_keys, RunSettings};
pub use values::SceneValue;
pub(crate) use xml::parse as parse_xml;

use crate::mechanism::Mechanism;
use crate::simulation::{Simulation, SimulationError};
use dalembert_system::RedundancyTreatment;
use std::path::Path;

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
/// symplectic-euler, rk4, dopri5, generalized-alpha, ali3-p)`. The integrators' names come from the
/// registry ([`dalembert_integrators::method_names`]).
/// When one of `names` is close to `value` (a likely typo), `; did you mean 'NAME'?` is added.
pub fn unknown_name(what: &str, value: &str, names: &[&str]) -> String {
    let hint = nearest(value, names).map_or(String::new(), |n| format!("; did you mean '{n}'?"));
    format!("unknown {what} '{value}' (expected {}){hint}", names.join(", "))
}

/// The one of `names` nearest to `value` by edit distance (insertions, deletions, substitutions
/// and swaps of neighbouring characters, case ignored), when it is near enough to be a typo of
/// it: at most one edit in three characters of the longer (a name differing only in case is
/// near). `None` when no name is that near, `value` is itself one of `names`, or two are equally
/// near.
pub fn nearest<'a>(value: &str, names: &[&'a str]) -> Option<&'a str> {
    if names.contains(&value) {
        return None;
    }
    let value: Vec<char> = value.to_lowercase().chars().collect();
    let mut best: Option<(usize, &'a str)> = None;
    let mut tie = false;
    for &name in names {
        let candidate: Vec<char> = name.to_lowercase().chars().collect();
        let d = edit_distance(&value, &candidate);
        let limit = (value.len().max(candidate.len()) / 3).max(1);
        if d > limit {
            continue;
        }
        match best {
            Some((b, _)) if d > b => {}
            Some((b, _)) if d == b => tie = true,
            _ => {
                best = Some((d, name));
                tie = false;
            }
        }
    }
    best.filter(|_| !tie).map(|(_, n)| n)
}

/// Optimal-string-alignment distance between `a` and `b`.
fn edit_distance(a: &[char], b: &[char]) -> usize {
    let w = b.len() + 1;
    let mut d = vec![0usize; (a.len() + 1) * w];
    for (i, row) in d.chunks_mut(w).enumerate() {
        row[0] = i;
    }
    for (j, x) in d[..w].iter_mut().enumerate() {
        *x = j;
    }
    for i in 1..=a.len() {
        for j in 1..=b.len() {
            let cost = usize::from(a[i - 1] != b[j - 1]);
            let mut v = (d[(i - 1) * w + j] + 1)
                .min(d[i * w + j - 1] + 1)
                .min(d[(i - 1) * w + j - 1] + cost);
            if i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] {
                v = v.min(d[(i - 2) * w + j - 2] + 1);
            }
            d[i * w + j] = v;
        }
    }
    d[a.len() * w + b.len()]
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
    /// The scene's named inputs (`{ input = "NAME" }`), in the order first met in the file: what a
    /// [`crate::Simulator`] sets between steps (0 until set, and in a run from start to end).
    pub inputs: Vec<String>,
    /// The scene's force elements of type `code`, in the file's order: their wrench comes from a
    /// function a [`crate::Simulator`] is given (`code_force.rs`; nothing without one).
    pub code_forces: Vec<String>,
    /// What the scene looks like (shapes, attachment points, pins, guides, springs), for
    /// [`crate::animation`].
    pub drawing: crate::animation::Drawing,
    /// The TOML text the scene was built from ([`Scene::with_values`] edits it; a scene sent to
    /// another process is this text).
    pub source: String,
    /// The name of the scene's origin in errors (the file's path).
    pub origin: String,
    /// What the reader left out of the model, one line each, for the user to see (a URDF's
    /// joint friction, elements that carry no dynamics it reads; `docs/import.md`). Empty for a
    /// TOML scene.
    pub notes: Vec<String>,
}

/// Why `mechanism` cannot run in joint coordinates (one line naming the element), or `None`.
pub(crate) fn joint_coordinates_problem(mechanism: &Mechanism) -> Option<String> {
    match mechanism.spatial() {
        None => Some("joint coordinates are for spatial scenes".to_string()),
        Some(m) => m.joint_coordinates().err().map(|e| e.to_string()),
    }
}

impl Scene {
    /// `Ok` unless the settings ask for joint coordinates that the model cannot take (one line
    /// naming the setting as `spelling` writes it and the joint, force or body at fault), or for a
    /// method the formulation cannot take (generalized-α with a formulation other than the
    /// augmented one): for settings changed after loading, by the command line or Python, checked
    /// before a run writes anything.
    pub fn check_settings(&self, spelling: Spelling) -> Result<(), String> {
        if let Some((joint, kind)) = crate::simulation::switching_joint(self.model.system().as_ref()) {
            let method = self.settings.method.entry();
            // Limits alone are taken while free (the run stops where one is reached).
            if method.applies == dalembert_integrators::Applies::AugmentedIndex3 && kind == "friction" {
                return Err(format!(
                    "invalid integrator options: {} integrates the index-3 equations without joint {kind}: use rk4 or dopri5 with the {kind} of {joint}",
                    method.name
                ));
            }
        }
        if self.settings.coordinates != crate::Coordinates::Joint {
            // A method the formulation cannot take, refused before anything (a CSV) is written.
            let f = self.settings.formulation;
            let why = self
                .settings
                .method
                .entry()
                .refuses(f.name(), f.entry().index3_augmented);
            return why.map_or(Ok(()), |w| Err(format!("invalid integrator options: {w}")));
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

    /// What to do about a run's failure `e`, where the scene's settings are the likely cause: a
    /// rank-deficient constraint Jacobian under `redundant = "error"` (the default) gets the
    /// setting that solves on an independent set; a servo thrown half a turn from its target, a
    /// smaller or adaptive step. `None` otherwise.
    pub fn advice(&self, e: &SimulationError) -> Option<&'static str> {
        use dalembert_integrators::IntegrationError;
        let dynamics = match e {
            SimulationError::Setup(d) => d,
            SimulationError::Integration(f) => match &f.error {
                IntegrationError::Dynamics(d) => d,
                _ => return None,
            },
            _ => return None,
        };
        if let dalembert_system::DynamicsError::ForceElement { what, .. } = dynamics {
            // A servo whose joint runs half a turn from its target within a run that started
            // near it has, almost always, been thrown there by a step its gains make unstable.
            return what.contains("from its target").then_some(
                "a servo's joint thrown this far from its target within a few steps is the sign of a step too large for its gains (an explicit method needs h below about 2.8 J/c for a servo damping c on an inertia J): use generalized-alpha (implicit: a step of the motion's own scale, and the run stops if a joint reaches a stop), dopri5, whose steps adapt, or a smaller step",
            );
        }
        let redundant = matches!(dynamics, dalembert_system::DynamicsError::RedundantConstraints { .. });
        (redundant && self.settings.redundancy == RedundancyTreatment::Error).then_some(
            "if the mechanism moves with these equations dependent (a redundant joint, as in Bricard's loop or a parallelogram with a third crank), set redundant = \"minimum-norm\" in [simulation] (--redundant minimum-norm; redundant=\"minimum-norm\" in Python): the run then solves on an independent set and shares the reactions by least norm",
        )
    }

    /// Reads, builds and assembles a scene file: a TOML scene, a URDF robot description (a name
    /// ending `.urdf`; [`Scene::from_urdf`]) or an MJCF model (`.xml`, `.mjcf`;
    /// [`Scene::from_mjcf`]).
    pub fn from_path(path: impl AsRef<Path>) -> Result<Scene, SceneError> {
        let path = path.as_ref();
        let origin = path.display().to_string();
        let extension = path.extension().map(|e| e.to_ascii_lowercase());
        let urdf = extension.as_ref().is_some_and(|e| e == "urdf");
        let mjcf = extension.as_ref().is_some_and(|e| e == "xml" || e == "mjcf");
        if urdf || mjcf {
            let size = std::fs::metadata(path).map_err(|e| SceneError::io(path, e))?.len();
            if size > xml::MAX_BYTES as u64 {
                return Err(SceneError::at(
                    &origin,
                    "",
                    None,
                    format!("{size} bytes is more than a model file may hold ({})", xml::MAX_BYTES),
                ));
            }
        }
        let text = std::fs::read_to_string(path).map_err(|e| SceneError::io(path, e))?;
        if urdf {
            return Scene::from_urdf(&text, &origin);
        }
        if mjcf {
            return Scene::from_mjcf(&text, &origin);
        }
        Scene::from_toml(&text, &origin)
    }

    /// Builds and assembles the scene a URDF robot description gives (`docs/import.md`): a body
    /// per moving link, the links joined by fixed joints merged, the root fixed to the ground, at
    /// rest with every joint at 0 under gravity `(0, 0, −9.81)`. Its [`Scene::source`] is the
    /// scene's TOML text, so sweeps and [`Scene::with_values`] work on it as on a file's;
    /// `origin` names the file in errors, which give the element's line.
    pub fn from_urdf(text: &str, origin: &str) -> Result<Scene, SceneError> {
        urdf::scene(text, origin)
    }

    /// Builds and assembles the scene an MJCF model gives, from the subset `docs/import.md`
    /// lists (a body per moving MuJoCo body, one joint each; inertias given or from geoms as
    /// MuJoCo computes them; `equality connect` and `weld` exact; `motor` actuators as named
    /// inputs); anything else is refused naming the element and its line.
    pub fn from_mjcf(text: &str, origin: &str) -> Result<Scene, SceneError> {
        mjcf::scene(text, origin)
    }

    /// Builds and assembles a scene from TOML text; `origin` names it in errors.
    pub fn from_toml(text: &str, origin: &str) -> Result<Scene, SceneError> {
        if let Ok(tables) = toml::from_str::<toml::Table>(text) {
            if urdf::reference(&tables).is_some() {
                return urdf::around(tables, text, origin);
            }
        }
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
            inputs: self.inputs.clone(),
            code_forces: self.code_forces.clone(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::nearest;

    /// Typos a user makes (a doubled, dropped, swapped or wrong letter) find the name; a word
    /// that is far from every name, or equally near two, finds none.
    #[test]
    fn nearest_names_a_typo_and_nothing_else() {
        let keys = ["name", "mass", "inertia", "position", "angle", "velocity"];
        assert_eq!(nearest("masss", &keys), Some("mass"));
        assert_eq!(nearest("postion", &keys), Some("position"));
        assert_eq!(nearest("intertia", &keys), Some("inertia"));
        assert_eq!(nearest("agnle", &keys), Some("angle"));
        assert_eq!(nearest("Mass", &keys), Some("mass"));
        assert_eq!(nearest("stiffness", &keys), None);
        assert_eq!(nearest("mass", &keys), None, "an exact name is no typo");
        assert_eq!(nearest("simulat", &["simulate", "sweep"]), Some("simulate"));
        assert_eq!(nearest("ab", &["ac", "ad"]), None, "a tie suggests nothing");
    }
}
