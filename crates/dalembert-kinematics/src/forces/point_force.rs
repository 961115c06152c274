use super::{add_point_force, check_body, ForceElement};
use crate::{Body, BodyRef, BodyState, PointState, Vec2};
use dalembert_system::TimeFunction;

/// A force given in global components, applied at a body-fixed point; each component a function of
/// time (use [`TimeFunction::Constant`] for a constant force).
#[derive(Debug, Clone)]
pub struct PointForce {
    /// Element name.
    pub name: String,
    /// Body the force acts on.
    pub body: BodyRef,
    /// Local point of application.
    pub point: Vec2,
    /// Global x component.
    pub fx: TimeFunction,
    /// Global y component.
    pub fy: TimeFunction,
}

impl PointForce {
    /// A constant global force `f` at local point `point` of `body`.
    pub fn constant(name: impl Into<String>, body: BodyRef, point: Vec2, f: Vec2) -> Self {
        PointForce {
            name: name.into(),
            body,
            point,
            fx: TimeFunction::Constant(f.x),
            fy: TimeFunction::Constant(f.y),
        }
    }
}

impl ForceElement for PointForce {
    fn bodies(&self) -> Option<Vec<BodyRef>> {
        Some(vec![self.body])
    }

    fn name(&self) -> &str {
        &self.name
    }

    fn add_generalized_force(&self, t: f64, _bodies: &[Body], q: &[f64], qd: &[f64], q_e: &mut [f64]) {
        let s = BodyState::of(self.body, q, qd);
        let p = PointState::new(&s, self.point);
        add_point_force(self.body, &p, Vec2::new(self.fx.value(t), self.fy.value(t)), q_e);
    }

    /// `Q_θ = perp(A u)·F` for a global force `F(t)`: `−∂Q_θ/∂θ = (A u)·F`.
    fn add_tangent(
        &self,
        t: f64,
        _bodies: &[Body],
        q: &[f64],
        qd: &[f64],
        out: &mut dalembert_system::TangentValues<'_>,
    ) -> bool {
        if let Some(id) = self.body.id() {
            let p = PointState::new(&BodyState::of(self.body, q, qd), self.point);
            let f = Vec2::new(self.fx.value(t), self.fy.value(t));
            out.add_q(3 * id.0 + 2, 3 * id.0 + 2, p.arm.dot(&f));
        }
        true
    }

    fn validate(&self, bodies: usize) -> Result<(), dalembert_system::ModelError> {
        check_body(&self.name, self.body, bodies)?;
        self.fx.validate(&format!("force '{}'", self.name))?;
        self.fy.validate(&format!("force '{}'", self.name))
    }
}
