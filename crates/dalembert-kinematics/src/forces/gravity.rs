use super::ForceElement;
use crate::rotation::rotation;
use crate::BodyRef;
use crate::{Body, Vec2};

/// Uniform gravity: the force `m g` at every body's centre of mass, potential `−m g·r_cm`.
#[derive(Debug, Clone, PartialEq)]
pub struct Gravity {
    /// Gravitational acceleration (e.g. `[0, −9.81]`).
    pub g: Vec2,
}

impl Gravity {
    /// Gravity with acceleration `g`.
    pub fn new(g: Vec2) -> Self {
        Gravity { g }
    }
}

impl ForceElement for Gravity {
    fn bodies(&self) -> Option<Vec<BodyRef>> {
        Some(Vec::new())
    }

    fn name(&self) -> &str {
        "gravity"
    }

    /// `Q_θ = (A c) × f` for a centre of mass `c` off the reference point: `−∂Q_θ/∂θ = (A c)·f`.
    fn add_tangent(
        &self,
        _t: f64,
        bodies: &[Body],
        q: &[f64],
        _qd: &[f64],
        out: &mut dalembert_system::TangentValues<'_>,
    ) -> bool {
        for (i, b) in bodies.iter().enumerate() {
            if b.center_of_mass != Vec2::zeros() {
                let arm = rotation(q[3 * i + 2]) * b.center_of_mass;
                out.add_q(3 * i + 2, 3 * i + 2, arm.dot(&(self.g * b.mass)));
            }
        }
        true
    }

    fn add_generalized_force(&self, _t: f64, bodies: &[Body], q: &[f64], _qd: &[f64], q_e: &mut [f64]) {
        for (i, b) in bodies.iter().enumerate() {
            let f = self.g * b.mass;
            let k = 3 * i;
            q_e[k] += f.x;
            q_e[k + 1] += f.y;
            if b.center_of_mass != Vec2::zeros() {
                let arm = rotation(q[k + 2]) * b.center_of_mass;
                q_e[k + 2] += crate::rotation::cross(arm, f);
            }
        }
    }

    fn is_conservative(&self) -> bool {
        true
    }

    fn potential_energy(&self, _t: f64, bodies: &[Body], q: &[f64]) -> Option<f64> {
        let mut v = 0.0;
        for (i, b) in bodies.iter().enumerate() {
            let k = 3 * i;
            let mut r = Vec2::new(q[k], q[k + 1]);
            if b.center_of_mass != Vec2::zeros() {
                r += rotation(q[k + 2]) * b.center_of_mass;
            }
            v -= b.mass * self.g.dot(&r);
        }
        Some(v)
    }
}
