//! The TOML structure of a scene file (serde). Unknown keys are errors, so typos are caught.

use super::strict;
pub(crate) use super::strict::{Points, ValueDef};
use serde::Deserialize;
use toml::Spanned;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct SceneFile {
    pub scene: Option<Meta>,
    #[serde(default)]
    pub bodies: Vec<Spanned<BodyDef>>,
    #[serde(default)]
    pub joints: Vec<Spanned<JointDef>>,
    #[serde(default)]
    pub drivers: Vec<Spanned<DriverDef>>,
    #[serde(default)]
    pub forces: Vec<Spanned<ForceDef>>,
    pub simulation: Option<Spanned<SimDef>>,
    /// Positions and velocities to start from, by output column.
    pub initial: Option<Spanned<super::initial::InitialDef>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct Meta {
    pub name: Option<String>,
    #[serde(default, deserialize_with = "strict::gravity_opt")]
    pub gravity: Option<[f64; 2]>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct BodyDef {
    pub name: String,
    pub mass: f64,
    pub inertia: Option<f64>,
    pub shape: Option<ShapeDef>,
    #[serde(deserialize_with = "strict::xy")]
    pub position: [f64; 2],
    #[serde(default)]
    pub angle: f64,
    #[serde(default, deserialize_with = "strict::xy_opt")]
    pub velocity: Option<[f64; 2]>,
    pub angular_velocity: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct ShapeDef {
    pub rod: Option<f64>,
    pub disk: Option<f64>,
    #[serde(default, deserialize_with = "strict::xy_opt")]
    pub rectangle: Option<[f64; 2]>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct JointDef {
    pub name: String,
    #[serde(rename = "type")]
    pub kind: String,
    #[serde(deserialize_with = "strict::two_names")]
    pub bodies: [String; 2],
    pub at: Option<Points>,
    #[serde(default, deserialize_with = "strict::two_points_opt")]
    pub points: Option<[[f64; 2]; 2]>,
    #[serde(default, deserialize_with = "strict::xy_opt")]
    pub axis: Option<[f64; 2]>,
    pub length: Option<f64>,
    pub ratio: Option<f64>,
    pub radius: Option<f64>,
    pub friction: Option<Spanned<FrictionDef>>,
    /// `limits = [lower, upper]` on a revolute or prismatic joint (`docs/limits.md`).
    pub limits: Option<Spanned<Vec<f64>>>,
    /// Newton's coefficient of restitution at the limits (default 0).
    pub restitution: Option<Spanned<f64>>,
    /// The rebound speed below which the joint rests on a limit (default 1e-3).
    pub rest_speed: Option<Spanned<f64>>,
}

/// `friction = { coefficient = μ, radius = r, constant = f₀, viscous = c, stick_speed = w }` on a
/// revolute or prismatic joint (`docs/friction.md`): `μ` with the load, `f₀` without, or both.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct FrictionDef {
    pub coefficient: Option<f64>,
    pub constant: Option<f64>,
    pub radius: Option<f64>,
    pub viscous: Option<f64>,
    pub stick_speed: Option<f64>,
}

impl FrictionDef {
    /// `(μ, r, f₀)` of a friction table on a revolute (`revolute`) or prismatic joint, or what is
    /// wrong with it (`owner` names the joint): `μ` or `f₀` or both; `radius` on a revolute joint
    /// with `μ` only (it turns `μ |F|` into a torque), never on a prismatic one.
    pub(crate) fn law(&self, revolute: bool, owner: &str) -> Result<(f64, f64, f64), String> {
        if self.coefficient.is_none() && self.constant.is_none() {
            return Err(format!(
                "{owner}: friction needs 'coefficient' (μ, with the joint's load) or 'constant' (a force or torque without it), or both"
            ));
        }
        let coefficient = self.coefficient.unwrap_or(0.0);
        match (revolute, self.radius) {
            (false, Some(_)) => Err(format!(
                "{owner}: a prismatic joint's friction has no 'radius' (the friction force is μ N)"
            )),
            (true, None) if self.coefficient.is_some() => Err(format!(
                "{owner}: a revolute joint's friction needs 'radius', the pin radius in m (torque μ r |F|)"
            )),
            (true, Some(_)) if self.coefficient.is_none() => Err(format!(
                "{owner}: 'radius' turns μ's force into a torque: give 'coefficient' with it (a constant friction is a torque already)"
            )),
            (_, r) => Ok((coefficient, r.unwrap_or(0.0), self.constant.unwrap_or(0.0))),
        }
    }
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct FunctionDef {
    pub kind: Option<String>,
    pub input: Option<String>,
    pub value: Option<f64>,
    pub initial: Option<f64>,
    pub rate: Option<f64>,
    pub amplitude: Option<f64>,
    pub frequency: Option<f64>,
    pub phase: Option<f64>,
    pub offset: Option<f64>,
    pub coefficients: Option<Vec<f64>>,
    pub t0: Option<f64>,
    pub t1: Option<f64>,
    pub from: Option<f64>,
    pub to: Option<f64>,
    pub absolute: Option<bool>,
    /// An input's factor (`{ input = "u", gain = 2.0 }`).
    pub gain: Option<f64>,
    /// The interval an input's value is held in (`{ input = "u", range = [-1.0, 1.0] }`).
    pub range: Option<[f64; 2]>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct DriverDef {
    pub name: String,
    #[serde(rename = "type")]
    pub kind: String,
    pub body: Option<String>,
    pub coordinate: Option<String>,
    pub joint: Option<String>,
    #[serde(default, deserialize_with = "strict::two_names_opt")]
    pub bodies: Option<[String; 2]>,
    pub at: Option<Points>,
    pub function: FunctionDef,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct ForceDef {
    pub name: String,
    #[serde(rename = "type")]
    pub kind: String,
    pub body: Option<String>,
    #[serde(default, deserialize_with = "strict::two_names_opt")]
    pub bodies: Option<[String; 2]>,
    pub joint: Option<String>,
    pub at: Option<Points>,
    /// A `segment-segment` element's two segments, each by its two ends (global).
    #[serde(default, deserialize_with = "strict::two_segments2_opt")]
    pub segments: Option<strict::TwoSegments<2>>,
    #[serde(default, deserialize_with = "strict::xy_opt")]
    pub point: Option<[f64; 2]>,
    pub value: Option<ValueDef>,
    pub fx: Option<FunctionDef>,
    pub fy: Option<FunctionDef>,
    pub stiffness: Option<f64>,
    pub damping: Option<f64>,
    pub free_length: Option<f64>,
    pub free_angle: Option<f64>,
    pub actuator: Option<FunctionDef>,
    pub radius: Option<f64>,
    #[serde(default, deserialize_with = "strict::xy_opt")]
    pub radii: Option<[f64; 2]>,
    pub line: Option<LineDef>,
    /// A `circle-profile` element's cam profile.
    pub profile: Option<ProfileDef>,
    /// A `polygon-line` element's vertices (global, in the file's configuration).
    pub vertices: Option<Vec<[f64; 2]>>,
    /// A `polygon-polygon` element's two polygons' vertices (global, in the file's configuration).
    pub polygons: Option<[Vec<[f64; 2]>; 2]>,
    pub exponent: Option<f64>,
    pub dissipation: Option<f64>,
    pub friction: Option<f64>,
    pub smoothing_velocity: Option<f64>,
    /// `rigid = true`: a unilateral contact kept by impacts, not a compliant force
    /// (`docs/limits.md`, "Rigid contact").
    pub rigid: Option<bool>,
    pub restitution: Option<f64>,
    pub rest_speed: Option<f64>,
}

impl ForceDef {
    /// The optional keys the table gives, in the order of the format.
    pub(crate) fn keys_given(&self) -> impl Iterator<Item = &'static str> {
        [
            ("body", self.body.is_some()),
            ("bodies", self.bodies.is_some()),
            ("joint", self.joint.is_some()),
            ("at", self.at.is_some()),
            ("segments", self.segments.is_some()),
            ("point", self.point.is_some()),
            ("value", self.value.is_some()),
            ("fx", self.fx.is_some()),
            ("fy", self.fy.is_some()),
            ("stiffness", self.stiffness.is_some()),
            ("damping", self.damping.is_some()),
            ("free_length", self.free_length.is_some()),
            ("free_angle", self.free_angle.is_some()),
            ("actuator", self.actuator.is_some()),
            ("radius", self.radius.is_some()),
            ("radii", self.radii.is_some()),
            ("line", self.line.is_some()),
            ("profile", self.profile.is_some()),
            ("vertices", self.vertices.is_some()),
            ("polygons", self.polygons.is_some()),
            ("exponent", self.exponent.is_some()),
            ("dissipation", self.dissipation.is_some()),
            ("friction", self.friction.is_some()),
            ("smoothing_velocity", self.smoothing_velocity.is_some()),
            ("rigid", self.rigid.is_some()),
            ("restitution", self.restitution.is_some()),
            ("rest_speed", self.rest_speed.is_some()),
        ]
        .into_iter()
        .filter_map(|(k, given)| given.then_some(k))
    }
}

/// A line of the ground: a point and the normal out of the ground (any length but zero).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct LineDef {
    /// The body the line is fixed in (default the ground; a rigid contact only).
    pub body: Option<String>,
    #[serde(deserialize_with = "strict::xy")]
    pub point: [f64; 2],
    #[serde(deserialize_with = "strict::xy")]
    pub normal: [f64; 2],
}

/// A closed profile fixed in a body (a cam's): points in the file's configuration (global),
/// the last repeating the first.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct ProfileDef {
    pub body: String,
    pub points: Vec<[f64; 2]>,
}

/// `[simulation]`. The methods' parameters (`rtol`, `rho_inf`, …) come from the integrators'
/// registry: every other key lands in `parameters` and is checked against it
/// (`build::settings`), since serde's `deny_unknown_fields` does not combine with `flatten`.
#[derive(Debug, Deserialize)]
pub(crate) struct SimDef {
    pub end: Option<f64>,
    pub formulation: Option<String>,
    pub integrator: Option<String>,
    pub step: Option<f64>,
    pub output_every: Option<f64>,
    pub stabilization: Option<String>,
    pub redundant: Option<String>,
    pub independent: Option<Vec<String>>,
    pub coordinates: Option<String>,
    #[serde(flatten)]
    pub parameters: std::collections::BTreeMap<String, toml::Value>,
}

/// The fixed keys of `[simulation]`, for messages (the methods' parameters follow them).
pub(crate) const SIM_KEYS: &[&str] = &[
    "end",
    "formulation",
    "integrator",
    "step",
    "output_every",
    "stabilization",
    "redundant",
    "independent",
    "coordinates",
];
