//! Spatial scenes: the scene format with three-component vectors (`docs/scenes.md`, "Spatial
//! scenes"). A scene whose `[scene] gravity` has three components is read here.
//!
//! Bodies carry a centre of mass `position = [x, y, z]`, an `orientation` (axis and angle, a
//! sequence of rotations about body axes, or Euler parameters), `inertia` (principal moments or the
//! six tensor components, body frame) or a `shape` (box, sphere, cylinder), and optional
//! `velocity` / `angular_velocity` (global). Joints are placed by a global point `at` and a global
//! `axis` (`axes = [first, second]` for universal and perpendicular joints), as in the initial
//! configuration.

use super::error::SceneError;
use super::format::{FrictionDef, FunctionDef, SimDef};
use super::functions::time_function;
use super::limit_keys::{limit_keys, LimitKeys};
use super::names::{Ctx, Names};
use super::spatial_forces::{self, ForceDef};
use super::strict::{self, Inertia3, Points3};
use super::{build, Scene};
use crate::animation::{Drawing, Solid, SpatialDrawing};
use dalembert_spatial::body;
use dalembert_spatial::euler_parameters::{self, EulerParameters};
use dalembert_spatial::{Body, BodyRef, Coupling, Driver, DriverTarget, Joint, JointKind, ModelBuilder};
use dalembert_system::{MultibodySystem, SlipRow};
use nalgebra::{Matrix3, Vector3};
use serde::Deserialize;
use std::collections::HashMap;
use std::ops::Range;
use std::sync::Arc;
use toml::Spanned;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct SpatialFile {
    pub scene: Meta,
    #[serde(default)]
    pub bodies: Vec<Spanned<BodyDef>>,
    #[serde(default)]
    pub joints: Vec<Spanned<JointDef>>,
    #[serde(default)]
    pub drivers: Vec<Spanned<DriverDef>>,
    #[serde(default)]
    pub forces: Vec<Spanned<ForceDef>>,
    #[serde(default)]
    pub couplings: Vec<Spanned<CouplingDef>>,
    pub simulation: Option<Spanned<SimDef>>,
    pub initial: Option<Spanned<InitialDef>>,
}

/// A TOML scene around a URDF robot (`[scene] urdf`): the keys it may add, checked before the
/// robot's elements join them.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(dead_code)]
pub(crate) struct AroundFile {
    pub scene: AroundMeta,
    #[serde(default)]
    pub bodies: Vec<Spanned<BodyDef>>,
    #[serde(default)]
    pub joints: Vec<Spanned<JointDef>>,
    #[serde(default)]
    pub drivers: Vec<Spanned<DriverDef>>,
    #[serde(default)]
    pub forces: Vec<Spanned<ForceDef>>,
    #[serde(default)]
    pub couplings: Vec<Spanned<CouplingDef>>,
    pub simulation: Option<Spanned<SimDef>>,
    pub initial: Option<Spanned<InitialDef>>,
}

/// The `[scene]` of a scene around a robot.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(dead_code)]
pub(crate) struct AroundMeta {
    pub urdf: String,
    /// The robot's root link moves freely (a floating base) instead of being fixed to the ground.
    #[serde(default)]
    pub floating_base: bool,
    pub name: Option<String>,
    #[serde(default, deserialize_with = "strict::xyz_opt")]
    pub gravity: Option<[f64; 3]>,
    #[serde(default)]
    pub visual: Vec<super::visuals::VisualDef>,
}

pub(crate) use super::initial::InitialDef;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct Meta {
    pub name: Option<String>,
    #[serde(deserialize_with = "strict::xyz")]
    pub gravity: [f64; 3],
    /// The ground's shapes (world frame).
    #[serde(default)]
    pub visual: Vec<super::visuals::VisualDef>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct BodyDef {
    pub name: String,
    pub mass: f64,
    pub inertia: Option<Inertia3>,
    pub shape: Option<ShapeDef>,
    #[serde(deserialize_with = "strict::xyz")]
    pub position: [f64; 3],
    pub orientation: Option<OrientationDef>,
    #[serde(default, deserialize_with = "strict::xyz_opt")]
    pub velocity: Option<[f64; 3]>,
    #[serde(default, deserialize_with = "strict::xyz_opt")]
    pub angular_velocity: Option<[f64; 3]>,
    #[serde(default, deserialize_with = "strict::xyz_opt")]
    pub center_of_mass: Option<[f64; 3]>,
    pub inertia_about: Option<String>,
    #[serde(default)]
    pub visual: Vec<super::visuals::VisualDef>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct ShapeDef {
    pub sphere: Option<f64>,
    #[serde(rename = "box", default, deserialize_with = "strict::xyz_opt")]
    pub cuboid: Option<[f64; 3]>,
    pub cylinder: Option<CylinderDef>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct CylinderDef {
    pub radius: f64,
    pub length: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct OrientationDef {
    #[serde(default, deserialize_with = "strict::xyz_opt")]
    pub axis: Option<[f64; 3]>,
    pub angle: Option<f64>,
    pub sequence: Option<String>,
    pub angles: Option<Vec<f64>>,
    pub degrees: Option<toml::Value>,
    #[serde(default, deserialize_with = "strict::quaternion_opt")]
    pub quaternion: Option<[f64; 4]>,
    #[serde(default, deserialize_with = "strict::xyz_opt")]
    pub x_axis: Option<[f64; 3]>,
    #[serde(default, deserialize_with = "strict::xyz_opt")]
    pub y_axis: Option<[f64; 3]>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct JointDef {
    pub name: String,
    #[serde(rename = "type")]
    pub kind: String,
    #[serde(deserialize_with = "strict::two_names")]
    pub bodies: [String; 2],
    pub at: Option<Points3>,
    #[serde(default, deserialize_with = "strict::xyz_opt")]
    pub axis: Option<[f64; 3]>,
    #[serde(default, deserialize_with = "strict::two_axes_opt")]
    pub axes: Option<[[f64; 3]; 2]>,
    /// `friction = { coefficient, radius, viscous, stick_speed }` on a revolute or prismatic
    /// joint (`docs/friction.md`).
    pub friction: Option<Spanned<FrictionDef>>,
    /// `limits = [lower, upper]` on a revolute or prismatic joint (`docs/limits.md`).
    pub limits: Option<Spanned<Vec<f64>>>,
    /// Newton's coefficient of restitution at the limits (default 0).
    pub restitution: Option<Spanned<f64>>,
    /// The rebound speed below which the joint rests on a limit (default 1e-3).
    pub rest_speed: Option<Spanned<f64>>,
}

/// `[[couplings]]`: joint `follower`'s value as `multiplier · leader + offset`, or as the
/// polynomial `c₀ + c₁ leader + …` (`docs/couplings.md`).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct CouplingDef {
    pub name: String,
    pub leader: Option<String>,
    pub follower: String,
    pub multiplier: Option<f64>,
    pub offset: Option<f64>,
    pub polynomial: Option<Vec<f64>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct DriverDef {
    pub name: String,
    #[serde(rename = "type")]
    pub kind: String,
    pub joint: Option<String>,
    pub body: Option<String>,
    pub coordinate: Option<String>,
    pub function: FunctionDef,
}

/// An error from the model builder, placed at the first element it names (`joint 'B': …`).
fn model_err(ctx: &Ctx<'_>, names: &Names<BodyRef>, message: String) -> SceneError {
    let span = message.split('\'').skip(1).step_by(2).find_map(|name| names.span(name));
    ctx.err(span, message)
}

/// The inertia tensor (body frame, about the centre of mass) that `inertia` or `shape` gives.
fn inertia(def: &BodyDef) -> Result<Matrix3<f64>, String> {
    let m = def.mass;
    let positive = |v: f64, what: &str| {
        if v.is_finite() && v > 0.0 {
            Ok(v)
        } else {
            Err(format!("shape: {what} must be positive and finite, got {v}"))
        }
    };
    match (&def.inertia, &def.shape) {
        (Some(Inertia3::Principal(j)), None) => Ok(Matrix3::from_diagonal(&Vector3::from(*j))),
        (Some(Inertia3::Tensor([xx, yy, zz, xy, xz, yz])), None) => {
            Ok(Matrix3::new(*xx, *xy, *xz, *xy, *yy, *yz, *xz, *yz, *zz))
        }
        (None, Some(s)) => {
            let principal = match (s.sphere, s.cuboid, &s.cylinder) {
                (Some(r), None, None) => {
                    let r = positive(r, "sphere radius")?;
                    [0.4 * m * r * r; 3]
                }
                (None, Some([a, b, c]), None) => {
                    let (a, b, c) = (positive(a, "box x")?, positive(b, "box y")?, positive(c, "box z")?);
                    let k = m / 12.0;
                    [k * (b * b + c * c), k * (a * a + c * c), k * (a * a + b * b)]
                }
                (None, None, Some(c)) => {
                    let (r, l) = (positive(c.radius, "cylinder radius")?, positive(c.length, "cylinder length")?);
                    let across = m * (3.0 * r * r + l * l) / 12.0;
                    [across, across, 0.5 * m * r * r]
                }
                _ => {
                    return Err(
                        "shape takes exactly one of sphere = r, box = [a, b, c], cylinder = { radius = r, length = l }"
                            .into(),
                    )
                }
            };
            Ok(Matrix3::from_diagonal(&Vector3::from(principal)))
        }
        (Some(_), Some(_)) => Err("give 'inertia' or 'shape', not both".into()),
        (None, None) => Err("give 'inertia' ([Jx, Jy, Jz] or [Jxx, Jyy, Jzz, Jxy, Jxz, Jyz], kg·m² about the centre of mass, body axes) or 'shape'".into()),
    }
}

/// Euler parameters from an `orientation` table.
pub(crate) fn orientation(def: &OrientationDef) -> Result<EulerParameters, String> {
    let degrees = |v: &toml::Value| -> Option<Vec<f64>> {
        match v {
            toml::Value::Array(a) => a
                .iter()
                .map(|x| x.as_float().or(x.as_integer().map(|i| i as f64)))
                .collect(),
            x => x.as_float().or(x.as_integer().map(|i| i as f64)).map(|d| vec![d]),
        }
    };
    let radians = |d: Vec<f64>| d.into_iter().map(f64::to_radians).collect::<Vec<_>>();
    if def.x_axis.is_some() || def.y_axis.is_some() {
        let only_axes = def.axis.is_none()
            && def.sequence.is_none()
            && def.quaternion.is_none()
            && def.angle.is_none()
            && def.angles.is_none()
            && def.degrees.is_none();
        let (Some(x), Some(y), true) = (def.x_axis, def.y_axis, only_axes) else {
            return Err("an orientation by axes gives both 'x_axis' and 'y_axis' (global) and nothing else".into());
        };
        return frame_from_axes(x, y);
    }
    let p = match (def.axis, def.sequence.as_deref(), def.quaternion) {
        (Some(axis), None, None) => {
            let angle = match (def.angle, &def.degrees, &def.angles) {
                (Some(a), None, None) => a,
                (None, Some(d), None) => match degrees(d).as_deref() {
                    Some([d]) => d.to_radians(),
                    _ => return Err("'degrees' with an 'axis' is one number".into()),
                },
                _ => return Err("an 'axis' takes one 'angle' (radians) or 'degrees'".into()),
            };
            let a = Vector3::from(axis);
            let n = a.norm();
            if !(n.is_finite() && n > 0.0) {
                return Err(format!("'axis' must be a non-zero finite vector, got {axis:?}"));
            }
            euler_parameters::from_axis_angle(&(a / n), angle)
        }
        (None, Some(seq), None) => {
            let angles = match (&def.angles, &def.degrees, def.angle) {
                (Some(a), None, None) => a.clone(),
                (None, Some(d), None) => radians(degrees(d).ok_or("'degrees' must be numbers")?),
                _ => return Err("a 'sequence' takes 'angles' (radians) or 'degrees', one per axis".into()),
            };
            if seq.is_empty() || seq.chars().count() != angles.len() {
                return Err(format!(
                    "sequence \"{seq}\" names {} axes but {} angles are given",
                    seq.chars().count(),
                    angles.len()
                ));
            }
            // Rotations about the body's own (successively rotated) axes: A = A₁(θ₁) A₂(θ₂) ….
            let mut p = euler_parameters::IDENTITY;
            for (c, angle) in seq.chars().zip(angles) {
                let axis = match c {
                    'x' => Vector3::x(),
                    'y' => Vector3::y(),
                    'z' => Vector3::z(),
                    other => return Err(format!("sequence \"{seq}\": '{other}' is not an axis (x, y or z)")),
                };
                p = euler_parameters::product(&p, &euler_parameters::from_axis_angle(&axis, angle));
            }
            p
        }
        (None, None, Some(e)) => {
            if def.angle.is_some() || def.angles.is_some() || def.degrees.is_some() {
                return Err("a 'quaternion' takes no angles".into());
            }
            let n = e.iter().map(|x| x * x).sum::<f64>().sqrt();
            if !(n.is_finite() && (n - 1.0).abs() < 1e-6) {
                return Err(format!(
                    "'quaternion' [e0, e1, e2, e3] must have unit length (to 1e-6), got length {n}"
                ));
            }
            e
        }
        _ => {
            return Err(
                "orientation takes one of { axis = [x, y, z], angle = a }, { sequence = \"zyx\", angles = [a, b, c] }, { x_axis = [..], y_axis = [..] } or { quaternion = [e0, e1, e2, e3] } (angles in radians; 'degrees' instead of 'angle'/'angles')"
                    .into(),
            )
        }
    };
    if !p.iter().all(|x| x.is_finite()) {
        return Err("orientation must be finite".into());
    }
    Ok(p)
}

/// Euler parameters of the body frame whose `x` axis is along `x` and whose `y` axis is `y` made
/// perpendicular to `x` (global components); `z = x × y`.
fn frame_from_axes(x: [f64; 3], y: [f64; 3]) -> Result<EulerParameters, String> {
    let x = Vector3::from(x);
    let y = Vector3::from(y);
    let nx = x.norm();
    if !(nx.is_finite() && nx > 0.0) {
        return Err(format!(
            "'x_axis' must be a non-zero finite vector, got {:?}",
            x.as_slice()
        ));
    }
    let ex = x / nx;
    let yp = y - ex * ex.dot(&y);
    let ny = yp.norm();
    if !(ny.is_finite() && ny > 1e-9 * y.norm()) {
        return Err("'y_axis' must be finite and not parallel to 'x_axis'".into());
    }
    let ey = yp / ny;
    let a = Matrix3::from_columns(&[ex, ey, ex.cross(&ey)]);
    Ok(euler_parameters::from_rotation(&a))
}

/// The error for a planar body (`position = [x, y]` or an `angle`) in a scene whose three-component
/// gravity makes it spatial, placed at the body: clearer than the format's complaint about the
/// body's keys. `None` when no body looks planar.
pub(crate) fn planar_body_in_spatial_scene(text: &str, origin: &str) -> Option<SceneError> {
    #[derive(Deserialize)]
    struct Probe {
        #[serde(default)]
        bodies: Vec<Spanned<ProbeBody>>,
    }
    #[derive(Deserialize)]
    struct ProbeBody {
        name: Option<String>,
        position: Option<toml::Value>,
        angle: Option<toml::Value>,
    }
    let probe: Probe = toml::from_str(text).ok()?;
    let planar = probe.bodies.iter().find(|b| {
        let b = b.get_ref();
        b.angle.is_some() || matches!(&b.position, Some(toml::Value::Array(a)) if a.len() == 2)
    })?;
    let name = planar.get_ref().name.as_deref().unwrap_or("?");
    Some(SceneError::at(
        origin,
        text,
        Some(planar.span()),
        format!(
            "body '{name}' is planar (position [x, y] or an angle) but the scene is spatial because its gravity has three components: write gravity = [gx, gy] for a planar scene, or give the body position = [x, y, z] and an orientation"
        ),
    ))
}

/// Builds and assembles a spatial scene.
pub(crate) fn build(file: SpatialFile, text: &str, origin: &str) -> Result<Scene, SceneError> {
    let (inputs, code_forces) = (std::cell::RefCell::new(Vec::new()), std::cell::RefCell::new(Vec::new()));
    let ctx = Ctx {
        file: origin,
        text,
        inputs: &inputs,
        code_forces: &code_forces,
    };
    let g = file.scene.gravity;
    if !g.iter().all(|x| x.is_finite()) {
        return Err(ctx.err(None, format!("[scene] gravity must be finite, got {g:?}")));
    }
    if file.bodies.is_empty() {
        return Err(ctx.err(None, "the scene has no [[bodies]]"));
    }
    let mut model = ModelBuilder::new(g);
    let mut names = Names::new(BodyRef::Ground);
    let mut positions = Vec::new();
    let mut weights = Vec::new();
    for sb in &file.bodies {
        let span = sb.span();
        let d = sb.get_ref();
        names.unique(&ctx, &d.name, &span, "body")?;
        let at = |m: String| ctx.err(Some(span.clone()), format!("body '{}': {m}", d.name));
        let p = d
            .orientation
            .as_ref()
            .map_or(Ok(euler_parameters::IDENTITY), orientation)
            .map_err(at)?;
        let (v, w) = (d.velocity.unwrap_or_default(), d.angular_velocity.unwrap_or_default());
        // With `center_of_mass`, `position` (and `velocity`) are a reference point's; the model's
        // coordinates stay the centre of mass.
        let c = d.center_of_mass.unwrap_or_default();
        let j = match d.inertia_about.as_deref() {
            None | Some("center-of-mass") => inertia(d).map_err(at)?,
            Some("reference") if d.inertia.is_some() => {
                let j = body::inertia_about_center(d.mass, &inertia(d).map_err(at)?, c);
                let smallest = j.symmetric_eigenvalues().min();
                if smallest < -1e-12 * j.amax() {
                    return Err(at(format!(
                        "the inertia about the reference point is less than the centre of mass's share m (|c|² I − c cᵀ): about the centre of mass it would have the eigenvalue {smallest:.3e}"
                    )));
                }
                j
            }
            Some("reference") => {
                return Err(at(
                    "inertia_about = \"reference\" applies to 'inertia' (a shape is about its centre)".into(),
                ))
            }
            Some(other) => {
                return Err(at(format!(
                    "unknown inertia_about '{other}' (expected center-of-mass or reference)"
                )))
            }
        };
        let body = Body::new(&d.name, d.mass, [0.0; 3])
            .with_inertia(j)
            .oriented(p)
            .moving(v, w)
            .with_reference_point(d.position, c);
        let com: [f64; 3] = body.position.into();
        // Velocities given in the file are kept as far as the constraints allow.
        let weight = |given: bool| if given { build::GIVEN_VELOCITY_WEIGHT } else { 1.0 };
        weights.extend([weight(d.velocity.is_some()); 3]);
        weights.extend([weight(d.angular_velocity.is_some()); 3]);
        positions.push(com);
        let r = model.body(body);
        names.add_body(&d.name, r);
    }
    let mut joint_kinds = HashMap::new();
    let (mut limits, mut limit_spans) = (Vec::new(), Vec::new());
    let (mut frictions, mut friction_spans) = (Vec::new(), Vec::new());
    for sj in &file.joints {
        let span = sj.span();
        let d = sj.get_ref();
        names.unique(&ctx, &d.name, &span, "joint")?;
        let owner = format!("joint '{}'", d.name);
        let pair = [
            names.body(&ctx, &d.bodies[0], &span, &owner)?,
            names.body(&ctx, &d.bodies[1], &span, &owner)?,
        ];
        if pair[0] == pair[1] {
            return Err(ctx.err(
                Some(span.clone()),
                format!("{owner}: both bodies are '{}'", d.bodies[0]),
            ));
        }
        let joint = joint(d, pair).map_err(|m| ctx.err(Some(span.clone()), format!("{owner}: {m}")))?;
        joint_kinds.insert(d.name.clone(), joint.kind);
        model.joint(joint);
        let keys = LimitKeys {
            limits: d.limits.as_ref(),
            restitution: d.restitution.as_ref(),
            rest_speed: d.rest_speed.as_ref(),
        };
        if let Some((limit, at)) = limit_keys(&ctx, &d.name, keys)? {
            limits.push(limit);
            limit_spans.push(at);
        }
        if let Some(def) = &d.friction {
            let f = def.get_ref();
            if !matches!(d.kind.as_str(), "revolute" | "prismatic") {
                return Err(ctx.err(
                    Some(def.span()),
                    format!("{owner}: friction is for revolute and prismatic joints"),
                ));
            }
            let (coefficient, radius, constant) = f
                .law(d.kind == "revolute", &owner)
                .map_err(|m| ctx.err(Some(def.span()), m))?;
            frictions.push(dalembert_spatial::friction::SpatialFriction {
                joint: d.name.clone(),
                coefficient,
                radius,
                constant,
                viscous: f.viscous.unwrap_or(0.0),
                stick_speed: f.stick_speed.unwrap_or(dalembert_constraints::STICK_SPEED),
            });
            friction_spans.push(def.span());
        }
    }
    for sd in &file.drivers {
        let span = sd.span();
        let d = sd.get_ref();
        names.unique(&ctx, &d.name, &span, "driver")?;
        let owner = format!("driver '{}'", d.name);
        let err = |m: String| ctx.err(Some(span.clone()), format!("{owner}: {m}"));
        let joint_name = |kind: &str| -> Result<String, SceneError> {
            let name = d
                .joint
                .as_deref()
                .ok_or_else(|| err(format!("a {kind} driver needs 'joint'")))?;
            if !joint_kinds.contains_key(name) {
                return Err(err(format!("unknown joint '{name}'")));
            }
            Ok(name.to_string())
        };
        // A joint's angle and displacement are 0 in the file's configuration; a coordinate is
        // what the file says.
        let (target, start) = match d.kind.as_str() {
            "joint-angle" => (DriverTarget::JointAngle(joint_name("joint-angle")?), 0.0),
            "joint-displacement" => (DriverTarget::JointDisplacement(joint_name("joint-displacement")?), 0.0),
            "body-coordinate" => {
                let name = d.body.as_deref().ok_or_else(|| err("needs 'body'".into()))?;
                let body = names.body(&ctx, name, &span, &owner)?;
                let BodyRef::Body(i) = body else {
                    return Err(err("cannot drive the ground".into()));
                };
                let axis = match d.coordinate.as_deref() {
                    Some("x") => 0,
                    Some("y") => 1,
                    Some("z") => 2,
                    Some(other) => {
                        return Err(err(format!(
                            "'coordinate' must be \"x\", \"y\" or \"z\", got \"{other}\""
                        )))
                    }
                    None => return Err(err("needs 'coordinate' (\"x\", \"y\" or \"z\")".into())),
                };
                (DriverTarget::BodyCoordinate { body, axis }, positions[i][axis])
            }
            other => {
                return Err(err(format!(
                    "unknown type '{other}' (expected joint-angle, joint-displacement, body-coordinate)"
                )))
            }
        };
        if d.kind != "body-coordinate" && (d.body.is_some() || d.coordinate.is_some()) {
            return Err(err("'body' and 'coordinate' belong to a body-coordinate driver".into()));
        }
        let function = time_function(&d.function, Some(start), ctx.inputs).map_err(err)?;
        model.driver(Driver::new(&d.name, target, function));
    }
    let couplings = couplings(&ctx, &file, &mut names, &joint_kinds)?;
    for c in &couplings {
        model.coupling(c.clone());
    }
    // A plane a contact rolls on is drawn as a square of the ground.
    let mut floors = Vec::new();
    let mut rigid = Vec::new();
    let mut rigid_pairs = Vec::new();
    for sf in &file.forces {
        let span = sf.span();
        let d = sf.get_ref();
        names.unique(&ctx, &d.name, &span, "force")?;
        let owner = format!("force '{}'", d.name);
        if d.rigid == Some(true) && d.kind == "sphere-sphere" {
            let pair = spatial_forces::rigid_sphere_pair(d, &names, &ctx, &span, &owner, &positions)?;
            rigid_pairs.push((pair, span.clone()));
            continue;
        }
        if d.rigid == Some(true) {
            let contact = spatial_forces::rigid_sphere_plane(d, &names, &ctx, &span, &owner, &positions)?;
            if contact.plane_body.is_none() {
                floors.push(spatial_forces::floor_visual(&contact.point, &contact.normal, &owner));
            }
            rigid.push((contact, span.clone()));
            continue;
        }
        let f = spatial_forces::force(d, &names, &ctx, &span, &owner, &positions)?;
        // A plane of the ground is drawn as a floor; one on a body is its body's face.
        if let dalembert_spatial::Force::SpherePlane {
            point,
            normal,
            plane_body: BodyRef::Ground,
            ..
        }
        | dalembert_spatial::Force::BoxPlane {
            point,
            normal,
            plane_body: BodyRef::Ground,
            ..
        }
        | dalembert_spatial::Force::CapsulePlane {
            point,
            normal,
            plane_body: BodyRef::Ground,
            ..
        } = &f
        {
            floors.push(spatial_forces::floor_visual(point, normal, &owner));
        }
        model.force(f);
    }
    let model = model.build().map_err(|e| model_err(&ctx, &names, e.to_string()))?;
    let model = model.with_frictions(frictions.clone()).map_err(|e| {
        let message = e.to_string();
        let at = frictions
            .iter()
            .zip(&friction_spans)
            .find(|(f, _)| message.contains(&format!("'{}'", f.joint)));
        ctx.err(at.map(|(_, s)| s.clone()), message)
    })?;
    let model = model.with_limits(limits.clone()).map_err(|e| {
        let message = e.to_string();
        let at = limits
            .iter()
            .zip(&limit_spans)
            .find(|(l, _)| message.contains(&format!("'{}'", l.name)));
        ctx.err(at.map(|(_, s)| s.clone()), message)
    })?;
    let mut spans: Vec<(String, Range<usize>)> = rigid_pairs
        .iter()
        .map(
            |(c, s): &(dalembert_spatial::limits::SphereSphereContact, Range<usize>)| {
                (format!("'{}'", c.name), s.clone())
            },
        )
        .collect();
    spans.extend(
        rigid
            .iter()
            .map(|(c, s): &(_, Range<usize>)| (format!("'{}'", c.name), s.clone())),
    );
    let model = model
        .with_rigid_contacts(rigid.into_iter().map(|(c, _)| c).collect())
        .and_then(|m| m.with_rigid_sphere_pairs(rigid_pairs.into_iter().map(|(c, _)| c).collect()))
        .map_err(|e| {
            let message = e.to_string();
            let at = spans
                .iter()
                .find(|(n, _)| message.contains(n.as_str()))
                .map(|(_, s)| s.clone());
            ctx.err(at, message)
        })?;
    let (mut q, mut qd) = model.initial_state();
    if let Some(initial) = &file.initial {
        let span = Some(initial.span());
        let moves = initial_moves(initial.get_ref(), &file.drivers).map_err(|m| ctx.err(span.clone(), m))?;
        model
            .move_joints(&mut q, &mut qd, &moves)
            .map_err(|e| ctx.err(span.clone(), format!("[initial]: {e}")))?;
        let mut row = SlipRow::default();
        for (k, l) in model.limit_specs().iter().enumerate() {
            let value = model.limit_row(k, 0.0, &q, &[], &mut row);
            // A limited revolute joint's turns are counted from its start, read within a turn.
            let beyond = |m: &&dalembert_spatial::joint_values::JointMove| {
                l.within_turn && m.joint == l.name && m.value.abs() >= std::f64::consts::PI
            };
            if let Some(m) = moves.iter().find(beyond) {
                return Err(ctx.err(
                    span.clone(),
                    format!(
                        "[initial]: joint '{}' starts at {} rad, half a turn or more from the file's configuration: a limited joint counts its turns from a start within (−π, π)",
                        l.name, m.value
                    ),
                ));
            }
            if value < l.lower || value > l.upper {
                return Err(ctx.err(
                    span.clone(),
                    format!(
                        "[initial]: {} '{}' starts at {value}, outside its limits [{}, {}]",
                        l.element, l.name, l.lower, l.upper
                    ),
                ));
            }
        }
    }
    let follow = coupling_moves(&couplings, file.initial.as_ref().map(Spanned::get_ref));
    if !follow.is_empty() {
        model
            .move_joints(&mut q, &mut qd, &follow)
            .map_err(|e| model_err(&ctx, &names, format!("coupling: its follower cannot be placed: {e}")))?;
    }
    let shapes: Vec<Option<Solid>> = file.bodies.iter().map(|b| solid(b.get_ref())).collect();
    let visuals = file
        .bodies
        .iter()
        .map(|b| {
            let d = b.get_ref();
            let line = super::error::line_col(text, b.span().start).0;
            let declared = format!("{origin} line {line}");
            super::visuals::visuals(&d.visual, d.center_of_mass.unwrap_or_default(), &declared)
                .map_err(|m| ctx.err(Some(b.span()), format!("body '{}': {m}", d.name)))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let mut ground = super::visuals::visuals(&file.scene.visual, [0.0; 3], &format!("{origin} [scene]"))
        .map_err(|m| ctx.err(None, format!("[scene] {m}")))?;
    ground.extend(floors);
    let drawing = Drawing {
        spatial: Some(SpatialDrawing {
            ground,
            ..SpatialDrawing::of(&model, &shapes, &visuals)
        }),
        ..Drawing::default()
    };
    let mechanism: crate::mechanism::Mechanism = Arc::new(model).into();
    let settings = build::settings(
        ctx.file,
        ctx.text,
        file.simulation.as_ref(),
        &mechanism.velocity_names(),
    )?;
    build::check_coordinates(&ctx, file.simulation.as_ref(), &mechanism, &settings)?;
    if let Some(initial) = &file.initial {
        super::initial::apply(&mechanism, initial.get_ref(), &mut q, &mut qd, &mut weights)
            .map_err(|m| ctx.err(Some(initial.span()), m))?;
    }
    let name = file.scene.name.unwrap_or_else(|| origin.to_string());
    build::assembled(&ctx, name, mechanism, (q, qd, weights), settings, drawing)
}

/// The solid a body's `shape` gives the viewer (`None`: no shape, or one the inertia check
/// refuses).
fn solid(def: &BodyDef) -> Option<Solid> {
    let s = def.shape.as_ref()?;
    match (s.sphere, s.cuboid, &s.cylinder) {
        (Some(radius), None, None) => Some(Solid::Sphere { radius }),
        (None, Some(size), None) => Some(Solid::Box { size }),
        (None, None, Some(c)) => Some(Solid::Cylinder {
            radius: c.radius,
            length: c.length,
        }),
        _ => None,
    }
}

/// The couplings of `[[couplings]]`, checked against the joints and drivers (`joint_kinds`: the
/// joints' names).
fn couplings(
    ctx: &Ctx<'_>,
    file: &SpatialFile,
    names: &mut Names<BodyRef>,
    joint_kinds: &HashMap<String, JointKind>,
) -> Result<Vec<Coupling>, SceneError> {
    let mut out = Vec::with_capacity(file.couplings.len());
    for sc in &file.couplings {
        let span = sc.span();
        let d = sc.get_ref();
        names.unique(ctx, &d.name, &span, "coupling")?;
        let err = |m: String| ctx.err(Some(span.clone()), format!("coupling '{}': {m}", d.name));
        let polynomial =
            match (&d.polynomial, d.multiplier, d.offset) {
                (Some(p), None, None) => p.clone(),
                (Some(_), _, _) => return Err(err("give 'polynomial' or 'multiplier' and 'offset', not both".into())),
                (None, _, _) if d.leader.is_none() => return Err(err(
                    "needs 'leader', the joint it follows (or a 'polynomial' of one coefficient, the value it holds)"
                        .into(),
                )),
                (None, m, o) => vec![o.unwrap_or(0.0), m.unwrap_or(1.0)],
            };
        for j in d.leader.iter().chain([&d.follower]) {
            if !joint_kinds.contains_key(j) {
                return Err(err(format!("unknown joint '{j}'")));
            }
        }
        if let Some(driver) = file
            .drivers
            .iter()
            .find(|x| x.get_ref().joint.as_ref() == Some(&d.follower))
        {
            return Err(err(format!(
                "joint '{}' is driven by '{}' too: a joint follows one rule",
                d.follower,
                driver.get_ref().name
            )));
        }
        if let Some(other) = out.iter().find(|c: &&Coupling| c.follower == d.follower) {
            return Err(err(format!(
                "joint '{}' follows coupling '{}' already: a joint follows one rule",
                d.follower, other.name
            )));
        }
        out.push(Coupling {
            name: d.name.clone(),
            leader: d.leader.clone(),
            follower: d.follower.clone(),
            polynomial,
        });
    }
    Ok(out)
}

/// The moves that put each coupling's follower where its leader's start (`[initial]`, or the
/// file's configuration) places it, unless `[initial]` places the follower itself: the follower
/// value `p(x)` and rate `p′(x) ẋ` (a follower's value is relative to its own joint, so moving
/// other joints first leaves it unchanged).
fn coupling_moves(
    couplings: &[Coupling],
    initial: Option<&InitialDef>,
) -> Vec<dalembert_spatial::joint_values::JointMove> {
    let given = |j: &str| initial.is_some_and(|i| i.joints.contains_key(j) || i.rates.contains_key(j));
    let start = |j: &str| {
        initial.map_or((0.0, 0.0), |i| {
            (
                i.joints.get(j).copied().unwrap_or(0.0),
                i.rates.get(j).copied().unwrap_or(0.0),
            )
        })
    };
    let mut moves = Vec::new();
    for c in couplings.iter().filter(|c| !given(&c.follower)) {
        let (x, rate) = c.leader.as_deref().map_or((0.0, 0.0), start);
        let [value, slope, _] = c.polynomial_at(x);
        let (value, rate) = if c.leader.is_some() {
            (value, slope * rate)
        } else {
            (c.polynomial[0], 0.0)
        };
        if value != 0.0 || rate != 0.0 {
            moves.push(dalembert_spatial::joint_values::JointMove {
                joint: c.follower.clone(),
                value,
                rate,
            });
        }
    }
    moves
}

/// The joint moves `[initial]` asks for; a driven joint is refused (its driver sets its motion).
fn initial_moves(
    initial: &InitialDef,
    drivers: &[Spanned<DriverDef>],
) -> Result<Vec<dalembert_spatial::joint_values::JointMove>, String> {
    let names: std::collections::BTreeSet<&String> = initial.joints.keys().chain(initial.rates.keys()).collect();
    let mut moves = Vec::with_capacity(names.len());
    for name in names {
        if let Some(d) = drivers.iter().find(|d| d.get_ref().joint.as_ref() == Some(name)) {
            return Err(format!(
                "[initial]: joint '{name}' is driven by '{}', whose function sets its motion",
                d.get_ref().name
            ));
        }
        moves.push(dalembert_spatial::joint_values::JointMove {
            joint: name.clone(),
            value: initial.joints.get(name).copied().unwrap_or(0.0),
            rate: initial.rates.get(name).copied().unwrap_or(0.0),
        });
    }
    Ok(moves)
}

/// The joint a `[[joints]]` table describes.
fn joint(d: &JointDef, [bi, bj]: [BodyRef; 2]) -> Result<Joint, String> {
    let kind = JointKind::ALL.into_iter().find(|k| k.name() == d.kind).ok_or_else(|| {
        let names: Vec<&str> = JointKind::ALL.iter().map(|k| k.name()).collect();
        format!("unknown type '{}' (expected {})", d.kind, names.join(", "))
    })?;
    let uses_axis = !matches!(kind, JointKind::Spherical | JointKind::Fixed | JointKind::Distance);
    let crossed = matches!(kind, JointKind::Universal | JointKind::Perpendicular);
    let finite_nonzero = |a: &[f64; 3], what: &str| {
        let n = Vector3::from(*a).norm();
        if n.is_finite() && n > 0.0 {
            Ok(())
        } else {
            Err(format!("'{what}' must be a non-zero finite vector, got {a:?}"))
        }
    };
    let point = |p: &[f64; 3]| {
        if p.iter().all(|x| x.is_finite()) {
            Ok(*p)
        } else {
            Err(format!("'at' must be finite, got {p:?}"))
        }
    };
    match (d.axis, d.axes) {
        (Some(_), _) if !uses_axis || crossed => {
            return Err(if crossed {
                format!(
                    "a {} joint takes 'axes = [[on first body], [on second body]]', not 'axis'",
                    kind.name()
                )
            } else {
                format!("a {} joint has no axis", kind.name())
            })
        }
        (_, Some(_)) if !crossed => {
            return Err(format!(
                "'axes' belongs to universal and perpendicular joints; a {} joint takes 'axis'",
                kind.name()
            ))
        }
        (None, None) if uses_axis => {
            return Err(if crossed {
                "needs 'axes = [[x1, y1, z1], [x2, y2, z2]]' (an axis on each body, global)".to_string()
            } else {
                "needs 'axis = [x, y, z]' (global)".to_string()
            })
        }
        _ => {}
    }
    if let Some(a) = &d.axis {
        finite_nonzero(a, "axis")?;
    }
    if let Some([a, b]) = &d.axes {
        finite_nonzero(a, "axes")?;
        finite_nonzero(b, "axes")?;
    }
    let axis = d.axis.unwrap_or([0.0, 0.0, 1.0]);
    Ok(match (kind, d.at) {
        (JointKind::Distance, Some(Points3::Two([p, q]))) => Joint::distance(&d.name, bi, point(&p)?, bj, point(&q)?),
        (JointKind::Distance, _) => {
            return Err("needs 'at = [[x1, y1, z1], [x2, y2, z2]]' (a point on each body, global)".into())
        }
        (_, Some(Points3::One(p))) if crossed => {
            let [a, b] = d.axes.unwrap_or_default();
            Joint::crossed(&d.name, kind, bi, bj, point(&p)?, a, b)
        }
        (_, Some(Points3::One(p))) => Joint::new(&d.name, kind, bi, bj, point(&p)?, axis),
        (_, Some(Points3::Two(_))) => return Err("'at' is one point [x, y, z] for this joint".into()),
        (JointKind::Parallel | JointKind::Perpendicular, None) => {
            let [a, b] = d.axes.unwrap_or([axis, axis]);
            Joint::crossed(&d.name, kind, bi, bj, [0.0; 3], a, b)
        }
        (_, None) => return Err("needs 'at = [x, y, z]' (the joint's point, global)".into()),
    })
}
