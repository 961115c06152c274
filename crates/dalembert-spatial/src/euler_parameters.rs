//! Euler parameters (unit quaternions) `p = (e₀, e₁, e₂, e₃)` for orientation (Shabana,
//! *Computational Dynamics*, §7.3; Nikravesh, *Computer-Aided Analysis of Mechanical Systems*, §6.3).
//!
//! ```text
//! A(p) = (e₀² − eᵀe) I + 2 e eᵀ + 2 e₀ ẽ          body frame → global frame, e = (e₁, e₂, e₃)
//! ṗ = ½ p ⊗ (0, ω')                             ω' the angular velocity in the body frame
//! p(t + h) = p ⊗ (cos(h|ω'|/2), sin(h|ω'|/2) ω'/|ω'|)   exact for constant ω'
//! ```
//!
//! [`rotation`] divides by `pᵀp`, so `A` is a rotation for any non-zero `p` (an explicit
//! Runge–Kutta stage may leave `|p|` off 1 by the local error before the step is normalized).

use nalgebra::{Matrix3, Vector3};

/// Euler parameters `[e₀, e₁, e₂, e₃]`.
pub type EulerParameters = [f64; 4];

/// The identity orientation `(1, 0, 0, 0)`.
pub const IDENTITY: EulerParameters = [1.0, 0.0, 0.0, 0.0];

/// `A(p)`, body frame to global frame (`p` need not be exactly unit: the result is scaled by
/// `1 / pᵀp`, which is a rotation for any `p ≠ 0`).
#[inline]
pub fn rotation(p: &EulerParameters) -> Matrix3<f64> {
    let [e0, e1, e2, e3] = *p;
    let s = 1.0 / (e0 * e0 + e1 * e1 + e2 * e2 + e3 * e3);
    let d = (e0 * e0 - e1 * e1 - e2 * e2 - e3 * e3) * s;
    let t = 2.0 * s;
    Matrix3::new(
        d + t * e1 * e1,
        t * (e1 * e2 - e0 * e3),
        t * (e1 * e3 + e0 * e2),
        t * (e1 * e2 + e0 * e3),
        d + t * e2 * e2,
        t * (e2 * e3 - e0 * e1),
        t * (e1 * e3 - e0 * e2),
        t * (e2 * e3 + e0 * e1),
        d + t * e3 * e3,
    )
}

/// Quaternion product `a ⊗ b`.
#[inline]
pub fn product(a: &EulerParameters, b: &EulerParameters) -> EulerParameters {
    let [a0, a1, a2, a3] = *a;
    let [b0, b1, b2, b3] = *b;
    [
        a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3,
        a0 * b1 + a1 * b0 + a2 * b3 - a3 * b2,
        a0 * b2 - a1 * b3 + a2 * b0 + a3 * b1,
        a0 * b3 + a1 * b2 - a2 * b1 + a3 * b0,
    ]
}

/// `ṗ = ½ p ⊗ (0, ω')` for the body-frame angular velocity `ω'`.
#[inline]
pub fn rates(p: &EulerParameters, omega_body: &Vector3<f64>) -> EulerParameters {
    let w = product(p, &[0.0, omega_body.x, omega_body.y, omega_body.z]);
    [0.5 * w[0], 0.5 * w[1], 0.5 * w[2], 0.5 * w[3]]
}

/// The rotation by the vector `θ` (axis `θ/|θ|`, angle `|θ|`) as Euler parameters: the exponential
/// map, with its Taylor series below `|θ| = 1e-4` (relative error under 1e-18 there).
#[inline]
pub fn from_rotation_vector(theta: &Vector3<f64>) -> EulerParameters {
    let angle2 = theta.norm_squared();
    let (c, s_over) = if angle2 < 1e-8 {
        // cos(x/2) and sin(x/2)/x to the first neglected term x⁴/3840.
        (1.0 - angle2 / 8.0 + angle2 * angle2 / 384.0, 0.5 - angle2 / 48.0)
    } else {
        let angle = angle2.sqrt();
        let (s, c) = (0.5 * angle).sin_cos();
        (c, s / angle)
    };
    [c, s_over * theta.x, s_over * theta.y, s_over * theta.z]
}

/// `p ← p ⊗ exp(θ'/2)`: rotates by the body-frame rotation vector `θ'` (`h ω'` over a step with
/// constant `ω'`, or a correction).
#[inline]
pub fn rotate_body(p: &mut EulerParameters, theta_body: &Vector3<f64>) {
    *p = product(p, &from_rotation_vector(theta_body));
}

/// `J_r(φ)⁻¹ ω'`: the rate of the rotation vector `φ` of `R = R₀ Exp(φ)` (fixed `R₀`) when the
/// body-frame angular velocity is `ω'` (`ω' = J_r(φ) φ̇`):
/// `φ̇ = ω' + ½ φ × ω' + (1/θ² − (1 + cos θ)/(2 θ sin θ)) φ × (φ × ω')`, `θ = |φ|`, the last
/// coefficient from its series `1/12 + θ²/720` below `θ = 1e-3` (relative error under 1e-13).
#[inline]
pub fn inverse_right_jacobian(phi: &Vector3<f64>, w: &Vector3<f64>) -> Vector3<f64> {
    let theta2 = phi.norm_squared();
    let c = if theta2 < 1e-6 {
        1.0 / 12.0 + theta2 / 720.0
    } else {
        let theta = theta2.sqrt();
        1.0 / theta2 - (1.0 + theta.cos()) / (2.0 * theta * theta.sin())
    };
    let pw = phi.cross(w);
    w + 0.5 * pw + c * phi.cross(&pw)
}

/// `p / |p|` (a zero `p` is left alone: it is reported by the model's state checks).
#[inline]
pub fn normalized(p: &EulerParameters) -> EulerParameters {
    let n = p.iter().map(|x| x * x).sum::<f64>().sqrt();
    if n > 0.0 {
        p.map(|x| x / n)
    } else {
        *p
    }
}

/// Euler parameters of the rotation by `angle` (radians) about `axis` (any non-zero length).
pub fn from_axis_angle(axis: &Vector3<f64>, angle: f64) -> EulerParameters {
    let u = axis.normalize();
    let (s, c) = (0.5 * angle).sin_cos();
    [c, s * u.x, s * u.y, s * u.z]
}

/// Euler parameters of a rotation matrix (Shepperd's method: the largest of the four squares is
/// taken first, so the result is accurate for every rotation).
pub fn from_rotation(a: &Matrix3<f64>) -> EulerParameters {
    let tr = a.trace();
    let cands = [tr, a[(0, 0)], a[(1, 1)], a[(2, 2)]];
    let k = (0..4).max_by(|&i, &j| cands[i].total_cmp(&cands[j])).unwrap_or(0);
    let p = match k {
        0 => {
            let e0 = 0.5 * (1.0 + tr).sqrt();
            let f = 0.25 / e0;
            [
                e0,
                f * (a[(2, 1)] - a[(1, 2)]),
                f * (a[(0, 2)] - a[(2, 0)]),
                f * (a[(1, 0)] - a[(0, 1)]),
            ]
        }
        1 => {
            let e1 = 0.5 * (1.0 + 2.0 * a[(0, 0)] - tr).sqrt();
            let f = 0.25 / e1;
            [
                f * (a[(2, 1)] - a[(1, 2)]),
                e1,
                f * (a[(0, 1)] + a[(1, 0)]),
                f * (a[(0, 2)] + a[(2, 0)]),
            ]
        }
        2 => {
            let e2 = 0.5 * (1.0 + 2.0 * a[(1, 1)] - tr).sqrt();
            let f = 0.25 / e2;
            [
                f * (a[(0, 2)] - a[(2, 0)]),
                f * (a[(0, 1)] + a[(1, 0)]),
                e2,
                f * (a[(1, 2)] + a[(2, 1)]),
            ]
        }
        _ => {
            let e3 = 0.5 * (1.0 + 2.0 * a[(2, 2)] - tr).sqrt();
            let f = 0.25 / e3;
            [
                f * (a[(1, 0)] - a[(0, 1)]),
                f * (a[(0, 2)] + a[(2, 0)]),
                f * (a[(1, 2)] + a[(2, 1)]),
                e3,
            ]
        }
    };
    if p[0] < 0.0 {
        p.map(|x| -x)
    } else {
        p
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn sample() -> EulerParameters {
        normalized(&[0.8, -0.3, 0.45, 0.2])
    }

    /// `φ̇ = J_r(φ)⁻¹ ω'` moves `Exp(φ)` as the body-frame angular velocity `ω'` does:
    /// `Exp(φ + ε φ̇) = Exp(φ) Exp(ε ω') + O(ε²)`, so the central difference of the two rotations
    /// over `±ε` agrees to `O(ε²)` (ε = 1e-5: 1e-10 with unit rates). At small, moderate and
    /// large angles (both branches of the coefficient).
    #[test]
    fn inverse_right_jacobian_is_the_rate_of_the_rotation_vector() {
        let w = Vector3::new(0.7, -1.3, 0.4);
        for phi in [
            Vector3::new(2e-4, -1e-4, 3e-4),
            Vector3::new(0.3, 0.2, -0.5),
            Vector3::new(1.9, -1.1, 1.4),
        ] {
            let rate = inverse_right_jacobian(&phi, &w);
            let eps = 1e-5;
            let along = |s: f64| rotation(&from_rotation_vector(&(phi + s * rate)));
            let turned = |s: f64| {
                let mut p = from_rotation_vector(&phi);
                rotate_body(&mut p, &(s * w));
                rotation(&p)
            };
            let chart = (along(eps) - along(-eps)) / (2.0 * eps);
            let body = (turned(eps) - turned(-eps)) / (2.0 * eps);
            assert_relative_eq!(chart, body, epsilon = 1e-9);
        }
    }

    /// `A` is orthogonal with determinant 1, equals Rodrigues' formula for the same axis and angle,
    /// and `from_rotation` inverts it.
    #[test]
    fn rotation_is_rodrigues_and_inverts() {
        let axis = Vector3::new(0.3, -1.2, 0.7);
        let angle = 2.1;
        let a = rotation(&from_axis_angle(&axis, angle));
        let u = axis.normalize();
        let ux = u.cross_matrix();
        let rodrigues = Matrix3::identity() + angle.sin() * ux + (1.0 - angle.cos()) * ux * ux;
        assert_relative_eq!(a, rodrigues, epsilon = 1e-15);
        assert_relative_eq!(a.transpose() * a, Matrix3::identity(), epsilon = 1e-15);
        assert_relative_eq!(a.determinant(), 1.0, epsilon = 1e-15);
        let p = sample();
        let back = from_rotation(&rotation(&p));
        for k in 0..4 {
            assert_relative_eq!(back[k], p[k], epsilon = 1e-15);
        }
    }

    /// `ṗ = ½ p ⊗ ω'` is the derivative of `p ⊗ exp(t ω'/2)` at `t = 0` (central difference, error
    /// `O(h²) ≈ 1e-12`), and `Ȧ = A ω̃'` for it.
    #[test]
    fn rates_match_the_exponential_update() {
        let p = sample();
        let w = Vector3::new(0.7, -1.1, 2.3);
        let h = 1e-6;
        let (mut fwd, mut back) = (p, p);
        rotate_body(&mut fwd, &(h * w));
        rotate_body(&mut back, &(-h * w));
        let r = rates(&p, &w);
        for k in 0..4 {
            assert_relative_eq!((fwd[k] - back[k]) / (2.0 * h), r[k], epsilon = 1e-9);
        }
        let a_dot = (rotation(&fwd) - rotation(&back)) / (2.0 * h);
        assert_relative_eq!(a_dot, rotation(&p) * w.cross_matrix(), epsilon = 1e-9);
    }

    /// The series branch of the exponential agrees with the closed form where they meet.
    #[test]
    fn small_rotation_series_matches_closed_form() {
        let theta = Vector3::new(3e-5, -6e-5, 5e-5);
        let series = from_rotation_vector(&theta);
        let closed = from_axis_angle(&theta, theta.norm());
        for k in 0..4 {
            assert_relative_eq!(series[k], closed[k], epsilon = 1e-17);
        }
    }
}
