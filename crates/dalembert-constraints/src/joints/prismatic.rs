use crate::primitives::hessian;
use crate::primitives::{line_coordinate, relative_angle, unit};
use crate::{Constraint, ConstraintEval, ConstraintRole};
use dalembert_kinematics::rotation::perp;
use dalembert_kinematics::{BodyRef, BodyState, PointState, Vec2};

/// Prismatic (translational) joint: point `u_j` of the second body stays on the line through `u_i`
/// along `axis` (fixed in the first body), and the relative angle stays `θ₀`.
///
/// ```text
/// C₁ = n_iᵀ (p_j − p_i) = 0,   n_i = A_i perp(axis)      (line_coordinate primitive)
/// C₂ = θ_j − θ_i − θ₀ = 0
/// ```
///
/// The reaction carries a torque, reported about the slider point `p_j`.
#[derive(Debug, Clone, PartialEq)]
pub struct Prismatic {
    /// Joint name.
    pub name: String,
    /// `[first (guide), second (slider)]`.
    pub bodies: [BodyRef; 2],
    /// Local points: on the guide line (first body) and on the slider (second body).
    pub points: [Vec2; 2],
    /// Sliding direction in the first body's frame (need not be unit; normalised on use).
    pub axis: Vec2,
    /// Relative angle `θ_j − θ_i` held fixed.
    pub angle: f64,
}

impl Prismatic {
    /// A prismatic joint through global point `p` along global direction `axis`, in configuration `q`.
    pub fn at(name: impl Into<String>, bodies: [BodyRef; 2], p: Vec2, axis: Vec2, q: &[f64]) -> Self {
        let si = super::pose_or_ground(bodies[0], q);
        let sj = super::pose_or_ground(bodies[1], q);
        Prismatic {
            name: name.into(),
            points: [
                super::local_point_of(bodies[0], q, p),
                super::local_point_of(bodies[1], q, p),
            ],
            axis: super::local_direction_of(bodies[0], q, axis),
            bodies,
            angle: sj.angle - si.angle,
        }
    }

    /// The unit sliding direction in the first body's frame.
    pub fn unit_axis(&self) -> Vec2 {
        unit(self.axis).unwrap_or(Vec2::x())
    }
}

impl Constraint for Prismatic {
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
        ConstraintRole::Joint { carries_torque: true }
    }
    fn equation_label(&self, k: usize) -> &'static str {
        ["normal", "angle"][k]
    }
    fn evaluate(&self, _t: f64, first: &BodyState, second: &BodyState, out: &mut ConstraintEval) {
        let n = perp(self.unit_axis());
        out.set_row(0, &line_coordinate(first, self.points[0], n, second, self.points[1]));
        out.set_row(1, &relative_angle(first, second, 1.0).drive([self.angle, 0.0, 0.0]));
    }
    fn weighted_hessian(
        &self,
        _t: f64,
        first: &BodyState,
        second: &BodyState,
        lambda: &[f64],
    ) -> Option<dalembert_kinematics::second_derivatives::Pair6> {
        let n = perp(self.unit_axis());
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
        super::check_finite(
            &self.name,
            "points and angle",
            &[p[0].x, p[0].y, p[1].x, p[1].y, self.angle],
        )?;
        super::check_direction(&self.name, self.axis)
    }
}
