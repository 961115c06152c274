use crate::primitives::distance;
use crate::primitives::hessian;
use crate::{Constraint, ConstraintEval, ConstraintRole};
use dalembert_kinematics::{BodyRef, BodyState, PointState, Vec2};

/// Distance joint (massless rod): `C = |p_j − p_i| − L` (1 equation). With this form `λ` is the rod's
/// tension in newtons (positive pulls the points together).
#[derive(Debug, Clone, PartialEq)]
pub struct Distance {
    /// Joint name.
    pub name: String,
    /// `[first, second]`.
    pub bodies: [BodyRef; 2],
    /// Local end points on each body.
    pub points: [Vec2; 2],
    /// Rod length `L` (> 0).
    pub length: f64,
}

impl Distance {
    /// A rod between global points `a` (on the first body) and `b` (on the second) of configuration
    /// `q`, with the length they have there.
    pub fn between(name: impl Into<String>, bodies: [BodyRef; 2], a: Vec2, b: Vec2, q: &[f64]) -> Self {
        Distance {
            name: name.into(),
            points: [
                super::local_point_of(bodies[0], q, a),
                super::local_point_of(bodies[1], q, b),
            ],
            bodies,
            length: (b - a).norm(),
        }
    }
}

impl Constraint for Distance {
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
        ConstraintRole::Joint { carries_torque: false }
    }
    fn equation_label(&self, _k: usize) -> &'static str {
        "length"
    }
    fn evaluate(&self, _t: f64, first: &BodyState, second: &BodyState, out: &mut ConstraintEval) {
        // Coincident end points: the Jacobian row is zero there and the structure check reports it.
        let row = distance(first, self.points[0], second, self.points[1]).unwrap_or_default();
        out.set_row(0, &row.drive([self.length, 0.0, 0.0]));
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
        let p = &self.points;
        super::check_finite(
            &self.name,
            "points and length",
            &[p[0].x, p[0].y, p[1].x, p[1].y, self.length],
        )?;
        if self.length <= 0.0 {
            return Err(dalembert_system::ModelError::InvalidParameter {
                element: format!("joint '{}'", self.name),
                what: format!("distance must be positive, got {}", self.length),
            });
        }
        Ok(())
    }
}
