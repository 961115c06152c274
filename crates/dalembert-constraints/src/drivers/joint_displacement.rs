use crate::primitives::hessian;
use crate::primitives::{line_coordinate, unit};
use crate::{Constraint, ConstraintEval, ConstraintRole, Prismatic};
use dalembert_kinematics::{BodyRef, BodyState, PointState, Vec2};
use dalembert_system::TimeFunction;

/// Prescribes the displacement of a prismatic joint: `C = a_iᵀ (p_j − p_i) − f(t)` with `a_i` the
/// unit axis in the first body. The effort `−λ` is the actuator force on the second body along the axis.
#[derive(Debug, Clone)]
pub struct JointDisplacement {
    /// Driver name.
    pub name: String,
    /// The joint's bodies.
    pub bodies: [BodyRef; 2],
    /// The joint's local points.
    pub points: [Vec2; 2],
    /// The joint's axis (first body frame).
    pub axis: Vec2,
    /// `f(t)`: the displacement along the axis.
    pub function: TimeFunction,
}

impl JointDisplacement {
    /// Drives the displacement of `joint` with `function`.
    pub fn on(name: impl Into<String>, joint: &Prismatic, function: TimeFunction) -> Self {
        JointDisplacement {
            name: name.into(),
            bodies: joint.bodies,
            points: joint.points,
            axis: joint.axis,
            function,
        }
    }
}

impl Constraint for JointDisplacement {
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
        "displacement"
    }
    fn evaluate(&self, t: f64, first: &BodyState, second: &BodyState, out: &mut ConstraintEval) {
        let a = unit(self.axis).unwrap_or(Vec2::x());
        let row = line_coordinate(first, self.points[0], a, second, self.points[1]);
        out.set_row(0, &row.drive(self.function.eval(t)));
    }
    fn weighted_hessian(
        &self,
        _t: f64,
        first: &BodyState,
        second: &BodyState,
        lambda: &[f64],
    ) -> Option<dalembert_kinematics::second_derivatives::Pair6> {
        let a = unit(self.axis).unwrap_or(Vec2::x());
        Some(hessian::line_coordinate(
            first,
            self.points[0],
            a,
            second,
            self.points[1],
            lambda[0],
        ))
    }
    fn reaction_point(&self, _first: &BodyState, second: &BodyState) -> Vec2 {
        PointState::new(second, self.points[1]).position
    }
    fn validate(&self) -> Result<(), dalembert_system::ModelError> {
        crate::joints::check_direction(&self.name, self.axis)?;
        self.function.validate(&format!("driver '{}'", self.name))
    }
}
