//! From the parsed file to an assembled model.

use super::error::SceneError;
use super::format::SIM_KEYS;
use super::format::{BodyDef, DriverDef, ForceDef, FrictionDef, JointDef, Points, SceneFile, SimDef, ValueDef};
use super::functions::time_function;
use super::limit_keys::{limit_keys, LimitKeys};
use super::names::{Ctx, Names};
use super::{method_parameter, parameter_keys, unknown_name, RunSettings, Scene};
use crate::animation::{xy, BodyDrawing, DrawBody, Drawing, Mark, Shape};
use crate::mechanism::Mechanism;
use crate::simulation::{assemble, Coordinates, FormulationKind};
use dalembert_constraints::joints::{local_direction_of, local_point_of};
use dalembert_constraints::{
    Against, BodyCoordinate, Constraint, Coordinate, Distance, DistanceDriver, Friction, FrictionJoint, Gear,
    JointAngle, JointDisplacement, Limit, Model, PointOnLine, Prismatic, Profile, ProfileContact, RackPinion, Revolute,
    Rigid, RigidContact, STICK_SPEED,
};
use dalembert_integrators::{method_names, Method, Stabilization};
use dalembert_kinematics::{
    Body, BodyId, BodyRef, BodyState, CircleCircle, CircleLine, ConvexPolygon, ForceElement, Gravity, Line, PointForce,
    PolygonPair, RotationalSpringDamper, SegmentSegment, ShapeLine, SpringDamper, Torque, Vec2,
};
use dalembert_system::{TimeFunction, REST_SPEED};
use std::cell::RefCell;
use std::collections::HashMap;
use std::ops::Range;
use std::sync::Arc;
use toml::Spanned;

/// Weight of a velocity given in the file in the initial velocity analysis (others weigh 1): held
/// exactly when the constraints allow it ([`Simulation::velocity_weights`]).
pub(crate) const GIVEN_VELOCITY_WEIGHT: f64 = f64::INFINITY;

fn v2(p: [f64; 2]) -> Vec2 {
    Vec2::new(p[0], p[1])
}

/// What a joint name refers to, for drivers and torques.
enum JointInfo {
    Revolute(Revolute),
    Prismatic(Prismatic),
    Other([BodyRef; 2]),
}

impl JointInfo {
    fn bodies(&self) -> [BodyRef; 2] {
        match self {
            JointInfo::Revolute(r) => r.bodies,
            JointInfo::Prismatic(p) => p.bodies,
            JointInfo::Other(b) => *b,
        }
    }
}

struct Builder<'a> {
    ctx: Ctx<'a>,
    names: Names<BodyRef>,
    q: Vec<f64>,
}

impl Builder<'_> {
    fn body(&self, name: &str, span: &Range<usize>, owner: &str) -> Result<BodyRef, SceneError> {
        self.names.body(&self.ctx, name, span, owner)
    }

    fn unique(&mut self, name: &str, span: &Range<usize>, what: &str) -> Result<(), SceneError> {
        self.names.unique(&self.ctx, name, span, what)
    }

    fn local_points(&self, def: &JointDef, pair: [BodyRef; 2], span: &Range<usize>) -> Result<[Vec2; 2], SceneError> {
        match (&def.at, &def.points) {
            (Some(Points::One(p)), None) => Ok([
                local_point_of(pair[0], &self.q, v2(*p)),
                local_point_of(pair[1], &self.q, v2(*p)),
            ]),
            (Some(Points::Two([a, b])), None) => Ok([
                local_point_of(pair[0], &self.q, v2(*a)),
                local_point_of(pair[1], &self.q, v2(*b)),
            ]),
            (None, Some([a, b])) => Ok([v2(*a), v2(*b)]),
            (None, None) => Err(self.ctx.err(
                Some(span.clone()),
                format!("joint '{}': give 'at' (global) or 'points' (local)", def.name),
            )),
            (Some(_), Some(_)) => Err(self.ctx.err(
                Some(span.clone()),
                format!("joint '{}': give 'at' or 'points', not both", def.name),
            )),
        }
    }

    fn angle(&self, b: BodyRef) -> f64 {
        BodyState::of(b, &self.q, &[]).angle
    }
}

fn inertia(def: &BodyDef) -> Result<f64, String> {
    let m = def.mass;
    match (def.inertia, &def.shape) {
        (Some(j), None) => Ok(j),
        (None, Some(s)) => {
            let positive = |v: f64, what: &str| {
                if v.is_finite() && v > 0.0 {
                    Ok(v)
                } else {
                    Err(format!("shape: {what} must be positive and finite, got {v}"))
                }
            };
            match (s.rod, s.disk, s.rectangle) {
                (Some(l), None, None) => positive(l, "rod length").map(|l| m * l * l / 12.0),
                (None, Some(r), None) => positive(r, "disk radius").map(|r| 0.5 * m * r * r),
                (None, None, Some([w, h])) => {
                    let (w, h) = (positive(w, "rectangle width")?, positive(h, "rectangle height")?);
                    Ok(m * (w * w + h * h) / 12.0)
                }
                _ => Err("shape takes exactly one of rod = L, disk = r, rectangle = [w, h]".into()),
            }
        }
        (Some(_), Some(_)) => Err("give 'inertia' or 'shape', not both".into()),
        (None, None) => Err("give 'inertia' (kg·m² about the centre of mass) or 'shape'".into()),
    }
}

/// The outline a body's `shape` key describes.
fn shape(def: &BodyDef) -> Shape {
    match def.shape.as_ref().map(|s| (s.rod, s.disk, s.rectangle)) {
        Some((Some(length), None, None)) => Shape::Rod { length },
        Some((None, Some(radius), None)) => Shape::Disk { radius },
        Some((None, None, Some([width, height]))) => Shape::Rectangle { width, height },
        _ => Shape::Unspecified,
    }
}

/// A body reference as the drawing stores it.
fn draw_body(b: BodyRef) -> DrawBody {
    b.id().map(|id| id.0)
}

pub(crate) fn build(file: SceneFile, text: &str, origin: &str) -> Result<Scene, SceneError> {
    let (inputs, code_forces) = (std::cell::RefCell::new(Vec::new()), std::cell::RefCell::new(Vec::new()));
    let ctx = Ctx {
        file: origin,
        text,
        inputs: &inputs,
        code_forces: &code_forces,
    };
    let mut b = Builder {
        ctx,
        names: Names::new(BodyRef::Ground),
        q: Vec::new(),
    };
    if file.bodies.is_empty() {
        return Err(b.ctx.err(None, "the scene has no [[bodies]]"));
    }
    // Bodies.
    let mut drawing = Drawing::default();
    let mut bodies = Vec::new();
    let mut qd = Vec::new();
    let mut weights = Vec::new();
    for (i, sb) in file.bodies.iter().enumerate() {
        let span = sb.span();
        let d = sb.get_ref();
        b.unique(&d.name, &span, "body")?;
        let j = inertia(d).map_err(|m| b.ctx.err(Some(span.clone()), format!("body '{}': {m}", d.name)))?;
        let body = Body::new(d.name.clone(), d.mass, j).map_err(|e| b.ctx.err(Some(span.clone()), e.to_string()))?;
        let finite = d
            .position
            .iter()
            .chain(d.velocity.iter().flatten())
            .chain([&d.angle, &d.angular_velocity.unwrap_or(0.0)])
            .all(|x| x.is_finite());
        if !finite {
            return Err(b.ctx.err(
                Some(span.clone()),
                format!("body '{}': position, angle and velocities must be finite", d.name),
            ));
        }
        drawing.bodies.push(BodyDrawing {
            name: d.name.clone(),
            shape: shape(d),
            points: Vec::new(),
            slider: false,
            point_mass: j == 0.0 && d.shape.is_none(),
        });
        bodies.push(body);
        b.names.add_body(&d.name, BodyRef::Body(BodyId(i)));
        b.q.extend_from_slice(&[d.position[0], d.position[1], d.angle]);
        let v = d.velocity.unwrap_or([0.0, 0.0]);
        qd.extend_from_slice(&[v[0], v[1], d.angular_velocity.unwrap_or(0.0)]);
        // Velocities given in the file are kept as far as the constraints allow.
        let w = |given: bool| if given { GIVEN_VELOCITY_WEIGHT } else { 1.0 };
        weights.extend_from_slice(&[
            w(d.velocity.is_some()),
            w(d.velocity.is_some()),
            w(d.angular_velocity.is_some()),
        ]);
    }
    // Joints.
    let mut constraints: Vec<Box<dyn Constraint>> = Vec::new();
    let mut joints: HashMap<String, JointInfo> = HashMap::new();
    let mut frictions = Vec::new();
    let mut limits = Vec::new();
    for sj in &file.joints {
        let span = sj.span();
        let d = sj.get_ref();
        b.unique(&d.name, &span, "joint")?;
        let owner = format!("joint '{}'", d.name);
        let pair = [
            b.body(&d.bodies[0], &span, &owner)?,
            b.body(&d.bodies[1], &span, &owner)?,
        ];
        if pair[0] == pair[1] {
            return Err(b.ctx.err(
                Some(span.clone()),
                format!("{owner}: both bodies are '{}'", d.bodies[0]),
            ));
        }
        let name = d.name.clone();
        let axis_global = v2(d.axis.unwrap_or([1.0, 0.0]));
        let db = [draw_body(pair[0]), draw_body(pair[1])];
        let (c, info, mark): (Box<dyn Constraint>, JointInfo, Option<Mark>) = match d.kind.as_str() {
            "revolute" => {
                let r = Revolute::new(name.clone(), pair, b.local_points(d, pair, &span)?);
                let mark = Mark::Pin { name, bodies: db, points: r.points.map(xy) };
                (Box::new(r.clone()), JointInfo::Revolute(r), Some(mark))
            }
            "prismatic" => {
                let p = Prismatic {
                    name: name.clone(),
                    bodies: pair,
                    points: b.local_points(d, pair, &span)?,
                    axis: local_direction_of(pair[0], &b.q, axis_global),
                    angle: b.angle(pair[1]) - b.angle(pair[0]),
                };
                if let Some(k) = db[1] {
                    drawing.bodies[k].slider = true;
                }
                let mark = Mark::Guide {
                    name,
                    body: db[0],
                    point: xy(p.points[0]),
                    direction: xy(p.axis),
                    follower: db[1],
                    follower_point: xy(p.points[1]),
                };
                (Box::new(p.clone()), JointInfo::Prismatic(p), Some(mark))
            }
            "rigid" => {
                let points = if d.at.is_none() && d.points.is_none() {
                    let p = BodyState::of(pair[1], &b.q, &[]).position;
                    [local_point_of(pair[0], &b.q, p), Vec2::zeros()]
                } else {
                    b.local_points(d, pair, &span)?
                };
                let angle = b.angle(pair[1]) - b.angle(pair[0]);
                (Box::new(Rigid { name, bodies: pair, points, angle }), JointInfo::Other(pair), None)
            }
            "distance" => {
                let points = b.local_points(d, pair, &span)?;
                let si = BodyState::of(pair[0], &b.q, &[]);
                let sj = BodyState::of(pair[1], &b.q, &[]);
                let now = (dalembert_kinematics::point::global_point(sj.position, sj.angle, points[1])
                    - dalembert_kinematics::point::global_point(si.position, si.angle, points[0]))
                .norm();
                let length = d.length.unwrap_or(now);
                let mark = Mark::Link { name: name.clone(), bodies: db, points: points.map(xy) };
                (Box::new(Distance { name, bodies: pair, points, length }), JointInfo::Other(pair), Some(mark))
            }
            "point-on-line" => {
                let points = b.local_points(d, pair, &span)?;
                let direction = local_direction_of(pair[0], &b.q, axis_global);
                let mark = Mark::Guide {
                    name: name.clone(),
                    body: db[0],
                    point: xy(points[0]),
                    direction: xy(direction),
                    follower: db[1],
                    follower_point: xy(points[1]),
                };
                (Box::new(PointOnLine { name, bodies: pair, points, direction }), JointInfo::Other(pair), Some(mark))
            }
            "gear" => {
                let ratio = d.ratio.ok_or_else(|| b.ctx.err(Some(span.clone()), format!("{owner}: a gear needs 'ratio'")))?;
                (Box::new(Gear::new(name, pair, ratio, &b.q)), JointInfo::Other(pair), None)
            }
            "rack-pinion" => {
                let radius =
                    d.radius.ok_or_else(|| b.ctx.err(Some(span.clone()), format!("{owner}: a rack and pinion needs 'radius'")))?;
                (Box::new(RackPinion::new(name, pair, axis_global, radius, &b.q)), JointInfo::Other(pair), None)
            }
            other => {
                return Err(b.ctx.err(
                    Some(span.clone()),
                    format!("{owner}: unknown type '{other}' (expected revolute, prismatic, rigid, distance, point-on-line, gear, rack-pinion)"),
                ))
            }
        };
        c.validate().map_err(|e| b.ctx.err(Some(span.clone()), e.to_string()))?;
        if let Some(mark) = mark {
            drawing.add(mark);
        }
        if let Some(def) = &d.friction {
            frictions.push(friction(&b, d, def, &info, constraints.len())?);
        }
        if let Some(l) = limit(&b, d, &info, constraints.len())? {
            limits.push(l);
        }
        constraints.push(c);
        joints.insert(d.name.clone(), info);
    }
    // Drivers.
    for sd in &file.drivers {
        let span = sd.span();
        let d = sd.get_ref();
        b.unique(&d.name, &span, "driver")?;
        constraints.push(driver(&b, d, &span, &joints)?);
    }
    // Forces.
    let mut forces: Vec<Box<dyn ForceElement>> = Vec::new();
    if let Some(g) = file.scene.as_ref().and_then(|s| s.gravity) {
        if !g.iter().all(|x| x.is_finite()) {
            return Err(b.ctx.err(None, format!("[scene] gravity must be finite, got {g:?}")));
        }
        forces.push(Box::new(Gravity::new(v2(g))));
    }
    let mut rigid_contacts = Vec::new();
    for sf in &file.forces {
        let span = sf.span();
        let d = sf.get_ref();
        b.unique(&d.name, &span, "force")?;
        if d.rigid == Some(true) {
            let contacts = match d.kind.as_str() {
                "polygon-line" | "segment-line" => rigid_corners(&b, d, &span)?,
                _ => vec![rigid_contact(&b, d, &span)?],
            };
            for contact in contacts {
                drawing.add(contact_mark(&contact, d.kind.as_str()));
                rigid_contacts.push(contact);
            }
            continue;
        }
        let (element, mark) = force(&b, d, &span, &joints)?;
        if let Some(mark) = mark {
            drawing.add(mark);
        }
        forces.push(element);
    }
    let model = Model::new(bodies, forces, constraints)
        .and_then(|m| m.with_frictions(frictions))
        .and_then(|m| m.with_limits(limits))
        .and_then(|m| m.with_rigid_contacts(rigid_contacts, &b.q))
        .map_err(|e| b.ctx.err(None, e.to_string()))?;
    // The compliant contacts, whose forces the viewer draws: the elements with a gap.
    drawing.contacts = (model.forces().iter())
        .filter(|f| f.contact_gap(model.bodies(), &b.q).is_some())
        .map(|f| f.name().to_string())
        .collect();
    let mechanism: Mechanism = Arc::new(model).into();
    let settings = settings(
        b.ctx.file,
        b.ctx.text,
        file.simulation.as_ref(),
        &mechanism.velocity_names(),
    )?;
    check_coordinates(&b.ctx, file.simulation.as_ref(), &mechanism, &settings)?;
    let (mut q, mut qd, mut weights) = (b.q.clone(), qd, weights);
    if let Some(initial) = &file.initial {
        let span = Some(initial.span());
        let def = initial.get_ref();
        if !def.joints.is_empty() || !def.rates.is_empty() {
            return Err(b.ctx.err(
                span,
                "[initial]: joints and rates are for spatial scenes; a planar scene gives positions and velocities (by output column)",
            ));
        }
        super::initial::apply(&mechanism, def, &mut q, &mut qd, &mut weights).map_err(|m| b.ctx.err(span, m))?;
    }
    let name = file.scene.and_then(|s| s.name).unwrap_or_else(|| origin.to_string());
    let state = (q, qd, weights);
    assembled(&b.ctx, name, mechanism, state, settings, drawing)
}

/// The friction of joint `d` (`constraint`: its index in the model's constraint list), checked
/// against the joint's type (`docs/friction.md`); errors are placed at the `friction` table.
fn friction(
    b: &Builder<'_>,
    d: &JointDef,
    def: &Spanned<FrictionDef>,
    info: &JointInfo,
    constraint: usize,
) -> Result<Friction, SceneError> {
    let span = Some(def.span());
    let f = def.get_ref();
    let owner = format!("joint '{}'", d.name);
    let joint = match info {
        JointInfo::Revolute(r) => FrictionJoint::Revolute(r.clone()),
        JointInfo::Prismatic(p) => FrictionJoint::Prismatic(p.clone()),
        JointInfo::Other(_) => {
            return Err(b.ctx.err(
                span,
                format!(
                    "{owner}: friction is for revolute and prismatic joints, this one is '{}'",
                    d.kind
                ),
            ))
        }
    };
    let revolute = matches!(joint, FrictionJoint::Revolute(_));
    let (coefficient, radius, constant) = f.law(revolute, &owner).map_err(|m| b.ctx.err(span.clone(), m))?;
    let friction = Friction {
        joint,
        constraint,
        coefficient,
        radius,
        constant,
        viscous: f.viscous.unwrap_or(0.0),
        stick_speed: f.stick_speed.unwrap_or(STICK_SPEED),
    };
    friction.validate().map_err(|e| b.ctx.err(span, e.to_string()))?;
    Ok(friction)
}

/// The limit of joint `d` (`constraint`: its index in the model's constraint list), if it has
/// one ([`limit_keys`]), checked against the joint's type and its start (`docs/limits.md`);
/// errors are placed at the `limits` key.
fn limit(b: &Builder<'_>, d: &JointDef, info: &JointInfo, constraint: usize) -> Result<Option<Limit>, SceneError> {
    let keys = LimitKeys {
        limits: d.limits.as_ref(),
        restitution: d.restitution.as_ref(),
        rest_speed: d.rest_speed.as_ref(),
    };
    let Some((spec, span)) = limit_keys(&b.ctx, &d.name, keys)? else {
        return Ok(None);
    };
    let joint = match info {
        JointInfo::Revolute(r) => FrictionJoint::Revolute(r.clone()),
        JointInfo::Prismatic(p) => FrictionJoint::Prismatic(p.clone()),
        JointInfo::Other(_) => {
            return Err(b.ctx.err(
                Some(span),
                format!(
                    "joint '{}': limits are for revolute and prismatic joints, this one is '{}'",
                    d.name, d.kind
                ),
            ))
        }
    };
    let bounds = [spec.lower, spec.upper];
    let limit = Limit::new(joint, constraint, &b.q, bounds, spec.restitution, spec.rest_speed);
    limit.validate().map_err(|e| b.ctx.err(Some(span), e.to_string()))?;
    Ok(Some(limit))
}

/// A `circle-line` element with `rigid = true` (`docs/limits.md`, "Rigid contact"): the circle
/// and line as for the compliant element, `restitution` (0) and `rest_speed` (1e-3); the
/// compliant law's keys are refused.
fn rigid_contact(b: &Builder<'_>, d: &ForceDef, span: &Range<usize>) -> Result<RigidContact, SceneError> {
    let owner = format!("force '{}'", d.name);
    let err = |m: String| b.ctx.err(Some(span.clone()), format!("{owner}: {m}"));
    let keys: &[&str] = match d.kind.as_str() {
        "circle-line" => &["body", "at", "radius", "line", "rigid", "restitution", "rest_speed", "friction"],
        "circle-circle" => &["bodies", "at", "radii", "rigid", "restitution", "rest_speed", "friction"],
        "circle-profile" => &["body", "at", "radius", "profile", "rigid", "restitution", "rest_speed", "friction"],
        "line-profile" => &["body", "line", "profile", "rigid", "restitution", "rest_speed", "friction"],
        "segment-segment" => {
            return Err(err(
                "a rigid segment-segment contact is not built (two segments lying along each other touch along a line, and simultaneous impacts are not resolved): use the compliant law".into(),
            ))
        }
        "polygon-polygon" => {
            return Err(err(
                "a rigid polygon-polygon contact is not built (a vertex's nearest edge changes as it slides): use the compliant law"
                    .into(),
            ))
        }
        other => {
            return Err(err(format!(
                "'rigid' is for circle-line, circle-circle, circle-profile and line-profile contacts, this element is '{other}'"
            )))
        }
    };
    if let Some(key) = d.keys_given().find(|k| !keys.contains(k)) {
        return Err(err(format!(
            "'{key}' does not belong to a rigid contact (it has no compliant law)"
        )));
    }
    let (body, centre, radius, against) = if d.kind == "circle-profile" {
        circle_on_profile(b, d, span, &owner)?
    } else if d.kind == "line-profile" {
        face_on_profile(b, d, span, &owner)?
    } else if d.kind == "circle-line" {
        let c = circle_on_line(b, d, span, &owner)?;
        let line = Against::Line {
            body: c.line_body,
            point: c.point,
            normal: c.normal,
        };
        (c.body, c.centre, c.radius, line)
    } else {
        let (bodies, centres, radii) = two_circles(b, d, span, &owner)?;
        let first = Against::Circle {
            body: bodies[0],
            centre: centres[0],
            radius: radii[0],
        };
        (bodies[1], centres[1], radii[1], first)
    };
    let contact = RigidContact {
        name: d.name.clone(),
        body,
        centre,
        radius,
        against,
        restitution: d.restitution.unwrap_or(0.0),
        rest_speed: d.rest_speed.unwrap_or(REST_SPEED),
        friction: d.friction,
    };
    contact
        .validate(&b.q)
        .map_err(|e| b.ctx.err(Some(span.clone()), e.to_string()))?;
    Ok(contact)
}

/// A `polygon-line` or `segment-line` element with `rigid = true` (`docs/limits.md`, "Rigid
/// polygons and segments"): a rigid contact of each vertex (a circle of radius 0) or each end (a
/// circle of the segment's radius) with the line, named `<name>.<k>` (from 0, in the order given),
/// each with the element's `restitution`, `rest_speed` and `friction`; none may start into the
/// line.
fn rigid_corners(b: &Builder<'_>, d: &ForceDef, span: &Range<usize>) -> Result<Vec<RigidContact>, SceneError> {
    let owner = format!("force '{}'", d.name);
    let err = |m: String| b.ctx.err(Some(span.clone()), format!("{owner}: {m}"));
    let keys: &[&str] = if d.kind == "polygon-line" {
        &[
            "body",
            "vertices",
            "line",
            "rigid",
            "restitution",
            "rest_speed",
            "friction",
        ]
    } else {
        &[
            "body",
            "at",
            "radius",
            "line",
            "rigid",
            "restitution",
            "rest_speed",
            "friction",
        ]
    };
    if let Some(key) = d.keys_given().find(|k| !keys.contains(k)) {
        return Err(err(format!(
            "'{key}' does not belong to a rigid contact (it has no compliant law)"
        )));
    }
    let (body, corners, radius) = corners_of(b, d, span, &owner)?;
    let line = line_of(b, d, span, &owner)?;
    let what = if d.kind == "polygon-line" { "vertex" } else { "end" };
    let mut contacts = Vec::with_capacity(corners.len());
    for (k, centre) in corners.into_iter().enumerate() {
        let contact = RigidContact {
            name: format!("{}.{k}", d.name),
            body,
            centre,
            radius,
            against: Against::Line {
                body: line.body,
                point: line.point,
                normal: line.normal,
            },
            restitution: d.restitution.unwrap_or(0.0),
            rest_speed: d.rest_speed.unwrap_or(REST_SPEED),
            friction: d.friction,
        };
        let gap = contact.gap(&b.q);
        if gap < -1e-12 {
            return Err(err(format!("its {what} {k} starts {:.3e} m into the line", -gap)));
        }
        contact
            .validate(&b.q)
            .map_err(|e| b.ctx.err(Some(span.clone()), e.to_string()))?;
        contacts.push(contact);
    }
    Ok(contacts)
}

/// The body of a `polygon-line` or `segment-line` element and its corners (local): the polygon's
/// vertices (radius 0) or the segment's two ends (its radius).
fn corners_of(
    b: &Builder<'_>,
    d: &ForceDef,
    span: &Range<usize>,
    owner: &str,
) -> Result<(BodyRef, Vec<Vec2>, f64), SceneError> {
    let err = |m: &str| b.ctx.err(Some(span.clone()), format!("{owner}: {m}"));
    let name = d.body.as_deref().ok_or_else(|| err("needs 'body'"))?;
    let body = b.body(name, span, owner)?;
    if d.kind == "polygon-line" {
        let vertices = d
            .vertices
            .as_ref()
            .ok_or_else(|| err("needs 'vertices = [[x, y], …]' (the polygon's, global)"))?;
        if vertices.is_empty() {
            return Err(err("'vertices' is empty"));
        }
        Ok((
            body,
            vertices.iter().map(|&p| local_point_of(body, &b.q, v2(p))).collect(),
            0.0,
        ))
    } else {
        let Some(Points::Two(ends)) = d.at else {
            return Err(err("needs 'at = [[x1, y1], [x2, y2]]' (the segment's ends, global)"));
        };
        let radius = d.radius.ok_or_else(|| err("needs 'radius' (m)"))?;
        Ok((
            body,
            ends.iter().map(|&p| local_point_of(body, &b.q, v2(p))).collect(),
            radius,
        ))
    }
}

/// The `line` of a `circle-line`, `polygon-line` or `segment-line` element: of the ground, or of
/// the body it names; its point and unit normal local to that body.
fn line_of(b: &Builder<'_>, d: &ForceDef, span: &Range<usize>, owner: &str) -> Result<Line, SceneError> {
    let err = |m: &str| b.ctx.err(Some(span.clone()), format!("{owner}: {m}"));
    let line = d.line.as_ref().ok_or_else(|| {
        err("needs 'line = { point = [x, y], normal = [nx, ny] }' (global; of the ground unless it names a 'body', the normal out of it)")
    })?;
    let normal = v2(line.normal);
    if normal.norm().is_nan() || normal.norm() == 0.0 {
        return Err(err("the line's normal must not be zero"));
    }
    let body = match &line.body {
        Some(name) => b.body(name, span, owner)?,
        None => BodyRef::Ground,
    };
    Ok(Line {
        body,
        point: local_point_of(body, &b.q, v2(line.point)),
        normal: local_direction_of(body, &b.q, normal / normal.norm()),
    })
}

/// The circle and profile of a `circle-profile` element (a roller on a cam): the circle's body,
/// centre (local; default the body's reference point) and radius, and the profile on its body
/// (its points local to it, a periodic spline through them).
fn circle_on_profile(
    b: &Builder<'_>,
    d: &ForceDef,
    span: &Range<usize>,
    owner: &str,
) -> Result<(BodyRef, Vec2, f64, Against), SceneError> {
    let err = |m: String| b.ctx.err(Some(span.clone()), format!("{owner}: {m}"));
    let name = d
        .body
        .as_deref()
        .ok_or_else(|| err("needs 'body' (the circle's)".into()))?;
    let body = b.body(name, span, owner)?;
    let centre = match d.at {
        Some(Points::One(p)) => local_point_of(body, &b.q, v2(p)),
        None => Vec2::zeros(),
        Some(Points::Two(_)) => return Err(err("'at' is the circle's centre, one point [x, y] (global)".into())),
    };
    let radius = d.radius.ok_or_else(|| err("needs 'radius' (m)".into()))?;
    let (profile_body, profile) = profile_of(b, d, span, owner)?;
    Ok((
        body,
        centre,
        radius,
        Against::Profile {
            body: profile_body,
            profile,
        },
    ))
}

/// The profile of a `circle-profile` or `line-profile` element: its body and the spline through
/// its points (local to the body).
fn profile_of(
    b: &Builder<'_>,
    d: &ForceDef,
    span: &Range<usize>,
    owner: &str,
) -> Result<(BodyRef, Profile), SceneError> {
    let err = |m: String| b.ctx.err(Some(span.clone()), format!("{owner}: {m}"));
    let p = d.profile.as_ref().ok_or_else(|| {
        err(
            "needs 'profile = { body = \"cam\", points = [[x, y], …] }' (global, the last point repeating the first)"
                .into(),
        )
    })?;
    let body = b.body(&p.body, span, owner)?;
    let local: Vec<Vec2> = p.points.iter().map(|&q| local_point_of(body, &b.q, v2(q))).collect();
    Ok((body, Profile::closed_spline(&local).map_err(err)?))
}

/// The face and profile of a `line-profile` element (a flat-faced follower on a cam): the face's
/// body, its point (local), 0 for the unused radius, and the profile with the face's unit normal
/// (local, towards the profile).
fn face_on_profile(
    b: &Builder<'_>,
    d: &ForceDef,
    span: &Range<usize>,
    owner: &str,
) -> Result<(BodyRef, Vec2, f64, Against), SceneError> {
    let err = |m: &str| b.ctx.err(Some(span.clone()), format!("{owner}: {m}"));
    let name = d.body.as_deref().ok_or_else(|| err("needs 'body' (the face's)"))?;
    let body = b.body(name, span, owner)?;
    let line = d.line.as_ref().ok_or_else(|| {
        err("needs 'line = { point = [x, y], normal = [nx, ny] }' (the face on 'body', global, the normal towards the profile)")
    })?;
    if line.body.is_some() {
        return Err(err("the face is on 'body': its 'line' takes no body of its own"));
    }
    let normal = v2(line.normal);
    if normal.norm().is_nan() || normal.norm() == 0.0 {
        return Err(err("the line's normal must not be zero"));
    }
    let (profile_body, profile) = profile_of(b, d, span, owner)?;
    Ok((
        body,
        local_point_of(body, &b.q, v2(line.point)),
        0.0,
        Against::ProfileFace {
            body: profile_body,
            profile,
            normal: local_direction_of(body, &b.q, normal / normal.norm()),
        },
    ))
}

/// How the viewer draws a rigid contact ([`Mark::Contact`]): its shapes and the arrow of its
/// normal force (`<name>.normal`).
fn contact_mark(c: &RigidContact, form: &str) -> Mark {
    let form = match form {
        "circle-circle" => "circle-circle",
        "circle-profile" => "circle-profile",
        "line-profile" => "line-profile",
        _ => "circle-line",
    };
    let (other, point, radius, normal, profile) = match &c.against {
        Against::Line { body, point, normal } => (*body, xy(*point), 0.0, xy(*normal), Vec::new()),
        Against::Circle { body, centre, radius } => (*body, xy(*centre), *radius, [0.0; 2], Vec::new()),
        Against::Profile { body, profile } => (
            *body,
            [0.0; 2],
            0.0,
            [0.0; 2],
            profile.points().iter().map(|p| xy(*p)).collect(),
        ),
        Against::ProfileFace { body, profile, normal } => (
            *body,
            [0.0; 2],
            0.0,
            xy(*normal),
            profile.points().iter().map(|p| xy(*p)).collect(),
        ),
    };
    Mark::Contact {
        name: c.name.clone(),
        form,
        bodies: [draw_body(c.body), draw_body(other)],
        points: [xy(c.centre), point],
        radii: [c.radius, radius],
        normal,
        profile,
        force: true,
    }
}

/// The two circles of a `circle-circle` element, compliant or rigid: their bodies, their
/// centres (local; default the bodies' reference points) and radii.
type TwoCircles = ([BodyRef; 2], [Vec2; 2], [f64; 2]);

fn two_circles(b: &Builder<'_>, d: &ForceDef, span: &Range<usize>, owner: &str) -> Result<TwoCircles, SceneError> {
    let err = |m: &str| b.ctx.err(Some(span.clone()), format!("{owner}: {m}"));
    let [n0, n1] = d.bodies.as_ref().ok_or_else(|| err("needs 'bodies'"))?;
    let pr = [b.body(n0, span, owner)?, b.body(n1, span, owner)?];
    let centres = match d.at {
        Some(Points::Two([c0, c1])) => [local_point_of(pr[0], &b.q, v2(c0)), local_point_of(pr[1], &b.q, v2(c1))],
        None => [Vec2::zeros(), Vec2::zeros()],
        Some(Points::One(_)) => return Err(err("'at' is the two circles' centres, [[x1, y1], [x2, y2]] (global)")),
    };
    let radii = d.radii.ok_or_else(|| err("needs 'radii = [r1, r2]' (m)"))?;
    Ok((pr, centres, radii))
}

/// The circle and line of a `circle-line` element, compliant or rigid: the circle's body, its
/// centre (local), its radius, the line's body (the ground unless `line.body` names one), its
/// point and unit normal (towards the circle), local to the line's body.
struct CircleOnLine {
    body: BodyRef,
    centre: Vec2,
    radius: f64,
    line_body: BodyRef,
    point: Vec2,
    normal: Vec2,
}

fn circle_on_line(b: &Builder<'_>, d: &ForceDef, span: &Range<usize>, owner: &str) -> Result<CircleOnLine, SceneError> {
    let err = |m: &str| b.ctx.err(Some(span.clone()), format!("{owner}: {m}"));
    let name = d.body.as_deref().ok_or_else(|| err("needs 'body'"))?;
    let body = b.body(name, span, owner)?;
    let centre = match d.at {
        Some(Points::One(p)) => local_point_of(body, &b.q, v2(p)),
        None => Vec2::zeros(),
        Some(Points::Two(_)) => return Err(err("'at' is the circle's centre, one point [x, y] (global)")),
    };
    let line = line_of(b, d, span, owner)?;
    Ok(CircleOnLine {
        body,
        centre,
        radius: d.radius.ok_or_else(|| err("needs 'radius' (m)"))?,
        line_body: line.body,
        point: line.point,
        normal: line.normal,
    })
}

/// `Ok` unless `settings` ask for joint coordinates that `mechanism` cannot take (a planar model,
/// or a spatial one that is not a tree of revolute and prismatic joints with gravity alone): the
/// error is placed at the `coordinates` key and names the element at fault.
pub(crate) fn check_coordinates(
    ctx: &Ctx<'_>,
    sim: Option<&Spanned<SimDef>>,
    mechanism: &Mechanism,
    settings: &RunSettings,
) -> Result<(), SceneError> {
    if settings.coordinates != Coordinates::Joint {
        return Ok(());
    }
    match super::joint_coordinates_problem(mechanism) {
        None => Ok(()),
        Some(what) => {
            let span = sim.map(|s| key_span(ctx.text, &s.span(), "coordinates").unwrap_or(s.span()));
            Err(ctx.err(span, format!("[simulation]: coordinates = \"joint\": {what}")))
        }
    }
}

/// The scene of `model` with its initial state `(q, q̇, velocity weights)` assembled (position
/// analysis, then the least weighted change of the velocities: velocities the file gave are held).
pub(crate) fn assembled(
    ctx: &Ctx<'_>,
    name: String,
    model: Mechanism,
    (q, qd, weights): (Vec<f64>, Vec<f64>, Vec<f64>),
    settings: RunSettings,
    drawing: Drawing,
) -> Result<Scene, SceneError> {
    let (mut q, mut qd) = (q, qd);
    assemble(model.as_system(), 0.0, &mut q, &mut qd, Some(&weights))
        .map_err(|e| ctx.err(None, format!("cannot assemble the mechanism: {e}")))?;
    if let Some(independent) = &settings.independent {
        // As many independent coordinates as degrees of freedom at the assembled position.
        let dof = crate::analysis::structure_at(&model, &q)
            .map_err(|e| ctx.err(None, e.to_string()))?
            .degrees_of_freedom;
        if independent.len() != dof {
            // The key's line in the `[simulation]` table (the TOML spans are no longer at hand).
            let table = (ctx.text.match_indices("[simulation]").map(|(i, _)| i))
                .find(|&i| i == 0 || ctx.text.as_bytes()[i - 1] == b'\n');
            return Err(ctx.err(
                table.and_then(|t| key_span(ctx.text, &(t..t), "independent")),
                format!(
                    "[simulation] independent names {} coordinate(s); the mechanism has {dof} degree(s) of freedom",
                    independent.len()
                ),
            ));
        }
    }
    Ok(Scene {
        name,
        model,
        q,
        qd,
        settings,
        inputs: ctx.input_names(),
        code_forces: ctx.code_force_names(),
        drawing,
        source: ctx.text.to_string(),
        origin: ctx.file.to_string(),
        notes: Vec::new(),
    })
}

fn driver(
    b: &Builder<'_>,
    d: &DriverDef,
    span: &Range<usize>,
    joints: &HashMap<String, JointInfo>,
) -> Result<Box<dyn Constraint>, SceneError> {
    let owner = format!("driver '{}'", d.name);
    let err = |m: String| b.ctx.err(Some(span.clone()), format!("{owner}: {m}"));
    let func = |v0: f64| time_function(&d.function, Some(v0), b.ctx.inputs).map_err(err);
    let joint = |kind: &str| -> Result<&JointInfo, SceneError> {
        let name = d
            .joint
            .as_deref()
            .ok_or_else(|| err(format!("a {kind} driver needs 'joint'")))?;
        joints.get(name).ok_or_else(|| err(format!("unknown joint '{name}'")))
    };
    Ok(match d.kind.as_str() {
        "body-coordinate" => {
            let name = d.body.as_deref().ok_or_else(|| err("needs 'body'".into()))?;
            let body = b.body(name, span, &owner)?;
            let BodyRef::Body(id) = body else {
                return Err(err("cannot drive the ground".into()));
            };
            let coordinate = match d.coordinate.as_deref() {
                Some("x") => Coordinate::X,
                Some("y") => Coordinate::Y,
                Some("angle") => Coordinate::Angle,
                Some(other) => {
                    return Err(err(format!(
                        "'coordinate' must be \"x\", \"y\" or \"angle\", got \"{other}\""
                    )))
                }
                None => return Err(err("needs 'coordinate' (\"x\", \"y\" or \"angle\")".into())),
            };
            let v0 = b.q[id.offset() + coordinate.index()];
            Box::new(BodyCoordinate {
                name: d.name.clone(),
                body: id,
                coordinate,
                function: func(v0)?,
            })
        }
        "joint-angle" => match joint("joint-angle")? {
            JointInfo::Revolute(r) => {
                let v0 = b.angle(r.bodies[1]) - b.angle(r.bodies[0]);
                Box::new(JointAngle::on(d.name.clone(), r, func(v0)?))
            }
            _ => return Err(err("'joint-angle' drives a revolute joint".into())),
        },
        "joint-displacement" => match joint("joint-displacement")? {
            JointInfo::Prismatic(p) => {
                let si = BodyState::of(p.bodies[0], &b.q, &[]);
                let sj = BodyState::of(p.bodies[1], &b.q, &[]);
                let row = dalembert_constraints::primitives::line_coordinate(
                    &si,
                    p.points[0],
                    p.unit_axis(),
                    &sj,
                    p.points[1],
                );
                Box::new(JointDisplacement::on(d.name.clone(), p, func(row.c)?))
            }
            _ => return Err(err("'joint-displacement' drives a prismatic joint".into())),
        },
        "distance" => {
            let [n0, n1] = d.bodies.as_ref().ok_or_else(|| err("needs 'bodies'".into()))?;
            let pair = [b.body(n0, span, &owner)?, b.body(n1, span, &owner)?];
            let Some(Points::Two([p0, p1])) = d.at else {
                return Err(err("needs 'at = [[x1, y1], [x2, y2]]' (global points)".into()));
            };
            let points = [
                local_point_of(pair[0], &b.q, v2(p0)),
                local_point_of(pair[1], &b.q, v2(p1)),
            ];
            let v0 = (v2(p1) - v2(p0)).norm();
            Box::new(DistanceDriver {
                name: d.name.clone(),
                bodies: pair,
                points,
                function: func(v0)?,
            })
        }
        other => {
            return Err(err(format!(
                "unknown type '{other}' (expected body-coordinate, joint-angle, joint-displacement, distance)"
            )))
        }
    })
}

fn value_function(v: &ValueDef, inputs: &RefCell<Vec<String>>) -> Result<TimeFunction, String> {
    match v {
        ValueDef::Number(x) => Ok(TimeFunction::Constant(*x)),
        ValueDef::Function(f) => time_function(f, None, inputs),
        ValueDef::Vector(_) => Err("expected a number or a function, got a vector".into()),
    }
}

fn force(
    b: &Builder<'_>,
    d: &ForceDef,
    span: &Range<usize>,
    joints: &HashMap<String, JointInfo>,
) -> Result<(Box<dyn ForceElement>, Option<Mark>), SceneError> {
    let owner = format!("force '{}'", d.name);
    let mut mark = None;
    let err = |m: String| b.ctx.err(Some(span.clone()), format!("{owner}: {m}"));
    let pair = || -> Result<[BodyRef; 2], SceneError> {
        let [n0, n1] = d.bodies.as_ref().ok_or_else(|| err("needs 'bodies'".into()))?;
        Ok([b.body(n0, span, &owner)?, b.body(n1, span, &owner)?])
    };
    const CONTACTS: [&str; 8] = [
        "circle-line",
        "circle-circle",
        "segment-segment",
        "circle-profile",
        "line-profile",
        "polygon-line",
        "segment-line",
        "polygon-polygon",
    ];
    if !CONTACTS.contains(&d.kind.as_str()) {
        const CONTACT: [&str; 11] = [
            "radius",
            "radii",
            "segments",
            "line",
            "profile",
            "vertices",
            "polygons",
            "exponent",
            "dissipation",
            "friction",
            "smoothing_velocity",
        ];
        if let Some(key) = d.keys_given().find(|k| CONTACT.contains(k)) {
            return Err(err(format!("'{key}' does not belong to a {} element", d.kind)));
        }
    }
    let element: Box<dyn ForceElement> = match d.kind.as_str() {
        "force" => {
            let name = d.body.as_deref().ok_or_else(|| err("needs 'body'".into()))?;
            let body = b.body(name, span, &owner)?;
            let point = match (d.at, d.point) {
                (Some(Points::One(p)), None) => local_point_of(body, &b.q, v2(p)),
                (None, Some(u)) => v2(u),
                (None, None) => Vec2::zeros(),
                _ => return Err(err("give 'at' (one global point) or 'point' (local)".into())),
            };
            let (fx, fy) = match (&d.value, &d.fx, &d.fy) {
                (Some(ValueDef::Vector([x, y])), None, None) => {
                    (TimeFunction::Constant(*x), TimeFunction::Constant(*y))
                }
                (None, fx, fy) if fx.is_some() || fy.is_some() => (
                    fx.as_ref()
                        .map_or(Ok(TimeFunction::Constant(0.0)), |f| {
                            time_function(f, None, b.ctx.inputs)
                        })
                        .map_err(err)?,
                    fy.as_ref()
                        .map_or(Ok(TimeFunction::Constant(0.0)), |f| {
                            time_function(f, None, b.ctx.inputs)
                        })
                        .map_err(err)?,
                ),
                _ => return Err(err("give 'value = [fx, fy]' or functions 'fx' / 'fy'".into())),
            };
            Box::new(PointForce {
                name: d.name.clone(),
                body,
                point,
                fx,
                fy,
            })
        }
        "torque" => {
            let value = value_function(
                d.value.as_ref().ok_or_else(|| err("needs 'value'".into()))?,
                b.ctx.inputs,
            )
            .map_err(err)?;
            let (body, reaction_body) = match (&d.body, &d.joint) {
                (Some(n), None) => (b.body(n, span, &owner)?, BodyRef::Ground),
                (None, Some(j)) => {
                    let info = joints.get(j).ok_or_else(|| err(format!("unknown joint '{j}'")))?;
                    let [first, second] = info.bodies();
                    (second, first)
                }
                _ => return Err(err("give 'body' or 'joint' (torque between the joint's bodies)".into())),
            };
            Box::new(Torque {
                name: d.name.clone(),
                body,
                reaction_body,
                value,
            })
        }
        "spring-damper" => {
            let pr = pair()?;
            let Some(Points::Two([p0, p1])) = d.at else {
                return Err(err(
                    "needs 'at = [[x1, y1], [x2, y2]]' (global attachment points)".into()
                ));
            };
            let actuator = d
                .actuator
                .as_ref()
                .map(|f| time_function(f, None, b.ctx.inputs))
                .transpose()
                .map_err(err)?;
            let points = (local_point_of(pr[0], &b.q, v2(p0)), local_point_of(pr[1], &b.q, v2(p1)));
            mark = Some(Mark::Spring {
                name: d.name.clone(),
                bodies: pr.map(draw_body),
                points: [xy(points.0), xy(points.1)],
            });
            Box::new(SpringDamper {
                name: d.name.clone(),
                bodies: (pr[0], pr[1]),
                points,
                stiffness: d.stiffness.ok_or_else(|| err("needs 'stiffness'".into()))?,
                damping: d.damping.unwrap_or(0.0),
                free_length: d.free_length.unwrap_or((v2(p1) - v2(p0)).norm()),
                actuator,
            })
        }
        "rotational-spring-damper" => {
            let pr = pair()?;
            Box::new(RotationalSpringDamper {
                name: d.name.clone(),
                bodies: (pr[0], pr[1]),
                stiffness: d.stiffness.ok_or_else(|| err("needs 'stiffness'".into()))?,
                damping: d.damping.unwrap_or(0.0),
                free_angle: d.free_angle.unwrap_or(b.angle(pr[1]) - b.angle(pr[0])),
            })
        }
        "circle-line" => {
            const KEYS: [&str; 10] = ["body", "at", "radius", "line", "stiffness", "exponent", "dissipation", "friction", "smoothing_velocity", "radii"];
            if let Some(key) = d.keys_given().find(|k| !KEYS.contains(k)) {
                return Err(err(format!("'{key}' does not belong to a circle-line element")));
            }
            if d.radii.is_some() {
                return Err(err("'radii' belongs to a circle-circle element: give 'radius'".into()));
            }
            let c = circle_on_line(b, d, span, &owner)?;
            let line = Line {
                body: c.line_body,
                point: c.point,
                normal: c.normal,
            };
            if line.body != BodyRef::Ground {
                // The viewer draws the line with its body (the ground's is drawn as the floor).
                let drawn = RigidContact {
                    name: d.name.clone(),
                    body: c.body,
                    centre: c.centre,
                    radius: c.radius,
                    against: Against::Line {
                        body: line.body,
                        point: line.point,
                        normal: line.normal,
                    },
                    restitution: 0.0,
                    rest_speed: REST_SPEED,
                    friction: None,
                };
                if let Mark::Contact { force, .. } = &mut mark.insert(contact_mark(&drawn, &d.kind)) {
                    *force = false;
                }
            }
            Box::new(CircleLine {
                name: d.name.clone(),
                body: c.body,
                centre: c.centre,
                radius: c.radius,
                line,
                law: contact_law(d).map_err(err)?,
            })
        }
        "circle-circle" => {
            const KEYS: [&str; 8] = ["bodies", "at", "radii", "stiffness", "exponent", "dissipation", "friction", "smoothing_velocity"];
            if let Some(key) = d.keys_given().find(|k| !KEYS.contains(k)) {
                return Err(err(format!("'{key}' does not belong to a circle-circle element")));
            }
            let (pr, [c0, c1], [r0, r1]) = two_circles(b, d, span, &owner)?;
            Box::new(CircleCircle {
                name: d.name.clone(),
                bodies: (pr[0], pr[1]),
                centres: (c0, c1),
                radii: (r0, r1),
                law: contact_law(d).map_err(err)?,
            })
        }
        "polygon-polygon" => {
            const KEYS: [&str; 7] = ["bodies", "polygons", "stiffness", "exponent", "dissipation", "friction", "smoothing_velocity"];
            if let Some(key) = d.keys_given().find(|k| !KEYS.contains(k)) {
                return Err(err(format!("'{key}' does not belong to a polygon-polygon element")));
            }
            let bodies = pair()?;
            let lists = d.polygons.as_ref().ok_or_else(|| {
                err("needs 'polygons = [[[x, y], …], [[x, y], …]]' (the two convex polygons' vertices, global)".into())
            })?;
            let polygon = |k: usize| {
                let local: Vec<Vec2> = lists[k].iter().map(|&p| local_point_of(bodies[k], &b.q, v2(p))).collect();
                ConvexPolygon::new(bodies[k], &local).map_err(|m| err(format!("polygon {}: {m}", k + 1)))
            };
            Box::new(PolygonPair {
                name: d.name.clone(),
                polygons: [polygon(0)?, polygon(1)?],
                law: contact_law(d).map_err(err)?,
            })
        }
        "polygon-line" | "segment-line" => {
            let keys: &[&str] = if d.kind == "polygon-line" {
                &["body", "vertices", "line", "stiffness", "exponent", "dissipation", "friction", "smoothing_velocity"]
            } else {
                &["body", "at", "radius", "line", "stiffness", "exponent", "dissipation", "friction", "smoothing_velocity"]
            };
            if let Some(key) = d.keys_given().find(|k| !keys.contains(k)) {
                return Err(err(format!("'{key}' does not belong to a {} element", d.kind)));
            }
            let (body, centres, radius) = corners_of(b, d, span, &owner)?;
            Box::new(ShapeLine {
                name: d.name.clone(),
                body,
                centres,
                radius,
                line: line_of(b, d, span, &owner)?,
                law: contact_law(d).map_err(err)?,
            })
        }
        "segment-segment" => {
            const KEYS: [&str; 8] = [
                "bodies",
                "segments",
                "radii",
                "stiffness",
                "exponent",
                "dissipation",
                "friction",
                "smoothing_velocity",
            ];
            if let Some(key) = d.keys_given().find(|k| !KEYS.contains(k)) {
                return Err(err(format!("'{key}' does not belong to a segment-segment element")));
            }
            let pr = pair()?;
            let [s0, s1] = d.segments.ok_or_else(|| {
                err("needs 'segments = [[[x1, y1], [x2, y2]], [[x3, y3], [x4, y4]]]' (each segment's ends, global)".into())
            })?;
            let local = |k: usize, s: [[f64; 2]; 2]| s.map(|p| local_point_of(pr[k], &b.q, v2(p)));
            let [r0, r1] = d.radii.ok_or_else(|| err("needs 'radii = [r1, r2]' (m)".into()))?;
            Box::new(SegmentSegment {
                name: d.name.clone(),
                bodies: (pr[0], pr[1]),
                segments: (local(0, s0), local(1, s1)),
                radii: (r0, r1),
                law: contact_law(d).map_err(err)?,
            })
        }
        "circle-profile" | "line-profile" => {
            let roller = d.kind == "circle-profile";
            let shape: &[&str] = if roller { &["body", "at", "radius", "profile"] } else { &["body", "line", "profile"] };
            const LAW: [&str; 5] = ["stiffness", "exponent", "dissipation", "friction", "smoothing_velocity"];
            if let Some(key) = d.keys_given().find(|k| !shape.contains(k) && !LAW.contains(k)) {
                return Err(err(format!("'{key}' does not belong to a {} element", d.kind)));
            }
            let (body, centre, radius, against) = if roller {
                circle_on_profile(b, d, span, &owner)?
            } else {
                face_on_profile(b, d, span, &owner)?
            };
            // The viewer draws the profile and the roller or face as for a rigid contact; the
            // arrow is the resultant's, as for every compliant contact.
            let drawn = RigidContact {
                name: d.name.clone(),
                body,
                centre,
                radius,
                against: against.clone(),
                restitution: 0.0,
                rest_speed: REST_SPEED,
                friction: None,
            };
            if let Mark::Contact { force, .. } = &mut mark.insert(contact_mark(&drawn, &d.kind)) {
                *force = false;
            }
            let (profile_body, profile, face) = match against {
                Against::Profile { body, profile } => (body, profile, None),
                Against::ProfileFace { body, profile, normal } => (body, profile, Some(normal)),
                Against::Line { .. } | Against::Circle { .. } => {
                    return Err(err("a profile contact is between a roller or a face and a profile".into()))
                }
            };
            Box::new(ProfileContact {
                name: d.name.clone(),
                body,
                centre,
                radius,
                face,
                profile_body,
                profile,
                law: contact_law(d).map_err(err)?,
            })
        }
        "code" => {
            if let Some(key) = d.keys_given().find(|k| *k != "body") {
                return Err(err(format!(
                    "'{key}' does not belong to a code element (its force comes from code: give 'body' only)"
                )));
            }
            let name = d.body.as_deref().ok_or_else(|| err("needs 'body'".into()))?;
            Box::new(crate::code_force::PlanarCodeForce {
                name: d.name.clone(),
                body: b.body(name, span, &owner)?,
                index: b.ctx.code_force(&d.name),
            })
        }
        other => {
            return Err(err(format!(
                "unknown type '{other}' (expected force, torque, spring-damper, rotational-spring-damper, circle-line, circle-circle, segment-segment, circle-profile, line-profile, polygon-line, segment-line, polygon-polygon, code)"
            )))
        }
    };
    // The element's own message names it ("force '…': …").
    element
        .validate(b.q.len() / 3)
        .map_err(|e| b.ctx.err(Some(span.clone()), e.to_string()))?;
    Ok((element, mark))
}

/// The run settings of a `[simulation]` table (`file` and `text` for errors; `coordinates`: the
/// model's velocity names, `body.label`, for `independent`).
pub(crate) fn settings(
    file: &str,
    text: &str,
    sim: Option<&Spanned<SimDef>>,
    coordinates: &[String],
) -> Result<RunSettings, SceneError> {
    let mut s = RunSettings::default();
    let Some(sim) = sim else { return Ok(s) };
    let span = sim.span();
    let d = sim.get_ref();
    let err = |m: String| SceneError::at(file, text, Some(span.clone()), format!("[simulation]: {m}"));
    if let Some(f) = &d.formulation {
        s.formulation =
            FormulationKind::parse(f).ok_or_else(|| err(unknown_name("formulation", f, FormulationKind::NAMES)))?;
    }
    if let Some(c) = &d.coordinates {
        s.coordinates = Coordinates::parse(c).ok_or_else(|| err(unknown_name("coordinates", c, Coordinates::NAMES)))?;
    }
    if let Some(r) = &d.redundant {
        s.redundancy = super::parse_redundancy(r)
            .ok_or_else(|| err(unknown_name("redundancy treatment", r, super::REDUNDANCY_NAMES)))?;
    }
    if let Some(st) = &d.stabilization {
        s.stabilization =
            Stabilization::parse(st).ok_or_else(|| err(unknown_name("stabilization", st, Stabilization::NAMES)))?;
    }
    if let Some(names) = &d.independent {
        let mut indices = Vec::with_capacity(names.len());
        for name in names {
            let i = coordinates.iter().position(|c| c == name).ok_or_else(|| {
                let shown: Vec<&str> = coordinates.iter().take(6).map(|c| c.as_str()).collect();
                let more = if coordinates.len() > 6 { ", …" } else { "" };
                err(format!(
                    "independent: unknown coordinate '{name}' (expected body.label: {}{more})",
                    shown.join(", ")
                ))
            })?;
            if indices.contains(&i) {
                return Err(err(format!("independent: '{name}' is named twice")));
            }
            indices.push(i);
        }
        s.independent = Some(indices);
    }
    // The methods' parameters: a key no method declares is an unknown field, located at its line.
    for (key, value) in &d.parameters {
        if method_parameter(key).is_none() {
            let keys: Vec<String> = SIM_KEYS
                .iter()
                .chain(parameter_keys().iter())
                .map(|k| format!("`{k}`"))
                .collect();
            return Err(SceneError::at(
                file,
                text,
                Some(key_span(text, &span, key).unwrap_or(span.clone())),
                format!("unknown field `{key}`, expected one of {}", keys.join(", ")),
            ));
        }
        let v = match value {
            toml::Value::Float(v) => *v,
            toml::Value::Integer(i) => *i as f64,
            _ => return Err(err(format!("'{key}' must be a number"))),
        };
        s.set_parameter(key, v, &|k| format!("'{k}'")).map_err(err)?;
    }
    if let Some(i) = &d.integrator {
        let m = Method::named(i).ok_or_else(|| err(unknown_name("integrator", i, &method_names())))?;
        s.set_method(m);
    }
    s.end = d.end.unwrap_or(s.end);
    s.step = d.step.unwrap_or(s.step);
    s.output_every = d.output_every.unwrap_or(s.output_every);
    for (v, what) in [(s.end, "end"), (s.step, "step"), (s.output_every, "output_every")] {
        if !(v.is_finite() && v > 0.0) {
            return Err(err(format!("'{what}' must be positive, got {v}")));
        }
    }
    Ok(s)
}

/// The span of `key` where the table starting at `table` sets it (`key = …` at the start of a
/// line, before the next table header).
pub(crate) fn key_span(text: &str, table: &std::ops::Range<usize>, key: &str) -> Option<std::ops::Range<usize>> {
    let body = text.get(table.start..)?;
    let mut offset = table.start;
    for (k, line) in body.split_inclusive('\n').enumerate() {
        let trimmed = line.trim_start();
        if k > 0 && trimmed.starts_with('[') {
            return None;
        }
        if let Some(rest) = trimmed.strip_prefix(key) {
            if rest.trim_start().starts_with('=') {
                let start = offset + (line.len() - trimmed.len());
                return Some(start..start + key.len());
            }
        }
        offset += line.len();
    }
    None
}

/// The contact law of a `circle-line` or `circle-circle` element (the spatial reader's rule).
fn contact_law(d: &ForceDef) -> Result<dalembert_system::ContactLaw, String> {
    super::spatial_forces::contact_law(d.stiffness, d.exponent, d.dissipation, d.friction, d.smoothing_velocity)
}
