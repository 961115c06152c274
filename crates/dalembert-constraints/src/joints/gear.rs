use crate::primitives::relative_angle;
use crate::{Constraint, ConstraintEval, ConstraintRole};
use dalembert_kinematics::{BodyRef, BodyState, Vec2};

/// Gear pair: `C = (θ_j − θ_j⁰) − ratio · (θ_i − θ_i⁰)` (1 equation), angles absolute (gears on
/// axles fixed to the ground or to a common carrier that does not rotate). An external pair of pitch
/// radii `r_i`, `r_j` has `ratio = −r_i / r_j`; an internal pair `+r_i / r_j`. The axles themselves
/// are separate revolute joints. The reaction is a torque (no force).
#[derive(Debug, Clone, PartialEq)]
pub struct Gear {
    /// Joint name.
    pub name: String,
    /// `[first (driving), second (driven)]`.
    pub bodies: [BodyRef; 2],
    /// Speed ratio `θ̇_j / θ̇_i`.
    pub ratio: f64,
    /// Reference angles `[θ_i⁰, θ_j⁰]` at which the constraint is satisfied.
    pub reference_angles: [f64; 2],
}

impl Gear {
    /// A gear pair meshing at configuration `q`.
    pub fn new(name: impl Into<String>, bodies: [BodyRef; 2], ratio: f64, q: &[f64]) -> Self {
        let a = |b| super::pose_or_ground(b, q).angle;
        Gear {
            name: name.into(),
            bodies,
            ratio,
            reference_angles: [a(bodies[0]), a(bodies[1])],
        }
    }
}

impl Constraint for Gear {
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
        "mesh"
    }
    fn evaluate(&self, _t: f64, first: &BodyState, second: &BodyState, out: &mut ConstraintEval) {
        let offset = self.reference_angles[1] - self.ratio * self.reference_angles[0];
        out.set_row(0, &relative_angle(first, second, self.ratio).drive([offset, 0.0, 0.0]));
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
        first.position
    }
    fn validate(&self) -> Result<(), dalembert_system::ModelError> {
        let r = &self.reference_angles;
        super::check_finite(&self.name, "ratio and angles", &[self.ratio, r[0], r[1]])?;
        if self.ratio == 0.0 {
            return Err(dalembert_system::ModelError::InvalidParameter {
                element: format!("joint '{}'", self.name),
                what: "gear ratio must be non-zero".into(),
            });
        }
        Ok(())
    }
}
