//! Spatial joints, each a fixed set of primitives (`joints/primitives.rs`) between a marker on body `i` and one on body
//! `j` (either may be the ground).
//!
//! A joint is given where it is in the **initial configuration** (a global point and global axes,
//! as one reads them off a drawing); the model turns that into body-frame markers from the bodies'
//! initial poses. Both markers then share one frame: `z` along the joint axis, `x`, `y` completing
//! it ([`complete_frame`]).
//!
//! | joint | equations | primitives (`x, y, z` the marker axes) |
//! |---|---|---|
//! | spherical | 3 | point |
//! | revolute | 5 | point; `z_i·x_j = 0`, `z_i·y_j = 0` |
//! | universal | 4 | point; `z_i·z_j = 0` (axis `i` on body `i`, axis `j` on body `j`) |
//! | cylindrical | 4 | `z_i·x_j`, `z_i·y_j`; `x_i·d`, `y_i·d` |
//! | prismatic | 5 | cylindrical; `x_i·y_j = 0` |
//! | fixed | 6 | point; `z_i·x_j`, `z_i·y_j`, `x_i·y_j` |
//! | distance | 1 | `|P_j − P_i| = L` (`L` from the initial configuration) |
//! | point on line | 2 | `x_i·d = 0`, `y_i·d = 0` (line through `P_i` along `z_i`) |
//! | point in plane | 1 | `z_i·d = 0` (plane through `P_i` with normal `z_i`) |
//! | parallel | 2 | `z_i·x_j = 0`, `z_i·y_j = 0` |
//! | perpendicular | 1 | `z_i·z_j = 0` |
//!
//! `d = P_j − P_i`.

pub(crate) mod primitives;
pub(crate) mod second_derivatives;

use crate::frame::Frame;
use crate::BodyRef;
use dalembert_system::ModelError;
use nalgebra::{Matrix3, Vector3};
use primitives::Primitive;

type V3 = Vector3<f64>;

/// The kinds of joint.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum JointKind {
    /// Ball joint: the two points coincide (3 equations).
    Spherical,
    /// Hinge about an axis (5).
    Revolute,
    /// Cardan joint: points coincide, axis `i` stays perpendicular to axis `j` (4).
    Universal,
    /// Slides along and turns about an axis (4).
    Cylindrical,
    /// Slides along an axis (5).
    Prismatic,
    /// Welds the bodies together (6).
    Fixed,
    /// Keeps two points at their initial distance (1).
    Distance,
    /// A point of `j` stays on a line of `i` (2).
    PointOnLine,
    /// A point of `j` stays in a plane of `i` (1).
    PointInPlane,
    /// An axis of `j` stays parallel to an axis of `i` (2).
    Parallel,
    /// An axis of `j` stays perpendicular to an axis of `i` (1).
    Perpendicular,
}

impl JointKind {
    /// Name used in messages and scenes.
    pub fn name(self) -> &'static str {
        match self {
            JointKind::Spherical => "spherical",
            JointKind::Revolute => "revolute",
            JointKind::Universal => "universal",
            JointKind::Cylindrical => "cylindrical",
            JointKind::Prismatic => "prismatic",
            JointKind::Fixed => "fixed",
            JointKind::Distance => "distance",
            JointKind::PointOnLine => "point-on-line",
            JointKind::PointInPlane => "point-in-plane",
            JointKind::Parallel => "parallel",
            JointKind::Perpendicular => "perpendicular",
        }
    }

    /// Every kind, for generated tests and messages.
    pub const ALL: [JointKind; 11] = [
        JointKind::Spherical,
        JointKind::Revolute,
        JointKind::Universal,
        JointKind::Cylindrical,
        JointKind::Prismatic,
        JointKind::Fixed,
        JointKind::Distance,
        JointKind::PointOnLine,
        JointKind::PointInPlane,
        JointKind::Parallel,
        JointKind::Perpendicular,
    ];
}

/// A joint as placed in the initial configuration (global components).
#[derive(Debug, Clone, PartialEq)]
pub struct Joint {
    /// Name (messages and output).
    pub name: String,
    /// Kind.
    pub kind: JointKind,
    /// First body.
    pub body_i: BodyRef,
    /// Second body.
    pub body_j: BodyRef,
    /// The joint's point (on both bodies; for a distance joint, on body `i`).
    pub point: V3,
    /// The point on body `j` for a distance joint (equal to `point` otherwise).
    pub point_j: V3,
    /// The joint axis on body `i` (hinge or sliding axis, line direction, plane normal).
    pub axis: V3,
    /// The axis on body `j` (universal and perpendicular joints; equal to `axis` otherwise).
    pub axis_j: V3,
}

impl Joint {
    /// A joint of `kind` at `point` with `axis` (ignored by spherical, fixed and distance joints;
    /// universal and perpendicular joints need [`Joint::crossed`]).
    pub fn new(name: &str, kind: JointKind, body_i: BodyRef, body_j: BodyRef, point: [f64; 3], axis: [f64; 3]) -> Self {
        let (point, axis) = (V3::from(point), V3::from(axis));
        Joint {
            name: name.to_string(),
            kind,
            body_i,
            body_j,
            point,
            point_j: point,
            axis,
            axis_j: axis,
        }
    }

    /// A ball joint at `point`.
    pub fn spherical(name: &str, body_i: BodyRef, body_j: BodyRef, point: [f64; 3]) -> Self {
        Joint::new(name, JointKind::Spherical, body_i, body_j, point, [0.0, 0.0, 1.0])
    }

    /// A hinge at `point` about `axis`.
    pub fn revolute(name: &str, body_i: BodyRef, body_j: BodyRef, point: [f64; 3], axis: [f64; 3]) -> Self {
        Joint::new(name, JointKind::Revolute, body_i, body_j, point, axis)
    }

    /// A joint with one axis on each body (universal at `point`, or perpendicular).
    pub fn crossed(
        name: &str,
        kind: JointKind,
        body_i: BodyRef,
        body_j: BodyRef,
        point: [f64; 3],
        axis_i: [f64; 3],
        axis_j: [f64; 3],
    ) -> Self {
        Joint {
            axis_j: V3::from(axis_j),
            ..Joint::new(name, kind, body_i, body_j, point, axis_i)
        }
    }

    /// Keeps `point_i` (on body `i`) and `point_j` (on body `j`) at their initial distance.
    pub fn distance(name: &str, body_i: BodyRef, point_i: [f64; 3], body_j: BodyRef, point_j: [f64; 3]) -> Self {
        Joint {
            point_j: V3::from(point_j),
            ..Joint::new(name, JointKind::Distance, body_i, body_j, point_i, [0.0, 0.0, 1.0])
        }
    }
}

/// A unit `z` along `axis` completed to a right-handed orthonormal frame `(x, y, z)`: `x` is the
/// unit vector of `e × z` for the global axis `e` least aligned with `z`.
pub fn complete_frame(axis: &V3) -> [V3; 3] {
    let z = axis.normalize();
    let k = (0..3).min_by(|&a, &b| z[a].abs().total_cmp(&z[b].abs())).unwrap_or(0);
    let x = V3::ith(k, 1.0).cross(&z).normalize();
    [x, z.cross(&x), z]
}

/// A joint in body-frame terms: its primitives and the label of each equation.
#[derive(Debug, Clone)]
pub(crate) struct JointData {
    pub name: String,
    pub body_i: Option<usize>,
    pub body_j: Option<usize>,
    pub primitives: Vec<Primitive>,
    pub labels: Vec<&'static str>,
    /// The joint's point on body `i` (body frame): where its reaction moment is taken.
    pub point_i: V3,
    /// The joint frame's axes `x, y, z` on body `i` (body frame, columns).
    pub axes_i: Matrix3<f64>,
    /// The joint's point and axes on body `j` (drivers measure from them).
    pub point_j: V3,
    /// The joint frame's axes on body `j` (body frame, columns).
    pub axes_j: Matrix3<f64>,
    /// The joint's kind (`None` for a driver).
    pub kind: Option<JointKind>,
}

fn invalid(joint: &Joint, what: impl Into<String>) -> ModelError {
    ModelError::InvalidParameter {
        element: format!("joint '{}'", joint.name),
        what: what.into(),
    }
}

impl JointData {
    /// Markers from the global description and the bodies' initial frames.
    pub fn new(
        joint: &Joint,
        body_i: Option<usize>,
        body_j: Option<usize>,
        fi: &Frame,
        fj: &Frame,
    ) -> Result<Self, ModelError> {
        let finite = [joint.point, joint.point_j, joint.axis, joint.axis_j]
            .iter()
            .all(|v| v.iter().all(|x| x.is_finite()));
        if !finite {
            return Err(invalid(joint, "points and axes must be finite"));
        }
        if body_i.is_some() && body_i == body_j || body_i.is_none() && body_j.is_none() {
            return Err(invalid(joint, "must join two different bodies (one may be the ground)"));
        }
        for (axis, which) in [(joint.axis, "axis"), (joint.axis_j, "second axis")] {
            if axis.norm() < 1e-12 {
                return Err(invalid(joint, format!("{which} must not be zero")));
            }
        }
        let local_i = |v: &V3| fi.a.transpose() * v;
        let local_j = |v: &V3| fj.a.transpose() * v;
        let [x, y, z] = complete_frame(&joint.axis);
        let si = local_i(&(joint.point - fi.r));
        let sj = local_j(&(joint.point - fj.r));
        let point = Primitive::Point { si, sj };
        let dot1 = |a: &V3, b: &V3| Primitive::Dot1 {
            ai: local_i(a),
            aj: local_j(b),
            value: 0.0,
        };
        let dot2 = |a: &V3| Primitive::Dot2 {
            ai: local_i(a),
            si,
            sj,
            value: 0.0,
        };
        let crossed = || -> Result<Primitive, ModelError> {
            let (a, b) = (joint.axis.normalize(), joint.axis_j.normalize());
            if a.dot(&b).abs() > 1e-9 {
                return Err(invalid(
                    joint,
                    format!("its two axes must be perpendicular (cosine {:.3e})", a.dot(&b)),
                ));
            }
            Ok(dot1(&a, &b))
        };
        use JointKind as K;
        let (primitives, labels): (Vec<Primitive>, Vec<&'static str>) = match joint.kind {
            K::Spherical => (vec![point], vec!["x", "y", "z"]),
            K::Revolute => (
                vec![point, dot1(&z, &x), dot1(&z, &y)],
                vec!["x", "y", "z", "axis x", "axis y"],
            ),
            K::Universal => (vec![point, crossed()?], vec!["x", "y", "z", "cross"]),
            K::Cylindrical => (
                vec![dot1(&z, &x), dot1(&z, &y), dot2(&x), dot2(&y)],
                vec!["axis x", "axis y", "line x", "line y"],
            ),
            K::Prismatic => (
                vec![dot1(&z, &x), dot1(&z, &y), dot2(&x), dot2(&y), dot1(&x, &y)],
                vec!["axis x", "axis y", "line x", "line y", "twist"],
            ),
            K::Fixed => (
                vec![point, dot1(&z, &x), dot1(&z, &y), dot1(&x, &y)],
                vec!["x", "y", "z", "axis x", "axis y", "twist"],
            ),
            K::Distance => {
                let length = (joint.point_j - joint.point).norm();
                if length < 1e-12 {
                    return Err(invalid(joint, "its two points coincide: use a spherical joint"));
                }
                let d = Primitive::Distance {
                    si,
                    sj: local_j(&(joint.point_j - fj.r)),
                    length,
                };
                (vec![d], vec!["distance"])
            }
            K::PointOnLine => (vec![dot2(&x), dot2(&y)], vec!["line x", "line y"]),
            K::PointInPlane => (vec![dot2(&z)], vec!["plane"]),
            K::Parallel => (vec![dot1(&z, &x), dot1(&z, &y)], vec!["axis x", "axis y"]),
            K::Perpendicular => (vec![crossed()?], vec!["cross"]),
        };
        Ok(JointData {
            name: joint.name.clone(),
            kind: Some(joint.kind),
            body_i,
            body_j,
            primitives,
            labels,
            point_i: si,
            axes_i: fi.a.transpose() * Matrix3::from_columns(&[x, y, z]),
            point_j: sj,
            axes_j: fj.a.transpose() * Matrix3::from_columns(&[x, y, z]),
        })
    }

    /// Number of scalar equations.
    pub fn num_equations(&self) -> usize {
        self.labels.len()
    }
}
