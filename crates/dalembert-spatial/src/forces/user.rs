//! Forces the user writes: implement [`UserForce`] and add it with
//! `ModelBuilder::force(Force::User(Arc::new(..)))`. The element reads the bodies' frames
//! ([`Frames`]) and writes global forces and torques ([`Loads`]); the model turns them into
//! generalized forces as for its own elements.

use super::{add_point_force, add_torque};
use crate::frame::Frame;
use crate::BodyRef;
use nalgebra::Vector3;

/// A user-written force element.
///
/// [`UserForce::add`] runs inside the stepping loop: it must not allocate. It may touch only the
/// bodies [`UserForce::bodies`] names (the model checks they exist when it is built).
pub trait UserForce: Send + Sync + std::fmt::Debug {
    /// Name used in messages.
    fn name(&self) -> &str;

    /// The bodies the element reads or loads.
    fn bodies(&self) -> Vec<BodyRef>;

    /// Adds the element's loads at time `t` for the bodies' state in `frames`.
    fn add(&self, t: f64, frames: &Frames<'_>, loads: &mut Loads<'_>);

    /// Potential energy at `t`, if the element has one (counted in the model's energy).
    fn potential(&self, _t: f64, _frames: &Frames<'_>) -> Option<f64> {
        None
    }

    /// True when the element does no work beyond [`UserForce::potential`]. Default `false`.
    fn is_conservative(&self) -> bool {
        false
    }
}

/// The bodies' frames (position, orientation, velocity, angular velocity) at one state.
pub struct Frames<'a> {
    frame: &'a dyn Fn(Option<usize>) -> Frame,
}

impl<'a> Frames<'a> {
    pub(crate) fn new(frame: &'a dyn Fn(Option<usize>) -> Frame) -> Self {
        Frames { frame }
    }

    /// The frame of `body` (the ground: at the origin, at rest).
    pub fn of(&self, body: BodyRef) -> Frame {
        (self.frame)(index(body))
    }
}

/// Where a [`UserForce`] writes its loads.
pub struct Loads<'a> {
    frame: &'a dyn Fn(Option<usize>) -> Frame,
    out: &'a mut [f64],
}

fn index(body: BodyRef) -> Option<usize> {
    match body {
        BodyRef::Ground => None,
        BodyRef::Body(i) => Some(i),
    }
}

impl<'a> Loads<'a> {
    pub(crate) fn new(frame: &'a dyn Fn(Option<usize>) -> Frame, out: &'a mut [f64]) -> Self {
        Loads { frame, out }
    }

    /// A global force `force` at the global point `point` of `body` (nothing on the ground).
    pub fn force(&mut self, body: BodyRef, point: &Vector3<f64>, force: &Vector3<f64>) {
        if let BodyRef::Body(b) = body {
            let f = (self.frame)(Some(b));
            add_point_force(self.out, b, &f, &(point - f.r), force);
        }
    }

    /// A global torque on `body` (nothing on the ground).
    pub fn torque(&mut self, body: BodyRef, torque: &Vector3<f64>) {
        if let BodyRef::Body(b) = body {
            add_torque(self.out, b, &(self.frame)(Some(b)), torque);
        }
    }
}
