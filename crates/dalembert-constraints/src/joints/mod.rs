//! Joints: passive constraints between two bodies (either may be the ground).
//!
//! Local points and directions are in each body's frame; for the ground they are global.
//! [`local_point_of`] converts a global point of the current configuration to a body's frame.

mod distance;
mod gear;
mod point_on_line;
mod prismatic;
mod rack_pinion;
mod revolute;
mod rigid;

pub use distance::Distance;
pub use gear::Gear;
pub use point_on_line::PointOnLine;
pub use prismatic::Prismatic;
pub use rack_pinion::RackPinion;
pub use revolute::Revolute;
pub use rigid::Rigid;

use dalembert_kinematics::{point::local_point, BodyRef, BodyState, ModelError, Vec2};

/// The local coordinates, in `body`'s frame at configuration `q`, of global point `p`.
pub fn local_point_of(body: BodyRef, q: &[f64], p: Vec2) -> Vec2 {
    let s = BodyState::of(body, q, &[]);
    local_point(s.position, s.angle, p)
}

/// The local components, in `body`'s frame at configuration `q`, of global direction `v`.
pub fn local_direction_of(body: BodyRef, q: &[f64], v: Vec2) -> Vec2 {
    let s = BodyState::of(body, q, &[]);
    dalembert_kinematics::rotation(s.angle).transpose() * v
}

pub(crate) fn check_finite(name: &str, what: &str, xs: &[f64]) -> Result<(), ModelError> {
    if xs.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(ModelError::InvalidParameter {
            element: format!("joint '{name}'"),
            what: format!("{what} must be finite"),
        })
    }
}

pub(crate) fn check_direction(name: &str, v: Vec2) -> Result<(), ModelError> {
    if crate::primitives::unit(v).is_some() {
        Ok(())
    } else {
        Err(ModelError::InvalidParameter {
            element: format!("joint '{name}'"),
            what: "axis/direction must be a finite non-zero vector".into(),
        })
    }
}
