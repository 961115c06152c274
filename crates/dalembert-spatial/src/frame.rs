//! A body's pose and velocity in the global frame at one state: what the joint primitives and the
//! force elements read.

use crate::euler_parameters::{self, EulerParameters};
use nalgebra::{Matrix3, Vector3};

/// Position coordinates of a spatial body: `x y z` of its centre of mass, then Euler parameters.
pub const POSITION_LABELS: &[&str] = &["x", "y", "z", "e0", "e1", "e2", "e3"];
/// Velocity coordinates: the centre of mass's velocity (global), then the angular velocity in the
/// body frame.
pub const VELOCITY_LABELS: &[&str] = &["vx", "vy", "vz", "wx'", "wy'", "wz'"];

/// Positions per body.
pub const NQ: usize = 7;
/// Velocities per body.
pub const NV: usize = 6;

/// Pose and velocity of a body (or of the ground) in the global frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    /// Centre of mass.
    pub r: Vector3<f64>,
    /// Rotation matrix, body frame to global frame.
    pub a: Matrix3<f64>,
    /// Velocity of the centre of mass.
    pub v: Vector3<f64>,
    /// Angular velocity in the **global** frame (`ω = A ω'`).
    pub w: Vector3<f64>,
}

impl Frame {
    /// The ground: at the origin, not rotated, at rest.
    pub const GROUND: Frame = Frame {
        r: Vector3::new(0.0, 0.0, 0.0),
        a: Matrix3::new(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0),
        v: Vector3::new(0.0, 0.0, 0.0),
        w: Vector3::new(0.0, 0.0, 0.0),
    };

    /// The frame of body `b` from the system vectors (`v` empty: at rest).
    #[inline]
    pub fn of(b: usize, q: &[f64], v: &[f64]) -> Frame {
        let (r, p) = position(b, q);
        let a = euler_parameters::rotation(&p);
        let (lin, ang) = if v.is_empty() {
            (Vector3::zeros(), Vector3::zeros())
        } else {
            velocity(b, v)
        };
        Frame {
            r,
            a,
            v: lin,
            w: a * ang,
        }
    }

    /// A body-fixed vector `s'` in global components, `A s'`.
    #[inline]
    pub fn global(&self, s: &Vector3<f64>) -> Vector3<f64> {
        self.a * s
    }

    /// The global point of the body-fixed point `s'`.
    #[inline]
    pub fn point(&self, s: &Vector3<f64>) -> Vector3<f64> {
        self.r + self.a * s
    }

    /// The velocity of the body point whose global arm from the centre of mass is `s`.
    #[inline]
    pub fn point_velocity(&self, s: &Vector3<f64>) -> Vector3<f64> {
        self.v + self.w.cross(s)
    }

    /// The centripetal acceleration `ω × (ω × s)` of a body-fixed global arm `s`.
    #[inline]
    pub fn centripetal(&self, s: &Vector3<f64>) -> Vector3<f64> {
        self.w.cross(&self.w.cross(s))
    }
}

/// Centre of mass and Euler parameters of body `b` in `q`.
#[inline]
pub fn position(b: usize, q: &[f64]) -> (Vector3<f64>, EulerParameters) {
    let o = NQ * b;
    (
        Vector3::new(q[o], q[o + 1], q[o + 2]),
        [q[o + 3], q[o + 4], q[o + 5], q[o + 6]],
    )
}

/// Velocity of the centre of mass (global) and body-frame angular velocity of body `b` in `v`.
#[inline]
pub fn velocity(b: usize, v: &[f64]) -> (Vector3<f64>, Vector3<f64>) {
    let o = NV * b;
    (
        Vector3::new(v[o], v[o + 1], v[o + 2]),
        Vector3::new(v[o + 3], v[o + 4], v[o + 5]),
    )
}
