//! Joint limits with impacts (`docs/limits.md`): what a system says about each limited joint
//! ([`JointLimit`]), and the event function and impact law the switching formulation
//! ([`crate::Frictional`]) applies to it.
//!
//! A limited joint has a coordinate `s` (an angle or a displacement, zero in the file's
//! configuration), its rate `w = g·v` and its acceleration `ẇ = g·v̇ + b` (the same row as a
//! friction element's slip, [`crate::SlipRow`]). The joint is in one of three modes:
//!
//! ```text
//! free:            lower < s < upper, no force                                           (L1)
//! held at a bound: ẇ = 0 with the force F g, σ F ≥ 0 (σ = +1 at lower, −1 at upper)      (L2)
//! impact at a bound, w⁻ towards it:  P = −(1 + e) w⁻ / (g·A),  v⁺ = v⁻ + A P,  w⁺ = −e w⁻ (L3)
//! ```
//!
//! `A` is the formulation's response to a unit generalized force along `g` (the same response
//! serves an impulse), so the impulse keeps every constraint's velocity at zero. After an impact
//! whose rebound `|w⁺|` is below the limit's rest speed the joint is held (L2); a held joint is
//! released (free) where its force `σ F` passes zero.

use crate::{DynamicsError, Formulation};

/// One joint limit of a system, as the system describes it once; also a rigid contact, whose
/// coordinate is its gap with the single bound `0 ≤ s` (`docs/limits.md`, "Rigid contact").
#[derive(Debug, Clone, PartialEq)]
pub struct JointLimit {
    /// What the element is, in messages: `"joint"` or `"contact"`.
    pub element: &'static str,
    /// The joint's or contact's name (in errors and outputs).
    pub name: String,
    /// The lower bound of the joint's coordinate (rad or m; `−∞` for none).
    pub lower: f64,
    /// The upper bound (rad or m; `+∞` for none).
    pub upper: f64,
    /// Newton's coefficient of restitution `e ∈ [0, 1]`.
    pub restitution: f64,
    /// The rebound speed below which an impact leaves the joint held at its bound (rad/s or m/s).
    pub rest_speed: f64,
    /// True when the system measures the coordinate within a turn (`(−π, π]`, a spatial revolute
    /// joint in absolute coordinates): the switching formulation then follows it across half
    /// turns ([`unwrap_angle`]), so bounds may lie beyond `±π`.
    pub within_turn: bool,
}

/// How far (rad or m) a free joint's event function reaches past a bound, so that a joint
/// that leaves a bound, its coordinate there to round-off, starts clear of its event.
pub const LIMIT_SLACK: f64 = 1e-14;

impl JointLimit {
    /// A rigid contact's limit: its gap with the single bound `0 ≤ s`.
    pub fn contact(name: &str, restitution: f64, rest_speed: f64) -> Self {
        JointLimit {
            element: "contact",
            name: name.to_string(),
            lower: 0.0,
            upper: f64::INFINITY,
            restitution,
            rest_speed,
            within_turn: false,
        }
    }

    /// The event function of a free joint at coordinate `s`: positive inside the bounds.
    pub fn free_event(&self, s: f64) -> f64 {
        (s - self.lower).min(self.upper - s) + LIMIT_SLACK
    }

    /// The bound a joint at `s` is nearer to, as its sign `σ`: `+1` the lower, `−1` the upper.
    pub fn nearer_bound(&self, s: f64) -> f64 {
        if s - self.lower <= self.upper - s {
            1.0
        } else {
            -1.0
        }
    }

    /// Checks the bounds and coefficients, naming the joint.
    pub fn check(&self) -> Result<(), String> {
        let one_finite = self.lower.is_finite() || self.upper.is_finite();
        if !(self.lower < self.upper && one_finite && self.lower != f64::INFINITY && self.upper != f64::NEG_INFINITY) {
            return Err(format!(
                "limits must have lower < upper and one of them finite, got [{}, {}]",
                self.lower, self.upper
            ));
        }
        if !(0.0..=1.0).contains(&self.restitution) {
            return Err(format!("restitution must be within [0, 1], got {}", self.restitution));
        }
        if !(self.rest_speed.is_finite() && self.rest_speed > 0.0) {
            return Err(format!("rest_speed must be > 0, got {}", self.rest_speed));
        }
        Ok(())
    }
}

/// The angle `candidate` (in `(−π, π]`) moved by a whole number of turns to lie within half a
/// turn of `previous`: a continuous angle from evaluation to evaluation when the joint turns less
/// than half a turn between them.
pub fn unwrap_angle(previous: f64, candidate: f64) -> f64 {
    let turn = std::f64::consts::TAU;
    previous + (candidate - previous - turn * ((candidate - previous) / turn).round())
}

/// The default rebound speed below which an impact leaves a joint held at its bound: 1e-3 m/s
/// or rad/s (`docs/limits.md`).
pub const REST_SPEED: f64 = 1e-3;

/// The impulse of (L3) for a joint whose rate is `w` and whose response to a unit force along
/// its row has rate `g·A` (`response`): `−(1 + e) w / (g·A)`.
pub fn impact_impulse(limit: &JointLimit, w: f64, response: f64, time: f64) -> Result<f64, DynamicsError> {
    if !(response > 0.0 && response.is_finite()) {
        return Err(DynamicsError::Limit {
            time,
            element: format!("{} '{}'", limit.element, limit.name),
            what: format!("an impulse at its bound does not move it (its response is {response:e})"),
        });
    }
    Ok(-(1.0 + limit.restitution) * w / response)
}

/// The kinetic energy an impulse `P` along a row takes from the motion, rate `w⁻` before and
/// `w⁺` after: `−P (w⁻ + w⁺) / 2` (J).
pub fn impact_loss(impulse: f64, before: f64, after: f64) -> f64 {
    -0.5 * impulse * (before + after)
}

/// The first limit of `system` at or past a bound at `(t, q)` (within [`LIMIT_SLACK`]), with its
/// coordinate there (read within a turn where the system reads it so): where an analysis that
/// holds only while every limit is free (a linearization, an equilibrium) does not hold. `None`
/// where every limit is free. Allocates a velocity vector (not for stepping).
pub fn limit_reached<'a>(system: &'a dyn crate::MultibodySystem, t: f64, q: &[f64]) -> Option<(&'a JointLimit, f64)> {
    let v = vec![0.0; system.layout().n_v()];
    let mut row = crate::SlipRow::default();
    system.limits().iter().enumerate().find_map(|(k, limit)| {
        let s = system.limit_row(k, t, q, &v, &mut row);
        (limit.free_event(s) <= LIMIT_SLACK).then_some((limit, s))
    })
}

/// True when a formulation's system has joint friction or joint limits (a model that needs the
/// switching formulation, [`crate::Frictional`]).
pub fn switches(f: &dyn Formulation) -> bool {
    let s = f.system();
    !s.frictions().is_empty() || !s.limits().is_empty()
}
