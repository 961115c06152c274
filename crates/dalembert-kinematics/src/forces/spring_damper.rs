use super::{add_point_force, check_body, ForceElement};
use crate::{Body, BodyRef, BodyState, PointState, Vec2};
use dalembert_system::TimeFunction;

/// A translational spring–damper–actuator between point `P_i` on `bodies.0` and `P_j` on `bodies.1`.
///
/// With `d = r_j − r_i`, `L = |d|`, `e = d / L` and `L̇ = e·ḋ`, the tension is
/// `f = k (L − L₀) + c L̇ + f_a(t)`; body i receives `+f e` at `P_i` and body j `−f e` at `P_j`
/// (a stretched spring pulls the points together). Potential energy `½ k (L − L₀)²`.
#[derive(Debug, Clone)]
pub struct SpringDamper {
    /// Element name.
    pub name: String,
    /// The two bodies (either may be the ground).
    pub bodies: (BodyRef, BodyRef),
    /// Local attachment points on each body.
    pub points: (Vec2, Vec2),
    /// Stiffness `k` (N/m).
    pub stiffness: f64,
    /// Damping `c` (N·s/m).
    pub damping: f64,
    /// Free length `L₀` (m).
    pub free_length: f64,
    /// Actuator tension `f_a(t)` (N), added to the spring and damper forces; `None` for none.
    pub actuator: Option<TimeFunction>,
}

impl SpringDamper {
    fn geometry(&self, q: &[f64], qd: &[f64]) -> (PointState, PointState, f64, Vec2, f64) {
        let si = BodyState::of(self.bodies.0, q, qd);
        let sj = BodyState::of(self.bodies.1, q, qd);
        let pi = PointState::new(&si, self.points.0);
        let pj = PointState::new(&sj, self.points.1);
        let d = pj.position - pi.position;
        let len = d.norm();
        let e = if len > 0.0 { d / len } else { Vec2::zeros() };
        let len_dot = e.dot(&(pj.velocity - pi.velocity));
        (pi, pj, len, e, len_dot)
    }

    /// Current tension `f` (positive when pulling the points together).
    pub fn tension(&self, t: f64, q: &[f64], qd: &[f64]) -> f64 {
        let (_, _, len, _, len_dot) = self.geometry(q, qd);
        let fa = self.actuator.as_ref().map_or(0.0, |f| f.value(t));
        self.stiffness * (len - self.free_length) + self.damping * len_dot + fa
    }
}

impl ForceElement for SpringDamper {
    fn bodies(&self) -> Option<Vec<BodyRef>> {
        Some(vec![self.bodies.0, self.bodies.1])
    }

    fn name(&self) -> &str {
        &self.name
    }

    fn add_generalized_force(&self, t: f64, _b: &[Body], q: &[f64], qd: &[f64], q_e: &mut [f64]) {
        let (pi, pj, len, e, len_dot) = self.geometry(q, qd);
        let fa = self.actuator.as_ref().map_or(0.0, |f| f.value(t));
        let f = self.stiffness * (len - self.free_length) + self.damping * len_dot + fa;
        add_point_force(self.bodies.0, &pi, e * f, q_e);
        add_point_force(self.bodies.1, &pj, -e * f, q_e);
    }

    /// `Q = −f g` with `g = ∂L/∂p` over the two bodies' coordinates `p`, `f = k (L − L₀) + c L̇ +
    /// f_a`, `L̇ = g·ṗ`: `−∂Q/∂q = g (k g + c H ṗ)ᵀ + f H`, `−∂Q/∂q̇ = c g gᵀ`, `H = ∂²L/∂p²`
    /// ([`crate::second_derivatives::distance_derivatives`]). `false` where the points coincide.
    fn add_tangent(
        &self,
        t: f64,
        _bodies: &[Body],
        q: &[f64],
        qd: &[f64],
        out: &mut dalembert_system::TangentValues<'_>,
    ) -> bool {
        use crate::second_derivatives::{add_pair, distance_derivatives, Pair6};
        let (pi, pj, len, _, len_dot) = self.geometry(q, qd);
        let Some((g, h)) = distance_derivatives(&pi, &pj) else {
            return false;
        };
        let fa = self.actuator.as_ref().map_or(0.0, |f| f.value(t));
        let f = self.stiffness * (len - self.free_length) + self.damping * len_dot + fa;
        let mut pdot = [0.0; 6];
        for (side, body) in [self.bodies.0, self.bodies.1].into_iter().enumerate() {
            if let Some(id) = body.id() {
                pdot[3 * side..3 * side + 3].copy_from_slice(&qd[3 * id.0..3 * id.0 + 3]);
            }
        }
        let mut df = [0.0; 6];
        for (a, d) in df.iter_mut().enumerate() {
            *d = self.stiffness * g[a] + self.damping * (0..6).map(|b| h[a][b] * pdot[b]).sum::<f64>();
        }
        let (mut dq, mut dv): (Pair6, Pair6) = ([[0.0; 6]; 6], [[0.0; 6]; 6]);
        for a in 0..6 {
            for b in 0..6 {
                dq[a][b] = g[a] * df[b] + f * h[a][b];
                dv[a][b] = self.damping * g[a] * g[b];
            }
        }
        let bodies = [self.bodies.0, self.bodies.1];
        add_pair(out, bodies, &dq, 1.0, false);
        add_pair(out, bodies, &dv, 1.0, true);
        true
    }

    fn is_conservative(&self) -> bool {
        self.damping == 0.0 && self.actuator.is_none()
    }

    fn potential_energy(&self, _t: f64, _b: &[Body], q: &[f64]) -> Option<f64> {
        let (_, _, len, _, _) = self.geometry(q, &[]);
        Some(0.5 * self.stiffness * (len - self.free_length).powi(2))
    }

    fn validate(&self, bodies: usize) -> Result<(), dalembert_system::ModelError> {
        check_body(&self.name, self.bodies.0, bodies)?;
        check_body(&self.name, self.bodies.1, bodies)?;
        let ok = [self.stiffness, self.damping, self.free_length]
            .iter()
            .all(|x| x.is_finite());
        if !ok || self.stiffness < 0.0 || self.damping < 0.0 || self.free_length < 0.0 {
            return Err(dalembert_system::ModelError::InvalidParameter {
                element: format!("force '{}'", self.name),
                what: "stiffness, damping and free length must be finite and non-negative".into(),
            });
        }
        if let Some(a) = &self.actuator {
            a.validate(&format!("force '{}'", self.name))?;
        }
        Ok(())
    }
}
