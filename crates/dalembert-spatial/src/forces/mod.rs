//! Applied forces on spatial bodies, as generalized forces on `(ṙ, ω')`: a force `F` at body
//! point `s = A s'` contributes `F` and `Aᵀ(s × F)`, a torque `T` contributes `Aᵀ T` (Nikravesh
//! §6.5). Gravity and the gyroscopic term `−ω' × J'ω'` are added by the model.
//!
//! | element | law | file |
//! |---|---|---|
//! | point force | `F(t)` at a body point, global or body components | here |
//! | torque | `T(t)`, global or body components | here |
//! | spring–damper–actuator | tension `k (ℓ − ℓ₀) + c ℓ̇ + f(t)` along the line of its points | here |
//! | joint torque, rotational spring–damper | `τ = −k (θ − θ₀) − c θ̇ + f(t)` about a revolute or cylindrical joint's axis | [`about_axis`] |
//! | joint servo | `τ = clamp(−k (θ − θ*(t)) − c θ̇ + f(t), τ_lo, τ_hi)` about the same axis | [`about_axis`] |
//! | sphere–plane contact | Hunt–Crossley normal force and regularized Coulomb friction between a sphere on a body and a plane of the ground | `contact.rs` |
//! | sphere–sphere, capsule–capsule contact | the same law between spheres or capsules on two bodies | `contact.rs` |
//! | capsule group | the same law between every two capsules of a group not on one body or joined, a broad phase finding the pairs | `capsule_group.rs` |
//! | user force | whatever [`UserForce::add`] writes | [`user`] |

pub mod about_axis;
mod along_axis;
mod capsule_group;
mod contact;
mod jacobians;
pub mod user;

use crate::frame::{Frame, NV};
use crate::joints::{JointData, JointKind};
use crate::BodyRef;
use about_axis::AxisForce;
use along_axis::SlideForce;
use capsule_group::{CapsuleGroup, Member};
use contact::{SpherePlane, SweptPair};
use dalembert_system::{AxisLaw, ContactLaw};
use dalembert_system::{ModelError, TimeFunction};
use nalgebra::Vector3;
use std::sync::Arc;
pub use user::{Frames, Loads, UserForce};

type V3 = Vector3<f64>;

/// The axes a force's or a torque's components are given in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum ForceFrame {
    /// Global axes (the direction is fixed in space).
    #[default]
    Global,
    /// The body's own axes (the direction turns with the body).
    Body,
}

/// A force element, placed in the initial configuration (global components).
#[derive(Debug, Clone)]
#[non_exhaustive]
pub enum Force {
    /// A force at a body point: components `force` (functions of time) in `frame`.
    PointForce {
        /// Name.
        name: String,
        /// The body.
        body: BodyRef,
        /// Point of application in the initial configuration (global).
        point: [f64; 3],
        /// Components (N) along the axes of `frame`.
        force: [TimeFunction; 3],
        /// Global or body axes.
        frame: ForceFrame,
    },
    /// A torque on a body: components `torque` (functions of time) in `frame`.
    Torque {
        /// Name.
        name: String,
        /// The body.
        body: BodyRef,
        /// Components (N·m) along the axes of `frame`.
        torque: [TimeFunction; 3],
        /// Global or body axes.
        frame: ForceFrame,
    },
    /// A translational spring–damper–actuator between two points: tension
    /// `k (ℓ − ℓ₀) + c ℓ̇ + f(t)` (positive pulls the points together).
    SpringDamper {
        /// Name.
        name: String,
        /// First body and its point in the initial configuration (global).
        body_i: BodyRef,
        /// Point on the first body.
        point_i: [f64; 3],
        /// Second body.
        body_j: BodyRef,
        /// Point on the second body.
        point_j: [f64; 3],
        /// Stiffness `k`.
        stiffness: f64,
        /// Damping `c`.
        damping: f64,
        /// Free length `ℓ₀`.
        free_length: f64,
        /// Actuator tension `f(t)` (N), if any.
        actuator: Option<TimeFunction>,
    },
    /// A torque `f(t)` about the axis of the named revolute or cylindrical joint: `+` on the
    /// joint's second body, `−` on its first.
    JointTorque {
        /// Name.
        name: String,
        /// The joint.
        joint: String,
        /// Torque (N·m) about the joint axis.
        torque: TimeFunction,
    },
    /// A rotational spring–damper about the axis of the named revolute or cylindrical joint:
    /// torque `−k (θ − θ₀) − c θ̇` on the second body (the opposite on the first), with `θ` the
    /// joint angle (0 in the initial configuration, deflections measured within ±π).
    RotationalSpringDamper {
        /// Name.
        name: String,
        /// The joint.
        joint: String,
        /// Stiffness `k` (N·m/rad).
        stiffness: f64,
        /// Damping `c` (N·m·s/rad).
        damping: f64,
        /// Free angle `θ₀` (rad).
        free_angle: f64,
    },
    /// A servo about the axis of the named revolute or cylindrical joint, or along a prismatic
    /// one's (an MJCF `position` actuator, or a `general` one with an affine bias): torque
    /// `clamp(−k (θ − θ*(t)) − c θ̇ + f(t), lo, hi)` on the second body (the opposite on the
    /// first), with `θ` the joint angle (0 in the initial configuration) and its distance from the
    /// target measured within ±π; on a prismatic joint `θ` is the displacement and the torque a
    /// force along the axis.
    JointServo {
        /// Name.
        name: String,
        /// The joint.
        joint: String,
        /// Stiffness `k` (N·m/rad): the position gain.
        stiffness: f64,
        /// Damping `c` (N·m·s/rad): the velocity gain.
        damping: f64,
        /// The target angle `θ*(t)` (rad; 0 when absent).
        target: Option<TimeFunction>,
        /// A torque `f(t)` added before the range (N·m).
        torque: Option<TimeFunction>,
        /// The torque is held within `[lo, hi]` (N·m; infinite bounds for none).
        range: [f64; 2],
    },
    /// Compliant contact of a sphere on `body` with a plane of the ground or of `plane_body`
    /// (`docs/contact.md`): normal force `k δⁿ (1 + d δ̇)` with `δ` the penetration, Coulomb
    /// friction `μ F_n` regularized below `smoothing_velocity`.
    SpherePlane {
        /// Name.
        name: String,
        /// The body carrying the sphere.
        body: BodyRef,
        /// The sphere's centre in the initial configuration (global).
        centre: [f64; 3],
        /// Radius (m).
        radius: f64,
        /// The plane's body ([`BodyRef::Ground`] for a floor).
        plane_body: BodyRef,
        /// A point of the plane (global).
        point: [f64; 3],
        /// The plane's normal, out of the solid (any length but zero).
        normal: [f64; 3],
        /// The contact law (checked when the model is built).
        law: ContactLaw,
    },
    /// Compliant contact of a box on `body` with a plane of the ground or of `plane_body`, the law of
    /// [`Force::SpherePlane`] at each of its eight corners that penetrates (`docs/contact.md`).
    BoxPlane {
        /// Name.
        name: String,
        /// The body carrying the box.
        body: BodyRef,
        /// The box's centre in the initial configuration (global).
        centre: [f64; 3],
        /// Its edge lengths along the body's axes (m).
        size: [f64; 3],
        /// The plane's body ([`BodyRef::Ground`] for a floor).
        plane_body: BodyRef,
        /// A point of the plane (global).
        point: [f64; 3],
        /// The plane's normal, out of the solid (any length but zero).
        normal: [f64; 3],
        /// The contact law (checked when the model is built).
        law: ContactLaw,
    },
    /// Compliant contact of a capsule on `body` (a segment swept by a sphere) with a plane of the
    /// ground or of `plane_body`, the law of [`Force::SpherePlane`] at each of its two end caps that penetrates.
    CapsulePlane {
        /// Name.
        name: String,
        /// The body carrying the capsule.
        body: BodyRef,
        /// The segment's two ends in the initial configuration (global).
        ends: [[f64; 3]; 2],
        /// Radius (m).
        radius: f64,
        /// The plane's body ([`BodyRef::Ground`] for a floor).
        plane_body: BodyRef,
        /// A point of the plane (global).
        point: [f64; 3],
        /// The plane's normal, out of the solid (any length but zero).
        normal: [f64; 3],
        /// The contact law (checked when the model is built).
        law: ContactLaw,
    },
    /// Compliant contact of two spheres on two bodies (either may be the ground), with the law of
    /// [`Force::SpherePlane`].
    SphereSphere {
        /// Name.
        name: String,
        /// The two bodies.
        bodies: [BodyRef; 2],
        /// The spheres' centres in the initial configuration (global).
        centres: [[f64; 3]; 2],
        /// Radii (m).
        radii: [f64; 2],
        /// The contact law (checked when the model is built).
        law: ContactLaw,
    },
    /// Compliant contact of two capsules (segments swept by spheres) on two bodies (either may be
    /// the ground), with the law of [`Force::SpherePlane`] at the closest points of their axes
    /// (`docs/contact.md`, "Capsules"); a segment whose ends are one point is a sphere.
    CapsuleCapsule {
        /// Name.
        name: String,
        /// The two bodies.
        bodies: [BodyRef; 2],
        /// Each capsule's segment's two ends in the initial configuration (global).
        segments: [[[f64; 3]; 2]; 2],
        /// Radii (m).
        radii: [f64; 2],
        /// The contact law (checked when the model is built).
        law: ContactLaw,
    },
    /// Compliant contact among a group of capsules (`docs/contact.md`, "Groups and the broad
    /// phase"): the law of [`Force::CapsuleCapsule`] between every two members on different bodies
    /// that no joint joins, the pairs found by a broad phase.
    CapsuleGroup {
        /// Name.
        name: String,
        /// The members: each a body, its segment's two ends in the initial configuration (global)
        /// and its radius (m).
        members: Vec<(BodyRef, [[f64; 3]; 2], f64)>,
        /// The contact law (checked when the model is built).
        law: ContactLaw,
    },
    /// A force the user writes ([`UserForce`]).
    User(Arc<dyn UserForce>),
}

impl Force {
    /// The element's name.
    pub fn name(&self) -> &str {
        match self {
            Force::PointForce { name, .. }
            | Force::Torque { name, .. }
            | Force::SpringDamper { name, .. }
            | Force::JointTorque { name, .. }
            | Force::SpherePlane { name, .. }
            | Force::BoxPlane { name, .. }
            | Force::CapsulePlane { name, .. }
            | Force::SphereSphere { name, .. }
            | Force::CapsuleCapsule { name, .. }
            | Force::CapsuleGroup { name, .. }
            | Force::RotationalSpringDamper { name, .. }
            | Force::JointServo { name, .. } => name,
            Force::User(u) => u.name(),
        }
    }

    /// A constant global force at `point` (initial configuration, global) of `body`.
    pub fn constant_force(name: &str, body: BodyRef, point: [f64; 3], force: [f64; 3]) -> Force {
        Force::PointForce {
            name: name.to_string(),
            body,
            point,
            force: force.map(TimeFunction::Constant),
            frame: ForceFrame::Global,
        }
    }

    /// A constant global torque on `body`.
    pub fn constant_torque(name: &str, body: BodyRef, torque: [f64; 3]) -> Force {
        Force::Torque {
            name: name.to_string(),
            body,
            torque: torque.map(TimeFunction::Constant),
            frame: ForceFrame::Global,
        }
    }
}

/// A force element in body-frame terms.
#[derive(Debug, Clone)]
pub(crate) enum ForceData {
    PointForce {
        body: usize,
        point: V3,
        force: [TimeFunction; 3],
        frame: ForceFrame,
    },
    Torque {
        body: usize,
        torque: [TimeFunction; 3],
        frame: ForceFrame,
    },
    SpringDamper {
        ends: [(Option<usize>, V3); 2],
        stiffness: f64,
        damping: f64,
        free_length: f64,
        actuator: Option<TimeFunction>,
    },
    AboutAxis(AxisForce),
    /// A law along a prismatic joint's axis (a servo on a slide).
    AlongAxis(SlideForce),
    SpherePlane(SpherePlane),
    SweptPair(SweptPair),
    CapsuleGroup(CapsuleGroup),
    User(Arc<dyn UserForce>),
}

/// Adds the generalized force of global force `f` at global arm `s` on body `b`.
#[inline]
pub(crate) fn add_point_force(out: &mut [f64], b: usize, frame: &Frame, s: &V3, f: &V3) {
    let o = NV * b;
    let n = frame.a.transpose() * s.cross(f);
    for k in 0..3 {
        out[o + k] += f[k];
        out[o + 3 + k] += n[k];
    }
}

/// Adds the generalized force of global torque `t` on body `b`.
#[inline]
pub(crate) fn add_torque(out: &mut [f64], b: usize, frame: &Frame, t: &V3) {
    let n = frame.a.transpose() * t;
    for k in 0..3 {
        out[NV * b + 3 + k] += n[k];
    }
}

/// `Ok` when `v` is positive and finite; the message names `what` otherwise.
fn positive(v: f64, what: &str) -> Result<(), String> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(format!("{what} must be positive and finite, got {v}"))
    }
}

/// The three components at `t`.
fn components(f: &[TimeFunction; 3], t: f64) -> V3 {
    V3::new(f[0].value(t), f[1].value(t), f[2].value(t))
}

/// The joint named `name`, which must be revolute or cylindrical (an axis-bound element).
fn axis_joint<'a>(joints: &'a [JointData], name: &str) -> Result<(usize, &'a JointData), String> {
    let (k, j) = joints
        .iter()
        .enumerate()
        .find(|(_, j)| j.name == name)
        .ok_or_else(|| format!("no joint named '{name}'"))?;
    match j.kind {
        Some(JointKind::Revolute | JointKind::Cylindrical) => Ok((k, j)),
        Some(k) => Err(format!(
            "joint '{name}' is {}: a torque about a joint axis needs a revolute or cylindrical joint",
            k.name()
        )),
        None => Err(format!("'{name}' is a driver, not a joint")),
    }
}

impl ForceData {
    /// Converts `force` with the bodies' initial frames (`index` maps a body to its index,
    /// `frame` to its initial frame) and the joints already built.
    pub fn new(
        force: &Force,
        index: &dyn Fn(BodyRef) -> Result<Option<usize>, ModelError>,
        frame: &dyn Fn(Option<usize>) -> Frame,
        joints: &[JointData],
    ) -> Result<Self, ModelError> {
        let element = format!("force '{}'", force.name());
        let bad = |what: &str| ModelError::InvalidParameter {
            element: element.clone(),
            what: what.to_string(),
        };
        let moving = |b: BodyRef| index(b)?.ok_or_else(|| bad("acts on the ground: give it a moving body"));
        let local = |b: Option<usize>, p: &[f64; 3]| {
            let f = frame(b);
            f.a.transpose() * (V3::from(*p) - f.r)
        };
        let finite = |xs: &[f64]| xs.iter().all(|x| x.is_finite());
        // Two spheres or capsules: their bodies, segments (global), radii and law.
        let swept = |bodies: &[BodyRef; 2], segments: [[[f64; 3]; 2]; 2], radii: &[f64; 2], law: &ContactLaw| {
            positive(radii[0], "radius")
                .and_then(|()| positive(radii[1], "radius"))
                .and_then(|()| law.check())
                .map_err(|m| bad(&m))?;
            let (bi, bj) = (index(bodies[0])?, index(bodies[1])?);
            if bi == bj {
                return Err(bad("must be between two different bodies"));
            }
            let ends = |b: Option<usize>, s: &[[f64; 3]; 2]| [local(b, &s[0]), local(b, &s[1])];
            Ok(ForceData::SweptPair(SweptPair {
                ends: [(bi, ends(bi, &segments[0])), (bj, ends(bj, &segments[1]))],
                radii: *radii,
                law: *law,
            }))
        };
        let functions =
            |fs: &[TimeFunction]| -> Result<(), ModelError> { fs.iter().try_for_each(|f| f.validate(&element)) };
        let non_negative = |pairs: &[(f64, &str)]| -> Result<(), ModelError> {
            for (v, what) in pairs {
                if !(v.is_finite() && *v >= 0.0) {
                    return Err(bad(&format!("{what} must be finite and non-negative, got {v}")));
                }
            }
            Ok(())
        };
        Ok(match force {
            Force::PointForce {
                body,
                point,
                force: f,
                frame: axes,
                ..
            } => {
                if !finite(point) {
                    return Err(bad("point must be finite"));
                }
                functions(f)?;
                let b = moving(*body)?;
                ForceData::PointForce {
                    body: b,
                    point: local(Some(b), point),
                    force: f.clone(),
                    frame: *axes,
                }
            }
            Force::Torque {
                body,
                torque,
                frame: axes,
                ..
            } => {
                functions(torque)?;
                ForceData::Torque {
                    body: moving(*body)?,
                    torque: torque.clone(),
                    frame: *axes,
                }
            }
            Force::SpringDamper {
                body_i,
                point_i,
                body_j,
                point_j,
                stiffness,
                damping,
                free_length,
                actuator,
                ..
            } => {
                if !finite(point_i) || !finite(point_j) {
                    return Err(bad("points must be finite"));
                }
                non_negative(&[
                    (*stiffness, "stiffness"),
                    (*damping, "damping"),
                    (*free_length, "free length"),
                ])?;
                functions(actuator.as_slice())?;
                let (bi, bj) = (index(*body_i)?, index(*body_j)?);
                if bi == bj {
                    return Err(bad("must connect two different bodies"));
                }
                ForceData::SpringDamper {
                    ends: [(bi, local(bi, point_i)), (bj, local(bj, point_j))],
                    stiffness: *stiffness,
                    damping: *damping,
                    free_length: *free_length,
                    actuator: actuator.clone(),
                }
            }
            Force::JointTorque { joint, torque, .. } => {
                functions(std::slice::from_ref(torque))?;
                let j = axis_joint(joints, joint).map_err(|m| bad(&m))?;
                ForceData::AboutAxis(AxisForce::new(
                    j,
                    AxisLaw {
                        torque: Some(torque.clone()),
                        ..AxisLaw::spring(0.0, 0.0, 0.0)
                    },
                ))
            }
            Force::RotationalSpringDamper {
                joint,
                stiffness,
                damping,
                free_angle,
                ..
            } => {
                non_negative(&[(*stiffness, "stiffness"), (*damping, "damping")])?;
                if !free_angle.is_finite() {
                    return Err(bad("free angle must be finite"));
                }
                let j = axis_joint(joints, joint).map_err(|m| bad(&m))?;
                ForceData::AboutAxis(AxisForce::new(j, AxisLaw::spring(*stiffness, *damping, *free_angle)))
            }
            Force::JointServo {
                joint,
                stiffness,
                damping,
                target,
                torque,
                range,
                ..
            } => {
                non_negative(&[(*stiffness, "stiffness"), (*damping, "damping")])?;
                functions(target.as_slice())?;
                functions(torque.as_slice())?;
                let [lo, hi] = *range;
                if lo.is_nan() || hi.is_nan() || lo > hi {
                    return Err(bad(&format!("range [{lo}, {hi}]: the first bound is above the second")));
                }
                if target.is_some() && *stiffness == 0.0 {
                    return Err(bad("a target needs a stiffness (the gain that pulls the joint to it)"));
                }
                let law = AxisLaw {
                    target: target.clone(),
                    torque: torque.clone(),
                    range: *range,
                    ..AxisLaw::spring(*stiffness, *damping, 0.0)
                };
                // A servo on a slide pushes along its axis; on a revolute or cylindrical joint it
                // turns about it.
                match joints.iter().enumerate().find(|(_, j)| j.name == *joint) {
                    Some((k, j)) if j.kind == Some(JointKind::Prismatic) => {
                        ForceData::AlongAxis(SlideForce::new((k, j), law))
                    }
                    _ => ForceData::AboutAxis(AxisForce::new(axis_joint(joints, joint).map_err(|m| bad(&m))?, law)),
                }
            }
            Force::SpherePlane {
                body,
                centre,
                radius,
                plane_body,
                point,
                normal,
                law,
                ..
            } => {
                if !finite(centre) || !finite(point) || !finite(normal) {
                    return Err(bad("centre, point and normal must be finite"));
                }
                let n = V3::from(*normal);
                if n.norm() == 0.0 {
                    return Err(bad("the plane's normal must not be zero"));
                }
                positive(*radius, "radius").map_err(|m| bad(&m))?;
                law.check().map_err(|m| bad(&m))?;
                let b = moving(*body)?;
                let plane = index(*plane_body)?;
                if plane == Some(b) {
                    return Err(bad(
                        "the plane is on the body the shape is on: give it another body or the ground",
                    ));
                }
                ForceData::SpherePlane(SpherePlane {
                    body: b,
                    centres: vec![local(Some(b), centre)],
                    radius: *radius,
                    plane_body: plane,
                    point: local(plane, point),
                    normal: frame(plane).a.transpose() * (n / n.norm()),
                    law: *law,
                })
            }
            Force::BoxPlane {
                body,
                centre,
                size,
                plane_body,
                point,
                normal,
                law,
                ..
            } => {
                if !finite(centre) || !finite(point) || !finite(normal) {
                    return Err(bad("centre, point and normal must be finite"));
                }
                for (side, axis) in size.iter().zip(["x", "y", "z"]) {
                    positive(*side, &format!("size along {axis}")).map_err(|m| bad(&m))?;
                }
                let n = V3::from(*normal);
                if n.norm() == 0.0 {
                    return Err(bad("the plane's normal must not be zero"));
                }
                law.check().map_err(|m| bad(&m))?;
                let b = moving(*body)?;
                let plane = index(*plane_body)?;
                if plane == Some(b) {
                    return Err(bad(
                        "the plane is on the body the shape is on: give it another body or the ground",
                    ));
                }
                let c = local(Some(b), centre);
                let half = V3::from(*size) / 2.0;
                let corners = (0..8)
                    .map(|k| {
                        let sign = |bit: usize| if k >> bit & 1 == 1 { 1.0 } else { -1.0 };
                        c + V3::new(sign(0) * half.x, sign(1) * half.y, sign(2) * half.z)
                    })
                    .collect();
                ForceData::SpherePlane(SpherePlane {
                    body: b,
                    centres: corners,
                    radius: 0.0,
                    plane_body: plane,
                    point: local(plane, point),
                    normal: frame(plane).a.transpose() * (n / n.norm()),
                    law: *law,
                })
            }
            Force::CapsulePlane {
                body,
                ends,
                radius,
                plane_body,
                point,
                normal,
                law,
                ..
            } => {
                if !finite(&ends[0]) || !finite(&ends[1]) || !finite(point) || !finite(normal) {
                    return Err(bad("ends, point and normal must be finite"));
                }
                let n = V3::from(*normal);
                if n.norm() == 0.0 {
                    return Err(bad("the plane's normal must not be zero"));
                }
                positive(*radius, "radius").map_err(|m| bad(&m))?;
                law.check().map_err(|m| bad(&m))?;
                let b = moving(*body)?;
                let plane = index(*plane_body)?;
                if plane == Some(b) {
                    return Err(bad(
                        "the plane is on the body the shape is on: give it another body or the ground",
                    ));
                }
                ForceData::SpherePlane(SpherePlane {
                    body: b,
                    centres: vec![local(Some(b), &ends[0]), local(Some(b), &ends[1])],
                    radius: *radius,
                    plane_body: plane,
                    point: local(plane, point),
                    normal: frame(plane).a.transpose() * (n / n.norm()),
                    law: *law,
                })
            }
            Force::SphereSphere {
                bodies,
                centres,
                radii,
                law,
                ..
            } => {
                if !finite(&centres[0]) || !finite(&centres[1]) {
                    return Err(bad("centres must be finite"));
                }
                swept(bodies, [[centres[0]; 2], [centres[1]; 2]], radii, law)?
            }
            Force::CapsuleCapsule {
                bodies,
                segments,
                radii,
                law,
                ..
            } => {
                if !segments.iter().flatten().all(|p| finite(p)) {
                    return Err(bad("the segments' ends must be finite"));
                }
                swept(bodies, *segments, radii, law)?
            }
            Force::CapsuleGroup { members, law, .. } => {
                if members.len() < 2 {
                    return Err(bad("needs at least two members"));
                }
                law.check().map_err(|m| bad(&m))?;
                let mut built = Vec::with_capacity(members.len());
                for (k, (body, ends, radius)) in members.iter().enumerate() {
                    let member = |m: &str| bad(&format!("member {}: {m}", k + 1));
                    if !ends.iter().all(|p| finite(p)) {
                        return Err(member("its segment's ends must be finite"));
                    }
                    positive(*radius, "radius").map_err(|m| member(&m))?;
                    let b = index(*body)?;
                    built.push(Member {
                        body: b,
                        ends: [local(b, &ends[0]), local(b, &ends[1])],
                        radius: *radius,
                    });
                }
                let key = |b: Option<usize>| b.unwrap_or(usize::MAX);
                let joined = joints.iter().map(|j| (key(j.body_i), key(j.body_j))).collect();
                ForceData::CapsuleGroup(CapsuleGroup::new(built, joined, *law))
            }
            Force::User(u) => ForceData::User(u.clone()),
        })
    }

    /// The moving bodies the element reads or loads (the sparsity of the implicit integrator's
    /// iteration matrix).
    pub fn bodies(&self) -> Vec<usize> {
        match self {
            ForceData::PointForce { body, .. } | ForceData::Torque { body, .. } => vec![*body],
            ForceData::SpherePlane(c) => [Some(c.body), c.plane_body].into_iter().flatten().collect(),
            ForceData::SweptPair(c) => c.ends.iter().filter_map(|e| e.0).collect(),
            ForceData::CapsuleGroup(c) => c.members.iter().filter_map(|m| m.body).collect(),
            ForceData::SpringDamper { ends, .. } => ends.iter().filter_map(|e| e.0).collect(),
            ForceData::AboutAxis(a) => a.bodies(),
            ForceData::AlongAxis(a) => a.bodies(),
            ForceData::User(u) => u
                .bodies()
                .into_iter()
                .filter_map(|b| match b {
                    BodyRef::Body(i) => Some(i),
                    BodyRef::Ground => None,
                })
                .collect(),
        }
    }

    /// Adds the element's generalized force at time `t` and the state behind `frame`.
    pub fn add(&self, t: f64, frame: &dyn Fn(Option<usize>) -> Frame, out: &mut [f64]) {
        match self {
            ForceData::PointForce {
                body,
                point,
                force,
                frame: axes,
            } => {
                let f = frame(Some(*body));
                let components = components(force, t);
                let global = match axes {
                    ForceFrame::Body => f.a * components,
                    ForceFrame::Global => components,
                };
                add_point_force(out, *body, &f, &f.global(point), &global);
            }
            ForceData::Torque {
                body,
                torque,
                frame: axes,
            } => {
                let components = components(torque, t);
                match axes {
                    // Body components are the generalized force on ω' itself.
                    ForceFrame::Body => {
                        for k in 0..3 {
                            out[NV * body + 3 + k] += components[k];
                        }
                    }
                    ForceFrame::Global => add_torque(out, *body, &frame(Some(*body)), &components),
                }
            }
            ForceData::SpringDamper {
                ends,
                stiffness,
                damping,
                free_length,
                actuator,
            } => {
                let (fi, fj) = (frame(ends[0].0), frame(ends[1].0));
                let (si, sj) = (fi.global(&ends[0].1), fj.global(&ends[1].1));
                let d = fj.r + sj - fi.r - si;
                let length = d.norm();
                if length == 0.0 {
                    // Coincident ends: the line of action is undefined, and the element exerts
                    // no force there (exact for a free length of zero).
                    return;
                }
                let u = d / length;
                let rate = u.dot(&(fj.point_velocity(&sj) - fi.point_velocity(&si)));
                let tension =
                    stiffness * (length - free_length) + damping * rate + actuator.as_ref().map_or(0.0, |f| f.value(t));
                if let Some(b) = ends[0].0 {
                    add_point_force(out, b, &fi, &si, &(tension * u));
                }
                if let Some(b) = ends[1].0 {
                    add_point_force(out, b, &fj, &sj, &(-tension * u));
                }
            }
            ForceData::AboutAxis(a) => a.add(t, frame, out),
            ForceData::AlongAxis(a) => a.add(t, frame, out),
            ForceData::SpherePlane(c) => c.add(frame, out),
            ForceData::SweptPair(c) => c.add(frame, out),
            ForceData::CapsuleGroup(c) => c.add(frame, out),
            ForceData::User(u) => u.add(t, &Frames::new(frame), &mut Loads::new(frame, out)),
        }
    }

    /// Potential energy of a conservative element at `t` (zero for the others).
    pub fn potential(&self, t: f64, frame: &dyn Fn(Option<usize>) -> Frame) -> f64 {
        match self {
            ForceData::SpringDamper {
                ends,
                stiffness,
                free_length,
                ..
            } => {
                let (fi, fj) = (frame(ends[0].0), frame(ends[1].0));
                let d = fj.point(&ends[1].1) - fi.point(&ends[0].1);
                0.5 * stiffness * (d.norm() - free_length).powi(2)
            }
            ForceData::AboutAxis(a) => a.potential(t, frame),
            ForceData::AlongAxis(a) => a.potential(t, frame),
            ForceData::SpherePlane(c) => c.potential(frame),
            ForceData::SweptPair(c) => c.potential(frame),
            ForceData::CapsuleGroup(c) => c.potential(frame),
            ForceData::User(u) => u.potential(t, &Frames::new(frame)).unwrap_or(0.0),
            ForceData::PointForce { .. } | ForceData::Torque { .. } => 0.0,
        }
    }

    /// A compliant contact's resultant at the state behind `frame`
    /// ([`dalembert_system::ContactResultant`]);
    /// `None` for the other elements.
    pub fn resultant(&self, frame: &dyn Fn(Option<usize>) -> Frame) -> Option<dalembert_system::ContactResultant<3>> {
        match self {
            ForceData::SpherePlane(c) => Some(c.resultant(frame)),
            ForceData::SweptPair(c) => Some(c.resultant(frame)),
            ForceData::CapsuleGroup(c) => Some(c.resultant(frame)),
            _ => None,
        }
    }

    /// True for a contact element (it has a gap: [`ForceData::gap`]).
    pub fn is_contact(&self) -> bool {
        matches!(
            self,
            ForceData::SpherePlane(_) | ForceData::SweptPair(_) | ForceData::CapsuleGroup(_)
        )
    }

    /// A contact's gap at the state behind `frame` (positive apart, negative in contact), the
    /// event function of [`dalembert_system::MultibodySystem::events`]; `None` for the other
    /// elements.
    pub fn gap(&self, frame: &dyn Fn(Option<usize>) -> Frame) -> Option<f64> {
        match self {
            ForceData::SpherePlane(c) => Some(-c.penetration(frame)),
            ForceData::SweptPair(c) => Some(-c.overlap(frame)),
            ForceData::CapsuleGroup(c) => Some(c.gap(frame)),
            _ => None,
        }
    }

    /// True when the element is conservative with its potential counted by [`ForceData::potential`].
    pub fn is_conservative(&self) -> bool {
        match self {
            ForceData::SpringDamper { damping, actuator, .. } => *damping == 0.0 && actuator.is_none(),
            ForceData::AboutAxis(a) => a.is_conservative(),
            ForceData::AlongAxis(a) => a.is_conservative(),
            ForceData::SpherePlane(c) => c.is_conservative(),
            ForceData::SweptPair(c) => c.is_conservative(),
            ForceData::CapsuleGroup(c) => c.is_conservative(),
            ForceData::User(u) => u.is_conservative(),
            ForceData::PointForce { .. } | ForceData::Torque { .. } => false,
        }
    }

    /// Checks that the element's law holds at `t` and the state behind `frame`: `Err(what)` when it has
    /// left its range.
    pub fn check(&self, t: f64, frame: &dyn Fn(Option<usize>) -> Frame) -> Result<(), String> {
        match self {
            ForceData::AboutAxis(a) => a.check(t, frame),
            _ => Ok(()),
        }
    }
}
