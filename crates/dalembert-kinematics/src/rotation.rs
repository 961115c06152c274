//! Planar rotation matrices `A(θ)`, `A_θ(θ)` and the 90° rotation `perp`.

use crate::Vec2;
use nalgebra::Matrix2;

/// Rotation matrix `A(θ) = [[cos θ, −sin θ], [sin θ, cos θ]]`: body frame to global frame.
#[inline]
pub fn rotation(theta: f64) -> Matrix2<f64> {
    let (s, c) = theta.sin_cos();
    Matrix2::new(c, -s, s, c)
}

/// Derivative `A_θ(θ) = dA/dθ = [[−sin θ, −cos θ], [cos θ, −sin θ]]`.
///
/// Note the identity `A_θ u = perp(A u)`, used throughout instead of forming `A_θ`.
#[inline]
pub fn rotation_derivative(theta: f64) -> Matrix2<f64> {
    let (s, c) = theta.sin_cos();
    Matrix2::new(-s, -c, c, -s)
}

/// The vector rotated by +90°: `perp([x, y]) = [−y, x]`, i.e. `ω × v` for a unit `ω` along +z.
#[inline]
pub fn perp(v: Vec2) -> Vec2 {
    Vec2::new(-v.y, v.x)
}

/// Planar cross product `a × b = a_x b_y − a_y b_x` (the z component).
#[inline]
pub fn cross(a: Vec2, b: Vec2) -> f64 {
    a.x * b.y - a.y * b.x
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derivative_matches_perp_identity_and_finite_difference() {
        let u = Vec2::new(0.3, -1.7);
        for &th in &[0.0, 0.4, 2.5, -3.0] {
            let lhs = rotation_derivative(th) * u;
            let rhs = perp(rotation(th) * u);
            assert!((lhs - rhs).norm() < 1e-15);
            let h = 1e-6;
            let fd = (rotation(th + h) - rotation(th - h)) / (2.0 * h);
            // Central difference error is O(h²) ≈ 1e-12 relative to entries of size 1.
            assert!((fd - rotation_derivative(th)).norm() < 1e-9);
        }
    }
}
