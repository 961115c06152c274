//! Coulomb friction in spatial revolute and prismatic joints, loaded by the joint's reaction
//! (`docs/friction.md`): the slip row of each joint (its value's rate, [`crate::limits`]) and the
//! multiplier rows of its load, for the seam's stick–slip law ([`dalembert_system::friction`]).
//!
//! ```text
//! revolute:  w = z_i·(ω_j − ω_i),  load |F| = |λ_x, λ_y, λ_z| (the pin's force rows),  torque ≤ μ r |F|
//! prismatic: w = ṡ,                load N = |λ_line x, λ_line y| (across the guide),      force ≤ μ N
//! ```
//!
//! As in the planar joints, the moment rows do not load the friction (a short pin or slider).

use crate::joints::JointKind;
use crate::Model;
use dalembert_system::{JointFriction, ModelError, SlipRow};

/// Friction asked for in one joint.
#[derive(Debug, Clone, PartialEq)]
pub struct SpatialFriction {
    /// The joint's name (a revolute or prismatic joint of the model).
    pub joint: String,
    /// Coulomb's `μ ≥ 0`.
    pub coefficient: f64,
    /// The pin radius `r > 0` (m) of a revolute joint; ignored for a prismatic one.
    pub radius: f64,
    /// Viscous friction `c ≥ 0` (N·m·s/rad or N·s/m).
    pub viscous: f64,
    /// A load-independent friction torque (N·m) or force (N) `f₀ ≥ 0`, added to `μ r |F|` or
    /// `μ N`.
    pub constant: f64,
    /// The slip rate within which a stuck joint stays stuck (rad/s or m/s).
    pub stick_speed: f64,
}

impl Model {
    /// The model with friction in some of its revolute and prismatic joints. Errors name the
    /// joint.
    pub fn with_frictions(mut self, frictions: Vec<SpatialFriction>) -> Result<Self, ModelError> {
        let mut specs = Vec::with_capacity(frictions.len());
        let mut joints = Vec::with_capacity(frictions.len());
        for f in &frictions {
            let bad = |what: String| ModelError::InvalidParameter {
                element: format!("joint '{}'", f.joint),
                what,
            };
            let index = self
                .joints()
                .iter()
                .position(|j| j.name == f.joint)
                .ok_or_else(|| bad("friction refers to a joint the model does not hold".into()))?;
            let first: usize = self.joints()[..index].iter().map(|j| j.num_equations()).sum();
            let (coefficient, load_rows) = match self.joints()[index].kind {
                Some(JointKind::Revolute) => {
                    // The radius scales μ's torque; a constant friction alone needs none.
                    if f.coefficient > 0.0 && !(f.radius.is_finite() && f.radius > 0.0) {
                        return Err(bad(format!("friction radius must be > 0 m, got {}", f.radius)));
                    }
                    (f.coefficient * f.radius, vec![first, first + 1, first + 2])
                }
                Some(JointKind::Prismatic) => (f.coefficient, vec![first + 2, first + 3]),
                _ => return Err(bad("friction is for revolute and prismatic joints".into())),
            };
            if !(f.coefficient.is_finite() && f.coefficient >= 0.0) {
                return Err(bad(format!("friction coefficient must be ≥ 0, got {}", f.coefficient)));
            }
            if !(f.viscous.is_finite() && f.viscous >= 0.0) {
                return Err(bad(format!("viscous friction must be ≥ 0, got {}", f.viscous)));
            }
            if !(f.constant.is_finite() && f.constant >= 0.0) {
                return Err(bad(format!("constant friction must be ≥ 0, got {}", f.constant)));
            }
            if !(f.stick_speed.is_finite() && f.stick_speed > 0.0) {
                return Err(bad(format!("stick_speed must be > 0, got {}", f.stick_speed)));
            }
            specs.push(JointFriction {
                element: "joint",
                name: f.joint.clone(),
                coefficient,
                viscous: f.viscous,
                constant: f.constant,
                load_rows,
                load_limit: None,
                stick_speed: f.stick_speed,
                cone: None,
            });
            joints.push(index);
        }
        self.frictions = specs;
        self.friction_joints = joints;
        self.add_contact_frictions();
        Ok(self)
    }

    /// The joints' friction elements, in order.
    pub fn friction_specs(&self) -> &[JointFriction] {
        &self.frictions
    }

    /// The slip row of friction element `k` at `(q, v)`.
    pub(crate) fn slip_row_into(&self, k: usize, q: &[f64], v: &[f64], row: &mut SlipRow) {
        match self.friction_joints.get(k) {
            Some(&joint) => {
                self.joint_row_into(joint, q, v, row);
            }
            None => self.tangent_row_into(k - self.friction_joints.len(), q, v, row),
        }
    }
}
