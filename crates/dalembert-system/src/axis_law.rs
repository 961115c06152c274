//! The torque law about a joint axis that the spatial models' joint torques, rotational
//! springs and servos share, in absolute coordinates (`dalembert-spatial`, measuring the angle
//! from the bodies' frames) and in joint coordinates ([`crate::JointSpace::with_axis_laws`], the
//! angle being the coordinate):
//!
//! ```text
//! τ = clamp(−k (θ − θ₀ − θ*(t)) − c θ̇ + f(t), τ_lo, τ_hi)
//! ```
//!
//! with `θ₀` the free angle, `θ*(t)` a servo's target and `f(t)` an applied torque.

use crate::TimeFunction;

/// The law (see the module documentation). Without a target or a range it is a rotational
/// spring–damper with a torque; with either, a servo.
#[derive(Debug, Clone)]
pub struct AxisLaw {
    /// `k` (N·m/rad).
    pub stiffness: f64,
    /// `c` (N·m·s/rad).
    pub damping: f64,
    /// `θ₀` (rad).
    pub free_angle: f64,
    /// `f(t)` (N·m).
    pub torque: Option<TimeFunction>,
    /// A servo's target `θ*(t)` (rad).
    pub target: Option<TimeFunction>,
    /// `[τ_lo, τ_hi]` (infinite bounds for none).
    pub range: [f64; 2],
}

impl AxisLaw {
    /// The rotational spring–damper `−k (θ − θ₀) − c θ̇`: no torque, target or range.
    pub fn spring(stiffness: f64, damping: f64, free_angle: f64) -> Self {
        AxisLaw {
            stiffness,
            damping,
            free_angle,
            torque: None,
            target: None,
            range: [f64::NEG_INFINITY, f64::INFINITY],
        }
    }

    /// The angle the law pulls toward at `t`: `θ₀ + θ*(t)`.
    pub fn free(&self, t: f64) -> f64 {
        self.free_angle + self.target.as_ref().map_or(0.0, |f| f.value(t))
    }

    /// The torque at `t` for the deflection `θ − θ₀ − θ*(t)` and the rate `θ̇`, and whether it is
    /// inside its range (held at a bound, it does not change with the state).
    pub fn torque(&self, t: f64, deflection: f64, rate: f64) -> (f64, bool) {
        let free =
            -self.stiffness * deflection - self.damping * rate + self.torque.as_ref().map_or(0.0, |f| f.value(t));
        let [lo, hi] = self.range;
        (free.clamp(lo, hi), free > lo && free < hi)
    }

    /// A target or a range: a servo, whose torque has no potential.
    pub fn is_servo(&self) -> bool {
        self.target.is_some() || self.range != [f64::NEG_INFINITY, f64::INFINITY]
    }

    /// No damping, no applied torque, not a servo: `½ k (θ − θ₀)²` is its potential.
    pub fn is_conservative(&self) -> bool {
        self.damping == 0.0 && self.torque.is_none() && !self.is_servo()
    }

    /// `½ k (θ − θ₀)²` for the deflection, zero for a servo.
    pub fn potential(&self, deflection: f64) -> f64 {
        if self.is_servo() {
            0.0
        } else {
            0.5 * self.stiffness * deflection * deflection
        }
    }

    /// The power the potential does not count, at the deflection and rate: the whole torque's for
    /// a servo, the damper's and the applied torque's otherwise.
    pub fn nonconservative_power(&self, t: f64, deflection: f64, rate: f64) -> f64 {
        let (tau, _) = self.torque(t, deflection, rate);
        if self.is_servo() {
            tau * rate
        } else {
            (tau + self.stiffness * deflection) * rate
        }
    }
}
