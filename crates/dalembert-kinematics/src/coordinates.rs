//! The system coordinate layout and per-body states read from it.
//!
//! `q = [x₀, y₀, θ₀, x₁, y₁, θ₁, …]`: three entries per moving body, in body order. The ground is
//! not in `q`. Velocities `q̇` and accelerations `q̈` use the same layout.

use crate::{BodyId, BodyRef, Vec2};

/// The layout of the system vector for a number of moving bodies.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Coordinates {
    bodies: usize,
}

impl Coordinates {
    /// Layout for `bodies` moving bodies.
    pub fn new(bodies: usize) -> Self {
        Coordinates { bodies }
    }

    /// Number of moving bodies.
    #[inline]
    pub fn bodies(&self) -> usize {
        self.bodies
    }

    /// Length `n = 3 × bodies` of `q`.
    #[inline]
    pub fn len(&self) -> usize {
        3 * self.bodies
    }

    /// True when there is no moving body.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.bodies == 0
    }

    /// The body owning coordinate index `i` and which of its coordinates it is (0 = x, 1 = y, 2 = θ).
    #[inline]
    pub fn owner(&self, i: usize) -> (BodyId, usize) {
        (BodyId(i / 3), i % 3)
    }
}

/// Pose and velocity of one body (or of the ground: all zero).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct BodyState {
    /// Global position of the reference point `R`.
    pub position: Vec2,
    /// Orientation `θ` (rad).
    pub angle: f64,
    /// Velocity of the reference point `Ṙ`.
    pub velocity: Vec2,
    /// Angular velocity `θ̇` (rad/s).
    pub omega: f64,
    /// `cos θ`, cached.
    pub cos: f64,
    /// `sin θ`, cached.
    pub sin: f64,
}

impl BodyState {
    /// The ground's state: at the origin, not rotated, at rest.
    pub const GROUND: BodyState = BodyState {
        position: Vec2::new(0.0, 0.0),
        angle: 0.0,
        velocity: Vec2::new(0.0, 0.0),
        omega: 0.0,
        cos: 1.0,
        sin: 0.0,
    };

    /// A state from its parts (computes and caches `cos θ`, `sin θ`).
    #[inline]
    pub fn new(position: Vec2, angle: f64, velocity: Vec2, omega: f64) -> BodyState {
        let (sin, cos) = angle.sin_cos();
        BodyState {
            position,
            angle,
            velocity,
            omega,
            cos,
            sin,
        }
    }

    /// The rotation matrix `A(θ)` from the cached sine and cosine.
    #[inline]
    pub fn rotation(&self) -> nalgebra::Matrix2<f64> {
        nalgebra::Matrix2::new(self.cos, -self.sin, self.sin, self.cos)
    }

    /// Reads the state of `body` from the system vectors (`qd` may be empty: zero velocity).
    #[inline]
    pub fn of(body: BodyRef, q: &[f64], qd: &[f64]) -> BodyState {
        match body {
            BodyRef::Ground => BodyState::GROUND,
            BodyRef::Body(id) => {
                let (sin, cos) = q[id.offset() + 2].sin_cos();
                Self::of_with_rotation(body, q, qd, sin, cos)
            }
        }
    }

    /// [`BodyState::of`] with `sin θ` and `cos θ` already known (computed once per body per
    /// evaluation by the constraint assembly).
    #[inline]
    pub fn of_with_rotation(body: BodyRef, q: &[f64], qd: &[f64], sin: f64, cos: f64) -> BodyState {
        match body {
            BodyRef::Ground => BodyState::GROUND,
            BodyRef::Body(id) => {
                let k = id.offset();
                let (velocity, omega) = if qd.is_empty() {
                    (Vec2::zeros(), 0.0)
                } else {
                    (Vec2::new(qd[k], qd[k + 1]), qd[k + 2])
                };
                BodyState {
                    position: Vec2::new(q[k], q[k + 1]),
                    angle: q[k + 2],
                    velocity,
                    omega,
                    cos,
                    sin,
                }
            }
        }
    }
}
