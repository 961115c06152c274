use super::{add_torque, check_body, ForceElement};
use crate::{Body, BodyRef};
use dalembert_system::TimeFunction;

/// A torque `T(t)` on `body`, with the reaction `−T(t)` on `reaction_body` (the ground by default:
/// then it is simply an external torque). Between the two bodies of a joint this is a motor.
#[derive(Debug, Clone)]
pub struct Torque {
    /// Element name.
    pub name: String,
    /// Body receiving `+T`.
    pub body: BodyRef,
    /// Body receiving `−T`.
    pub reaction_body: BodyRef,
    /// The torque as a function of time (N·m, counter-clockwise positive).
    pub value: TimeFunction,
}

impl Torque {
    /// An external torque on `body`.
    pub fn on(name: impl Into<String>, body: BodyRef, value: TimeFunction) -> Self {
        Torque {
            name: name.into(),
            body,
            reaction_body: BodyRef::Ground,
            value,
        }
    }
}

impl ForceElement for Torque {
    fn bodies(&self) -> Option<Vec<BodyRef>> {
        Some(vec![self.body, self.reaction_body])
    }

    fn name(&self) -> &str {
        &self.name
    }

    fn add_generalized_force(&self, t: f64, _b: &[Body], _q: &[f64], _qd: &[f64], q_e: &mut [f64]) {
        let tau = self.value.value(t);
        add_torque(self.body, tau, q_e);
        add_torque(self.reaction_body, -tau, q_e);
    }

    /// A torque that depends on time only: no derivative.
    fn add_tangent(
        &self,
        _t: f64,
        _bodies: &[Body],
        _q: &[f64],
        _qd: &[f64],
        _out: &mut dalembert_system::TangentValues<'_>,
    ) -> bool {
        true
    }

    fn validate(&self, bodies: usize) -> Result<(), dalembert_system::ModelError> {
        check_body(&self.name, self.body, bodies)?;
        check_body(&self.name, self.reaction_body, bodies)?;
        self.value.validate(&format!("force '{}'", self.name))
    }
}
