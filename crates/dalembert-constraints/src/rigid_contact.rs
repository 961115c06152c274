//! Rigid (unilateral) contact of a circle on a planar body with a line on another body or the
//! ground, or with another circle (`docs/limits.md`, "Rigid contact"): a gap `s ≥ 0` kept by the
//! same impact and resting law as a joint limit ([`dalembert_system::limit`]), with no friction.
//!
//! - Against a line with point `p` and unit normal `n` fixed in its body: `s = n·(c − p) − R`,
//!   where `s + R` is the coordinate of the centre `c` along `n` from `p`, the
//!   [`line_coordinate`] primitive (its row gives `w = ṡ` and the bias of `s̈`).
//! - Against another circle: `s = |c₂ − c₁| − R₁ − R₂`, the [`distance`] primitive.
//!
//! The normal passes through the centres, so the impulse along it turns no body about them.

use crate::primitives::{distance, line_coordinate};
use dalembert_kinematics::{BodyRef, BodyState, Vec2};
use dalembert_system::{JointLimit, ModelError, SlipRow};

/// A circle on a body in rigid contact with a line on another body or the ground.
#[derive(Debug, Clone, PartialEq)]
pub struct RigidContact {
    /// The contact's name.
    pub name: String,
    /// The body carrying the circle.
    pub body: BodyRef,
    /// The circle's centre, local to the body.
    pub centre: Vec2,
    /// The circle's radius (m).
    pub radius: f64,
    /// What the circle touches.
    pub against: Against,
    /// Newton's coefficient of restitution `e ∈ [0, 1]`.
    pub restitution: f64,
    /// The rebound speed below which the circle rests on the line (m/s).
    pub rest_speed: f64,
}

/// What a rigid contact's circle touches.
#[derive(Debug, Clone, PartialEq)]
pub enum Against {
    /// A line fixed in a body or the ground.
    Line {
        /// The body carrying the line (the ground: global point and normal).
        body: BodyRef,
        /// A point of the line, local to its body.
        point: Vec2,
        /// The line's unit normal, towards the circle's side, local to its body.
        normal: Vec2,
    },
    /// Another circle.
    Circle {
        /// The body carrying it.
        body: BodyRef,
        /// Its centre, local to its body.
        centre: Vec2,
        /// Its radius (m).
        radius: f64,
    },
}

impl RigidContact {
    /// The body the circle touches (a line's or the other circle's).
    fn other_body(&self) -> BodyRef {
        match self.against {
            Against::Line { body, .. } | Against::Circle { body, .. } => body,
        }
    }

    /// What the seam sees: a limit on the gap with the single bound `0 ≤ s`.
    pub fn spec(&self) -> JointLimit {
        JointLimit::contact(&self.name, self.restitution, self.rest_speed)
    }

    /// Checks the geometry and coefficients, naming the contact; the shapes must start apart or
    /// touching (a gap of at least −1e-12 m).
    pub fn validate(&self, q0: &[f64]) -> Result<(), ModelError> {
        let bad = |what: String| ModelError::InvalidParameter {
            element: format!("force '{}'", self.name),
            what,
        };
        let other = self.other_body();
        if self.body == BodyRef::Ground && other == BodyRef::Ground {
            return Err(bad("one of the two shapes must be on a moving body".into()));
        }
        if self.body == other {
            return Err(bad(match self.against {
                Against::Line { .. } => "the circle and the line are on the same body".into(),
                Against::Circle { .. } => "the two circles are on the same body".into(),
            }));
        }
        if let Against::Circle { radius, .. } = self.against {
            if !(radius.is_finite() && radius >= 0.0) {
                return Err(bad(format!("radii must be finite and ≥ 0, got {radius}")));
            }
        }
        if !(self.radius.is_finite() && self.radius >= 0.0) {
            return Err(bad(format!("radius must be finite and ≥ 0, got {}", self.radius)));
        }
        if let Against::Line { normal, .. } = self.against {
            let off_unit = (normal.norm() - 1.0).abs();
            if off_unit.is_nan() || off_unit >= 1e-12 {
                return Err(bad("the line's normal must be a unit vector".into()));
            }
        }
        self.spec().check().map_err(bad)?;
        let gap = self.gap(q0);
        if gap < -1e-12 {
            let what = match self.against {
                Against::Line { .. } => "the circle starts {} m into the line",
                Against::Circle { .. } => "the circles start {} m into each other",
            };
            return Err(bad(what.replace("{}", &format!("{:e}", -gap))));
        }
        Ok(())
    }

    /// The gap at `q`.
    pub fn gap(&self, q: &[f64]) -> f64 {
        self.gap_row(q, &[], &mut SlipRow::default())
    }

    /// The gap's row at `(q, v)` for the seam (`v` empty: at rest), and the gap.
    pub fn gap_row(&self, q: &[f64], v: &[f64], out: &mut SlipRow) -> f64 {
        let circle = BodyState::of(self.body, q, v);
        let other = BodyState::of(self.other_body(), q, v);
        let (row, reach) = match self.against {
            Against::Line { point, normal, .. } => (
                line_coordinate(&other, point, normal, &circle, self.centre),
                self.radius,
            ),
            Against::Circle { centre, radius, .. } => match distance(&other, centre, &circle, self.centre) {
                Some(row) => (row, self.radius + radius),
                // Concentric: no direction to part along (a gap of minus both radii).
                None => {
                    out.clear();
                    return -(self.radius + radius);
                }
            },
        };
        out.clear();
        for (body, block) in [(self.other_body(), row.first), (self.body, row.second)] {
            if let BodyRef::Body(id) = body {
                for (k, x) in block.iter().enumerate() {
                    if *x != 0.0 {
                        out.push(id.offset() + k, *x);
                    }
                }
            }
        }
        // C_q q̈ = Q_d: the gap's acceleration is g·q̈ − Q_d.
        out.bias = -row.gamma;
        row.c - reach
    }
}
