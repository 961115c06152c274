//! The block-diagonal system mass matrix (`docs/equations.md` §1).
//!
//! Body `i` contributes the 3×3 block
//!
//! ```text
//! M_i = [ m I₂          m A_θ c ]        A_θ c = perp(A c)
//!       [ m (A_θ c)ᵀ    J_cm + m |c|² ]
//! ```
//!
//! which is `diag(m, m, J)` when the reference point is the centre of mass (`c = 0`), and the
//! quadratic-velocity force `Q_v = [m A c θ̇², 0]` on the body's rows.

use crate::rotation::{perp, rotation};
use crate::{Body, BodyId};
use nalgebra::Matrix3;

/// The system mass matrix, stored as one 3×3 block per moving body.
#[derive(Debug, Clone, PartialEq)]
pub struct MassMatrix {
    blocks: Vec<Matrix3<f64>>,
    /// True when some body's reference point is away from its centre of mass (blocks depend on θ).
    configuration_dependent: bool,
}

impl MassMatrix {
    /// Builds the blocks for `bodies` at the angles in `q` (angles only matter for offset centres of mass).
    pub fn new(bodies: &[Body], q: &[f64]) -> Self {
        let configuration_dependent = bodies.iter().any(|b| b.center_of_mass != crate::Vec2::zeros());
        let mut m = MassMatrix {
            blocks: vec![Matrix3::zeros(); bodies.len()],
            configuration_dependent,
        };
        for (i, b) in bodies.iter().enumerate() {
            m.blocks[i] = Self::block(b, q[3 * i + 2]);
        }
        m
    }

    /// The 3×3 block of one body at angle `theta`.
    pub fn block(b: &Body, theta: f64) -> Matrix3<f64> {
        let m = b.mass;
        let cp = perp(rotation(theta) * b.center_of_mass) * m;
        Matrix3::new(m, 0.0, cp.x, 0.0, m, cp.y, cp.x, cp.y, b.inertia_about_reference())
    }

    /// Refreshes the blocks for a new configuration. Free when every body's reference point is its
    /// centre of mass (then the matrix is constant). Allocates nothing.
    pub fn update(&mut self, bodies: &[Body], q: &[f64]) {
        if !self.configuration_dependent {
            return;
        }
        for (i, b) in bodies.iter().enumerate() {
            self.blocks[i] = Self::block(b, q[3 * i + 2]);
        }
    }

    /// True when the blocks depend on the configuration.
    pub fn is_configuration_dependent(&self) -> bool {
        self.configuration_dependent
    }

    /// The block of body `id`.
    #[inline]
    pub fn body_block(&self, id: BodyId) -> &Matrix3<f64> {
        &self.blocks[id.0]
    }

    /// All blocks in body order.
    #[inline]
    pub fn blocks(&self) -> &[Matrix3<f64>] {
        &self.blocks
    }

    /// `y ← y + α M x`.
    pub fn mul_add(&self, alpha: f64, x: &[f64], y: &mut [f64]) {
        for (i, b) in self.blocks.iter().enumerate() {
            let k = 3 * i;
            for r in 0..3 {
                y[k + r] += alpha * (b[(r, 0)] * x[k] + b[(r, 1)] * x[k + 1] + b[(r, 2)] * x[k + 2]);
            }
        }
    }

    /// Kinetic energy `T = ½ q̇ᵀ M q̇`.
    pub fn kinetic_energy(&self, qd: &[f64]) -> f64 {
        let mut t = 0.0;
        for (i, b) in self.blocks.iter().enumerate() {
            let v = nalgebra::Vector3::new(qd[3 * i], qd[3 * i + 1], qd[3 * i + 2]);
            t += v.dot(&(b * v));
        }
        0.5 * t
    }

    /// Adds the quadratic-velocity force `Q_v = m A c θ̇²` of offset centres of mass to `q_e`.
    pub fn add_quadratic_velocity_force(bodies: &[Body], q: &[f64], qd: &[f64], q_e: &mut [f64]) {
        for (i, b) in bodies.iter().enumerate() {
            if b.center_of_mass == crate::Vec2::zeros() {
                continue;
            }
            let w = qd[3 * i + 2];
            let f = rotation(q[3 * i + 2]) * b.center_of_mass * (b.mass * w * w);
            q_e[3 * i] += f.x;
            q_e[3 * i + 1] += f.y;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Vec2;

    /// Kinetic energy from the coupled block equals ½ m |v_cm|² + ½ J_cm ω² computed directly.
    #[test]
    fn offset_block_gives_kinetic_energy_of_centre_of_mass() {
        let b = Body::new("b", 2.5, 0.3)
            .unwrap()
            .with_center_of_mass(Vec2::new(0.4, -0.1))
            .unwrap();
        let q = [0.1, 0.2, 0.9];
        let qd = [0.5, -1.0, 2.0];
        let m = MassMatrix::new(std::slice::from_ref(&b), &q);
        let arm = rotation(q[2]) * b.center_of_mass;
        let vcm = Vec2::new(qd[0], qd[1]) + perp(arm) * qd[2];
        let direct = 0.5 * b.mass * vcm.norm_squared() + 0.5 * b.inertia * qd[2] * qd[2];
        assert!((m.kinetic_energy(&qd) - direct).abs() < 1e-14);
    }
}
