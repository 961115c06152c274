//! Forces computed by the caller's code: a scene's `type = "code"` force element on one body, whose
//! wrench a [`crate::Simulator`] asks a Rust closure or a Python function for at every stage
//! ([`crate::Simulator::set_force`]). Outside a simulator with a function set (a run from start to
//! end, a check) the element applies nothing, as an input reads 0 before it is set.
//!
//! The function gets the time and the body's motion ([`BodyMotion`]: centre of mass, rotation,
//! velocity and angular velocity, global) and returns a force at the centre of mass and a torque
//! ([`Wrench`](dalembert_system::inputs::Wrench), global). The same function serves planar and spatial bodies (a planar one moves in
//! the x–y plane and takes `force[0]`, `force[1]` and `torque[2]`).

use dalembert_kinematics::forces::{add_point_force, add_torque, check_body, ForceElement};
use dalembert_kinematics::{Body, BodyRef, BodyState, PointState, Vec2};
use dalembert_spatial::forces::{Frames, Loads, UserForce};
use dalembert_system::inputs::{code_force, BodyMotion};
use nalgebra::Vector3;

/// A planar code force: element `index` of the model's code forces, on `body`.
#[derive(Debug, Clone)]
pub struct PlanarCodeForce {
    /// Element name.
    pub name: String,
    /// The body it loads.
    pub body: BodyRef,
    /// Its index among the model's code forces.
    pub index: usize,
}

impl ForceElement for PlanarCodeForce {
    fn name(&self) -> &str {
        &self.name
    }

    fn add_generalized_force(&self, t: f64, bodies: &[Body], q: &[f64], qd: &[f64], q_e: &mut [f64]) {
        let Some(id) = self.body.id() else {
            return;
        };
        let s = BodyState::of(self.body, q, qd);
        let p = PointState::new(&s, bodies[id.0].center_of_mass);
        let (c, si) = (s.cos, s.sin);
        let motion = BodyMotion {
            position: [p.position.x, p.position.y, 0.0],
            rotation: [[c, -si, 0.0], [si, c, 0.0], [0.0, 0.0, 1.0]],
            velocity: [p.velocity.x, p.velocity.y, 0.0],
            angular_velocity: [0.0, 0.0, s.omega],
        };
        let w = code_force(self.index, t, &motion);
        add_point_force(self.body, &p, Vec2::new(w.force[0], w.force[1]), q_e);
        add_torque(self.body, w.torque[2], q_e);
    }

    fn validate(&self, bodies: usize) -> Result<(), dalembert_system::ModelError> {
        check_body(&self.name, self.body, bodies)
    }

    fn bodies(&self) -> Option<Vec<BodyRef>> {
        Some(vec![self.body])
    }
}

/// A spatial code force: element `index` of the model's code forces, on `body`.
#[derive(Debug, Clone)]
pub struct SpatialCodeForce {
    /// Element name.
    pub name: String,
    /// The body it loads.
    pub body: dalembert_spatial::BodyRef,
    /// Its index among the model's code forces.
    pub index: usize,
}

impl UserForce for SpatialCodeForce {
    fn name(&self) -> &str {
        &self.name
    }

    fn bodies(&self) -> Vec<dalembert_spatial::BodyRef> {
        vec![self.body]
    }

    fn add(&self, t: f64, frames: &Frames<'_>, loads: &mut Loads<'_>) {
        let f = frames.of(self.body);
        let a = f.a;
        let motion = BodyMotion {
            position: [f.r.x, f.r.y, f.r.z],
            rotation: [
                [a[(0, 0)], a[(0, 1)], a[(0, 2)]],
                [a[(1, 0)], a[(1, 1)], a[(1, 2)]],
                [a[(2, 0)], a[(2, 1)], a[(2, 2)]],
            ],
            velocity: [f.v.x, f.v.y, f.v.z],
            angular_velocity: [f.w.x, f.w.y, f.w.z],
        };
        let w = code_force(self.index, t, &motion);
        loads.force(self.body, &f.r, &Vector3::from(w.force));
        loads.torque(self.body, &Vector3::from(w.torque));
    }
}
