//! Limits on planar revolute and prismatic joints (`docs/limits.md`): the joint's coordinate,
//! zero in the file's configuration, kept within `[lower, upper]` by impacts with Newton's
//! coefficient of restitution and by a one-sided force while it rests on a bound (the seam's law,
//! [`dalembert_system::limit`]).
//!
//! ```text
//! revolute:  s = (θ_j − θ_i) − (θ_j − θ_i)₀
//! prismatic: s = a_iᵀ (p_j − p_i) − (a_iᵀ (p_j − p_i))₀
//! ```

use crate::{FrictionJoint, Reaction};
use dalembert_system::{JointLimit, ModelError, SlipRow};

/// A limit on one joint.
#[derive(Debug, Clone, PartialEq)]
pub struct Limit {
    /// The joint.
    pub joint: FrictionJoint,
    /// The joint's index in the model's constraint list.
    pub constraint: usize,
    /// The lower bound of the joint's coordinate (rad or m, from the file's configuration).
    pub lower: f64,
    /// The upper bound (rad or m).
    pub upper: f64,
    /// Newton's coefficient of restitution `e ∈ [0, 1]`.
    pub restitution: f64,
    /// The rebound speed below which an impact leaves the joint resting on its bound (rad/s or
    /// m/s).
    pub rest_speed: f64,
    /// The joint's raw coordinate (relative angle, or displacement along the axis) in the file's
    /// configuration.
    pub origin: f64,
}

impl Limit {
    /// A limit on `joint` whose coordinate is zero at `q0` (the file's configuration).
    pub fn new(
        joint: FrictionJoint,
        constraint: usize,
        q0: &[f64],
        bounds: [f64; 2],
        restitution: f64,
        rest_speed: f64,
    ) -> Self {
        let origin = joint.row(q0, &[]).c;
        Limit {
            joint,
            constraint,
            lower: bounds[0],
            upper: bounds[1],
            restitution,
            rest_speed,
            origin,
        }
    }

    /// The joint's name.
    pub fn name(&self) -> &str {
        self.joint.name()
    }

    /// What the seam sees.
    pub fn spec(&self) -> JointLimit {
        JointLimit {
            element: "joint",
            name: self.name().to_string(),
            lower: self.lower,
            upper: self.upper,
            restitution: self.restitution,
            rest_speed: self.rest_speed,
            within_turn: false,
        }
    }

    /// Checks the bounds and coefficients, naming the joint; the file's configuration must lie
    /// within the bounds.
    pub fn validate(&self) -> Result<(), ModelError> {
        let bad = |what: String| ModelError::InvalidParameter {
            element: format!("joint '{}'", self.name()),
            what,
        };
        self.spec().check().map_err(bad)?;
        if self.lower > 0.0 || self.upper < 0.0 {
            return Err(bad(format!(
                "the joint starts outside its limits [{}, {}] (its coordinate is 0 in the file's configuration)",
                self.lower, self.upper
            )));
        }
        Ok(())
    }

    /// The joint's coordinate `s` at `q`.
    pub fn coordinate(&self, q: &[f64]) -> f64 {
        self.joint.row(q, &[]).c - self.origin
    }

    /// The joint's row at `(q, v)` for the seam, and its coordinate `s`.
    pub fn limit_row(&self, q: &[f64], v: &[f64], out: &mut SlipRow) -> f64 {
        self.joint.slip_row(q, v, out) - self.origin
    }

    /// Adds the limit's force `force` (along the joint, on the second body) to the joint's
    /// reaction.
    pub fn add_to_reaction(&self, q: &[f64], force: f64, reaction: &mut Reaction) {
        self.joint.add_to_reaction(q, force, reaction);
    }
}
