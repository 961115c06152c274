//! Drivers: prescribed motions `s(q) = f(t)` (the driver effort is `−λ`, `docs/sign-conventions.md`
//! §3).
//!
//! | target | `s(q)` | effort |
//! |---|---|---|
//! | joint angle (revolute, cylindrical) | rotation of body `j` relative to body `i` about the joint axis, right-handed, 0 in the initial configuration | torque about the axis on body `j` |
//! | joint displacement (prismatic, cylindrical) | `z_i · (P_j − P_i)`, 0 in the initial configuration | force along the axis on body `j` |
//! | body coordinate | `x`, `y` or `z` of a body's centre of mass | force along that axis |

use crate::joints::primitives::Primitive;
use crate::joints::{JointData, JointKind};
use crate::BodyRef;
use dalembert_system::{ModelError, TimeFunction};
use nalgebra::{Matrix3, Vector3};

/// What a driver prescribes.
#[derive(Debug, Clone)]
#[non_exhaustive]
pub enum DriverTarget {
    /// The angle of the named revolute or cylindrical joint.
    JointAngle(String),
    /// The displacement of the named prismatic or cylindrical joint.
    JointDisplacement(String),
    /// Centre-of-mass coordinate `axis` (0: x, 1: y, 2: z) of a body.
    BodyCoordinate {
        /// The body.
        body: BodyRef,
        /// 0, 1 or 2.
        axis: usize,
    },
}

/// A prescribed motion `s(q) = f(t)`.
#[derive(Debug, Clone)]
pub struct Driver {
    /// Name (messages and output).
    pub name: String,
    /// What is driven.
    pub target: DriverTarget,
    /// `f(t)` (should start at the target's initial value for a consistent start).
    pub function: TimeFunction,
}

impl Driver {
    /// A driver named `name` of `target` following `function`.
    pub fn new(name: &str, target: DriverTarget, function: TimeFunction) -> Self {
        Driver {
            name: name.to_string(),
            target,
            function,
        }
    }

    /// Builds the driver's constraint from the joints already built (`index` resolves a body).
    pub(crate) fn data(
        &self,
        joints: &[JointData],
        index: &dyn Fn(BodyRef) -> Result<Option<usize>, ModelError>,
    ) -> Result<JointData, ModelError> {
        let bad = |what: String| ModelError::InvalidParameter {
            element: format!("driver '{}'", self.name),
            what,
        };
        self.function.validate(&format!("driver '{}'", self.name))?;
        let f = self.function.clone();
        let joint = |name: &str, kinds: &[JointKind], what: &str| {
            joints
                .iter()
                .find(|j| j.name == name)
                .ok_or_else(|| bad(format!("no joint named '{name}'")))
                .and_then(|j| match j.kind {
                    Some(k) if kinds.contains(&k) => Ok(j),
                    Some(k) => Err(bad(format!(
                        "joint '{name}' is {}: a {what} driver needs a {}",
                        k.name(),
                        kinds.iter().map(|k| k.name()).collect::<Vec<_>>().join(" or ")
                    ))),
                    None => Err(bad(format!("'{name}' is a driver, not a joint"))),
                })
        };
        let column = |m: &Matrix3<f64>, k: usize| -> Vector3<f64> { m.column(k).into() };
        let (body_i, body_j, primitive, label, point_i, axes_i) = match &self.target {
            DriverTarget::JointAngle(name) => {
                let j = joint(name, &[JointKind::Revolute, JointKind::Cylindrical], "joint-angle")?;
                let p = Primitive::Angle {
                    xi: column(&j.axes_i, 0),
                    yi: column(&j.axes_i, 1),
                    xj: column(&j.axes_j, 0),
                    f,
                };
                (j.body_i, j.body_j, p, "angle", j.point_i, j.axes_i)
            }
            DriverTarget::JointDisplacement(name) => {
                let j = joint(
                    name,
                    &[JointKind::Prismatic, JointKind::Cylindrical],
                    "joint-displacement",
                )?;
                let p = Primitive::Slide {
                    ai: column(&j.axes_i, 2),
                    si: j.point_i,
                    sj: j.point_j,
                    f,
                };
                (j.body_i, j.body_j, p, "displacement", j.point_i, j.axes_i)
            }
            DriverTarget::BodyCoordinate { body, axis } => {
                if *axis > 2 {
                    return Err(bad(format!("coordinate axis must be 0, 1 or 2, got {axis}")));
                }
                let b = index(*body)?.ok_or_else(|| bad("drives the ground: give it a moving body".into()))?;
                let label = ["x", "y", "z"][*axis];
                let p = Primitive::Coordinate { k: *axis, f };
                (None, Some(b), p, label, Vector3::zeros(), Matrix3::identity())
            }
        };
        Ok(JointData {
            name: self.name.clone(),
            body_i,
            body_j,
            primitives: vec![primitive],
            labels: vec![label],
            point_i,
            axes_i,
            point_j: Vector3::zeros(),
            axes_j: Matrix3::identity(),
            kind: None,
        })
    }
}
