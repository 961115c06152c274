//! Kinematics of a point fixed on a body (`docs/equations.md` §1).
//!
//! ```text
//! r = R + A u
//! ṙ = Ṙ + A_θ u θ̇          (A_θ u = perp(A u))
//! r̈ = R̈ + A_θ u θ̈ − A u θ̇²
//! ```

use crate::rotation::{perp, rotation};
use crate::{BodyState, Vec2};

/// Position, velocity and the velocity-quadratic part of the acceleration of a body-fixed point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointState {
    /// The local offset rotated to global axes, `A u`.
    pub arm: Vec2,
    /// Global position `r = R + A u`.
    pub position: Vec2,
    /// Global velocity `ṙ = Ṙ + θ̇ perp(A u)`.
    pub velocity: Vec2,
    /// The part of `r̈` that does not depend on `q̈`: `−θ̇² A u`.
    pub quadratic_acceleration: Vec2,
}

impl PointState {
    /// Kinematics of the point at local offset `u` on a body in state `s`.
    #[inline]
    pub fn new(s: &BodyState, u: Vec2) -> PointState {
        let arm = s.rotation() * u;
        PointState {
            arm,
            position: s.position + arm,
            velocity: s.velocity + perp(arm) * s.omega,
            quadratic_acceleration: -arm * (s.omega * s.omega),
        }
    }

    /// The point's derivative with respect to the body's `θ`: `A_θ u = perp(A u)`.
    /// Together with the identity for `x, y` this is the 2×3 Jacobian `[I, A_θ u]`.
    #[inline]
    pub fn d_theta(&self) -> Vec2 {
        perp(self.arm)
    }

    /// Full acceleration `r̈ = R̈ + θ̈ perp(A u) − θ̇² A u` for given body accelerations.
    #[inline]
    pub fn acceleration(&self, body_acceleration: Vec2, alpha: f64) -> Vec2 {
        body_acceleration + perp(self.arm) * alpha + self.quadratic_acceleration
    }
}

/// Global position of local point `u` on a body at `position`, `angle`.
#[inline]
pub fn global_point(position: Vec2, angle: f64, u: Vec2) -> Vec2 {
    position + rotation(angle) * u
}

/// Local coordinates of global point `p` in a body at `position`, `angle`: `u = Aᵀ (p − R)`.
#[inline]
pub fn local_point(position: Vec2, angle: f64, p: Vec2) -> Vec2 {
    rotation(angle).transpose() * (p - position)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Velocity and acceleration against central differences along an analytic trajectory.
    #[test]
    fn derivatives_match_finite_differences() {
        let u = Vec2::new(0.7, -0.2);
        let traj = |t: f64| {
            BodyState::new(
                Vec2::new(t.sin(), 0.3 * t * t),
                0.5 + 1.3 * t + 0.2 * t * t,
                Vec2::new(t.cos(), 0.6 * t),
                1.3 + 0.4 * t,
            )
        };
        let accel = |t: f64| (Vec2::new(-t.sin(), 0.6), 0.4);
        let t = 0.37;
        let h = 1e-4;
        let p = |t| PointState::new(&traj(t), u);
        let fd_v = (p(t + h).position - p(t - h).position) / (2.0 * h);
        let fd_a = (p(t + h).position - 2.0 * p(t).position + p(t - h).position) / (h * h);
        // O(h²) truncation ~1e-8; second difference round-off ~1e-16/h² = 1e-8.
        assert!((fd_v - p(t).velocity).norm() < 1e-7);
        let (acc, al) = accel(t);
        assert!((fd_a - p(t).acceleration(acc, al)).norm() < 1e-6);
    }

    #[test]
    fn local_and_global_are_inverse() {
        let r = Vec2::new(1.0, 2.0);
        let u = Vec2::new(-0.3, 0.9);
        let p = global_point(r, 0.8, u);
        assert!((local_point(r, 0.8, p) - u).norm() < 1e-15);
    }
}
