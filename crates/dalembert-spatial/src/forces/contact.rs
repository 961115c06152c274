//! Compliant contact of a sphere on a body with a plane fixed to the ground
//! (`docs/contact.md`).
//!
//! With the sphere's centre `c`, radius `R`, the plane's point `p₀` and unit normal `n` (out of
//! the solid), the penetration is `δ = R − n·(c − p₀)` and its rate `δ̇ = −n·ċ`. Where `δ > 0` the
//! plane pushes at the sphere's lowest point `x = c − R n` with
//!
//! ```text
//! F_n = k δⁿ (1 + d δ̇)   (Hunt–Crossley; clamped at 0: the plane never pulls)        (K1)
//! F_t = −μ F_n v_t / max(|v_t|, v_s)                                                  (K2)
//! ```
//!
//! `v_t` is the velocity of the body's point at `x` along the plane. Above the smoothing velocity
//! `v_s` (m/s) the friction is Coulomb's `μ F_n` against the sliding; below it grows linearly with
//! `v_t`, so that a body at rest on a slope creeps at a speed below `v_s` instead of sticking.
//! With `d = 0` and `μ = 0` the element is conservative with the potential `k δⁿ⁺¹ / (n + 1)`.

use super::{add_point_force, V3};
use crate::frame::Frame;

/// A sphere on a body against a plane of the ground.
#[derive(Debug, Clone)]
pub(crate) struct SpherePlane {
    /// The body.
    pub body: usize,
    /// The sphere's centre in the body frame.
    pub centre: V3,
    /// Radius `R` (m).
    pub radius: f64,
    /// A point of the plane (global).
    pub point: V3,
    /// The plane's unit normal, out of the solid (global).
    pub normal: V3,
    /// `k` (N/mⁿ).
    pub stiffness: f64,
    /// `n`.
    pub exponent: f64,
    /// Hunt–Crossley's `d` (s/m).
    pub dissipation: f64,
    /// `μ`.
    pub friction: f64,
    /// `v_s` (m/s).
    pub smoothing_velocity: f64,
}

impl SpherePlane {
    /// The penetration `δ` at the state behind `frame` (negative: the gap).
    pub fn penetration(&self, frame: &dyn Fn(Option<usize>) -> Frame) -> f64 {
        let f = frame(Some(self.body));
        self.radius - self.normal.dot(&(f.point(&self.centre) - self.point))
    }

    /// Adds the contact force's generalized force (K1, K2).
    pub fn add(&self, frame: &dyn Fn(Option<usize>) -> Frame, out: &mut [f64]) {
        let f = frame(Some(self.body));
        let s_centre = f.global(&self.centre);
        let centre = f.r + s_centre;
        let depth = self.radius - self.normal.dot(&(centre - self.point));
        if depth <= 0.0 {
            return;
        }
        let rate = -self.normal.dot(&f.point_velocity(&s_centre));
        let normal_force = (self.stiffness * depth.powf(self.exponent) * (1.0 + self.dissipation * rate)).max(0.0);
        let arm = s_centre - self.radius * self.normal;
        let mut force = normal_force * self.normal;
        if self.friction > 0.0 && normal_force > 0.0 {
            let v = f.point_velocity(&arm);
            let sliding = v - self.normal.dot(&v) * self.normal;
            let speed = sliding.norm();
            force -= (self.friction * normal_force / speed.max(self.smoothing_velocity)) * sliding;
        }
        add_point_force(out, self.body, &f, &arm, &force);
    }

    /// `k δⁿ⁺¹ / (n + 1)` where the sphere penetrates, 0 elsewhere.
    pub fn potential(&self, frame: &dyn Fn(Option<usize>) -> Frame) -> f64 {
        let depth = self.penetration(frame);
        if depth <= 0.0 {
            return 0.0;
        }
        self.stiffness * depth.powf(self.exponent + 1.0) / (self.exponent + 1.0)
    }

    /// True without dissipation and friction.
    pub fn is_conservative(&self) -> bool {
        self.dissipation == 0.0 && self.friction == 0.0
    }
}
