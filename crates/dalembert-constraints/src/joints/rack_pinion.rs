use crate::primitives::hessian;
use crate::primitives::{line_coordinate, unit};
use crate::{Constraint, ConstraintEval, ConstraintRole};
use dalembert_kinematics::{BodyRef, BodyState, PointState, Vec2};

/// Rack and pinion: the pinion (first body, pitch radius `ρ`) rolls without slip on the rack
/// (second body, axis fixed in the rack). With `s = a_jᵀ (p_i − p_j)` the position of the pinion
/// centre along the rack axis `a_j = A_j axis`,
///
/// ```text
/// C = (s − s⁰) + ρ ((θ_i − θ_j) − (θ_i − θ_j)⁰) = 0     (1 equation)
/// ```
///
/// so a pinion turning clockwise (θ decreasing) moves along `+axis`. The pinion's axle and the
/// rack's guide are separate joints.
#[derive(Debug, Clone, PartialEq)]
pub struct RackPinion {
    /// Joint name.
    pub name: String,
    /// `[pinion, rack]`.
    pub bodies: [BodyRef; 2],
    /// Local points: the pinion centre, a reference point on the rack.
    pub points: [Vec2; 2],
    /// Rack axis in the rack's frame.
    pub axis: Vec2,
    /// Pitch radius `ρ` of the pinion.
    pub radius: f64,
    /// Reference values `[s⁰, (θ_i − θ_j)⁰]` at which the constraint holds.
    pub reference: [f64; 2],
}

impl RackPinion {
    /// A rack and pinion meshing at configuration `q`: pinion centre at its reference point
    /// (`u_i = 0`), rack axis `axis` (global) through the rack's reference point.
    pub fn new(name: impl Into<String>, bodies: [BodyRef; 2], axis: Vec2, radius: f64, q: &[f64]) -> Self {
        let mut j = RackPinion {
            name: name.into(),
            points: [Vec2::zeros(), Vec2::zeros()],
            axis: super::local_direction_of(bodies[1], q, axis),
            bodies,
            radius,
            reference: [0.0, 0.0],
        };
        let si = super::pose_or_ground(bodies[0], q);
        let sj = super::pose_or_ground(bodies[1], q);
        j.reference = [j.travel(&si, &sj), si.angle - sj.angle];
        j
    }

    fn travel(&self, pinion: &BodyState, rack: &BodyState) -> f64 {
        let a = unit(self.axis).unwrap_or(Vec2::x());
        line_coordinate(rack, self.points[1], a, pinion, self.points[0]).c
    }
}

impl Constraint for RackPinion {
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
        ConstraintRole::Joint { carries_torque: true }
    }
    fn equation_label(&self, _k: usize) -> &'static str {
        "rolling"
    }
    fn evaluate(&self, _t: f64, first: &BodyState, second: &BodyState, out: &mut ConstraintEval) {
        let a = unit(self.axis).unwrap_or(Vec2::x());
        // s with the line on the rack: `first` of the primitive's row is the rack.
        let mut row = line_coordinate(second, self.points[1], a, first, self.points[0]).swapped();
        let rho = self.radius;
        row.c += rho * (first.angle - second.angle) - self.reference[0] - rho * self.reference[1];
        row.first[2] += rho;
        row.second[2] -= rho;
        out.set_row(0, &row);
    }
    fn weighted_hessian(
        &self,
        _t: f64,
        first: &BodyState,
        second: &BodyState,
        lambda: &[f64],
    ) -> Option<dalembert_kinematics::second_derivatives::Pair6> {
        let a = unit(self.axis).unwrap_or(Vec2::x());
        Some(hessian::swapped(hessian::line_coordinate(
            second,
            self.points[1],
            a,
            first,
            self.points[0],
            lambda[0],
        )))
    }
    fn reaction_point(&self, first: &BodyState, _second: &BodyState) -> Vec2 {
        PointState::new(first, self.points[0]).position
    }
    fn validate(&self) -> Result<(), dalembert_system::ModelError> {
        let p = &self.points;
        super::check_finite(
            &self.name,
            "points, radius and references",
            &[
                p[0].x,
                p[0].y,
                p[1].x,
                p[1].y,
                self.radius,
                self.reference[0],
                self.reference[1],
            ],
        )?;
        super::check_direction(&self.name, self.axis)?;
        if self.radius <= 0.0 {
            return Err(dalembert_system::ModelError::InvalidParameter {
                element: format!("joint '{}'", self.name),
                what: "pinion radius must be positive".into(),
            });
        }
        Ok(())
    }
}
