//! Independent minimal-coordinate solutions of the reference mechanisms.

use crate::jet::Jet;
use crate::mechanisms::G;

/// Absolute-angle equations of motion of a two-rod chain (uniform rods, pinned at the origin,
/// gravity −y), derived by Lagrange's equations in `θ₁, θ₂`:
///
/// ```text
/// M₁₁ = m₁L₁²/4 + J₁ + m₂L₁²,  M₂₂ = m₂L₂²/4 + J₂,  M₁₂ = k cos(θ₁−θ₂),  k = m₂L₁L₂/2
/// M₁₁θ̈₁ + M₁₂θ̈₂ + k sin(θ₁−θ₂) θ̇₂² = −g (m₁L₁/2 + m₂L₁) cos θ₁ + Q₁
/// M₁₂θ̈₁ + M₂₂θ̈₂ − k sin(θ₁−θ₂) θ̇₁² = −g m₂L₂/2 cos θ₂ + Q₂
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DoublePendulum {
    /// Masses.
    pub m: [f64; 2],
    /// Lengths.
    pub l: [f64; 2],
}

impl DoublePendulum {
    /// `(M, h)` with `M θ̈ = h`, `h` holding gravity, velocity terms and generalized forces `q_ext`.
    pub fn system(&self, th: [f64; 2], w: [f64; 2], q_ext: [f64; 2]) -> ([[f64; 2]; 2], [f64; 2]) {
        let [m1, m2] = self.m;
        let [l1, l2] = self.l;
        let (j1, j2) = (m1 * l1 * l1 / 12.0, m2 * l2 * l2 / 12.0);
        let k = m2 * l1 * l2 / 2.0;
        let d = th[0] - th[1];
        let m11 = m1 * l1 * l1 / 4.0 + j1 + m2 * l1 * l1;
        let m22 = m2 * l2 * l2 / 4.0 + j2;
        let m12 = k * d.cos();
        let h1 = -G * (m1 * l1 / 2.0 + m2 * l1) * th[0].cos() - k * d.sin() * w[1] * w[1] + q_ext[0];
        let h2 = -G * m2 * l2 / 2.0 * th[1].cos() + k * d.sin() * w[0] * w[0] + q_ext[1];
        ([[m11, m12], [m12, m22]], [h1, h2])
    }

    /// Angular accelerations for absolute-angle generalized forces `q_ext`.
    pub fn accelerations(&self, th: [f64; 2], w: [f64; 2], q_ext: [f64; 2]) -> [f64; 2] {
        let (m, h) = self.system(th, w, q_ext);
        let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
        [
            (m[1][1] * h[0] - m[0][1] * h[1]) / det,
            (m[0][0] * h[1] - m[1][0] * h[0]) / det,
        ]
    }

    /// Joint torques `[τ₁, τ₂]` of the two-link arm (τ₁ ground→link 1, τ₂ link 1→link 2) that
    /// produce `θ̈`: `M θ̈ − h(τ = 0) = Q_abs`, and `τ₂ = Q_abs,2`, `τ₁ = Q_abs,1 + Q_abs,2`
    /// (virtual work of the relative joint angle `θ₂ − θ₁`).
    pub fn joint_torques(&self, th: [f64; 2], w: [f64; 2], acc: [f64; 2]) -> [f64; 2] {
        let (m, h) = self.system(th, w, [0.0, 0.0]);
        let q1 = m[0][0] * acc[0] + m[0][1] * acc[1] - h[0];
        let q2 = m[1][0] * acc[0] + m[1][1] * acc[1] - h[1];
        [q1 + q2, q2]
    }
}

/// Closed-form kinematics of a four-bar (ground pivots (0,0) and (d,0), crank a, coupler b,
/// rocker c, uniform rods of linear density 1 kg/m), as functions of the crank angle φ with exact
/// first and second derivatives (via [`Jet`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FourBar {
    /// Crank length.
    pub a: f64,
    /// Coupler length.
    pub b: f64,
    /// Rocker length.
    pub c: f64,
    /// Ground link length.
    pub d: f64,
    /// +1 or −1: which of the two assemblies (−1 is the anchors' elbow-down one).
    pub branch: f64,
}

impl FourBar {
    /// The four-bar of `shared/anchors`.
    pub const ANCHOR: FourBar = FourBar {
        a: 1.0,
        b: 2.5,
        c: 1.5,
        d: 2.0,
        branch: -1.0,
    };

    /// Body coordinates `[x, y, θ]` of crank, coupler, rocker (centres of mass) as jets in φ.
    pub fn coordinates(&self, phi: Jet) -> [Jet; 9] {
        let (a, b, c, d) = (Jet::c(self.a), Jet::c(self.b), Jet::c(self.c), Jet::c(self.d));
        let bx = a * phi.cos();
        let by = a * phi.sin();
        let (ex, ey) = (d - bx, -by);
        let dist = (ex * ex + ey * ey).sqrt();
        let along = (b * b - c * c + dist * dist) / (dist * Jet::c(2.0));
        let h = (b * b - along * along).sqrt() * self.branch;
        let (ux, uy) = (ex / dist, ey / dist);
        let cx = bx + ux * along - uy * h;
        let cy = by + uy * along + ux * h;
        let half = Jet::c(0.5);
        [
            bx * half,
            by * half,
            phi,
            (bx + cx) * half,
            (by + cy) * half,
            (cy - by).atan2(cx - bx),
            (d + cx) * half,
            cy * half,
            cy.atan2(cx - d),
        ]
    }

    /// Consistent `(q, q̇)` at crank angle φ and rate φ̇.
    pub fn state(&self, phi: f64, phi_dot: f64) -> (Vec<f64>, Vec<f64>) {
        let x = self.coordinates(Jet::var(phi));
        (
            x.iter().map(|j| j.v).collect(),
            x.iter().map(|j| j.d * phi_dot).collect(),
        )
    }

    /// Masses and centroidal inertias of the three rods (1 kg/m).
    fn inertia(&self) -> [(f64, f64); 3] {
        [self.a, self.b, self.c].map(|l| (l, l * l * l / 12.0))
    }

    /// Crank angular acceleration under gravity and a crank torque `tau`, from Lagrange's equation
    /// in φ: `(Σ Jᵀ M J) φ̈ + (Σ Jᵀ M H) φ̇² = Σ Jᵀ Q`, with `J = ∂x/∂φ`, `H = ∂²x/∂φ²`.
    pub fn crank_acceleration(&self, phi: f64, phi_dot: f64, tau: f64) -> f64 {
        let x = self.coordinates(Jet::var(phi));
        let mut mass = 0.0;
        let mut quad = 0.0;
        let mut force = tau; // ∂θ_crank/∂φ = 1
        for (k, (m, j)) in self.inertia().into_iter().enumerate() {
            let w = [m, m, j];
            for i in 0..3 {
                let e = x[3 * k + i];
                mass += w[i] * e.d * e.d;
                quad += w[i] * e.d * e.dd;
            }
            force += -m * G * x[3 * k + 1].d;
        }
        (force - quad * phi_dot * phi_dot) / mass
    }

    /// All body accelerations `q̈ = J φ̈ + H φ̇²`.
    pub fn accelerations(&self, phi: f64, phi_dot: f64, phi_ddot: f64) -> Vec<f64> {
        self.coordinates(Jet::var(phi))
            .iter()
            .map(|j| j.d * phi_ddot + j.dd * phi_dot * phi_dot)
            .collect()
    }
}

/// Complete elliptic integral of the first kind `K(k)` (modulus `k`), by the arithmetic–geometric
/// mean: `K = π / (2 AGM(1, √(1−k²)))`.
pub fn elliptic_k(k: f64) -> f64 {
    let (mut a, mut b) = (1.0f64, (1.0 - k * k).sqrt());
    for _ in 0..60 {
        let (an, bn) = (0.5 * (a + b), (a * b).sqrt());
        a = an;
        b = bn;
        if (a - b).abs() <= 1e-16 * a {
            break;
        }
    }
    std::f64::consts::PI / (2.0 * a)
}

/// Jacobi elliptic function `sn(u, k)` by the descending Landen (AGM) transformation
/// (Abramowitz & Stegun 16.4).
pub fn jacobi_sn(u: f64, k: f64) -> f64 {
    let mut a = vec![1.0f64];
    let mut c = vec![k];
    let mut b = (1.0 - k * k).sqrt();
    while c.last().is_some_and(|x| x.abs() > 1e-16) && a.len() < 40 {
        let an = *a.last().unwrap_or(&1.0);
        let cn = 0.5 * (an - b);
        let nb = (an * b).sqrt();
        a.push(0.5 * (an + b));
        c.push(cn);
        b = nb;
    }
    let n = a.len() - 1;
    let mut phi = (1u64 << n) as f64 * a[n] * u;
    for j in (1..=n).rev() {
        phi = 0.5 * (phi + (c[j] / a[j] * phi.sin()).asin());
    }
    phi.sin()
}

/// Angle from the downward vertical of an undamped pendulum `φ̈ = −ω₀² sin φ` released from rest
/// at `φ₀` (|φ₀| < π): `φ(t) = 2 asin(k sn(K − ω₀ t, k))`, `k = sin(φ₀/2)`.
pub fn pendulum_angle(phi0: f64, omega0: f64, t: f64) -> f64 {
    let k = (0.5 * phi0).sin();
    let kk = elliptic_k(k.abs());
    2.0 * (k * jacobi_sn(kk - omega0 * t, k.abs())).asin()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn elliptic_functions_match_known_values() {
        // K(sin 30°) = 1.685750354812596 (A&S table 17.1); sn(K, k) = 1; sn(u, 0) = sin u.
        assert!((elliptic_k(0.5) - 1.685750354812596).abs() < 1e-14);
        assert!((jacobi_sn(elliptic_k(0.7), 0.7) - 1.0).abs() < 1e-13);
        assert!((jacobi_sn(0.9, 0.0) - 0.9f64.sin()).abs() < 1e-15);
        // Small amplitude: the pendulum is harmonic.
        let p = pendulum_angle(1e-6, 2.0, 0.7);
        assert!((p - 1e-6 * (2.0f64 * 0.7).cos()).abs() < 1e-15);
    }
}
