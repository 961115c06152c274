//! A force along a prismatic joint's axis by the law the joint torques and servos have
//! ([`AxisLaw`]): `F = clamp(−k (s − s₀ − s*(t)) − c ṡ + f(t), F_lo, F_hi)` with `s` the joint's
//! displacement (0 in the initial configuration) and `ṡ` its rate, `+F` along the axis on the
//! joint's second body and `−F` on its first. Its generalized force is `F` times the row of the
//! displacement's rate (`ṡ = g · v`, the joint-value row the couplings and limits use), so its
//! virtual work is `F δs` whatever the bodies' poses.

use crate::couplings::joint_value_row;
use crate::frame::{Frame, NV};
use crate::joints::JointData;
use dalembert_system::AxisLaw;

/// The law along a prismatic joint (see the module documentation).
#[derive(Debug, Clone)]
pub(crate) struct SlideForce {
    joint: JointData,
    /// The joint's index in the model.
    index: usize,
    law: AxisLaw,
}

impl SlideForce {
    /// The law along `joint`'s axis (`joint`: its index in the model and its data).
    pub fn new(joint: (usize, &JointData), law: AxisLaw) -> Self {
        SlideForce {
            joint: joint.1.clone(),
            index: joint.0,
            law,
        }
    }

    /// The moving bodies the force acts between.
    pub fn bodies(&self) -> Vec<usize> {
        self.joint.body_i.into_iter().chain(self.joint.body_j).collect()
    }

    /// The joint's index in the model, and the law (for joint coordinates).
    pub fn joint_law(&self) -> (usize, &AxisLaw) {
        (self.index, &self.law)
    }

    /// The displacement at the state behind `frame`.
    pub fn displacement_at(&self, frame: &dyn Fn(Option<usize>) -> Frame) -> f64 {
        joint_value_row(&self.joint, &frame(self.joint.body_i), &frame(self.joint.body_j))
            .0
            .c
    }

    /// Adds `F` times the displacement's rate row at `t`.
    pub fn add(&self, t: f64, frame: &dyn Fn(Option<usize>) -> Frame, out: &mut [f64]) {
        let (fi, fj) = (frame(self.joint.body_i), frame(self.joint.body_j));
        let (row, rate) = joint_value_row(&self.joint, &fi, &fj);
        let (force, _) = self.law.torque(t, row.c - self.law.free(t), rate);
        for (body, f, g) in [(self.joint.body_i, &fi, row.i), (self.joint.body_j, &fj, row.j)] {
            let Some(b) = body else { continue };
            // The rotation part on the body-frame angular velocity: ∂/∂ω' = (∂/∂ω) A.
            let turn = f.a.transpose() * g[1];
            for k in 0..3 {
                out[NV * b + k] += force * g[0][k];
                out[NV * b + 3 + k] += force * turn[k];
            }
        }
    }

    /// `½ k (s − s₀)²`; zero for a servo.
    pub fn potential(&self, t: f64, frame: &dyn Fn(Option<usize>) -> Frame) -> f64 {
        self.law.potential(self.displacement_at(frame) - self.law.free(t))
    }

    /// No damping, no applied force, not a servo.
    pub fn is_conservative(&self) -> bool {
        self.law.is_conservative()
    }
}
