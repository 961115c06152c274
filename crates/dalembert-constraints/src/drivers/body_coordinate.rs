use crate::{Constraint, ConstraintEval, ConstraintRole};
use dalembert_kinematics::{BodyId, BodyRef, BodyState, Vec2};
use dalembert_system::TimeFunction;

/// Which coordinate of a body a [`BodyCoordinate`] driver prescribes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Coordinate {
    /// Global `x` of the reference point.
    X,
    /// Global `y` of the reference point.
    Y,
    /// Orientation `θ`.
    Angle,
}

impl Coordinate {
    /// Index in `[x, y, θ]`.
    pub fn index(self) -> usize {
        match self {
            Coordinate::X => 0,
            Coordinate::Y => 1,
            Coordinate::Angle => 2,
        }
    }
}

/// Prescribes one coordinate of a body: `C = q_k − f(t)`.
#[derive(Debug, Clone)]
pub struct BodyCoordinate {
    /// Driver name.
    pub name: String,
    /// The driven body.
    pub body: BodyId,
    /// The driven coordinate.
    pub coordinate: Coordinate,
    /// `f(t)`.
    pub function: TimeFunction,
}

impl Constraint for BodyCoordinate {
    fn name(&self) -> &str {
        &self.name
    }
    fn bodies(&self) -> [BodyRef; 2] {
        [BodyRef::Ground, BodyRef::Body(self.body)]
    }
    fn num_equations(&self) -> usize {
        1
    }
    fn role(&self) -> ConstraintRole {
        ConstraintRole::Driver
    }
    fn equation_label(&self, _k: usize) -> &'static str {
        match self.coordinate {
            Coordinate::X => "x",
            Coordinate::Y => "y",
            Coordinate::Angle => "angle",
        }
    }
    fn evaluate(&self, t: f64, _first: &BodyState, second: &BodyState, out: &mut ConstraintEval) {
        let k = self.coordinate.index();
        let value = [second.position.x, second.position.y, second.angle][k];
        let mut jac = [0.0; 3];
        jac[k] = 1.0;
        let row = crate::primitives::Row {
            c: value,
            c_t: 0.0,
            gamma: 0.0,
            first: [0.0; 3],
            second: jac,
        };
        out.set_row(0, &row.drive(self.function.eval(t)));
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
    fn reaction_point(&self, _first: &BodyState, second: &BodyState) -> Vec2 {
        second.position
    }
    fn validate(&self) -> Result<(), dalembert_system::ModelError> {
        self.function.validate(&format!("driver '{}'", self.name))
    }
}
