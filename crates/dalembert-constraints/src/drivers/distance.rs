use crate::primitives::distance;
use crate::primitives::hessian;
use crate::{Constraint, ConstraintEval, ConstraintRole};
use dalembert_kinematics::{BodyRef, BodyState, PointState, Vec2};
use dalembert_system::TimeFunction;

/// Prescribes the distance between two points: `C = |p_j − p_i| − f(t)` (a linear actuator).
/// The effort `−λ` is the actuator force, positive when it pushes the points apart.
#[derive(Debug, Clone)]
pub struct DistanceDriver {
    /// Driver name.
    pub name: String,
    /// `[first, second]`.
    pub bodies: [BodyRef; 2],
    /// Local points on each body.
    pub points: [Vec2; 2],
    /// `f(t)`: the distance.
    pub function: TimeFunction,
}

impl Constraint for DistanceDriver {
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
        "length"
    }
    fn evaluate(&self, t: f64, first: &BodyState, second: &BodyState, out: &mut ConstraintEval) {
        let row = distance(first, self.points[0], second, self.points[1]).unwrap_or_default();
        out.set_row(0, &row.drive(self.function.eval(t)));
    }
    fn weighted_hessian(
        &self,
        _t: f64,
        first: &BodyState,
        second: &BodyState,
        lambda: &[f64],
    ) -> Option<dalembert_kinematics::second_derivatives::Pair6> {
        hessian::distance(first, self.points[0], second, self.points[1], lambda[0])
    }
    fn reaction_point(&self, first: &BodyState, _second: &BodyState) -> Vec2 {
        PointState::new(first, self.points[0]).position
    }
    fn validate(&self) -> Result<(), dalembert_system::ModelError> {
        self.function.validate(&format!("driver '{}'", self.name))
    }
}
