//! Coulomb friction in planar revolute and prismatic joints, loaded by the joint's reaction
//! (`docs/friction.md`): the slip row of each joint, for the seam's stick–slip law
//! ([`dalembert_system::friction`]).
//!
//! ```text
//! revolute:  w = θ̇_j − θ̇_i,            load |F| = |(λ_x, λ_y)|,  torque ≤ μ r |F|
//! prismatic: w = ṡ, s = a_iᵀ (p_j − p_i),  load N = |λ_normal|,    force  ≤ μ N
//! ```
//!
//! The prismatic joint's moment row does not load its friction: the joint is a short slider
//! whose normal force is the reaction across the guide.

use crate::primitives::{angle_row, line_coordinate, unit, Row};
use crate::{Prismatic, Reaction, Revolute};
use dalembert_kinematics::rotation::cross;
use dalembert_kinematics::{BodyRef, BodyState, Vec2};
use dalembert_system::{JointFriction, ModelError, SlipRow};

/// A joint of one relative coordinate (an angle or a displacement) that carries friction or a
/// limit, with its geometry.
#[derive(Debug, Clone, PartialEq)]
pub enum FrictionJoint {
    /// A pin; the friction torque is `μ r |F|`.
    Revolute(Revolute),
    /// A slider; the friction force is `μ N`.
    Prismatic(Prismatic),
}

/// Friction in one joint.
#[derive(Debug, Clone, PartialEq)]
pub struct Friction {
    /// The joint.
    pub joint: FrictionJoint,
    /// The joint's index in the model's constraint list (its multipliers are the load).
    pub constraint: usize,
    /// Coulomb coefficient `μ ≥ 0`.
    pub coefficient: f64,
    /// Pin radius `r > 0` (m) of a revolute joint; ignored for a slider.
    pub radius: f64,
    /// Viscous coefficient `c ≥ 0` (N·s/m or N·m·s/rad).
    pub viscous: f64,
    /// A load-independent friction force (N) or torque (N·m) `f₀ ≥ 0`, added to `μ N`.
    pub constant: f64,
    /// Slip rate below which the joint counts as at rest (m/s or rad/s).
    pub stick_speed: f64,
}

/// The default slip rate within which a stuck joint stays stuck: 1e-6 m/s or rad/s
/// (`docs/friction.md`, "Stick speed").
pub const STICK_SPEED: f64 = 1e-6;

impl FrictionJoint {
    /// The joint's name.
    pub fn name(&self) -> &str {
        match self {
            FrictionJoint::Revolute(r) => &r.name,
            FrictionJoint::Prismatic(p) => &p.name,
        }
    }

    /// The joint's bodies.
    pub fn bodies(&self) -> [BodyRef; 2] {
        match self {
            FrictionJoint::Revolute(r) => r.bodies,
            FrictionJoint::Prismatic(p) => p.bodies,
        }
    }

    /// The row of the joint's coordinate (relative angle, or displacement along the axis) at
    /// `(q, v)` (`v` empty: at rest): its Jacobian blocks are the generalized force of a unit
    /// force along the joint on each body.
    pub fn row(&self, q: &[f64], v: &[f64]) -> Row {
        let bodies = self.bodies();
        match self {
            // The relative angle's row is constant: no body state (and no sine) to compute.
            FrictionJoint::Revolute(_) => {
                let angle = |body: BodyRef| match body {
                    BodyRef::Ground => 0.0,
                    BodyRef::Body(id) => q[id.offset() + 2],
                };
                angle_row(angle(bodies[0]), angle(bodies[1]), 1.0)
            }
            FrictionJoint::Prismatic(p) => {
                let first = BodyState::of(bodies[0], q, v);
                let second = BodyState::of(bodies[1], q, v);
                let a = unit(p.axis).unwrap_or(Vec2::x());
                line_coordinate(&first, p.points[0], a, &second, p.points[1])
            }
        }
    }

    /// Adds a force `force` along the joint (on the second body, its opposite on the first) to
    /// the joint's reaction (the force on the first body from the second, its torque about the
    /// reaction point; [`crate::reactions`]).
    pub fn add_to_reaction(&self, q: &[f64], force: f64, reaction: &mut Reaction) {
        let bodies = self.bodies();
        let row = self.row(q, &[]);
        let (side, block, sign) = if bodies[0] != BodyRef::Ground {
            (bodies[0], row.first, 1.0)
        } else {
            (bodies[1], row.second, -1.0)
        };
        let s = BodyState::of(side, q, &[]);
        let f = Vec2::new(block[0], block[1]) * force;
        reaction.force += sign * f;
        reaction.torque += sign * (block[2] * force - cross(reaction.point - s.position, f));
    }

    /// The joint's row at `(q, v)` for the seam (its rate and the bias of its acceleration), and
    /// its coordinate.
    pub fn slip_row(&self, q: &[f64], v: &[f64], out: &mut SlipRow) -> f64 {
        let bodies = self.bodies();
        let row = self.row(q, v);
        out.clear();
        for (body, block) in bodies.iter().zip([row.first, row.second]) {
            if let BodyRef::Body(id) = body {
                for (c, g) in block.iter().enumerate() {
                    if *g != 0.0 {
                        out.push(id.offset() + c, *g);
                    }
                }
            }
        }
        // C_q q̈ = Q_d: the slip acceleration is g·q̈ − Q_d.
        out.bias = -row.gamma;
        row.c
    }
}

impl Friction {
    /// The joint's name.
    pub fn name(&self) -> &str {
        self.joint.name()
    }

    /// Checks the coefficients, naming the joint.
    pub fn validate(&self) -> Result<(), ModelError> {
        let bad = |what: String| ModelError::InvalidParameter {
            element: format!("joint '{}'", self.name()),
            what,
        };
        if !(self.coefficient.is_finite() && self.coefficient >= 0.0) {
            return Err(bad(format!(
                "friction coefficient must be ≥ 0, got {}",
                self.coefficient
            )));
        }
        if !(self.constant.is_finite() && self.constant >= 0.0) {
            return Err(bad(format!("constant friction must be ≥ 0, got {}", self.constant)));
        }
        // The radius scales μ's torque; a constant friction alone needs none.
        let needs_radius = self.coefficient > 0.0;
        if needs_radius
            && matches!(self.joint, FrictionJoint::Revolute(_))
            && !(self.radius.is_finite() && self.radius > 0.0)
        {
            return Err(bad(format!("friction radius must be > 0 m, got {}", self.radius)));
        }
        if !(self.viscous.is_finite() && self.viscous >= 0.0) {
            return Err(bad(format!("viscous friction must be ≥ 0, got {}", self.viscous)));
        }
        if !(self.stick_speed.is_finite() && self.stick_speed > 0.0) {
            return Err(bad(format!("stick_speed must be > 0, got {}", self.stick_speed)));
        }
        Ok(())
    }

    /// What the seam sees, with the joint's first multiplier row `row_offset`.
    pub fn spec(&self, row_offset: usize) -> JointFriction {
        let (coefficient, load_rows) = match self.joint {
            FrictionJoint::Revolute(_) => (self.coefficient * self.radius, vec![row_offset, row_offset + 1]),
            FrictionJoint::Prismatic(_) => (self.coefficient, vec![row_offset]),
        };
        JointFriction {
            element: "joint",
            name: self.name().to_string(),
            coefficient,
            viscous: self.viscous,
            constant: self.constant,
            load_rows,
            load_limit: None,
            stick_speed: self.stick_speed,
            cone: None,
        }
    }

    /// The joint's bodies.
    pub fn bodies(&self) -> [BodyRef; 2] {
        self.joint.bodies()
    }

    /// The slip coordinate's row at `(q, v)` ([`FrictionJoint::row`]).
    pub fn row(&self, q: &[f64], v: &[f64]) -> Row {
        self.joint.row(q, v)
    }

    /// Adds the friction force `force` to the joint's reaction ([`FrictionJoint::add_to_reaction`]).
    pub fn add_to_reaction(&self, q: &[f64], force: f64, reaction: &mut Reaction) {
        self.joint.add_to_reaction(q, force, reaction);
    }

    /// The slip row at `(q, v)`.
    pub fn slip_row(&self, q: &[f64], v: &[f64], out: &mut SlipRow) {
        self.joint.slip_row(q, v, out);
    }
}
