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

use dalembert_kinematics::{point::local_point, BodyRef, BodyState, Vec2};
use dalembert_system::ModelError;

/// The pose of `body` in `q`, or `None` for a body whose coordinates `q` does not hold (the
/// model's constructor then reports the unknown body by name).
fn pose(body: BodyRef, q: &[f64]) -> Option<BodyState> {
    match body {
        BodyRef::Body(id) if q.len() < id.offset() + 3 => None,
        _ => Some(BodyState::of(body, q, &[])),
    }
}

/// The pose of `body` in `q` for a joint constructor, the ground's for a body outside `q` (the
/// joint is then refused by [`crate::Model::new`], naming it, instead of panicking here).
pub(crate) fn pose_or_ground(body: BodyRef, q: &[f64]) -> BodyState {
    pose(body, q).unwrap_or(BodyState::GROUND)
}

/// The local coordinates, in `body`'s frame at configuration `q`, of global point `p`. A body
/// outside `q` gets `p` unchanged: no panic here, and [`crate::Model::new`] names the joint that
/// refers to a body the model does not have.
pub fn local_point_of(body: BodyRef, q: &[f64], p: Vec2) -> Vec2 {
    pose(body, q).map_or(p, |s| local_point(s.position, s.angle, p))
}

/// The local components, in `body`'s frame at configuration `q`, of global direction `v` (`v`
/// unchanged for a body outside `q`, as in [`local_point_of`]).
pub fn local_direction_of(body: BodyRef, q: &[f64], v: Vec2) -> Vec2 {
    pose(body, q).map_or(v, |s| dalembert_kinematics::rotation(s.angle).transpose() * v)
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
