use super::{add_torque, check_body, ForceElement};
use crate::{Body, BodyRef, BodyState};

/// A rotational spring–damper between two bodies: with `φ = θ_j − θ_i − φ₀`, body j receives the
/// torque `−(k φ + c φ̇)` and body i the opposite. Potential energy `½ k φ²`.
#[derive(Debug, Clone)]
pub struct RotationalSpringDamper {
    /// Element name.
    pub name: String,
    /// `(i, j)`; either may be the ground.
    pub bodies: (BodyRef, BodyRef),
    /// Stiffness `k` (N·m/rad).
    pub stiffness: f64,
    /// Damping `c` (N·m·s/rad).
    pub damping: f64,
    /// Free relative angle `φ₀` (rad).
    pub free_angle: f64,
}

impl RotationalSpringDamper {
    fn angle(&self, q: &[f64], qd: &[f64]) -> (f64, f64) {
        let si = BodyState::of(self.bodies.0, q, qd);
        let sj = BodyState::of(self.bodies.1, q, qd);
        (sj.angle - si.angle - self.free_angle, sj.omega - si.omega)
    }
}

impl ForceElement for RotationalSpringDamper {
    fn bodies(&self) -> Option<Vec<BodyRef>> {
        Some(vec![self.bodies.0, self.bodies.1])
    }

    fn name(&self) -> &str {
        &self.name
    }

    fn add_generalized_force(&self, _t: f64, _b: &[Body], q: &[f64], qd: &[f64], q_e: &mut [f64]) {
        let (phi, phi_dot) = self.angle(q, qd);
        let tau = -(self.stiffness * phi + self.damping * phi_dot);
        add_torque(self.bodies.1, tau, q_e);
        add_torque(self.bodies.0, -tau, q_e);
    }

    /// `τ = −(k φ + c φ̇)`, `φ = θ_j − θ_i − φ₀`, on `θ_j` and `−τ` on `θ_i`: `−∂Q/∂q` is `k` on the
    /// diagonal and `−k` off it (over `θ_i, θ_j`), `−∂Q/∂q̇` the same with `c`.
    fn add_tangent(
        &self,
        _t: f64,
        _bodies: &[Body],
        _q: &[f64],
        _qd: &[f64],
        out: &mut dalembert_system::TangentValues<'_>,
    ) -> bool {
        use crate::second_derivatives::{add_pair, Pair6};
        let mut block: Pair6 = [[0.0; 6]; 6];
        block[2][2] = 1.0;
        block[5][5] = 1.0;
        block[2][5] = -1.0;
        block[5][2] = -1.0;
        let bodies = [self.bodies.0, self.bodies.1];
        add_pair(out, bodies, &block, self.stiffness, false);
        add_pair(out, bodies, &block, self.damping, true);
        true
    }

    fn is_conservative(&self) -> bool {
        self.damping == 0.0
    }

    fn potential_energy(&self, _t: f64, _b: &[Body], q: &[f64]) -> Option<f64> {
        let (phi, _) = self.angle(q, &[]);
        Some(0.5 * self.stiffness * phi * phi)
    }

    fn validate(&self, bodies: usize) -> Result<(), dalembert_system::ModelError> {
        check_body(&self.name, self.bodies.0, bodies)?;
        check_body(&self.name, self.bodies.1, bodies)?;
        let ok = [self.stiffness, self.damping, self.free_angle]
            .iter()
            .all(|x| x.is_finite());
        if !ok || self.stiffness < 0.0 || self.damping < 0.0 {
            return Err(dalembert_system::ModelError::InvalidParameter {
                element: format!("force '{}'", self.name),
                what: "stiffness and damping must be finite and non-negative".into(),
            });
        }
        Ok(())
    }
}
