//! Rigid (unilateral) contact of a circle on a planar body with a line of the ground
//! (`docs/limits.md`, "Rigid contact"): the gap `s = n·(c − p₀) − R ≥ 0`, kept by the same
//! impact and resting law as a joint limit ([`dalembert_system::limit`]), with no friction.
//!
//! ```text
//! s = n·(c − p₀) − R,   w = n·ċ,   g = [n_x, n_y, n·perp(A u)],   b = n·(−θ̇² A u)
//! ```
//!
//! with `c = R_b + A u` the circle's centre on the body. The normal impulse acts along `n` at
//! the contact point `c − R n`, whose arm about the body's reference point gives the same moment
//! as `A u` (the normal passes through the centre).

use dalembert_kinematics::{BodyRef, BodyState, PointState, Vec2};
use dalembert_system::{JointLimit, ModelError, SlipRow};

/// A circle on a body in rigid contact with a line of the ground.
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
    /// A point of the line (global).
    pub point: Vec2,
    /// The line's unit normal, out of the ground (global).
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
        if self.body == BodyRef::Ground {
            return Err(bad("the circle must be on a moving body".into()));
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
        let c = PointState::new(&BodyState::of(self.body, q, &[]), self.centre);
        self.normal.dot(&(c.position - self.point)) - self.radius
    }

    /// The gap's row at `(q, v)` for the seam, and the gap.
    pub fn gap_row(&self, q: &[f64], v: &[f64], out: &mut SlipRow) -> f64 {
        let c = PointState::new(&BodyState::of(self.body, q, v), self.centre);
        out.clear();
        if let BodyRef::Body(id) = self.body {
            let g = [self.normal.x, self.normal.y, self.normal.dot(&c.d_theta())];
            for (k, x) in g.iter().enumerate() {
                if *x != 0.0 {
                    out.push(id.offset() + k, *x);
                }
            }
        }
        out.bias = self.normal.dot(&c.quadratic_acceleration);
        self.normal.dot(&(c.position - self.point)) - self.radius
    }
}
