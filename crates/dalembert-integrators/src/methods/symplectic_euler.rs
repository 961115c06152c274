//! Semi-implicit (symplectic) Euler, fixed step, first order:
//! `vₙ₊₁ = vₙ + h v̇(tₙ, qₙ, vₙ)`, `qₙ₊₁ = qₙ ⊕ h vₙ₊₁`
//! ([`dalembert_system::MultibodySystem::integrate_positions`], `q + h v` for planar bodies).
//! One evaluation per step; bounded energy error on unconstrained or independent coordinates.

use crate::registry::{no_advice, Applies, MethodEntry, TradeAxis};
use crate::stepper::{Setup, StepControl, StepOutcome, Stepper};
use crate::{IntegrationError, Method};
use dalembert_system::{Baumgarte, Formulation};

/// The registry entry.
pub(crate) static ENTRY: MethodEntry = MethodEntry {
    name: "symplectic-euler",
    aliases: &["euler"],
    summary: "semi-implicit (symplectic) Euler: order 1, one evaluation per step, bounded energy error",
    order: 1,
    control: StepControl::Fixed,
    keeps_constraints: false,
    applies: Applies::AnyFormulation,
    parameters: &[],
    trade: TradeAxis::Steps,
    advice: no_advice,
    build,
};

impl Method {
    /// Semi-implicit (symplectic) Euler, fixed step.
    pub fn symplectic_euler() -> Self {
        Method::of(&ENTRY)
    }
}

struct SymplecticEuler {
    n_q: usize,
    qdd: Vec<f64>,
    lambda: Vec<f64>,
    baumgarte: Option<Baumgarte>,
}

fn build(_: &Method, s: Setup<'_>) -> Result<Box<dyn Stepper>, IntegrationError> {
    let n_v = s.y0.len() - s.n_q;
    Ok(Box::new(SymplecticEuler {
        n_q: s.n_q,
        qdd: vec![0.0; n_v],
        lambda: vec![0.0; s.formulation.system().num_equations()],
        baumgarte: s.baumgarte,
    }))
}

impl Stepper for SymplecticEuler {
    fn step(
        &mut self,
        f: &mut dyn Formulation,
        t: f64,
        h: f64,
        y: &mut [f64],
    ) -> Result<StepOutcome, IntegrationError> {
        {
            let (q, qd) = y.split_at(self.n_q);
            f.accelerations(t, q, qd, self.baumgarte, &mut self.qdd, &mut self.lambda)?;
        }
        let (q, qd) = y.split_at_mut(self.n_q);
        for (v, a) in qd.iter_mut().zip(&self.qdd) {
            *v += h * a;
        }
        f.system().integrate_positions(q, qd, h);
        Ok(StepOutcome::taken(h))
    }
}
