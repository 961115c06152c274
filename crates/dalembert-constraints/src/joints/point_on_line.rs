use crate::primitives::hessian;
use crate::primitives::{line_coordinate, unit};
use crate::{Constraint, ConstraintEval, ConstraintRole};
use dalembert_kinematics::rotation::perp;
use dalembert_kinematics::{BodyRef, BodyState, PointState, Vec2};

/// Point-on-line (pin-in-slot) joint: point `u_j` of the second body stays on the line through
/// `u_i` along `direction`, fixed in the first body; rotation is free.
/// `C = n_iᵀ (p_j − p_i)`, `n_i = A_i perp(direction)` (1 equation).
#[derive(Debug, Clone, PartialEq)]
pub struct PointOnLine {
    /// Joint name.
    pub name: String,
    /// `[first (line), second (point)]`.
    pub bodies: [BodyRef; 2],
    /// Local points: on the line (first body) and the follower point (second body).
    pub points: [Vec2; 2],
    /// Line direction in the first body's frame.
    pub direction: Vec2,
}

impl PointOnLine {
    /// A point-on-line joint through global point `p` with global direction `dir`, in configuration `q`.
    pub fn at(name: impl Into<String>, bodies: [BodyRef; 2], p: Vec2, dir: Vec2, q: &[f64]) -> Self {
        PointOnLine {
            name: name.into(),
            points: [
                super::local_point_of(bodies[0], q, p),
                super::local_point_of(bodies[1], q, p),
            ],
            direction: super::local_direction_of(bodies[0], q, dir),
            bodies,
        }
    }
}

impl Constraint for PointOnLine {
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
        "normal"
    }
    fn evaluate(&self, _t: f64, first: &BodyState, second: &BodyState, out: &mut ConstraintEval) {
        let n = perp(unit(self.direction).unwrap_or(Vec2::x()));
        out.set_row(0, &line_coordinate(first, self.points[0], n, second, self.points[1]));
    }
    fn weighted_hessian(
        &self,
        _t: f64,
        first: &BodyState,
        second: &BodyState,
        lambda: &[f64],
    ) -> Option<dalembert_kinematics::second_derivatives::Pair6> {
        let n = perp(unit(self.direction).unwrap_or(Vec2::x()));
        Some(hessian::line_coordinate(
            first,
            self.points[0],
            n,
            second,
            self.points[1],
            lambda[0],
        ))
    }
    fn reaction_point(&self, _first: &BodyState, second: &BodyState) -> Vec2 {
        PointState::new(second, self.points[1]).position
    }
    fn validate(&self) -> Result<(), dalembert_system::ModelError> {
        let p = &self.points;
        super::check_finite(&self.name, "points", &[p[0].x, p[0].y, p[1].x, p[1].y])?;
        super::check_direction(&self.name, self.direction)
    }
}
