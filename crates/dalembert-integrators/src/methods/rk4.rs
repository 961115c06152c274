//! The classic fourth-order Runge–Kutta method on `y = [q; v]`, fixed step: four evaluations per
//! step, slow energy drift.

use super::first_order::derivative;
use crate::registry::{no_advice, Applies, MethodEntry, TradeAxis};
use crate::stepper::{Setup, StepControl, StepOutcome, Stepper};
use crate::{IntegrationError, Method};
use dalembert_system::{Baumgarte, Formulation};

/// The registry entry.
pub(crate) static ENTRY: MethodEntry = MethodEntry {
    name: "rk4",
    aliases: &[],
    summary: "classic Runge-Kutta: order 4, four evaluations per step",
    order: 4,
    control: StepControl::Fixed,
    keeps_constraints: false,
    applies: Applies::AnyFormulation,
    parameters: &[],
    trade: TradeAxis::Steps,
    advice: no_advice,
    build,
};

impl Method {
    /// Classic fourth-order Runge–Kutta, fixed step.
    pub fn rk4() -> Self {
        Method::of(&ENTRY)
    }
}

struct Rk4 {
    k: [Vec<f64>; 4],
    y_tmp: Vec<f64>,
    qdd: Vec<f64>,
    lambda: Vec<f64>,
    baumgarte: Option<Baumgarte>,
}

fn build(_: &Method, s: Setup<'_>) -> Result<Box<dyn Stepper>, IntegrationError> {
    let len = s.y0.len();
    Ok(Box::new(Rk4 {
        k: std::array::from_fn(|_| vec![0.0; len]),
        y_tmp: vec![0.0; len],
        qdd: vec![0.0; len - s.n_q],
        lambda: vec![0.0; s.formulation.system().num_equations()],
        baumgarte: s.baumgarte,
    }))
}

impl Stepper for Rk4 {
    fn step(
        &mut self,
        f: &mut dyn Formulation,
        t: f64,
        h: f64,
        y: &mut [f64],
    ) -> Result<StepOutcome, IntegrationError> {
        let Rk4 {
            k,
            y_tmp,
            qdd,
            lambda,
            baumgarte,
        } = self;
        let b = *baumgarte;
        let [k1, k2, k3, k4] = k;
        derivative(f, t, y, b, qdd, lambda, k1)?;
        for i in 0..y.len() {
            y_tmp[i] = y[i] + 0.5 * h * k1[i];
        }
        derivative(f, t + 0.5 * h, y_tmp, b, qdd, lambda, k2)?;
        for i in 0..y.len() {
            y_tmp[i] = y[i] + 0.5 * h * k2[i];
        }
        derivative(f, t + 0.5 * h, y_tmp, b, qdd, lambda, k3)?;
        for i in 0..y.len() {
            y_tmp[i] = y[i] + h * k3[i];
        }
        derivative(f, t + h, y_tmp, b, qdd, lambda, k4)?;
        for i in 0..y.len() {
            y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
        Ok(StepOutcome::taken(h))
    }
}
