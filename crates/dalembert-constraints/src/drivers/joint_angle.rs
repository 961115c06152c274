use crate::primitives::relative_angle;
use crate::{Constraint, ConstraintEval, ConstraintRole, Revolute};
use dalembert_kinematics::{BodyRef, BodyState, Vec2};
use dalembert_system::TimeFunction;

/// Prescribes the relative angle of a revolute joint: `C = θ_j − θ_i − f(t)`. Its effort `−λ` is
/// the motor torque on the joint's second body (and `+λ` on the first).
#[derive(Debug, Clone)]
pub struct JointAngle {
    /// Driver name.
    pub name: String,
    /// The joint's bodies `[first, second]`.
    pub bodies: [BodyRef; 2],
    /// Point about which the torque is reported (global, of the first body's pin point).
    pub pin: Vec2,
    /// `f(t)`: the relative angle `θ_j − θ_i`.
    pub function: TimeFunction,
}

impl JointAngle {
    /// Drives the relative angle of `joint` with `function`.
    pub fn on(name: impl Into<String>, joint: &Revolute, function: TimeFunction) -> Self {
        JointAngle {
            name: name.into(),
            bodies: joint.bodies,
            pin: joint.points[0],
            function,
        }
    }
}

impl Constraint for JointAngle {
    fn name(&self) -> &str {
        &self.name
    }
    fn bodies(&self) -> [BodyRef; 2] {
        self.bodies
    }
    fn num_equations(&self) -> usize {
        1
    }
    fn role(&self) -> ConstraintRole {
        ConstraintRole::Driver
    }
    fn equation_label(&self, _k: usize) -> &'static str {
        "angle"
    }
    fn evaluate(&self, t: f64, first: &BodyState, second: &BodyState, out: &mut ConstraintEval) {
        out.set_row(0, &relative_angle(first, second, 1.0).drive(self.function.eval(t)));
    }
    /// Linear in the coordinates: no second derivative.
    fn weighted_hessian(
        &self,
        _t: f64,
        _first: &BodyState,
        _second: &BodyState,
        _lambda: &[f64],
    ) -> Option<dalembert_kinematics::second_derivatives::Pair6> {
        Some(crate::primitives::hessian::linear())
    }
    fn reaction_point(&self, first: &BodyState, _second: &BodyState) -> Vec2 {
        dalembert_kinematics::PointState::new(first, self.pin).position
    }
    fn validate(&self) -> Result<(), dalembert_system::ModelError> {
        self.function.validate(&format!("driver '{}'", self.name))
    }
}
