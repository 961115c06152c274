use crate::primitives::hessian;
use crate::primitives::point_coincidence;
use crate::{Constraint, ConstraintEval, ConstraintRole};
use dalembert_kinematics::{BodyRef, BodyState, PointState, Vec2};

/// Revolute (pin) joint: point `u_i` of the first body coincides with point `u_j` of the second.
///
/// `C = R_i + A_i u_i − R_j − A_j u_j` (2 equations). The reaction is a force at the pin.
#[derive(Debug, Clone, PartialEq)]
pub struct Revolute {
    /// Joint name.
    pub name: String,
    /// `[first, second]`.
    pub bodies: [BodyRef; 2],
    /// Local pin point on each body.
    pub points: [Vec2; 2],
}

impl Revolute {
    /// A pin between `bodies` at local points `points`.
    pub fn new(name: impl Into<String>, bodies: [BodyRef; 2], points: [Vec2; 2]) -> Self {
        Revolute {
            name: name.into(),
            bodies,
            points,
        }
    }

    /// A pin at the global point `p` of configuration `q`.
    pub fn at(name: impl Into<String>, bodies: [BodyRef; 2], p: Vec2, q: &[f64]) -> Self {
        let points = [
            super::local_point_of(bodies[0], q, p),
            super::local_point_of(bodies[1], q, p),
        ];
        Revolute::new(name, bodies, points)
    }
}

impl Constraint for Revolute {
    fn name(&self) -> &str {
        &self.name
    }
    fn bodies(&self) -> [BodyRef; 2] {
        self.bodies
    }
    fn num_equations(&self) -> usize {
        2
    }
    fn role(&self) -> ConstraintRole {
        ConstraintRole::Joint { carries_torque: false }
    }
    fn equation_label(&self, k: usize) -> &'static str {
        ["x", "y"][k]
    }
    fn evaluate(&self, _t: f64, first: &BodyState, second: &BodyState, out: &mut ConstraintEval) {
        let rows = point_coincidence(first, self.points[0], second, self.points[1]);
        out.set_row(0, &rows[0]);
        out.set_row(1, &rows[1]);
    }
    fn weighted_hessian(
        &self,
        _t: f64,
        first: &BodyState,
        second: &BodyState,
        lambda: &[f64],
    ) -> Option<dalembert_kinematics::second_derivatives::Pair6> {
        Some(hessian::point_coincidence(
            first,
            self.points[0],
            second,
            self.points[1],
            [lambda[0], lambda[1]],
        ))
    }
    fn reaction_point(&self, first: &BodyState, _second: &BodyState) -> Vec2 {
        PointState::new(first, self.points[0]).position
    }
    fn validate(&self) -> Result<(), dalembert_system::ModelError> {
        let p = &self.points;
        super::check_finite(&self.name, "pin points", &[p[0].x, p[0].y, p[1].x, p[1].y])
    }
}
