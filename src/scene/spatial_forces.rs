//! The `[[forces]]` of a spatial scene (`docs/scenes.md`, "Spatial scenes"): point forces and
//! torques (constant or functions of time, global or body axes), torques about a joint's axis,
//! spring–damper–actuators and rotational spring–dampers, and compliant sphere–plane and
//! sphere–sphere and capsule–capsule contact (`docs/contact.md`).

use super::error::SceneError;
use super::format::FunctionDef;
use super::functions::time_function;
use super::names::{Ctx, Names};
use super::strict::{self, Points3, ValueDef};
use dalembert_spatial::forces::ForceFrame;
use dalembert_spatial::{BodyRef, Force};
use dalembert_system::TimeFunction;
use nalgebra::Vector3;
use serde::Deserialize;
use std::cell::RefCell;
use std::ops::Range;

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
    pub at: Option<Points3>,
    pub value: Option<ValueDef<3>>,
    pub fx: Option<ValueDef<3>>,
    pub fy: Option<ValueDef<3>>,
    pub fz: Option<ValueDef<3>>,
    pub tx: Option<ValueDef<3>>,
    pub ty: Option<ValueDef<3>>,
    pub tz: Option<ValueDef<3>>,
    pub frame: Option<String>,
    pub stiffness: Option<f64>,
    pub damping: Option<f64>,
    pub free_length: Option<f64>,
    pub free_angle: Option<f64>,
    pub actuator: Option<FunctionDef>,
    /// A servo's target angle (rad): a number or a function.
    pub target: Option<ValueDef<3>>,
    /// A servo's torque range `[lo, hi]` (N·m).
    pub range: Option<[f64; 2]>,
    pub radius: Option<f64>,
    pub radii: Option<[f64; 2]>,
    /// A `capsule-group` element's members.
    pub members: Option<Vec<MemberDef>>,
    /// A `capsule-capsule` element's two segments, each by its two ends (global).
    #[serde(default, deserialize_with = "strict::two_segments_opt")]
    pub segments: Option<strict::TwoSegments>,
    /// A `box-plane` element's edge lengths along its body's axes.
    pub size: Option<[f64; 3]>,
    pub plane: Option<PlaneDef>,
    pub exponent: Option<f64>,
    pub dissipation: Option<f64>,
    pub friction: Option<f64>,
    pub smoothing_velocity: Option<f64>,
    /// `rigid = true`: a unilateral contact kept by impacts (`docs/limits.md`, "Rigid contact").
    pub rigid: Option<bool>,
    pub restitution: Option<f64>,
    pub rest_speed: Option<f64>,
}

/// A member of a `capsule-group`: a capsule (`at`, its segment's two ends) or a sphere (`at`, its
/// centre; default the body's position) of `radius` on `body`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct MemberDef {
    pub body: String,
    pub at: Option<Points3>,
    pub radius: f64,
}

/// A plane of the ground: a point and the normal out of the solid.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct PlaneDef {
    /// The body the plane is fixed in (default the ground).
    pub body: Option<String>,
    pub point: [f64; 3],
    pub normal: [f64; 3],
}

/// The side of the square the viewer draws a contact's plane with (m), centred on its point.
const FLOOR_SIDE: f64 = 4.0;

/// The viewer's drawing of a contact's plane: a thin square of side [`FLOOR_SIDE`] just below the
/// plane, turned from z to its normal.
pub(crate) fn floor_visual(point: &[f64; 3], normal: &[f64; 3], owner: &str) -> crate::animation::Visual {
    let n = Vector3::from(*normal).normalize();
    let z = Vector3::z();
    let axis = z.cross(&n);
    let rotation = if axis.norm() < 1e-12 {
        if n.z > 0.0 {
            [1.0, 0.0, 0.0, 0.0]
        } else {
            [0.0, 1.0, 0.0, 0.0]
        }
    } else {
        dalembert_spatial::euler_parameters::from_axis_angle(&axis, z.dot(&n).clamp(-1.0, 1.0).acos())
    };
    let thickness = 0.002;
    let centre = Vector3::from(*point) - 0.5 * thickness * n;
    crate::animation::Visual {
        shape: crate::animation::Solid::Box {
            size: [FLOOR_SIDE, FLOOR_SIDE, thickness],
        },
        position: centre.into(),
        rotation,
        declared: format!("{owner}'s plane"),
    }
}

/// The default smoothing velocity of contact friction (m/s): below it the friction force grows
/// linearly with the sliding speed (`docs/contact.md`).
pub(crate) const SMOOTHING_VELOCITY: f64 = 1e-3;

/// A contact law from a force table's keys (planar and spatial tables alike): `stiffness`
/// required, the rest defaulted (exponent 1.5, no dissipation or friction, smoothing velocity
/// 1 mm/s); its ranges are checked when the model is built.
pub(crate) fn contact_law(
    stiffness: Option<f64>,
    exponent: Option<f64>,
    dissipation: Option<f64>,
    friction: Option<f64>,
    smoothing_velocity: Option<f64>,
) -> Result<dalembert_system::ContactLaw, String> {
    Ok(dalembert_system::ContactLaw {
        stiffness: stiffness.ok_or("needs 'stiffness' (N/m^exponent)")?,
        exponent: exponent.unwrap_or(1.5),
        dissipation: dissipation.unwrap_or(0.0),
        friction: friction.unwrap_or(0.0),
        smoothing_velocity: smoothing_velocity.unwrap_or(SMOOTHING_VELOCITY),
    })
}

/// A number or a function (a vector is refused).
fn scalar(v: &ValueDef<3>, key: &str, inputs: &RefCell<Vec<String>>) -> Result<TimeFunction, String> {
    match v {
        ValueDef::Number(x) => Ok(TimeFunction::Constant(*x)),
        ValueDef::Function(f) => time_function(f, None, inputs).map_err(|m| format!("'{key}': {m}")),
        ValueDef::Vector(_) => Err(format!("'{key}' is one number or a function, got a vector")),
    }
}

impl ForceDef {
    /// The three components of a force (`f`) or a torque (`t`): `value = [x, y, z]` (constants) or
    /// the component keys, each a number or a function (missing ones are 0).
    fn components(&self, letter: &str, inputs: &RefCell<Vec<String>>) -> Result<[TimeFunction; 3], String> {
        let keys = if letter == "f" {
            [&self.fx, &self.fy, &self.fz]
        } else {
            [&self.tx, &self.ty, &self.tz]
        };
        let named = |axis: &str| format!("{letter}{axis}");
        match (&self.value, keys.iter().any(|k| k.is_some())) {
            (Some(ValueDef::Vector(v)), false) => Ok(v.map(TimeFunction::Constant)),
            (None, true) => {
                let mut out = [0, 1, 2].map(|_| TimeFunction::Constant(0.0));
                for ((o, k), axis) in out.iter_mut().zip(keys).zip(["x", "y", "z"]) {
                    if let Some(v) = k {
                        *o = scalar(v, &named(axis), inputs)?;
                    }
                }
                Ok(out)
            }
            _ => Err(format!(
                "give 'value = [{0}x, {0}y, {0}z]' (constant) or components '{0}x', '{0}y', '{0}z' (numbers or functions)",
                letter
            )),
        }
    }

    /// `frame = "global" | "body"`.
    fn axes(&self) -> Result<ForceFrame, String> {
        match self.frame.as_deref() {
            None | Some("global") => Ok(ForceFrame::Global),
            Some("body") => Ok(ForceFrame::Body),
            Some(other) => Err(format!("unknown frame '{other}' (expected global or body)")),
        }
    }

    /// Refuses keys that belong to other types of force.
    fn only(&self, allowed: &[&str]) -> Result<(), String> {
        let present = [
            ("body", self.body.is_some()),
            ("bodies", self.bodies.is_some()),
            ("joint", self.joint.is_some()),
            ("at", self.at.is_some()),
            ("value", self.value.is_some()),
            ("fx", self.fx.is_some()),
            ("fy", self.fy.is_some()),
            ("fz", self.fz.is_some()),
            ("tx", self.tx.is_some()),
            ("ty", self.ty.is_some()),
            ("tz", self.tz.is_some()),
            ("frame", self.frame.is_some()),
            ("stiffness", self.stiffness.is_some()),
            ("damping", self.damping.is_some()),
            ("free_length", self.free_length.is_some()),
            ("free_angle", self.free_angle.is_some()),
            ("actuator", self.actuator.is_some()),
            ("target", self.target.is_some()),
            ("range", self.range.is_some()),
            ("radius", self.radius.is_some()),
            ("radii", self.radii.is_some()),
            ("segments", self.segments.is_some()),
            ("members", self.members.is_some()),
            ("size", self.size.is_some()),
            ("plane", self.plane.is_some()),
            ("exponent", self.exponent.is_some()),
            ("dissipation", self.dissipation.is_some()),
            ("friction", self.friction.is_some()),
            ("smoothing_velocity", self.smoothing_velocity.is_some()),
            ("rigid", self.rigid.is_some()),
            ("restitution", self.restitution.is_some()),
            ("rest_speed", self.rest_speed.is_some()),
        ];
        match present.iter().find(|(k, p)| *p && !allowed.contains(k)) {
            Some((k, _)) => Err(format!("'{k}' does not belong to a {} element", self.kind)),
            None => Ok(()),
        }
    }
}

/// The force element a `[[forces]]` table describes.
pub(crate) fn force(
    d: &ForceDef,
    names: &Names<BodyRef>,
    ctx: &Ctx<'_>,
    span: &Range<usize>,
    owner: &str,
    positions: &[[f64; 3]],
) -> Result<Force, SceneError> {
    let err = |m: &str| ctx.err(Some(span.clone()), format!("{owner}: {m}"));
    let body = || -> Result<BodyRef, SceneError> {
        let n = d.body.as_deref().ok_or_else(|| err("needs 'body'"))?;
        names.body(ctx, n, span, owner)
    };
    let check = |r: Result<(), String>| r.map_err(|m| err(&m));
    // A contact's keys: its shapes' and its law's; a shape on a plane's (its own, `radius` or
    // `size`).
    let with_law = |shapes: &[&'static str]| {
        [
            shapes,
            &["stiffness", "exponent", "dissipation", "friction", "smoothing_velocity"],
        ]
        .concat()
    };
    let on_plane = |shape: &'static str| with_law(&["body", "at", shape, "plane"]);
    let law =
        || contact_law(d.stiffness, d.exponent, d.dissipation, d.friction, d.smoothing_velocity).map_err(|m| err(&m));
    let name = d.name.clone();
    Ok(match d.kind.as_str() {
        "force" => {
            check(d.only(&["body", "at", "value", "fx", "fy", "fz", "frame"]))?;
            let body = body()?;
            let point = match (d.at, body) {
                (Some(Points3::One(p)), _) => p,
                (None, BodyRef::Body(i)) => positions[i],
                (None, BodyRef::Ground) => [0.0; 3],
                (Some(Points3::Two(_)), _) => return Err(err("'at' is one point [x, y, z] (global)")),
            };
            Force::PointForce {
                name,
                body,
                point,
                force: d.components("f", ctx.inputs).map_err(|m| err(&m))?,
                frame: d.axes().map_err(|m| err(&m))?,
            }
        }
        "torque" if d.joint.is_some() => {
            check(d.only(&["joint", "value"]))?;
            let value = d
                .value
                .as_ref()
                .ok_or_else(|| err("needs 'value' (N·m about the joint axis)"))?;
            Force::JointTorque {
                name,
                joint: d.joint.clone().unwrap_or_default(),
                torque: scalar(value, "value", ctx.inputs).map_err(|m| err(&m))?,
            }
        }
        "torque" => {
            check(d.only(&["body", "value", "tx", "ty", "tz", "frame"]))?;
            Force::Torque {
                name,
                body: body()?,
                torque: d.components("t", ctx.inputs).map_err(|m| err(&m))?,
                frame: d.axes().map_err(|m| err(&m))?,
            }
        }
        "spring-damper" => {
            check(d.only(&["bodies", "at", "stiffness", "damping", "free_length", "actuator"]))?;
            let [n0, n1] = d.bodies.as_ref().ok_or_else(|| err("needs 'bodies'"))?;
            let (bi, bj) = (names.body(ctx, n0, span, owner)?, names.body(ctx, n1, span, owner)?);
            let Some(Points3::Two([p, q])) = d.at else {
                return Err(err(
                    "needs 'at = [[x1, y1, z1], [x2, y2, z2]]' (global attachment points)",
                ));
            };
            let initial = (Vector3::from(q) - Vector3::from(p)).norm();
            Force::SpringDamper {
                name,
                body_i: bi,
                point_i: p,
                body_j: bj,
                point_j: q,
                stiffness: d.stiffness.ok_or_else(|| err("needs 'stiffness'"))?,
                damping: d.damping.unwrap_or(0.0),
                free_length: d.free_length.unwrap_or(initial),
                actuator: d
                    .actuator
                    .as_ref()
                    .map(|f| time_function(f, None, ctx.inputs))
                    .transpose()
                    .map_err(|m| err(&format!("'actuator': {m}")))?,
            }
        }
        "rotational-spring-damper" => {
            check(d.only(&["joint", "stiffness", "damping", "free_angle"]))?;
            Force::RotationalSpringDamper {
                name,
                joint: d.joint.clone().ok_or_else(|| {
                    err("needs 'joint' (a revolute or cylindrical joint: the spring acts about its axis)")
                })?,
                stiffness: d.stiffness.ok_or_else(|| err("needs 'stiffness'"))?,
                damping: d.damping.unwrap_or(0.0),
                free_angle: d.free_angle.unwrap_or(0.0),
            }
        }
        "servo" => {
            check(d.only(&["joint", "stiffness", "damping", "target", "value", "range"]))?;
            let function = |v: &Option<ValueDef<3>>, key: &str| {
                v.as_ref()
                    .map(|v| scalar(v, key, ctx.inputs))
                    .transpose()
                    .map_err(|m| err(&m))
            };
            Force::JointServo {
                name,
                joint: d
                    .joint
                    .clone()
                    .ok_or_else(|| err("needs 'joint' (a revolute or cylindrical joint: the servo acts about its axis)"))?,
                stiffness: d.stiffness.unwrap_or(0.0),
                damping: d.damping.unwrap_or(0.0),
                target: function(&d.target, "target")?,
                torque: function(&d.value, "value")?,
                range: d.range.unwrap_or([f64::NEG_INFINITY, f64::INFINITY]),
            }
        }
        "sphere-plane" => {
            check(d.only(&on_plane("radius")))?;
            let (body, centre, radius, plane) = sphere_on_plane(d, names, ctx, span, owner, positions)?;
            Force::SpherePlane {
                name,
                body,
                centre,
                radius,
                plane_body: plane_body(plane, names, ctx, span, owner)?,
                point: plane.point,
                normal: plane.normal,
                law: law()?,
            }
        }
        "box-plane" => {
            check(d.only(&on_plane("size")))?;
            let (body, centre, plane) = shape_on_plane(d, names, ctx, span, owner)?;
            let centre = match centre {
                Some(Points3::One(p)) => p,
                None => body_position(body, positions),
                Some(Points3::Two(_)) => return Err(err("'at' is the box's centre, one point [x, y, z] (global)")),
            };
            Force::BoxPlane {
                name,
                body,
                centre,
                size: d.size.ok_or_else(|| err("needs 'size = [a, b, c]' (m: its edges along the body's axes)"))?,
                plane_body: plane_body(plane, names, ctx, span, owner)?,
                point: plane.point,
                normal: plane.normal,
                law: law()?,
            }
        }
        "capsule-plane" => {
            check(d.only(&on_plane("radius")))?;
            let (body, ends, plane) = shape_on_plane(d, names, ctx, span, owner)?;
            let Some(Points3::Two(ends)) = ends else {
                return Err(err("needs 'at = [[x1, y1, z1], [x2, y2, z2]]' (its segment's ends, global)"));
            };
            Force::CapsulePlane {
                name,
                body,
                ends,
                radius: d.radius.ok_or_else(|| err("needs 'radius' (m)"))?,
                plane_body: plane_body(plane, names, ctx, span, owner)?,
                point: plane.point,
                normal: plane.normal,
                law: law()?,
            }
        }
        "sphere-sphere" => {
            check(d.only(&with_law(&["bodies", "at", "radii"])))?;
            let (bodies, centres, radii) = two_spheres(d, names, ctx, span, owner, positions)?;
            Force::SphereSphere {
                name,
                bodies,
                centres,
                radii,
                law: law()?,
            }
        }
        "capsule-capsule" => {
            check(d.only(&with_law(&["bodies", "segments", "radii"])))?;
            let [n0, n1] = d.bodies.as_ref().ok_or_else(|| err("needs 'bodies'"))?;
            let bodies = [names.body(ctx, n0, span, owner)?, names.body(ctx, n1, span, owner)?];
            Force::CapsuleCapsule {
                name,
                bodies,
                segments: d.segments.ok_or_else(|| {
                    err("needs 'segments = [[[x1, y1, z1], [x2, y2, z2]], [[x3, y3, z3], [x4, y4, z4]]]' (each capsule's segment's ends, global)")
                })?,
                radii: d.radii.ok_or_else(|| err("needs 'radii = [r1, r2]' (m)"))?,
                law: law()?,
            }
        }
        "capsule-group" => {
            check(d.only(&with_law(&["members"])))?;
            let defs = d.members.as_ref().ok_or_else(|| {
                err("needs 'members = [{ body = \"..\", at = [[x1, y1, z1], [x2, y2, z2]], radius = r }, …]' (capsules; a sphere takes one point or none)")
            })?;
            let mut members = Vec::with_capacity(defs.len());
            for (k, m) in defs.iter().enumerate() {
                let body = names.body(ctx, &m.body, span, &format!("{owner}, member {}", k + 1))?;
                let ends = match m.at {
                    Some(Points3::Two(ends)) => ends,
                    Some(Points3::One(p)) => [p; 2],
                    None => [body_position(body, positions); 2],
                };
                members.push((body, ends, m.radius));
            }
            Force::CapsuleGroup {
                name,
                members,
                law: law()?,
            }
        }
        "code" => {
            check(
                d.only(&["body"])
                    .map_err(|m| format!("{m} (its force comes from code: give 'body' only)")),
            )?;
            Force::User(std::sync::Arc::new(crate::code_force::SpatialCodeForce {
                name: name.clone(),
                body: body()?,
                index: ctx.code_force(&name),
            }))
        }
        other => {
            return Err(err(&format!(
                "unknown type '{other}' (expected force, torque, spring-damper, rotational-spring-damper, servo, sphere-plane, box-plane, capsule-plane, sphere-sphere, capsule-capsule, capsule-group, code)"
            )))
        }
    })
}

/// The body, the `at` key and the plane of a `box-plane` or `capsule-plane` element.
fn shape_on_plane<'a>(
    d: &'a ForceDef,
    names: &Names<BodyRef>,
    ctx: &Ctx<'_>,
    span: &Range<usize>,
    owner: &str,
) -> Result<(BodyRef, Option<Points3>, &'a PlaneDef), SceneError> {
    let err = |m: &str| ctx.err(Some(span.clone()), format!("{owner}: {m}"));
    let name = d.body.as_deref().ok_or_else(|| err("needs 'body'"))?;
    let body = names.body(ctx, name, span, owner)?;
    let plane = d.plane.as_ref().ok_or_else(|| err(NEEDS_PLANE))?;
    Ok((body, d.at, plane))
}

/// What a contact on a plane needs.
const NEEDS_PLANE: &str =
    "needs 'plane = { point = [x, y, z], normal = [nx, ny, nz] }' (global; of the ground unless it names a 'body', the normal out of it)";

/// The body a compliant contact's plane is fixed in (the ground unless it names one).
fn plane_body(
    plane: &PlaneDef,
    names: &Names<BodyRef>,
    ctx: &Ctx<'_>,
    span: &Range<usize>,
    owner: &str,
) -> Result<BodyRef, SceneError> {
    match &plane.body {
        Some(name) => names.body(ctx, name, span, owner),
        None => Ok(BodyRef::Ground),
    }
}

/// A body's position in the file (the ground's origin for the ground).
fn body_position(body: BodyRef, positions: &[[f64; 3]]) -> [f64; 3] {
    match body {
        BodyRef::Body(i) => positions[i],
        BodyRef::Ground => [0.0; 3],
    }
}

/// A `sphere-plane` element with `rigid = true` (`docs/limits.md`, "Rigid contact"): the sphere
/// and plane as for the compliant element, `restitution` (0) and `rest_speed` (1e-3); the
/// compliant law's keys are refused.
pub(crate) fn rigid_sphere_plane(
    d: &ForceDef,
    names: &Names<BodyRef>,
    ctx: &Ctx<'_>,
    span: &Range<usize>,
    owner: &str,
    positions: &[[f64; 3]],
) -> Result<dalembert_spatial::limits::SpherePlaneContact, SceneError> {
    let err = |m: &str| ctx.err(Some(span.clone()), format!("{owner}: {m}"));
    if d.kind == "box-plane" || d.kind == "capsule-plane" {
        return Err(err(&format!(
            "a rigid {} contact is not built (its corners or caps strike at once, and simultaneous impacts are not resolved): use the compliant law",
            d.kind
        )));
    }
    if d.kind == "capsule-capsule" {
        return Err(err(
            "a rigid capsule-capsule contact is not built (two capsules lying along each other touch along a line, and simultaneous impacts are not resolved): use the compliant law",
        ));
    }
    if d.kind != "sphere-plane" {
        return Err(err(&format!(
            "'rigid' is for sphere-plane and sphere-sphere contacts, this element is '{}'",
            d.kind
        )));
    }
    d.only(&[
        "body",
        "at",
        "radius",
        "plane",
        "rigid",
        "restitution",
        "rest_speed",
        "friction",
    ])
    .map_err(|m| err(&format!("{m} (a rigid contact has no compliant law)")))?;
    let (body, centre, radius, plane) = sphere_on_plane(d, names, ctx, span, owner, positions)?;
    let BodyRef::Body(body) = body else {
        return Err(err("the sphere must be on a moving body"));
    };
    let plane_body = match &plane.body {
        None => None,
        Some(name) => match names.body(ctx, name, span, owner)? {
            BodyRef::Body(b) => Some(b),
            BodyRef::Ground => None,
        },
    };
    Ok(dalembert_spatial::limits::SpherePlaneContact {
        name: d.name.clone(),
        body,
        centre,
        radius,
        point: plane.point,
        normal: plane.normal,
        plane_body,
        restitution: d.restitution.unwrap_or(0.0),
        rest_speed: d.rest_speed.unwrap_or(dalembert_system::REST_SPEED),
        friction: d.friction,
    })
}

/// The sphere and plane of a `sphere-plane` element, compliant or rigid: the sphere's body, its
/// centre (global; default the body's position), its radius, and the plane.
fn sphere_on_plane<'a>(
    d: &'a ForceDef,
    names: &Names<BodyRef>,
    ctx: &Ctx<'_>,
    span: &Range<usize>,
    owner: &str,
    positions: &[[f64; 3]],
) -> Result<(BodyRef, [f64; 3], f64, &'a PlaneDef), SceneError> {
    let err = |m: &str| ctx.err(Some(span.clone()), format!("{owner}: {m}"));
    let name = d.body.as_deref().ok_or_else(|| err("needs 'body'"))?;
    let body = names.body(ctx, name, span, owner)?;
    let centre = match (d.at, body) {
        (Some(Points3::One(p)), _) => p,
        (None, BodyRef::Body(i)) => positions[i],
        (None, BodyRef::Ground) => [0.0; 3],
        (Some(Points3::Two(_)), _) => return Err(err("'at' is the sphere's centre, one point [x, y, z] (global)")),
    };
    let plane = d.plane.as_ref().ok_or_else(|| err(NEEDS_PLANE))?;
    Ok((body, centre, d.radius.ok_or_else(|| err("needs 'radius' (m)"))?, plane))
}

/// A `sphere-sphere` element with `rigid = true` (`docs/limits.md`, "Rigid contact"): the two
/// spheres as for the compliant element, `restitution` (0), `rest_speed` (1e-3) and `friction`
/// (Coulomb's coefficient; none by default).
pub(crate) fn rigid_sphere_pair(
    d: &ForceDef,
    names: &Names<BodyRef>,
    ctx: &Ctx<'_>,
    span: &Range<usize>,
    owner: &str,
    positions: &[[f64; 3]],
) -> Result<dalembert_spatial::limits::SphereSphereContact, SceneError> {
    let err = |m: &str| ctx.err(Some(span.clone()), format!("{owner}: {m}"));
    d.only(&[
        "bodies",
        "at",
        "radii",
        "rigid",
        "restitution",
        "rest_speed",
        "friction",
    ])
    .map_err(|m| err(&format!("{m} (a rigid contact has no compliant law)")))?;
    let (bodies, centres, radii) = two_spheres(d, names, ctx, span, owner, positions)?;
    let index = |b: BodyRef| match b {
        BodyRef::Body(i) => Some(i),
        BodyRef::Ground => None,
    };
    Ok(dalembert_spatial::limits::SphereSphereContact {
        name: d.name.clone(),
        bodies: bodies.map(index),
        centres,
        radii,
        restitution: d.restitution.unwrap_or(0.0),
        rest_speed: d.rest_speed.unwrap_or(dalembert_system::REST_SPEED),
        friction: d.friction,
    })
}

/// The two spheres of a `sphere-sphere` element, compliant or rigid: their bodies, centres
/// (global; default the bodies' positions) and radii.
type TwoSpheres = ([BodyRef; 2], [[f64; 3]; 2], [f64; 2]);

fn two_spheres(
    d: &ForceDef,
    names: &Names<BodyRef>,
    ctx: &Ctx<'_>,
    span: &Range<usize>,
    owner: &str,
    positions: &[[f64; 3]],
) -> Result<TwoSpheres, SceneError> {
    let err = |m: &str| ctx.err(Some(span.clone()), format!("{owner}: {m}"));
    let [n0, n1] = d.bodies.as_ref().ok_or_else(|| err("needs 'bodies'"))?;
    let bodies = [names.body(ctx, n0, span, owner)?, names.body(ctx, n1, span, owner)?];
    let position = |b: BodyRef| match b {
        BodyRef::Body(i) => positions[i],
        BodyRef::Ground => [0.0; 3],
    };
    let centres = match d.at {
        Some(Points3::Two(c)) => c,
        None => bodies.map(position),
        Some(Points3::One(_)) => {
            return Err(err(
                "'at' is the two spheres' centres, [[x1, y1, z1], [x2, y2, z2]] (global)",
            ))
        }
    };
    Ok((
        bodies,
        centres,
        d.radii.ok_or_else(|| err("needs 'radii = [r1, r2]' (m)"))?,
    ))
}
