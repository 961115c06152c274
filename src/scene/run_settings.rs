//! The run a scene asks for (`[simulation]`): formulation, method and its parameters (read from
//! the integrators' registry), step, output interval, stabilization.

use crate::simulation::{Coordinates, FormulationKind};
use dalembert_integrators::{IntegratorOptions, Method, Parameter, Stabilization, METHODS};
use dalembert_system::RedundancyTreatment;

/// Settings of the `[simulation]` table, with defaults for everything but `end`.
#[derive(Debug, Clone, PartialEq)]
pub struct RunSettings {
    /// End time (s). Default 1.
    pub end: f64,
    /// Formulation. Default augmented.
    pub formulation: FormulationKind,
    /// Integration method (`integrator = "…"`, a name of [`dalembert_integrators::METHODS`]) with
    /// its parameters. Default rk4.
    pub method: Method,
    /// Fixed step, or the initial step of an adaptive method. Default 1e-3 s.
    pub step: f64,
    /// Output interval. Default 1e-2 s.
    pub output_every: f64,
    /// How the constraints are kept (`stabilization = "none" | "baumgarte" | "projection"`).
    /// Default projection.
    pub stabilization: Stabilization,
    /// Redundant constraints (`redundant = "error" | "minimum-norm"`). Default: an error naming
    /// them.
    pub redundancy: RedundancyTreatment,
    /// Independent coordinates of the embedding formulation's partition (`independent =
    /// ["link1.angle", …]`, indices into the velocities), used while they stay independent; `None`:
    /// chosen by the formulation (full pivoting on `C_q`). Other formulations ignore it.
    pub independent: Option<Vec<usize>>,
    /// Every method parameter given (`rtol = 1e-6`), by key, whether or not [`Self::method`] has
    /// it: choosing another method later ([`RunSettings::set_method`]) applies those it has.
    pub parameters: Vec<(&'static str, f64)>,
    /// The coordinates integrated (`coordinates = "absolute" | "joint"`): joint coordinates for a
    /// spatial tree of revolute and prismatic joints (`docs/joint-coordinates.md`). Default
    /// absolute.
    pub coordinates: Coordinates,
}

impl Default for RunSettings {
    fn default() -> Self {
        RunSettings {
            end: 1.0,
            formulation: FormulationKind::Augmented,
            method: Method::rk4(),
            step: 1e-3,
            output_every: 1e-2,
            stabilization: Stabilization::projection(),
            redundancy: RedundancyTreatment::default(),
            independent: None,
            parameters: Vec::new(),
            coordinates: Coordinates::Absolute,
        }
    }
}

/// The registered parameter called `key` (the first method that declares it), if any.
pub fn method_parameter(key: &str) -> Option<&'static Parameter> {
    METHODS.iter().flat_map(|e| e.parameters).find(|p| p.key == key)
}

/// Every registered parameter key, once each, in registry order.
pub fn parameter_keys() -> Vec<&'static str> {
    let mut keys: Vec<&'static str> = Vec::new();
    for p in METHODS.iter().flat_map(|e| e.parameters) {
        if !keys.contains(&p.key) {
            keys.push(p.key);
        }
    }
    keys
}

impl RunSettings {
    /// Uses `method` (its defaults), then the given parameters it has.
    pub fn set_method(&mut self, method: Method) {
        let mut m = method;
        for &(key, v) in &self.parameters {
            if m.get(key).is_some() {
                // Checked when given.
                m = m.with(key, v).unwrap_or(m);
            }
        }
        self.method = m;
    }

    /// Gives parameter `key` (a registered key) the value `value`, checked against its range: the
    /// message is `'{key}' must …, got {value}` with the key spelled by `name`.
    pub fn set_parameter(&mut self, key: &str, value: f64, name: &dyn Fn(&str) -> String) -> Result<(), String> {
        let Some(p) = method_parameter(key) else {
            return Err(format!(
                "unknown method parameter {} (expected {})",
                name(key),
                parameter_keys().join(", ")
            ));
        };
        if !(p.valid)(value) {
            return Err(format!("{} {}, got {value}", name(key), p.expected));
        }
        self.parameters.retain(|(k, _)| *k != p.key);
        self.parameters.push((p.key, value));
        self.set_method(Method::of(self.method.entry()));
        Ok(())
    }

    /// The integrator options these settings describe.
    pub fn integrator_options(&self) -> IntegratorOptions {
        IntegratorOptions::fixed(self.method, self.step, self.output_every).with_stabilization(self.stabilization)
    }
}
