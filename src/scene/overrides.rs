//! Changes to a scene's run settings from the command line or from Python keyword arguments,
//! validated once for both (the messages name the flag or the keyword).

use super::{parse_redundancy, unknown_name, RunSettings, REDUNDANCY_NAMES};
use crate::{Coordinates, FormulationKind};
use dalembert_integrators::{method_names, Method, Stabilization, METHODS};

/// How the caller spells a setting's name in messages.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Spelling {
    /// Command-line flags: `--rho-inf`.
    #[default]
    Flags,
    /// Keyword arguments: `rho_inf`.
    Keywords,
}

/// Settings to change; `None` keeps the scene's.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RunOverrides {
    /// `augmented | embedding | amalgamated`.
    pub formulation: Option<String>,
    /// A method of [`dalembert_integrators::METHODS`]: `symplectic-euler | rk4 | dopri5 |
    /// generalized-alpha`.
    pub integrator: Option<String>,
    /// Method parameters by key (`rtol`, `atol`, `rho_inf`: [`super::parameter_keys`]).
    pub parameters: Vec<(String, f64)>,
    /// Fixed step, or the initial step of an adaptive method (s).
    pub step: Option<f64>,
    /// End time (s).
    pub end: Option<f64>,
    /// Output interval (s).
    pub every: Option<f64>,
    /// `none | baumgarte | projection`.
    pub stabilization: Option<String>,
    /// `error | minimum-norm`.
    pub redundant: Option<String>,
    /// `absolute | joint`.
    pub coordinates: Option<String>,
}

impl RunOverrides {
    /// `settings` with these changes, and the warnings they deserve (a parameter the chosen
    /// method does not have, a stabilization it ignores, the method's own advice). Errors are one
    /// line naming the setting.
    pub fn apply(&self, settings: &RunSettings, spelling: Spelling) -> Result<(RunSettings, Vec<String>), String> {
        let name = |flag: &str| match spelling {
            Spelling::Flags => format!("--{}", flag.replace('_', "-")),
            Spelling::Keywords => flag.to_string(),
        };
        let mut s = settings.clone();
        if let Some(f) = &self.formulation {
            s.formulation =
                FormulationKind::parse(f).ok_or_else(|| unknown_name("formulation", f, FormulationKind::NAMES))?;
        }
        for (key, v) in &self.parameters {
            s.set_parameter(key, *v, &name)?;
        }
        if let Some(i) = &self.integrator {
            let m = Method::named(i).ok_or_else(|| unknown_name("integrator", i, &method_names()))?;
            s.set_method(m);
        }
        if let Some(c) = &self.coordinates {
            s.coordinates = Coordinates::parse(c).ok_or_else(|| unknown_name("coordinates", c, Coordinates::NAMES))?;
        }
        if let Some(r) = &self.redundant {
            s.redundancy =
                parse_redundancy(r).ok_or_else(|| unknown_name("redundancy treatment", r, REDUNDANCY_NAMES))?;
        }
        if let Some(st) = &self.stabilization {
            s.stabilization =
                Stabilization::parse(st).ok_or_else(|| unknown_name("stabilization", st, Stabilization::NAMES))?;
        }
        for (dst, src, what) in [
            (&mut s.step, self.step, "step"),
            (&mut s.end, self.end, "end"),
            (&mut s.output_every, self.every, "every"),
        ] {
            if let Some(v) = src {
                if !(v.is_finite() && v > 0.0) {
                    return Err(format!("{} must be positive, got {v}", name(what)));
                }
                *dst = v;
            }
        }
        let mut warnings = Vec::new();
        let method = s.method;
        for (key, _) in &self.parameters {
            if method.get(key).is_none() {
                let users: Vec<&str> = METHODS
                    .iter()
                    .filter(|e| e.parameters.iter().any(|p| p.key == key))
                    .map(|e| e.name)
                    .collect();
                warnings.push(format!(
                    "{} applies to {} only; ignored with {}",
                    name(key),
                    users.join(", "),
                    method.name()
                ));
            }
        }
        warnings.extend((method.entry().advice)(&method));
        if s.independent.is_some() && s.formulation != FormulationKind::Embedding {
            warnings.push(format!(
                "the scene's independent coordinates apply to the embedding formulation only; ignored with {}",
                s.formulation.name()
            ));
        }
        if method.entry().keeps_constraints && self.stabilization.is_some() {
            warnings.push(format!(
                "{} is ignored with {} (it keeps the position constraints itself)",
                name("stabilization"),
                method.name()
            ));
        }
        Ok((s, warnings))
    }
}
