//! Rigid (unilateral) contact of a circle on a planar body with a line on another body or the
//! ground (`docs/limits.md`, "Rigid contact"): the gap `s = n·(c − p) − R ≥ 0`, kept by the
//! same impact and resting law as a joint limit ([`dalembert_system::limit`]), with no friction.
//!
//! With the line's point `p` and unit normal `n` fixed in its body and the circle's centre `c`
//! fixed in its own, the gap plus `R` is the coordinate of `c` along `n` from `p`: the
//! [`line_coordinate`] primitive (its row gives `w = ṡ` and the bias of `s̈`). The normal passes
//! through the centre, so the impulse along it turns neither body about the centre.

use crate::primitives::line_coordinate;
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
    /// The body carrying the line (the ground: global point and normal).
    pub line_body: BodyRef,
    /// A point of the line, local to its body.
    pub point: Vec2,
    /// The line's unit normal, towards the circle's side, local to its body.
    pub normal: Vec2,
    /// Newton's coefficient of restitution `e ∈ [0, 1]`.
    pub restitution: f64,
    /// The rebound speed below which the circle rests on the line (m/s).
    pub rest_speed: f64,
}

impl RigidContact {
    /// What the seam sees: a limit on the gap with the single bound `0 ≤ s`.
    pub fn spec(&self) -> JointLimit {
        JointLimit {
            element: "contact",
            name: self.name.clone(),
            lower: 0.0,
            upper: f64::INFINITY,
            restitution: self.restitution,
            rest_speed: self.rest_speed,
        }
    }

    /// Checks the geometry and coefficients, naming the contact; the circle must start on or
    /// above the line (a gap of at least −1e-12 m).
    pub fn validate(&self, q0: &[f64]) -> Result<(), ModelError> {
        let bad = |what: String| ModelError::InvalidParameter {
            element: format!("force '{}'", self.name),
            what,
        };
        if self.body == BodyRef::Ground && self.line_body == BodyRef::Ground {
            return Err(bad("the circle or the line must be on a moving body".into()));
        }
        if self.body == self.line_body {
            return Err(bad("the circle and the line are on the same body".into()));
        }
        if !(self.radius.is_finite() && self.radius >= 0.0) {
            return Err(bad(format!("radius must be finite and ≥ 0, got {}", self.radius)));
        }
        let off_unit = (self.normal.norm() - 1.0).abs();
        if off_unit.is_nan() || off_unit >= 1e-12 {
            return Err(bad("the line's normal must be a unit vector".into()));
        }
        self.spec().check().map_err(bad)?;
        let gap = self.gap(q0);
        if gap < -1e-12 {
            return Err(bad(format!("the circle starts {:e} m into the line", -gap)));
        }
        Ok(())
    }

    /// The gap at `q`.
    pub fn gap(&self, q: &[f64]) -> f64 {
        self.gap_row(q, &[], &mut SlipRow::default())
    }

    /// The gap's row at `(q, v)` for the seam (`v` empty: at rest), and the gap.
    pub fn gap_row(&self, q: &[f64], v: &[f64], out: &mut SlipRow) -> f64 {
        let line = BodyState::of(self.line_body, q, v);
        let circle = BodyState::of(self.body, q, v);
        let row = line_coordinate(&line, self.point, self.normal, &circle, self.centre);
        out.clear();
        for (body, block) in [(self.line_body, row.first), (self.body, row.second)] {
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
        row.c - self.radius
    }
}
