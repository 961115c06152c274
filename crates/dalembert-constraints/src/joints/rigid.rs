use crate::primitives::hessian;
use crate::primitives::{point_coincidence, relative_angle};
use crate::{Constraint, ConstraintEval, ConstraintRole};
use dalembert_kinematics::{BodyId, BodyRef, BodyState, PointState, Vec2};

/// Rigid (weld) joint: a revolute joint plus a fixed relative angle `θ_j − θ_i = θ₀` (3 equations).
/// With the ground as first body it fixes a body in place ([`Rigid::fix`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Rigid {
    /// Joint name.
    pub name: String,
    /// `[first, second]`.
    pub bodies: [BodyRef; 2],
    /// Local weld point on each body.
    pub points: [Vec2; 2],
    /// Relative angle `θ_j − θ_i` held fixed.
    pub angle: f64,
}

impl Rigid {
    /// A weld at global point `p`, holding the relative angle of configuration `q`.
    pub fn at(name: impl Into<String>, bodies: [BodyRef; 2], p: Vec2, q: &[f64]) -> Self {
        let si = super::pose_or_ground(bodies[0], q);
        let sj = super::pose_or_ground(bodies[1], q);
        Rigid {
            name: name.into(),
            points: [
                super::local_point_of(bodies[0], q, p),
                super::local_point_of(bodies[1], q, p),
            ],
            bodies,
            angle: sj.angle - si.angle,
        }
    }

    /// Fixes `body` to the ground at the pose it has in `q` (the "ground joint").
    pub fn fix(name: impl Into<String>, body: BodyId, q: &[f64]) -> Self {
        let k = body.offset();
        Rigid {
            name: name.into(),
            bodies: [BodyRef::Ground, BodyRef::Body(body)],
            points: [Vec2::new(q[k], q[k + 1]), Vec2::zeros()],
            angle: q[k + 2],
        }
    }
}

impl Constraint for Rigid {
    fn name(&self) -> &str {
        &self.name
    }
    fn bodies(&self) -> [BodyRef; 2] {
        self.bodies
    }
    fn num_equations(&self) -> usize {
        3
    }
    fn role(&self) -> ConstraintRole {
        ConstraintRole::Joint { carries_torque: true }
    }
    fn equation_label(&self, k: usize) -> &'static str {
        ["x", "y", "angle"][k]
    }
    fn evaluate(&self, _t: f64, first: &BodyState, second: &BodyState, out: &mut ConstraintEval) {
        let rows = point_coincidence(first, self.points[0], second, self.points[1]);
        out.set_row(0, &rows[0]);
        out.set_row(1, &rows[1]);
        out.set_row(2, &relative_angle(first, second, 1.0).drive([self.angle, 0.0, 0.0]));
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
        super::check_finite(
            &self.name,
            "weld points and angle",
            &[p[0].x, p[0].y, p[1].x, p[1].y, self.angle],
        )
    }
}
